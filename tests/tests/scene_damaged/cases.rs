//! The damaged inputs, in tables by what is broken: the GLB container, the JSON, buffers and
//! accessors, the values they hold, nodes and cameras, and URIs and images.

use aperture_scene::Error;
use aperture_tests::meshopt_writer::join_glb as glb;
use serde_json::{json, Value};

use crate::base::{triangle_bin, triangle_json};

/// One damaged input: the files to write, the one to load, and what the error must be.
pub struct Case {
    /// What is broken (and the name of its folder).
    pub kind: &'static str,
    /// The files to write; the first is the one to load.
    pub files: Vec<(&'static str, Vec<u8>)>,
    /// Whether the error is of the right kind.
    pub check: fn(&Error) -> bool,
    /// Text the message must contain (where the problem is).
    pub says: &'static str,
}

/// The triangle scene as `scene.gltf` + `tri.bin`, its JSON edited.
fn gltf_case(
    kind: &'static str,
    edit: impl FnOnce(&mut Value),
    check: fn(&Error) -> bool,
    says: &'static str,
) -> Case {
    let mut j = triangle_json(Some("tri.bin"));
    edit(&mut j);
    Case {
        kind,
        files: vec![
            ("scene.gltf", serde_json::to_vec_pretty(&j).unwrap()),
            ("tri.bin", triangle_bin()),
        ],
        check,
        says,
    }
}

/// The triangle scene as `scene.gltf` + `tri.bin`, with other bytes in `tri.bin`.
fn with_bin(
    kind: &'static str,
    bin: Vec<u8>,
    check: fn(&Error) -> bool,
    says: &'static str,
) -> Case {
    Case {
        kind,
        files: vec![
            (
                "scene.gltf",
                serde_json::to_vec(&triangle_json(Some("tri.bin"))).unwrap(),
            ),
            ("tri.bin", bin),
        ],
        check,
        says,
    }
}

/// A single `scene.glb` file.
fn glb_case(
    kind: &'static str,
    bytes: Vec<u8>,
    check: fn(&Error) -> bool,
    says: &'static str,
) -> Case {
    Case {
        kind,
        files: vec![("scene.glb", bytes)],
        check,
        says,
    }
}

/// Every damaged input.
pub fn cases() -> Vec<Case> {
    [
        glb_cases(),
        json_cases(),
        buffer_cases(),
        value_cases(),
        node_cases(),
        uri_cases(),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// A GLB container cut short or with wrong headers.
fn glb_cases() -> Vec<Case> {
    let good_glb = glb(&triangle_json(None), &triangle_bin());
    let mut huge_json = triangle_json(None);
    huge_json["accessors"][0]["count"] = json!(1u64 << 31);
    let mut wrong_chunk = good_glb.clone();
    wrong_chunk[16..20].copy_from_slice(&0x004E_4942u32.to_le_bytes());
    let mut long_chunk = good_glb.clone();
    long_chunk[12..16].copy_from_slice(&100_000u32.to_le_bytes());
    let mut bad_magic = good_glb.clone();
    bad_magic[..4].copy_from_slice(b"gLTF");
    let mut long_header = good_glb.clone();
    long_header[8..12].copy_from_slice(&100_000u32.to_le_bytes());

    vec![
        glb_case(
            "truncated GLB",
            good_glb[..good_glb.len() / 2].to_vec(),
            |e| matches!(e, Error::Glb { .. }),
            "truncated",
        ),
        glb_case(
            "GLB bad magic",
            bad_magic,
            |e| matches!(e, Error::Glb { .. }),
            "bad magic",
        ),
        glb_case(
            "GLB header length past the end",
            long_header,
            |e| matches!(e, Error::Glb { .. }),
            "header says 100000",
        ),
        glb_case(
            "GLB first chunk not JSON",
            wrong_chunk,
            |e| matches!(e, Error::Glb { .. }),
            "not JSON",
        ),
        glb_case(
            "GLB JSON chunk length past the end",
            long_chunk,
            |e| matches!(e, Error::Glb { .. }),
            "chunk 0",
        ),
        glb_case(
            "GLB claiming 2^31 vertices in a tiny file",
            glb(&huge_json, &triangle_bin()),
            |e| matches!(e, Error::OutOfBounds { .. }),
            "accessors[0]",
        ),
    ]
}

/// Files that are not JSON, not glTF, or need an extension we lack.
fn json_cases() -> Vec<Case> {
    vec![
        Case {
            kind: "bad JSON syntax",
            files: vec![(
                "scene.gltf",
                b"{\"asset\": {\"version\": \"2.0\"},".to_vec(),
            )],
            check: |e| matches!(e, Error::Json { .. }),
            says: "line 1",
        },
        Case {
            kind: "empty file",
            files: vec![("scene.gltf", Vec::new())],
            check: |e| matches!(e, Error::Json { .. }),
            says: "JSON",
        },
        gltf_case(
            "JSON that is not glTF (no asset)",
            |j| {
                j.as_object_mut().unwrap().remove("asset");
            },
            |e| matches!(e, Error::Json { .. }),
            "asset",
        ),
        gltf_case(
            "unsupported required extension",
            |j| j["extensionsRequired"] = json!(["ACME_made_up_extension"]),
            |e| matches!(e, Error::UnsupportedExtension { .. }),
            "ACME_made_up_extension",
        ),
    ]
}

/// Buffers, buffer views and accessors that are missing or reach past their data.
fn buffer_cases() -> Vec<Case> {
    vec![
        Case {
            kind: "missing buffer file",
            files: vec![(
                "scene.gltf",
                serde_json::to_vec(&triangle_json(Some("gone.bin"))).unwrap(),
            )],
            check: |e| matches!(e, Error::MissingFile { .. }),
            says: "buffers[0].uri",
        },
        with_bin(
            "buffer shorter than byteLength",
            triangle_bin()[..20].to_vec(),
            |e| matches!(e, Error::BufferTooShort { .. }),
            "buffers[0]",
        ),
        gltf_case(
            "accessor outside its buffer view",
            |j| j["accessors"][0]["count"] = json!(4),
            |e| matches!(e, Error::OutOfBounds { .. }),
            "meshes[0].primitives[0].attributes.POSITION (accessors[0])",
        ),
        gltf_case(
            "buffer view outside its buffer",
            |j| j["bufferViews"][0]["byteOffset"] = json!(40),
            |e| matches!(e, Error::OutOfBounds { .. }),
            "bufferViews[0]",
        ),
        gltf_case(
            "huge claimed count in a tiny file",
            |j| j["accessors"][1]["count"] = json!(3_000_000_000u64),
            |e| matches!(e, Error::OutOfBounds { .. }),
            "meshes[0].primitives[0].indices",
        ),
        gltf_case(
            "huge zero-filled sparse accessor",
            |j| {
                j["accessors"][0] = json!({"componentType": 5126, "count": 1u64 << 31, "type": "VEC3",
                    "min": [0, 0, 0], "max": [1, 1, 0],
                    "sparse": {"count": 1, "indices": {"bufferView": 1, "componentType": 5123},
                               "values": {"bufferView": 0}}});
            },
            |e| matches!(e, Error::OutOfBounds { .. }),
            "accessors[0]",
        ),
        gltf_case(
            "POSITION names a missing accessor",
            |j| j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9),
            |e| matches!(e, Error::Invalid { .. }),
            "attributes.POSITION",
        ),
    ]
}

/// Indices out of range or in a count not a multiple of 3, and non-finite positions.
fn value_cases() -> Vec<Case> {
    let mut nan_bin = triangle_bin();
    nan_bin[12..16].copy_from_slice(&f32::NAN.to_le_bytes());
    let mut big_index_bin = triangle_bin();
    big_index_bin[40..42].copy_from_slice(&7u16.to_le_bytes());

    vec![
        gltf_case(
            "sparse index out of range",
            |j| {
                // The index is byte 14 of the positions: 0x80 of the float 1.0, so 128.
                j["accessors"][0]["sparse"] = json!({"count": 1,
                    "indices": {"bufferView": 0, "componentType": 5121, "byteOffset": 14},
                    "values": {"bufferView": 0}});
            },
            |e| {
                matches!(
                    e,
                    Error::IndexOutOfRange {
                        index: 128,
                        vertices: 3,
                        ..
                    }
                )
            },
            "(accessors[0].sparse).indices[0]",
        ),
        with_bin(
            "index out of range",
            big_index_bin,
            |e| {
                matches!(
                    e,
                    Error::IndexOutOfRange {
                        index: 7,
                        vertices: 3,
                        ..
                    }
                )
            },
            "meshes[0].primitives[0].indices: index 7 out of range (3 vertices)",
        ),
        gltf_case(
            "index count not a multiple of 3",
            |j| j["accessors"][1]["count"] = json!(2),
            |e| matches!(e, Error::IndexCount { count: 2, .. }),
            "meshes[0].primitives[0].indices",
        ),
        with_bin(
            "NaN position",
            nan_bin,
            |e| matches!(e, Error::NonFinite { .. }),
            "POSITION[1]",
        ),
    ]
}

/// Nodes with non-finite transforms or a cycle, bad depth of field, and cameras or scenes that
/// do not exist.
fn node_cases() -> Vec<Case> {
    vec![
        gltf_case(
            "non-finite node matrix",
            |j| {
                j["nodes"][0]["matrix"] = json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1e39, 0, 0, 1])
            },
            |e| matches!(e, Error::NonFinite { .. }),
            "nodes[0].matrix",
        ),
        gltf_case(
            "non-finite node translation",
            |j| j["nodes"][0]["translation"] = json!([0, -1e40, 0]),
            |e| matches!(e, Error::NonFinite { .. }),
            "nodes[0].translation",
        ),
        gltf_case(
            "invalid DOF extras (zero f-stop)",
            |j| {
                j["cameras"] = json!([{"name": "Lens", "type": "perspective",
                    "perspective": {"yfov": 0.7, "znear": 0.1}, "extras": {"aperture_fstop": 0}}]);
                j["nodes"] = json!([{"mesh": 0}, {"camera": 0, "translation": [0, 0, 5]}]);
                j["scenes"] = json!([{"nodes": [0, 1]}]);
            },
            |e| matches!(e, Error::InvalidDof { .. }),
            "camera \"Lens\": cameras.extras.aperture_fstop = 0",
        ),
        gltf_case(
            "focus object behind the camera",
            |j| {
                j["cameras"] = json!([{"name": "Lens", "type": "perspective",
                    "perspective": {"yfov": 0.7, "znear": 0.1}}]);
                j["nodes"] = json!([{"mesh": 0, "name": "Tri"},
                    {"camera": 0, "translation": [0, 0, -5], "extras": {"focus_object": "Tri"}}]);
                j["scenes"] = json!([{"nodes": [0, 1]}]);
            },
            |e| matches!(e, Error::InvalidDof { .. }),
            "nodes.extras.focus_object = \"Tri\"",
        ),
        gltf_case(
            "node hierarchy cycle",
            |j| {
                j["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
            },
            |e| matches!(e, Error::NodeGraph { .. }),
            "nodes[",
        ),
        gltf_case(
            "scene index out of range",
            |j| j["scene"] = json!(4),
            |e| matches!(e, Error::Invalid { .. }),
            "scene",
        ),
        gltf_case(
            "camera type without its projection",
            |j| {
                j["cameras"] = json!([{"type": "perspective", "orthographic":
                    {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}}]);
                j["nodes"] = json!([{"mesh": 0}, {"camera": 0}]);
                j["scenes"] = json!([{"nodes": [0, 1]}]);
            },
            |e| matches!(e, Error::Invalid { .. }),
            "cameras[0].perspective",
        ),
    ]
}

/// URIs that leave the folder or cannot be decoded, and images that are missing or broken.
fn uri_cases() -> Vec<Case> {
    vec![
        gltf_case(
            "'..' URI",
            |j| j["buffers"][0]["uri"] = json!("../tri.bin"),
            |e| matches!(e, Error::ForbiddenUri { .. }),
            "'..'",
        ),
        gltf_case(
            "absolute path URI",
            |j| j["buffers"][0]["uri"] = json!("/etc/passwd"),
            |e| matches!(e, Error::ForbiddenUri { .. }),
            "absolute",
        ),
        gltf_case(
            "http URI",
            |j| j["buffers"][0]["uri"] = json!("http://example.com/tri.bin"),
            |e| matches!(e, Error::ForbiddenUri { .. }),
            "remote",
        ),
        gltf_case(
            "bad base64 data URI",
            |j| j["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,!!!!"),
            |e| matches!(e, Error::DataUri { .. }),
            "buffers[0].uri",
        ),
        gltf_case(
            "image with no source",
            |j| {
                j["images"] = json!([{"name": "nothing"}]);
                j["textures"] = json!([{"source": 0}]);
                j["materials"] =
                    json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
                j["meshes"][0]["primitives"][0]["material"] = json!(0);
            },
            |e| matches!(e, Error::Invalid { .. }),
            "images[0]",
        ),
        gltf_case(
            "missing image file",
            |j| {
                j["images"] = json!([{"uri": "gone.png"}]);
                j["textures"] = json!([{"source": 0}]);
                j["materials"] =
                    json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
                j["meshes"][0]["primitives"][0]["material"] = json!(0);
            },
            |e| matches!(e, Error::MissingFile { .. }),
            "images[0].uri",
        ),
        gltf_case(
            "corrupt image data",
            |j| {
                j["images"] = json!([{"uri": "data:image/png;base64,iVBORw0KGgoAAAA="}]);
                j["textures"] = json!([{"source": 0}]);
                j["materials"] = json!([{"emissiveTexture": {"index": 0}}]);
                j["meshes"][0]["primitives"][0]["material"] = json!(0);
            },
            |e| matches!(e, Error::Image { image: 0, .. }),
            "images[0]",
        ),
    ]
}
