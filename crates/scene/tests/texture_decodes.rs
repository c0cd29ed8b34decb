//! Texels are decoded only for textures a material reads, and not at all when a load skips
//! textures (`aperture info`; issue 59): counted by `aperture_scene::texture_decodes`.

mod common;

use aperture_scene::{texture_decodes, Animated, LoadOptions, Texels};
use serde_json::json;
use std::path::Path;

/// A `w`×`h` PNG in a buffer view's bytes.
fn png(w: u32, h: u32) -> Vec<u8> {
    let mut out = Vec::new();
    image::DynamicImage::ImageRgba8(image::RgbaImage::from_pixel(w, h, [9, 8, 7, 255].into()))
        .write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

/// One triangle with UVs whose material reads texture 0 (a 2×2 image); texture 1 (a 3×3
/// image) is in the file but no material reads it.
fn file() -> Vec<u8> {
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    let (used, unused) = (png(2, 2), png(3, 3));
    let used_at = bin.len();
    bin.extend_from_slice(&used);
    let unused_at = bin.len();
    bin.extend_from_slice(&unused);
    let doc = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 24},
            {"buffer": 0, "byteOffset": used_at, "byteLength": used.len()},
            {"buffer": 0, "byteOffset": unused_at, "byteLength": unused.len()}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}
        ],
        "images": [{"bufferView": 2, "mimeType": "image/png"},
            {"bufferView": 3, "mimeType": "image/png"}],
        "textures": [{"source": 0}, {"source": 1}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1},
            "material": 0}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    });
    common::glb::glb(&doc, &bin)
}

// One test in this binary: the counter is the process's.
#[test]
fn only_textures_a_material_reads_are_decoded_and_info_loads_decode_none() {
    let bytes = file();
    let load = |skip_textures| {
        let options = LoadOptions {
            skip_textures,
            ..LoadOptions::default()
        };
        Animated::load_bytes(&bytes, Path::new("."), &options)
            .and_then(|a| a.scene_at(None))
            .unwrap()
    };
    let before = texture_decodes();
    let skipped = load(true);
    assert_eq!(
        texture_decodes(),
        before,
        "a load skipping textures decoded one"
    );
    assert_eq!(skipped.textures.len(), 1);

    let full = load(false);
    assert_eq!(texture_decodes(), before + 1, "only the material's texture");
    let t = &full.textures[0];
    assert_eq!((t.width, t.height), (2, 2));
    assert_eq!(t.texels, Texels::Rgba8(vec![[9, 8, 7, 255]; 4]));
}
