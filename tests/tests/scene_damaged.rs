//! Damaged inputs: a generator writes small broken glTF/GLB files (one folder per kind) into the
//! test's temporary directory; each must load to the right typed error, saying where, and none
//! may panic.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use aperture_scene::{load, Error, LoadOptions};
use aperture_tests::meshopt_writer::join_glb as glb;
use serde_json::{json, Value};

/// A valid one-triangle scene: 3 float positions (36 bytes) then 3 u16 indices (6 bytes + 2 pad).
fn triangle_bin() -> Vec<u8> {
    let mut b = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            b.extend(c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2] {
        b.extend(i.to_le_bytes());
    }
    b.extend([0, 0]);
    b
}

fn triangle_json(uri: Option<&str>) -> Value {
    let mut buffer = json!({"byteLength": 44});
    if let Some(u) = uri {
        buffer["uri"] = json!(u);
    }
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6}
        ],
        "buffers": [buffer]
    })
}

/// One damaged input: the files to write, the one to load, and what the error must be.
struct Case {
    kind: &'static str,
    files: Vec<(&'static str, Vec<u8>)>,
    check: fn(&Error) -> bool,
    /// Text the message must contain (where the problem is).
    says: &'static str,
}

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

fn cases() -> Vec<Case> {
    let good_glb = glb(&triangle_json(None), &triangle_bin());
    let mut nan_bin = triangle_bin();
    nan_bin[12..16].copy_from_slice(&f32::NAN.to_le_bytes());
    let mut big_index_bin = triangle_bin();
    big_index_bin[40..42].copy_from_slice(&7u16.to_le_bytes());
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
            |j| j["extensionsRequired"] = json!(["EXT_lights_image_based"]),
            |e| matches!(e, Error::UnsupportedExtension { .. }),
            "EXT_lights_image_based",
        ),
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
            "POSITION names a missing accessor",
            |j| j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9),
            |e| matches!(e, Error::Invalid { .. }),
            "attributes.POSITION",
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

fn folder() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("damaged-inputs")
}

fn write(dir: &Path, case: &Case) -> PathBuf {
    let sub = dir.join(case.kind.replace(|c: char| !c.is_ascii_alphanumeric(), "_"));
    std::fs::create_dir_all(&sub).unwrap();
    for (name, bytes) in &case.files {
        std::fs::write(sub.join(name), bytes).unwrap();
    }
    sub.join(case.files[0].0)
}

#[test]
fn the_valid_base_files_load() {
    let dir = folder().join("valid");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tri.bin"), triangle_bin()).unwrap();
    std::fs::write(
        dir.join("scene.gltf"),
        serde_json::to_vec(&triangle_json(Some("tri.bin"))).unwrap(),
    )
    .unwrap();
    std::fs::write(
        dir.join("scene.glb"),
        glb(&triangle_json(None), &triangle_bin()),
    )
    .unwrap();
    for f in ["scene.gltf", "scene.glb"] {
        let s = load(&dir.join(f), &LoadOptions::default()).unwrap();
        assert_eq!(s.drawn_triangle_count(), 1, "{f}");
        assert_eq!(s.cameras.len(), 1, "{f}: automatic camera");
    }
}

