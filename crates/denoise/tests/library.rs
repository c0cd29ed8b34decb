//! The library found and not found, and a denoising that removes noise. Tests that need OIDN
//! skip with a message when it is missing, except under `CI=true`, where CI has installed it
//! (`tools/oidn/install.sh`) and a missing library is a failure.

use aperture_denoise::{DenoiseError, Denoiser, Images, Origin};
use std::path::Path;

/// The library, or `None` (with a message) outside CI when it is missing.
fn denoiser() -> Option<Denoiser> {
    match Denoiser::load(None) {
        Ok(d) => Some(d),
        Err(e) if std::env::var("CI").as_deref() != Ok("true") => {
            eprintln!("skipping: {e}");
            None
        }
        Err(e) => panic!("CI=true and no OIDN (tools/oidn/install.sh runs first): {e}"),
    }
}

#[test]
fn a_file_that_is_no_library_is_a_clean_error() {
    let path = std::env::temp_dir().join(format!("aperture-not-oidn-{}.so", std::process::id()));
    std::fs::write(&path, b"not an ELF file").unwrap();
    let err = Denoiser::load(Some(&path)).unwrap_err();
    std::fs::remove_file(&path).ok();
    match &err {
        DenoiseError::Load {
            path: p, origin, ..
        } => {
            assert_eq!(p, &path);
            assert_eq!(*origin, Origin::Explicit);
        }
        other => panic!("{other:?}"),
    }
    let line = err.to_string();
    assert!(!line.contains('\n'), "one line: {line}");
    assert!(line.contains("tools/oidn/install.sh"), "{line}");
}

#[test]
fn a_folder_without_the_library_is_a_clean_error() {
    let err = Denoiser::load(Some(Path::new("/"))).unwrap_err();
    assert!(matches!(err, DenoiseError::Load { .. }), "{err:?}");
    assert!(
        err.to_string().contains("libOpenImageDenoise.so.2"),
        "{err}"
    );
}

#[test]
fn the_library_is_found_and_is_version_2() {
    let Some(d) = denoiser() else { return };
    assert!(d.version_string().starts_with("2."), "{d:?}");
}

#[test]
fn an_explicit_path_to_the_library_loads_it() {
    let Some(d) = denoiser() else { return };
    if d.origin() == Origin::System {
        return; // a bare soname: no path to hand back
    }
    let again = Denoiser::load(Some(d.path())).unwrap();
    assert_eq!(again.origin(), Origin::Explicit);
    assert_eq!(again.version_string(), d.version_string());
}

/// A smooth gradient plus hash noise: denoising brings it much closer to the gradient.
#[test]
fn denoising_removes_noise_and_keeps_a_gradient() {
    let Some(d) = denoiser() else { return };
    let (w, h) = (64usize, 48usize);
    let clean: Vec<[f32; 3]> = (0..w * h)
        .map(|i| {
            let v = 0.2 + 0.6 * (i % w) as f32 / w as f32;
            [v, v * 0.5, 0.3]
        })
        .collect();
    let noisy: Vec<[f32; 3]> = clean
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let r = (((i as u32).wrapping_mul(2654435761) >> 8) % 1000) as f32 / 1000.0;
            let k = 0.4 + 1.2 * r; // mean 1
            [c[0] * k, c[1] * k, c[2] * k]
        })
        .collect();
    let albedo = vec![[0.8f32; 3]; w * h];
    let normal = vec![[0.0f32, 0.0, 1.0]; w * h];
    let images = Images {
        width: w,
        height: h,
        colour: &noisy,
        albedo: &albedo,
        normal: &normal,
    };
    let out = d.denoise(&images).unwrap();
    let rmse = |a: &[[f32; 3]]| {
        let s: f64 = a
            .iter()
            .zip(&clean)
            .flat_map(|(x, y)| (0..3).map(move |c| f64::from(x[c] - y[c]).powi(2)))
            .sum();
        (s / (3 * w * h) as f64).sqrt()
    };
    let (before, after) = (rmse(&noisy), rmse(&out));
    eprintln!("rmse noisy {before:.4}, denoised {after:.4}");
    assert!(after < 0.25 * before, "noisy {before}, denoised {after}");
}

#[test]
fn images_of_the_wrong_size_are_refused() {
    let Some(d) = denoiser() else { return };
    let px = vec![[0.5f32; 3]; 10];
    let images = Images {
        width: 4,
        height: 4,
        colour: &px,
        albedo: &px,
        normal: &px,
    };
    assert!(matches!(
        d.denoise(&images),
        Err(DenoiseError::Size {
            what: "colour",
            len: 10,
            ..
        })
    ));
}
