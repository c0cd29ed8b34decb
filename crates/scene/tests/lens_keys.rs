//! The bokeh image and chromatic aberration keys (issue 61) as the loader reads them: an image
//! path relative to the glTF file or a texture index, loaded once as transmissions; the
//! command line's image and numbers winning; bad values and unreadable images named.

use aperture_scene::{load_bytes, DofOverrides, Error, LoadOptions, Scene};
use serde_json::{json, Value};
use std::path::Path;

mod common;

/// A 4 × 2 greyscale PNG: the right half white, the left black.
fn half_png() -> Vec<u8> {
    let img = image::GrayImage::from_fn(4, 2, |x, _| image::Luma([if x >= 2 { 255 } else { 0 }]));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

fn doc(extras: Value) -> Value {
    json!({
        "asset": {"version": "2.0"},
        "cameras": [{"type": "perspective", "name": "Cam", "extras": extras,
                     "perspective": {"yfov": 0.5, "znear": 0.1}}],
        "nodes": [{"camera": 0}],
        "scenes": [{"nodes": [0]}]
    })
}

fn load(doc: &Value, dir: &Path, cli: DofOverrides) -> Result<Scene, Error> {
    let options = LoadOptions {
        dof_overrides: cli,
        ..LoadOptions::default()
    };
    load_bytes(&common::glb::glb(doc, &[]), dir, &options)
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir =
        std::env::temp_dir().join(format!("aperture-lens-keys-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("half.png"), half_png()).unwrap();
    dir
}

#[test]
fn an_image_path_and_chromatic_numbers_are_read() {
    let dir = scratch("read");
    let d = doc(
        json!({"aperture_image": "half.png", "chromatic_lateral": 0.01,
                       "chromatic_longitudinal": -0.02}),
    );
    let s = load(&d, &dir, DofOverrides::default()).unwrap();
    let o = &s.cameras[0].dof.lens_options;
    let image = o.aperture_image.as_ref().expect("an image");
    assert_eq!(
        (image.width, image.height, image.source.as_str()),
        (4, 2, "half.png")
    );
    assert_eq!(image.luminance[..4], [0.0, 0.0, 1.0, 1.0]);
    assert_eq!(
        (o.chromatic.lateral, o.chromatic.longitudinal),
        (0.01, -0.02)
    );
    // The command line wins: its own image and numbers.
    std::fs::write(dir.join("white.png"), {
        let img = image::GrayImage::from_pixel(2, 2, image::Luma([255]));
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Png).unwrap();
        out.into_inner()
    })
    .unwrap();
    let cli = DofOverrides {
        aperture_image: Some(dir.join("white.png")),
        chromatic_lateral: Some(0.0),
        ..DofOverrides::default()
    };
    let s = load(&d, &dir, cli).unwrap();
    let o = &s.cameras[0].dof.lens_options;
    assert!(o.aperture_image.as_ref().unwrap().is_constant());
    assert_eq!(
        (o.chromatic.lateral, o.chromatic.longitudinal),
        (0.0, -0.02)
    );
    // Absent: no image, no aberration.
    let s = load(&doc(json!({})), &dir, DofOverrides::default()).unwrap();
    let o = &s.cameras[0].dof.lens_options;
    assert!(o.aperture_image.is_none() && o.chromatic.is_zero());
}

#[test]
fn a_texture_index_names_the_files_image() {
    let dir = scratch("texture");
    let mut d = doc(json!({"aperture_image": 0}));
    d["images"] = json!([{"uri": "half.png"}]);
    d["textures"] = json!([{"source": 0}]);
    let s = load(&d, &dir, DofOverrides::default()).unwrap();
    let image = s.cameras[0]
        .dof
        .lens_options
        .aperture_image
        .clone()
        .unwrap();
    assert_eq!(image.luminance[..4], [0.0, 0.0, 1.0, 1.0]);
}

#[test]
fn bad_values_and_images_name_camera_key_and_value() {
    let dir = scratch("bad");
    std::fs::write(dir.join("black.png"), {
        let img = image::GrayImage::from_pixel(2, 2, image::Luma([0]));
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Png).unwrap();
        out.into_inner()
    })
    .unwrap();
    for (extras, want) in [
        (json!({"aperture_image": "missing.png"}), "missing.png"),
        (json!({"aperture_image": "../half.png"}), "../half.png"),
        (json!({"aperture_image": 3}), "textures[3]"),
        (json!({"aperture_image": ""}), "expected an image path"),
        (json!({"aperture_image": true}), "expected an image path"),
        (json!({"aperture_image": "black.png"}), "black"),
        (json!({"chromatic_lateral": 0.7}), "between -0.5 and 0.5"),
        (json!({"chromatic_longitudinal": "x"}), "expected a number"),
    ] {
        let e = load(&doc(extras.clone()), &dir, DofOverrides::default())
            .expect_err(&extras.to_string())
            .to_string();
        let key = extras.as_object().unwrap().keys().next().unwrap().clone();
        assert!(e.contains("Cam"), "{extras}: {e}");
        assert!(
            e.contains(&format!("cameras.extras.{key}")),
            "{extras}: {e}"
        );
        assert!(e.contains(want), "{extras}: {e}");
    }
    let cli = DofOverrides {
        aperture_image: Some(dir.join("nowhere.png")),
        ..DofOverrides::default()
    };
    let e = load(&doc(json!({})), &dir, cli).unwrap_err().to_string();
    assert!(
        e.contains("command line aperture_image") && e.contains("nowhere.png"),
        "{e}"
    );
}
