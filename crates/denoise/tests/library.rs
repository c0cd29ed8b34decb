//! The library found and not found, and a denoising that removes noise. Tests that need OIDN
//! skip with a message when it is missing, except under `CI=true`, where CI has installed it
//! (`tools/oidn/install.sh`) and a missing library is a failure.

use aperture_denoise::{DenoiseError, Denoiser, Images, Origin, Prefilter, Quality, Settings};
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
        err.to_string().contains(aperture_denoise::locate::LIBRARY),
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

/// A 64×48 smooth gradient and the same with hash noise of mean 1 (`salt` picks the noise).
fn gradient(salt: u32) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let (w, h) = (64usize, 48usize);
    let clean: Vec<[f32; 3]> = (0..w * h)
        .map(|i| {
            let v = 0.2 + 0.6 * (i % w) as f32 / w as f32;
            [v, v * 0.5, 0.3]
        })
        .collect();
    let noisy = clean
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let x = (i as u32 ^ salt.wrapping_mul(0x9e37_79b9)).wrapping_mul(2654435761);
            let r = ((x >> 8) % 1000) as f32 / 1000.0;
            let k = 0.4 + 1.2 * r; // mean 1
            [c[0] * k, c[1] * k, c[2] * k]
        })
        .collect();
    (clean, noisy)
}

/// Root-mean-square difference of two images.
fn rmse(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let s: f64 = a
        .iter()
        .zip(b)
        .flat_map(|(x, y)| (0..3).map(move |c| f64::from(x[c] - y[c]).powi(2)))
        .sum();
    (s / (3 * a.len()) as f64).sqrt()
}

/// Denoising brings a noisy gradient much closer to the gradient.
#[test]
fn denoising_removes_noise_and_keeps_a_gradient() {
    let Some(d) = denoiser() else { return };
    let (clean, noisy) = gradient(0);
    let albedo = vec![[0.8f32; 3]; clean.len()];
    let normal = vec![[0.0f32, 0.0, 1.0]; clean.len()];
    let images = Images {
        width: 64,
        height: 48,
        colour: &noisy,
        albedo: &albedo,
        normal: &normal,
    };
    let out = d.denoise(&images).unwrap();
    let (before, after) = (rmse(&noisy, &clean), rmse(&out, &clean));
    eprintln!("rmse noisy {before:.4}, denoised {after:.4}");
    assert!(after < 0.25 * before, "noisy {before}, denoised {after}");
}

/// Every quality and prefilter denoises the gradient with a clean albedo; with a grainy one,
/// the fast prefilter (the albedo taken as noisy) beats none (taken as clean: its grain
/// passes into the image) at every quality.
#[test]
fn every_setting_denoises_and_a_grainy_albedo_needs_a_prefilter() {
    if denoiser().is_none() {
        return;
    }
    let (clean, noisy) = gradient(0);
    let (_, grainy) = gradient(7);
    let flat = vec![[0.8f32; 3]; clean.len()];
    let grainy: Vec<[f32; 3]> = grainy.iter().map(|p| [p[0]; 3]).collect();
    let normal = vec![[0.0f32, 0.0, 1.0]; clean.len()];
    let error = |albedo: &[[f32; 3]], quality, prefilter| {
        let d = Denoiser::load(None)
            .unwrap()
            .with_settings(Settings { quality, prefilter });
        let images = Images {
            width: 64,
            height: 48,
            colour: &noisy,
            albedo,
            normal: &normal,
        };
        let out = d.denoise(&images).unwrap();
        assert!(out.iter().flatten().all(|v| v.is_finite()));
        rmse(&out, &clean)
    };
    let before = rmse(&noisy, &clean);
    for quality in [Quality::Fast, Quality::Balanced, Quality::High] {
        let all = [Prefilter::None, Prefilter::Fast, Prefilter::Accurate];
        let flat_error = all.map(|p| error(&flat, quality, p));
        let (trusted, cleaned) = (
            error(&grainy, quality, Prefilter::None),
            error(&grainy, quality, Prefilter::Fast),
        );
        eprintln!(
            "{quality:?}: noisy {before:.4}; flat albedo, none/fast/accurate {flat_error:.4?}; \
             grainy albedo, none {trusted:.4} fast {cleaned:.4}"
        );
        assert!(
            flat_error.iter().all(|e| *e < 0.3 * before),
            "{quality:?}: {flat_error:?}"
        );
        assert!(cleaned < 0.5 * trusted, "{quality:?}: {cleaned} {trusted}");
    }
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