#[test]
fn every_damaged_input_is_a_typed_error_and_none_panics() {
    let dir = folder();
    let cases = cases();
    assert!(cases.len() >= 15);
    let mut problems = Vec::new();
    for case in &cases {
        let path = write(&dir, case);
        let result = catch_unwind(AssertUnwindSafe(|| load(&path, &LoadOptions::default())));
        match result {
            Err(_) => problems.push(format!("{}: panicked", case.kind)),
            Ok(Ok(_)) => problems.push(format!("{}: loaded without error", case.kind)),
            Ok(Err(e)) => {
                let msg = e.to_string();
                eprintln!("{:<45} {msg}", case.kind);
                if !(case.check)(&e) || !msg.contains(case.says) {
                    problems.push(format!("{}: unexpected error {e:?} / {msg}", case.kind));
                }
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Loads bytes as a GLB or glTF from memory; true when it panicked.
fn panics(bytes: &[u8], dir: &Path) -> bool {
    catch_unwind(AssertUnwindSafe(|| {
        let _ = aperture_scene::load_bytes(bytes, dir, &LoadOptions::default());
    }))
    .is_err()
}

#[test]
fn no_byte_change_in_a_glb_panics() {
    let dir = folder().join("mutations");
    std::fs::create_dir_all(&dir).unwrap();
    let good = glb(&triangle_json(None), &triangle_bin());
    let mut bad = Vec::new();
    for i in 0..good.len() {
        for v in [0u8, 0xFF, good[i].wrapping_add(1), b'9', b'-'] {
            let mut m = good.clone();
            m[i] = v;
            if panics(&m, &dir) {
                bad.push(format!("byte {i} = {v:#x}"));
            }
        }
    }
    for n in 0..good.len() {
        if panics(&good[..n], &dir) {
            bad.push(format!("truncated to {n}"));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// Every leaf of a JSON value, as a list of keys/indices.
fn leaves(v: &Value, path: &mut Vec<Value>, out: &mut Vec<Vec<Value>>) {
    match v {
        Value::Object(m) => {
            for (k, c) in m {
                path.push(json!(k));
                leaves(c, path, out);
                path.pop();
            }
        }
        Value::Array(a) => {
            for (i, c) in a.iter().enumerate() {
                path.push(json!(i));
                leaves(c, path, out);
                path.pop();
            }
        }
        _ => out.push(path.clone()),
    }
    if !path.is_empty() {
        out.push(path.clone());
    }
}

fn at_mut<'a>(v: &'a mut Value, path: &[Value]) -> &'a mut Value {
    path.iter().fold(v, |v, k| match k {
        Value::String(s) => &mut v[s.as_str()],
        Value::Number(n) => &mut v[n.as_u64().unwrap() as usize],
        _ => unreachable!(),
    })
}

#[test]
fn no_json_value_change_panics() {
    // A richer base: camera, light, material with textures, sampler, instancing, sparse.
    let mut base = triangle_json(Some("tri.bin"));
    base["cameras"] = json!([{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1},
        "extras": {"aperture_fstop": 2.8, "focus_object": 0}}]);
    base["nodes"] = json!([{"mesh": 0, "children": [1]}, {"camera": 0, "translation": [0, 0, 3],
        "extensions": {"KHR_lights_punctual": {"light": 0}}}]);
    base["extensions"] = json!({"KHR_lights_punctual": {"lights": [{"type": "spot", "spot": {}}]}});
    base["samplers"] = json!([{"wrapS": 33071, "magFilter": 9728}]);
    base["images"] = json!([{"uri": "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8DwHwAFBQIAX8jx0gAAAABJRU5ErkJggg=="}]);
    base["textures"] = json!([{"source": 0, "sampler": 0}]);
    base["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
        "extensions": {"KHR_texture_transform": {"scale": [2, 2]}}}}, "normalTexture": {"index": 0}}]);
    base["meshes"][0]["primitives"][0]["material"] = json!(0);
    let dir = folder().join("json-mutations");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tri.bin"), triangle_bin()).unwrap();
    let s = aperture_scene::load_bytes(
        &serde_json::to_vec(&base).unwrap(),
        &dir,
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(
        s.textures.len(),
        2,
        "the base itself loads, with sRGB and linear uses"
    );

    let mut paths = Vec::new();
    leaves(&base, &mut Vec::new(), &mut paths);
    let replacements = [
        json!(null),
        json!(-1),
        json!(0),
        json!(1),
        json!(7),
        json!(4294967295u64),
        json!(1e39),
        json!("x"),
        json!([]),
        json!({}),
    ];
    let mut bad = Vec::new();
    for p in &paths {
        for r in &replacements {
            let mut m = base.clone();
            *at_mut(&mut m, p) = r.clone();
            if panics(&serde_json::to_vec(&m).unwrap(), &dir) {
                bad.push(format!("{p:?} = {r}"));
            }
        }
    }
    assert!(paths.len() > 50);
    assert!(bad.is_empty(), "{} panics:\n{}", bad.len(), bad.join("\n"));
}

/// Loads `json` + `bin` (written as `scene.gltf` + `scene.bin` in `dir`): `None` when it panicked.
fn load_pair(dir: &Path, json: &Value, bin: &[u8]) -> Option<Result<aperture_scene::Scene, Error>> {
    let mut json = json.clone();
    json["buffers"][0]["uri"] = json!("scene.bin");
    std::fs::write(dir.join("scene.gltf"), serde_json::to_vec(&json).unwrap()).unwrap();
    std::fs::write(dir.join("scene.bin"), bin).unwrap();
    let opts = LoadOptions {
        skip_textures: true,
        ..LoadOptions::default()
    };
    catch_unwind(AssertUnwindSafe(|| load(&dir.join("scene.gltf"), &opts))).ok()
}

/// Truncated and bit-flipped compressed streams: each is a typed error naming the primitive whose
/// data it holds (or, for a flip that still decodes, a scene), never a panic.
#[test]
fn damaged_compressed_buffers_are_errors_naming_the_primitive() {
    let Some(samples) = aperture_tests::samples_dir() else {
        return;
    };
    let dir = folder().join("compressed");
    std::fs::create_dir_all(&dir).unwrap();
    let mut report = Vec::new();
    let mut check =
        |name: &str, json: &Value, bin: &[u8], must_fail: bool| match load_pair(&dir, json, bin) {
            None => report.push(format!("{name}: PANIC")),
            Some(Err(e)) => {
                let msg = e.to_string();
                if !msg.contains("meshes[0].primitives[0]") {
                    report.push(format!("{name}: error does not name the primitive: {msg}"));
                }
            }
            Some(Ok(_)) if must_fail => report.push(format!("{name}: loaded without error")),
            Some(Ok(_)) => {}
        };

    // Draco: the Box-Draco sample's stream, cut short and with bits flipped.
    let path = samples.join("unsupported/Box-Draco/Box.gltf");
    let json: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let bin =
        std::fs::read(path.with_file_name(json["buffers"][0]["uri"].as_str().unwrap())).unwrap();
    let view = json["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]
        ["bufferView"]
        .as_u64()
        .unwrap() as usize;
    let offset = json["bufferViews"][view]["byteOffset"]
        .as_u64()
        .unwrap_or(0) as usize;
    let length = json["bufferViews"][view]["byteLength"].as_u64().unwrap() as usize;
    check("draco intact", &json, &bin, false);
    for keep in [0, 1, 4, length / 4, length / 2, length - 8, length - 1] {
        let mut j = json.clone();
        j["bufferViews"][view]["byteLength"] = json!(keep);
        check(
            &format!("draco cut to {keep} of {length} bytes"),
            &j,
            &bin,
            true,
        );
    }
    let mut flips = 0;
    for at in (0..length).step_by(3) {
        for bit in [0x01u8, 0x80] {
            let mut b = bin.clone();
            b[offset + at] ^= bit;
            check(&format!("draco byte {at} ^ {bit:#x}"), &json, &b, false);
            flips += 1;
        }
    }

    // meshopt: a compressed copy of BoxTextured, each stream cut short and flipped.
    let glb = std::fs::read(samples.join("correctness/BoxTextured/BoxTextured.glb")).unwrap();
    let (plain, plain_bin) = aperture_tests::meshopt_writer::split_glb(&glb);
    let (json, bin, _) = aperture_tests::meshopt_writer::compress(
        &plain,
        &plain_bin,
        aperture_tests::meshopt_writer::IndexMode::Triangles,
    );
    let json = {
        let mut j = json;
        j["buffers"][0].as_object_mut().unwrap().remove("uri");
        j
    };
    check("meshopt intact", &json, &bin, false);
    let views = json["bufferViews"].as_array().unwrap().len();
    for v in 0..views {
        let ext = json["bufferViews"][v]["extensions"]["EXT_meshopt_compression"].clone();
        if ext.is_null() {
            continue;
        }
        let (offset, length) = (
            ext["byteOffset"].as_u64().unwrap() as usize,
            ext["byteLength"].as_u64().unwrap() as usize,
        );
        for keep in [0, 1, length / 2, length - 1] {
            let mut j = json.clone();
            j["bufferViews"][v]["extensions"]["EXT_meshopt_compression"]["byteLength"] =
                json!(keep);
            check(
                &format!("meshopt view {v} cut to {keep} of {length}"),
                &j,
                &bin,
                true,
            );
        }
        for at in (0..length).step_by(2) {
            let mut b = bin.clone();
            b[offset + at] ^= 0x10;
            check(
                &format!("meshopt view {v} byte {at} ^ 0x10"),
                &json,
                &b,
                false,
            );
            flips += 1;
        }
        // A count the compressed bytes cannot hold.
        let mut j = json.clone();
        j["bufferViews"][v]["extensions"]["EXT_meshopt_compression"]["count"] = json!(1u64 << 40);
        check(&format!("meshopt view {v} count 2^40"), &j, &bin, true);
    }
    println!("{flips} bit flips and every truncation tried");
    assert!(report.is_empty(), "{}", report.join("\n"));
}
