//! Ray files (the Embree anchor's raw format): round trips bit for bit, and damaged files are
//! typed errors that name the file.

use aperture_accel::rayfile::{decode_rays, encode_rays, tmax_path, RAY_RECORD_BYTES};
use aperture_accel::{read_rays, write_rays, Ray, RayFileError};
use glam::Vec3;
use std::path::PathBuf;

/// A scratch folder, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let dir =
            std::env::temp_dir().join(format!("aperture-rayfile-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Rays with awkward values: negative zero, subnormals, large and tiny magnitudes.
fn awkward_rays() -> Vec<Ray> {
    let mut rays = Vec::new();
    for i in 0..50u32 {
        let f = i as f32;
        let origin = Vec3::new(f * 1.0e5 - 3.0, -0.0, f32::MIN_POSITIVE / (f + 1.0));
        let dir = Vec3::new(f.sin(), f.cos(), 0.1 * f - 2.0).normalize();
        rays.push(Ray::new(origin, dir));
    }
    rays
}

fn bits(rays: &[Ray]) -> Vec<[u32; 8]> {
    rays.iter()
        .map(|r| {
            [
                r.origin.x.to_bits(),
                r.origin.y.to_bits(),
                r.origin.z.to_bits(),
                r.dir.x.to_bits(),
                r.dir.y.to_bits(),
                r.dir.z.to_bits(),
                r.tmin.to_bits(),
                r.tmax.to_bits(),
            ]
        })
        .collect()
}

#[test]
fn written_rays_read_back_bit_for_bit() {
    let dir = Scratch::new("roundtrip");
    let path = dir.0.join("set.rays");
    let rays = awkward_rays();
    write_rays(&path, &rays).unwrap();
    assert_eq!(
        std::fs::metadata(&path).unwrap().len() as usize,
        RAY_RECORD_BYTES * rays.len()
    );
    // Rays to infinity need no sidecar.
    assert!(!tmax_path(&path).exists());
    assert_eq!(bits(&read_rays(&path).unwrap()), bits(&rays));
}

#[test]
fn finite_tmax_goes_to_the_sidecar_and_comes_back() {
    let dir = Scratch::new("tmax");
    let path = dir.0.join("shadow.rays");
    let mut rays = awkward_rays();
    for (i, r) in rays.iter_mut().enumerate() {
        r.tmax = 0.5 + i as f32;
    }
    write_rays(&path, &rays).unwrap();
    assert_eq!(
        std::fs::metadata(tmax_path(&path)).unwrap().len() as usize,
        4 * rays.len()
    );
    assert_eq!(bits(&read_rays(&path).unwrap()), bits(&rays));
    // The .rays file alone (as Embree reads it) has the rays to infinity.
    let plain = decode_rays(&std::fs::read(&path).unwrap(), &path).unwrap();
    assert!(plain.iter().all(|r| r.tmax == f32::INFINITY));
    // Writing rays to infinity over it removes the stale sidecar.
    write_rays(&path, &awkward_rays()).unwrap();
    assert!(!tmax_path(&path).exists());
}

#[test]
fn embree_layout_is_six_little_endian_floats() {
    let ray = Ray::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, 0.6, 0.8));
    let bytes = encode_rays(&[ray]);
    let expected: Vec<u8> = [1.0f32, 2.0, 3.0, 0.0, 0.6, 0.8]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    assert_eq!(bytes, expected);
}

#[test]
fn truncated_file_is_a_length_error_naming_it() {
    let dir = Scratch::new("truncated");
    let path = dir.0.join("cut.rays");
    let mut bytes = encode_rays(&awkward_rays());
    bytes.truncate(bytes.len() - 5);
    std::fs::write(&path, &bytes).unwrap();
    let err = read_rays(&path).unwrap_err();
    assert!(
        matches!(&err, RayFileError::Length { path: p, len, record: 24 } if *p == path && *len == bytes.len()),
        "{err:?}"
    );
    assert!(err.to_string().contains("cut.rays"), "{err}");
}

#[test]
fn missing_file_and_nan_are_errors_naming_the_file() {
    let dir = Scratch::new("bad");
    let missing = dir.0.join("missing.rays");
    let err = read_rays(&missing).unwrap_err();
    assert!(matches!(err, RayFileError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("missing.rays"), "{err}");

    let path = dir.0.join("nan.rays");
    let mut rays = awkward_rays();
    rays[7].dir.y = f32::NAN;
    std::fs::write(&path, encode_rays(&rays)).unwrap();
    let err = read_rays(&path).unwrap_err();
    assert!(
        matches!(&err, RayFileError::NotFinite { ray: 7, .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("nan.rays"), "{err}");
}

#[test]
fn sidecar_of_another_length_is_an_error_naming_it() {
    let dir = Scratch::new("sidecar");
    let path = dir.0.join("s.rays");
    write_rays(&path, &awkward_rays()).unwrap();
    std::fs::write(tmax_path(&path), 1.0f32.to_le_bytes()).unwrap();
    let err = read_rays(&path).unwrap_err();
    assert!(
        matches!(
            &err,
            RayFileError::TmaxCount {
                found: 1,
                expected: 50,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("s.tmax"), "{err}");
    std::fs::write(tmax_path(&path), [0u8; 3]).unwrap();
    assert!(matches!(
        read_rays(&path).unwrap_err(),
        RayFileError::Length { record: 4, .. }
    ));
}
