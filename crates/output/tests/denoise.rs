//! Denoised output (SPEC §6, issue 45): `render_exr_denoised` keeps the noisy beauty as
//! `Noisy Image` (bit for bit the undenoised render's beauty) with the Denoising passes and
//! alpha, with regions, half floats and adaptive sampling; merge refuses denoised parts and
//! `merge_exr_denoised` denoises the merged image once. Tests that need Open Image Denoise
//! skip with a message without it, except under `CI=true`, where they fail.

mod common;

use aperture_denoise::Denoiser;
use aperture_imageio::{read_exr, Image, MetaValue, SampleType};
use aperture_output::denoised::{check_channels, DenoisingError, DENOISED, NOISY_IMAGE};
use aperture_output::merge::{merge_exr, merge_exr_denoised, MergeError, MergeOptions};
use aperture_output::ExrOptions;
use aperture_render::{AdaptiveOptions, PassSet, RenderOptions, Window};
use aperture_shading::test_scenes;
use std::path::PathBuf;

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

fn opts() -> RenderOptions {
    RenderOptions {
        width: 48,
        height: 32,
        spp: 8,
        passes: PassSet::compositing(),
        ..RenderOptions::default()
    }
}

fn scratch(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("aperture-denoise-{}-{name}", std::process::id()))
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|f| f.to_bits()).collect()
}

/// Renders `o` with `exr` plain and denoised; returns both files read back.
fn both(o: &RenderOptions, exr: &ExrOptions, d: &Denoiser, name: &str) -> (Image, Image) {
    let scene = test_scenes::balls();
    let (plain, den) = (
        scratch(&format!("{name}-plain.exr")),
        scratch(&format!("{name}.exr")),
    );
    common::write_exr(&scene, o, &plain, exr, None, &|_, _| {}).unwrap();
    common::write_exr(&scene, o, &den, exr, Some(d), &|_, _| {}).unwrap();
    let images = (read_exr(&plain).unwrap(), read_exr(&den).unwrap());
    std::fs::remove_file(plain).ok();
    std::fs::remove_file(den).ok();
    images
}

/// The denoised file against the plain one: the noisy beauty kept bit for bit, alpha and
/// every pass equal, a different (denoised) RGB, the header flag set.
fn check(plain: &Image, den: &Image) {
    let noisy = den.layer(NOISY_IMAGE).expect("Noisy Image layer");
    assert_eq!(noisy.channels, ["R", "G", "B", "A"]);
    assert_eq!(noisy.sample_type, plain.beauty_type);
    assert_eq!(bits(&noisy.data), bits(plain.rgba.as_flattened()));
    for (a, b) in den.rgba.iter().zip(&plain.rgba) {
        assert_eq!(a[3].to_bits(), b[3].to_bits(), "alpha kept");
    }
    assert_ne!(
        bits(den.rgba.as_flattened()),
        bits(plain.rgba.as_flattened())
    );
    for layer in &plain.layers {
        let l = den.layer(&layer.name).expect("pass kept");
        assert_eq!(bits(&l.data), bits(&layer.data), "{}", layer.name);
    }
    assert!(den.layer("Denoising Albedo").is_some() && den.layer("Denoising Normal").is_some());
    assert_eq!(den.meta(DENOISED), Some(&MetaValue::Int(1)));
    assert_eq!(den.placement, plain.placement);
}

#[test]
fn a_denoised_render_keeps_the_noisy_beauty_the_passes_and_alpha() {
    let Some(d) = denoiser() else { return };
    let (plain, den) = both(&opts(), &ExrOptions::default(), &d, "whole");
    check(&plain, &den);
}

#[test]
fn denoising_works_with_regions_half_floats_and_adaptive_sampling() {
    let Some(d) = denoiser() else { return };
    let mut o = opts();
    o.adaptive = Some(AdaptiveOptions {
        threshold: 0.05,
        min_spp: 4,
    });
    let exr = ExrOptions {
        region: Some(Window {
            x0: 8,
            y0: 4,
            width: 24,
            height: 20,
        }),
        half: true,
        ..ExrOptions::default()
    };
    let (plain, den) = both(&o, &exr, &d, "region");
    assert_eq!((den.width, den.height), (24, 20));
    assert_eq!(den.beauty_type, SampleType::F16);
    check(&plain, &den);
}

#[test]
fn passes_none_still_gets_the_denoising_passes() {
    let Some(d) = denoiser() else { return };
    let o = RenderOptions {
        passes: PassSet::NONE,
        ..opts()
    };
    let scene = test_scenes::balls();
    let path = scratch("none.exr");
    common::write_exr(
        &scene,
        &o,
        &path,
        &ExrOptions::default(),
        Some(&d),
        &|_, _| {},
    )
    .unwrap();
    let den = read_exr(&path).unwrap();
    std::fs::remove_file(path).ok();
    assert!(den.layer("Denoising Albedo").is_some() && den.layer(NOISY_IMAGE).is_some());
}

