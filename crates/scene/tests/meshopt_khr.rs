//! `KHR_meshopt_compression` (issue 48): a file that requires the Khronos name loads, every
//! filter decodes under it (exponential positions, octahedral normals, YCoCg colours, quaternion
//! rotations of an animation), and it loads exactly as the same file under the vendor name
//! `EXT_meshopt_compression`. The streams are written here with meshoptimizer's own encoder.

use aperture_scene::{load_bytes, LoadOptions};
use glam::{Quat, Vec3};
use meshopt::encoding::{
    encode_filter_color, encode_filter_exp, encode_filter_oct, encode_filter_quat,
    encode_vertex_buffer, EncodeExpMode,
};
use serde_json::{json, Value};
use std::path::Path;

mod common;

const POSITIONS: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.5, 0.0, 0.25], [0.0, 2.0, -0.5]];
const NORMALS: [[f32; 4]; 3] = [
    [0.0, 0.0, 1.0, 0.0],
    [0.6, 0.0, 0.8, 0.0],
    [0.0, -0.6, 0.8, 0.0],
];
const COLORS: [[f32; 4]; 3] = [
    [1.0, 0.0, 0.0, 1.0],
    [0.2, 0.7, 0.1, 1.0],
    [0.3, 0.3, 0.9, 1.0],
];

fn rotations() -> [Quat; 2] {
    [Quat::from_rotation_z(0.5), Quat::from_rotation_z(0.5)]
}

/// One compressed attribute stream: bytes, stride, element count, filter.
struct Stream(Vec<u8>, usize, usize, &'static str);

/// Appends a compressed stream to `bin`; returns its buffer view (decoded into the fallback
/// buffer at `decoded_at`).
fn view(bin: &mut Vec<u8>, decoded_at: &mut usize, s: Stream, ext: &str) -> Value {
    let Stream(stream, stride, count, filter) = s;
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let at = bin.len();
    bin.extend_from_slice(&stream);
    let length = stride * count;
    let v = json!({"buffer": 1, "byteOffset": *decoded_at, "byteLength": length,
        "byteStride": stride,
        "extensions": {ext: {"buffer": 0, "byteOffset": at, "byteLength": stream.len(),
            "byteStride": stride, "count": count, "mode": "ATTRIBUTES", "filter": filter}}});
    *decoded_at += length;
    v
}

/// A one-triangle file whose node turns (a rotation animation), every attribute compressed under
/// the extension name `ext`, each with one of the four filters.
fn file(ext: &str) -> Vec<u8> {
    let mut bin = Vec::new();
    let mut decoded = 0;
    let exp = encode_filter_exp::<3>(&POSITIONS, 15, EncodeExpMode::Separate);
    let oct = encode_filter_oct::<i8>(&NORMALS, 8);
    let col = encode_filter_color::<u8>(&COLORS, 8);
    let q: Vec<[f32; 4]> = rotations().iter().map(|r| r.to_array()).collect();
    let quat = encode_filter_quat(&q, 12);
    let streams = [
        Stream(encode_vertex_buffer(&exp).unwrap(), 12, 3, "EXPONENTIAL"),
        Stream(encode_vertex_buffer(&oct).unwrap(), 4, 3, "OCTAHEDRAL"),
        Stream(encode_vertex_buffer(&col).unwrap(), 4, 3, "COLOR"),
        Stream(encode_vertex_buffer(&quat).unwrap(), 8, 2, "QUATERNION"),
    ];
    let mut views: Vec<Value> = streams
        .into_iter()
        .map(|s| view(&mut bin, &mut decoded, s, ext))
        .collect();
    // Plain data after the streams: indices and the animation's times.
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let plain = bin.len();
    for i in [0u16, 1, 2, 0] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    for t in [0.0f32, 1.0] {
        bin.extend_from_slice(&t.to_le_bytes());
    }
    views.push(json!({"buffer": 0, "byteOffset": plain, "byteLength": 6}));
    views.push(json!({"buffer": 0, "byteOffset": plain + 8, "byteLength": 8}));
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": [ext, "KHR_mesh_quantization"],
        "extensionsRequired": [ext, "KHR_mesh_quantization"],
        "buffers": [
            {"byteLength": bin.len()},
            {"byteLength": decoded, "extensions": {ext: {"fallback": true}}}
        ],
        "bufferViews": views,
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0.0, 0.0, -0.5], "max": [1.5, 2.0, 0.25]},
            {"bufferView": 1, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC4"},
            {"bufferView": 3, "componentType": 5122, "normalized": true, "count": 2, "type": "VEC4"},
            {"bufferView": 4, "componentType": 5123, "count": 3, "type": "SCALAR"},
            {"bufferView": 5, "componentType": 5126, "count": 2, "type": "SCALAR",
             "min": [0.0], "max": [1.0]}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "COLOR_0": 2},
            "indices": 4}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "animations": [{"samplers": [{"input": 5, "output": 3}],
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "rotation"}}]}]
    });
    common::glb::glb(&doc, &bin)
}

fn posed() -> LoadOptions {
    LoadOptions {
        time: Some(0.5),
        ..LoadOptions::default()
    }
}

#[test]
fn every_filter_decodes_under_the_khronos_name() {
    let s = load_bytes(&file("KHR_meshopt_compression"), Path::new("."), &posed()).unwrap();
    let m = &s.meshes[0];
    for (got, want) in m.positions.iter().zip(POSITIONS) {
        assert!(
            (*got - Vec3::from(want)).length() < 1e-3,
            "position {got} != {want:?}"
        );
    }
    for (got, want) in m.normals.iter().zip(NORMALS) {
        let want = Vec3::new(want[0], want[1], want[2]);
        assert!(got.normalize().dot(want) > 0.999, "normal {got} != {want}");
    }
    for (got, want) in m.colors.iter().zip(COLORS) {
        for k in 0..4 {
            assert!((got[k] - want[k]).abs() < 0.02, "colour {got} != {want:?}");
        }
    }
    assert_eq!(m.indices, vec![[0, 1, 2]]);
    let (_, rotation, _) = s.instances[0]
        .world_from_object
        .to_scale_rotation_translation();
    assert!(
        rotation.angle_between(rotations()[0]) < 2e-3,
        "the animated rotation decodes as {rotation}"
    );
}

#[test]
fn the_khronos_and_vendor_names_load_the_same_scene() {
    let khr = load_bytes(&file("KHR_meshopt_compression"), Path::new("."), &posed()).unwrap();
    let ext = load_bytes(&file("EXT_meshopt_compression"), Path::new("."), &posed()).unwrap();
    let (a, b) = (&khr.meshes[0], &ext.meshes[0]);
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.normals, b.normals);
    assert_eq!(a.colors, b.colors);
    assert_eq!(
        khr.instances[0].world_from_object,
        ext.instances[0].world_from_object
    );
}

#[test]
fn a_damaged_stream_names_the_khronos_extension() {
    let mut bytes = file("KHR_meshopt_compression");
    // The first stream's header byte (0xa0 or 0xa1) starts the BIN chunk's data.
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    bytes[20 + json_len + 8] = 0x55;
    let e = load_bytes(&bytes, Path::new("."), &posed()).unwrap_err();
    assert!(
        e.to_string()
            .contains("bufferViews[0].extensions.KHR_meshopt_compression"),
        "{e}"
    );
}
