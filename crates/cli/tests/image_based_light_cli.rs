//! `EXT_lights_image_based` (issue 50): a file's own image-based light lights and backs the
//! render when no `--env` is given: a camera looking along −Z sees the −Z face of its cube map
//! times its intensity, and the light's rotation turns which face that is; `--env` still wins.

mod common;

use aperture_imageio::read_exr;
use common::{aperture, Scratch};
use serde_json::json;
use std::process::Command;

/// A 4 × 4 PNG of one RGBA colour.
fn png(rgba: [u8; 4]) -> Vec<u8> {
    let img = image::RgbaImage::from_pixel(4, 4, image::Rgba(rgba));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// No geometry; a camera at the origin looking along −Z; an image-based light whose faces
/// (+X, −X, +Y, −Y, +Z, −Z) are red, green, blue, yellow, cyan and magenta.
fn file(rotation: [f32; 4], intensity: f32) -> Vec<u8> {
    let colours = [
        [255, 0, 0, 255],
        [0, 255, 0, 255],
        [0, 0, 255, 255],
        [255, 255, 0, 255],
        [0, 255, 255, 255],
        [255, 0, 255, 255],
    ];
    let (mut bin, mut views) = (Vec::new(), Vec::new());
    for c in colours {
        let p = png(c);
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": p.len()}));
        bin.extend(p);
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
    }
    let images: Vec<_> = (0..6)
        .map(|i| json!({"bufferView": i, "mimeType": "image/png"}))
        .collect();
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["EXT_lights_image_based"],
        "extensions": {"EXT_lights_image_based": {"lights": [{
            "rotation": rotation, "intensity": intensity,
            "irradianceCoefficients": vec![[0.0, 0.0, 0.0]; 9],
            "specularImageSize": 4, "specularImages": [[0, 1, 2, 3, 4, 5]]}]}},
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "images": images,
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.2, "znear": 0.1}}],
        "nodes": [{"camera": 0}],
        "scenes": [{"nodes": [0], "extensions": {"EXT_lights_image_based": {"light": 0}}}]
    });
    common::glb::glb(&doc, &bin)
}

/// The centre pixel of a render of `file` with `args`.
fn centre(dir: &Scratch, name: &str, file: &[u8], args: &[&str]) -> [f32; 4] {
    let scene = dir.path(&format!("{name}.glb"));
    std::fs::write(&scene, file).unwrap();
    let out = dir.path(&format!("{name}.exr"));
    let status = Command::new(aperture())
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .args(["--width", "9", "--height", "9", "--spp", "1", "--quiet"])
        .args(args)
        .status()
        .unwrap();
    assert!(status.success(), "{name}");
    let img = read_exr(&out).unwrap();
    img.rgba[4 * 9 + 4]
}

fn close(a: [f32; 4], b: [f32; 3]) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() < 1e-3)
}

#[test]
fn the_files_image_based_light_is_the_environment() {
    let dir = Scratch::new("ibl");
    let plain = centre(&dir, "plain", &file([0.0, 0.0, 0.0, 1.0], 2.0), &[]);
    assert!(
        close(plain, [2.0, 0.0, 2.0]),
        "−Z face, magenta × 2: {plain:?}"
    );
    // Turned 90° about +Y: +X goes to −Z, so the camera sees the red face.
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let turned = centre(&dir, "turned", &file([0.0, h, 0.0, h], 1.0), &[]);
    assert!(close(turned, [1.0, 0.0, 0.0]), "+X face, red: {turned:?}");
    let over = centre(
        &dir,
        "over",
        &file([0.0, 0.0, 0.0, 1.0], 2.0),
        &["--env", "0.5,0.5,0.5"],
    );
    assert!(close(over, [0.5, 0.5, 0.5]), "--env wins: {over:?}");
    // info no longer calls the extension ignored.
    let info = Command::new(aperture())
        .arg("info")
        .arg(dir.path("plain.glb"))
        .output()
        .unwrap();
    let text = String::from_utf8(info.stdout).unwrap();
    assert!(
        text.contains("extension: EXT_lights_image_based supported"),
        "{text}"
    );
}