#[test]
fn merge_refuses_a_denoised_part_and_merge_denoised_denoises_once() {
    let Some(d) = denoiser() else { return };
    let scene = test_scenes::balls();
    let o = opts();
    let tiles: Vec<PathBuf> = (0..2)
        .map(|k| {
            let path = scratch(&format!("tile{k}.exr"));
            let exr = ExrOptions {
                region: Window::band(k, 2, o.width, o.height),
                tile: Some((k, 2)),
                ..ExrOptions::default()
            };
            if k == 0 {
                common::write_exr(&scene, &o, &path, &exr, Some(&d), &|_, _| {})
            } else {
                common::write_exr(&scene, &o, &path, &exr, None, &|_, _| {})
            }
            .unwrap();
            path
        })
        .collect();
    let out = scratch("merged.exr");
    let err = merge_exr(&tiles, &out, &MergeOptions::default()).unwrap_err();
    assert!(
        matches!(&err, MergeError::DenoisedPart { path } if *path == tiles[0]),
        "{err}"
    );
    assert!(err.to_string().contains("not linear"), "{err}");
    assert!(!out.exists(), "nothing written");
    // Both tiles undenoised: merged, then denoised once.
    let exr = ExrOptions {
        region: Window::band(0, 2, o.width, o.height),
        tile: Some((0, 2)),
        ..ExrOptions::default()
    };
    common::write_exr(&scene, &o, &tiles[0], &exr, None, &|_, _| {}).unwrap();
    merge_exr_denoised(&tiles, &out, &MergeOptions::default(), &d).unwrap();
    let merged = read_exr(&out).unwrap();
    assert_eq!(merged.meta(DENOISED), Some(&MetaValue::Int(1)));
    assert!(merged.layer(NOISY_IMAGE).is_some());
    // Its parts' noisy beauty, pasted, is the merged file's Noisy Image.
    let whole = scratch("whole.exr");
    common::write_exr(&scene, &o, &whole, &ExrOptions::default(), None, &|_, _| {}).unwrap();
    let whole_img = read_exr(&whole).unwrap();
    let noisy = merged.layer(NOISY_IMAGE).unwrap();
    assert_eq!(bits(&noisy.data), bits(whole_img.rgba.as_flattened()));
    for p in tiles.iter().chain([&out, &whole]) {
        std::fs::remove_file(p).ok();
    }
}

#[test]
fn missing_denoising_channels_are_named() {
    let err = check_channels(&["R", "G", "B", "A", "Denoising Albedo.R", "Depth.Z"]).unwrap_err();
    let DenoisingError::Missing { missing } = &err else {
        panic!("{err:?}")
    };
    assert_eq!(
        missing,
        &[
            "Denoising Albedo.G",
            "Denoising Albedo.B",
            "Denoising Normal.X",
            "Denoising Normal.Y",
            "Denoising Normal.Z"
        ]
    );
    assert!(err.to_string().contains("Denoising Normal.X"), "{err}");
    // Blender's multilayer names (view layer prefix, Combined beauty) are accepted.
    let blender = [
        "ViewLayer.Combined.R",
        "ViewLayer.Combined.G",
        "ViewLayer.Combined.B",
        "ViewLayer.Denoising Albedo.R",
        "ViewLayer.Denoising Albedo.G",
        "ViewLayer.Denoising Albedo.B",
        "ViewLayer.Denoising Normal.X",
        "ViewLayer.Denoising Normal.Y",
        "ViewLayer.Denoising Normal.Z",
    ];
    assert!(check_channels(&blender).is_ok());
    let err = check_channels(&blender[3..]).unwrap_err();
    assert!(
        err.to_string().contains("missing channels R, G, B"),
        "{err}"
    );
}

/// A file Cycles denoised has its own `<view layer>.Noisy Image`: that is what gets denoised,
/// and it is kept, not written twice.
#[test]
fn an_existing_noisy_image_is_denoised_and_kept() {
    let Some(d) = denoiser() else { return };
    let (w, h) = (24u32, 16u32);
    let n = (w * h) as usize;
    let mut img = Image::new(w, h);
    let noisy: Vec<f32> = (0..n)
        .flat_map(|i| {
            let v = 0.5 + 0.4 * (((i as u32).wrapping_mul(2654435761) >> 24) as f32 / 255.0 - 0.5);
            [v, v, v, 1.0]
        })
        .collect();
    for p in &mut img.rgba {
        *p = [0.2, 0.2, 0.2, 1.0]; // the beauty Cycles denoised (here: something else)
    }
    img.layers = vec![
        aperture_imageio::Layer::new(
            "ViewLayer.Denoising Albedo",
            &["R", "G", "B"],
            vec![0.8; 3 * n],
        ),
        aperture_imageio::Layer::new(
            "ViewLayer.Denoising Normal",
            &["X", "Y", "Z"],
            [0.0, 0.0, 1.0].repeat(n),
        ),
        aperture_imageio::Layer::new(
            "ViewLayer.Noisy Image",
            &["R", "G", "B", "A"],
            noisy.clone(),
        ),
    ];
    aperture_output::denoised::denoise_image(&mut img, &d).unwrap();
    let layers: Vec<&str> = img.layers.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(
        layers.iter().filter(|l| l.ends_with(NOISY_IMAGE)).count(),
        1,
        "{layers:?}"
    );
    assert_eq!(
        bits(&img.layer("ViewLayer.Noisy Image").unwrap().data),
        bits(&noisy)
    );
    // The noisy image was denoised, not the old beauty (0.2): its mean stays near 0.5.
    let mean = img.rgba.iter().map(|p| p[0]).sum::<f32>() / n as f32;
    assert!((mean - 0.5).abs() < 0.05, "{mean}");
}
