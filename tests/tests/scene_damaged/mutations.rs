//! Every byte of a GLB and every value of a glTF's JSON changed in turn: none may panic.

use aperture_scene::LoadOptions;
use aperture_tests::meshopt_writer::join_glb as glb;
use serde_json::{json, Value};

use crate::base::{folder, panics, triangle_bin, triangle_json};

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
