//! The demo scene `assets/demo.glb`: reproducible from `tests/src/demo.rs`, a well-formed GLB, and
//! a camera whose depth-of-field extras say what the README promises.

use aperture_tests::demo;
use glam::{Quat, Vec3};
use serde_json::Value;

fn read_u32(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap())
}

/// Splits a GLB into its JSON document and BIN chunk, checking the container on the way.
fn parse_glb(glb: &[u8]) -> (Value, &[u8]) {
    assert_eq!(&glb[0..4], b"glTF", "GLB magic");
    assert_eq!(read_u32(glb, 4), 2, "GLB version");
    assert_eq!(read_u32(glb, 8) as usize, glb.len(), "GLB length field");
    let json_len = read_u32(glb, 12) as usize;
    assert_eq!(&glb[16..20], b"JSON", "first chunk is JSON");
    assert_eq!(json_len % 4, 0, "JSON chunk is 4-byte aligned");
    let text = &glb[20..20 + json_len];
    let trailing = text.iter().rev().take_while(|&&b| b == b' ').count();
    assert!(trailing < 4, "JSON padded with at most 3 spaces");
    let json: Value = serde_json::from_slice(text).expect("JSON chunk parses");
    let at = 20 + json_len;
    let bin_len = read_u32(glb, at) as usize;
    assert_eq!(&glb[at + 4..at + 8], b"BIN\0", "second chunk is BIN");
    assert_eq!(bin_len % 4, 0, "BIN chunk is 4-byte aligned");
    assert_eq!(at + 8 + bin_len, glb.len(), "nothing after the BIN chunk");
    (json, &glb[at + 8..])
}

fn vec3(v: &Value) -> Vec3 {
    Vec3::new(
        v[0].as_f64().unwrap() as f32,
        v[1].as_f64().unwrap() as f32,
        v[2].as_f64().unwrap() as f32,
    )
}

fn node_named<'a>(json: &'a Value, name: &str) -> &'a Value {
    json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n["name"] == name)
        .unwrap_or_else(|| panic!("no node named {name}"))
}

/// Depth of `node`'s origin along the camera node's −Z (every node of the demo is a root node).
fn depth_from_camera(json: &Value, node: &Value) -> f32 {
    let cam = node_named(json, demo::CAMERA_NAME);
    let r = &cam["rotation"];
    let q = Quat::from_xyzw(
        r[0].as_f64().unwrap() as f32,
        r[1].as_f64().unwrap() as f32,
        r[2].as_f64().unwrap() as f32,
        r[3].as_f64().unwrap() as f32,
    )
    .normalize();
    let forward = q * Vec3::NEG_Z;
    (vec3(&node["translation"]) - vec3(&cam["translation"])).dot(forward)
}

#[test]
fn committed_asset_is_reproducible() {
    let built = demo::build_glb();
    let path = demo::asset_path();
    let committed =
        std::fs::read(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    assert!(
        built == committed,
        "{} ({} bytes) differs from what tests/src/demo.rs builds ({} bytes): run \
         `cargo run -p aperture-tests --example make_demo` and commit the result",
        path.display(),
        committed.len(),
        built.len()
    );
    assert_eq!(built, demo::build_glb(), "two builds in one process differ");
    assert!(built.len() < 2 << 20, "demo.glb is {} bytes", built.len());
}

#[test]
fn glb_is_well_formed() {
    let glb = demo::build_glb();
    let (json, bin) = parse_glb(&glb);
    assert_eq!(json["asset"]["version"], "2.0");
    let byte_length = json["buffers"][0]["byteLength"].as_u64().unwrap() as usize;
    assert!(byte_length <= bin.len() && bin.len() - byte_length < 4);

    for view in json["bufferViews"].as_array().unwrap() {
        let offset = view["byteOffset"].as_u64().unwrap() as usize;
        let len = view["byteLength"].as_u64().unwrap() as usize;
        assert_eq!(offset % 4, 0, "buffer view aligned: {view}");
        assert!(
            offset + len <= byte_length,
            "buffer view inside the buffer: {view}"
        );
    }
    let accessors = json["accessors"].as_array().unwrap();
    let views = json["bufferViews"].as_array().unwrap();
    let mut triangles = 0;
    for mesh in json["meshes"].as_array().unwrap() {
        for prim in mesh["primitives"].as_array().unwrap() {
            let pos = &accessors[prim["attributes"]["POSITION"].as_u64().unwrap() as usize];
            let nrm = &accessors[prim["attributes"]["NORMAL"].as_u64().unwrap() as usize];
            assert!(
                pos["min"].is_array() && pos["max"].is_array(),
                "POSITION min/max"
            );
            assert_eq!(pos["count"], nrm["count"]);
            let count = pos["count"].as_u64().unwrap() as u32;

            // Positions lie inside min/max, normals are unit length.
            let floats = |acc: &Value| -> Vec<f32> {
                let view = &views[acc["bufferView"].as_u64().unwrap() as usize];
                let off = view["byteOffset"].as_u64().unwrap() as usize;
                let len = view["byteLength"].as_u64().unwrap() as usize;
                bin[off..off + len]
                    .chunks_exact(4)
                    .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
                    .collect()
            };
            let (min, max) = (vec3(&pos["min"]), vec3(&pos["max"]));
            for p in floats(pos).chunks_exact(3) {
                let p = Vec3::from_slice(p);
                assert!(p.cmpge(min).all() && p.cmple(max).all());
            }
            for n in floats(nrm).chunks_exact(3) {
                assert!((Vec3::from_slice(n).length() - 1.0).abs() < 1e-5);
            }

            // Indices are in range and make triangles.
            let idx = &accessors[prim["indices"].as_u64().unwrap() as usize];
            let view = &views[idx["bufferView"].as_u64().unwrap() as usize];
            let off = view["byteOffset"].as_u64().unwrap() as usize;
            let n = idx["count"].as_u64().unwrap() as usize;
            let indices: Vec<u32> = match idx["componentType"].as_u64().unwrap() {
                5123 => bin[off..off + 2 * n]
                    .chunks_exact(2)
                    .map(|c| u32::from(u16::from_le_bytes([c[0], c[1]])))
                    .collect(),
                5125 => bin[off..off + 4 * n]
                    .chunks_exact(4)
                    .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
                    .collect(),
                other => panic!("index component type {other}"),
            };
            assert_eq!(indices.len() % 3, 0);
            assert!(indices.iter().all(|&i| i < count));
            triangles += indices.len() / 3;
        }
    }
    assert!(triangles > 1000, "{triangles} unique triangles");
    let stats = demo::build().stats;
    assert!(
        (3_000..=30_000).contains(&stats.drawn_triangles),
        "{} triangles drawn",
        stats.drawn_triangles
    );
}

#[test]
fn camera_extras_and_lights() {
    let (json, _) = parse_glb(&demo::build_glb());
    let camera = &json["cameras"][0];
    assert_eq!(camera["type"], "perspective");
    let extras = &camera["extras"];
    assert_eq!(extras["use_dof"], true);
    let fstop = extras["aperture_fstop"].as_f64().unwrap();
    assert!((1.4..=2.8).contains(&fstop));
    assert_eq!(extras["aperture_blades"], 6);
    assert_eq!(extras["focus_object"], demo::FOCUS_OBJECT);
    let lens = extras["lens"].as_f64().unwrap();

    // yfov and lens agree for a 36 mm sensor fitted to the wider side (Blender's AUTO).
    let yfov = camera["perspective"]["yfov"].as_f64().unwrap();
    let aspect = camera["perspective"]["aspectRatio"].as_f64().unwrap();
    assert!((aspect - 16.0 / 9.0).abs() < 1e-6);
    let expected = 2.0 * (18.0 / lens / aspect).atan();
    assert!((yfov - expected).abs() < 1e-6, "yfov {yfov} vs {expected}");

    // The camera node carries camera 0; the focus object is in front of it, mid-row.
    assert_eq!(node_named(&json, demo::CAMERA_NAME)["camera"], 0);
    let focus = depth_from_camera(&json, node_named(&json, demo::FOCUS_OBJECT));
    let row: Vec<f32> = (0..8)
        .map(|i| {
            let node = json["nodes"]
                .as_array()
                .unwrap()
                .iter()
                .find(|n| n["name"].as_str().unwrap().starts_with(&format!("Row{i}_")))
                .unwrap();
            depth_from_camera(&json, node)
        })
        .collect();
    assert!(row.windows(2).all(|w| w[0] < w[1]), "row recedes: {row:?}");
    assert!(focus > row[0] && focus < row[7]);

    // Bokeh lights on both sides of the focal plane, each blurred over several pixels at 1080p.
    let radius = lens * 0.001 / (2.0 * fstop);
    let tan_half = (yfov / 2.0).tan();
    let (mut front, mut behind) = (0, 0);
    for node in json["nodes"].as_array().unwrap() {
        if !node["name"].as_str().unwrap().starts_with("Bulb") {
            continue;
        }
        let z = f64::from(depth_from_camera(&json, node));
        let coc = radius * (1.0 / f64::from(focus) - 1.0 / z).abs() * 1080.0 / tan_half;
        assert!(
            coc > 20.0,
            "bulb at depth {z} has a {coc} px circle of confusion"
        );
        if z < f64::from(focus) {
            front += 1;
        } else {
            behind += 1;
        }
    }
    assert_eq!((front, behind), demo::build().stats.bokeh_lights);
    assert!(front >= 2 && behind >= 2);

    // A sun (directional, lux) listed as used but not required, bright enough to expose well.
    let used: Vec<&str> = json["extensionsUsed"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(used.contains(&"KHR_lights_punctual"));
    assert!(json.get("extensionsRequired").is_none());
    let sun = &json["extensions"]["KHR_lights_punctual"]["lights"][0];
    assert_eq!(sun["type"], "directional");
    let irradiance = sun["intensity"].as_f64().unwrap() / 683.0;
    assert!((1.0..10.0).contains(&irradiance), "{irradiance} W/m²");
    assert_eq!(
        node_named(&json, "Sun")["extensions"]["KHR_lights_punctual"]["light"],
        0
    );
}

#[test]
fn deterministic_trig_matches_std() {
    for k in -400..=400 {
        let x = k as f64 * 0.0173;
        let (s, c) = demo::sin_cos(x);
        assert!(
            (s - x.sin()).abs() < 1e-15 && (c - x.cos()).abs() < 1e-15,
            "x = {x}"
        );
        assert!((demo::atan(x) - x.atan()).abs() < 1e-15, "x = {x}");
    }
}

#[test]
fn loader_resolves_the_camera_dof() {
    let (json, _) = parse_glb(&demo::build_glb());
    let scene = aperture_scene::load(&demo::asset_path(), &Default::default())
        .expect("assets/demo.glb loads");
    let camera = scene
        .cameras
        .iter()
        .find(|c| c.name == demo::CAMERA_NAME)
        .expect("the demo camera is loaded");
    let dof = &camera.dof;
    assert!(dof.enabled, "use_dof: true");
    let radius = (demo::LENS_MM * 0.001 / (2.0 * demo::FSTOP)) as f32;
    assert!(
        (dof.aperture_radius - radius).abs() < 1e-6,
        "radius {} vs lens·0.001/(2·fstop) = {radius}",
        dof.aperture_radius
    );
    assert!((dof.effective_radius() - radius).abs() < 1e-6);
    let depth = depth_from_camera(&json, node_named(&json, demo::FOCUS_OBJECT));
    assert!(
        (dof.focus_distance - depth).abs() < 1e-4,
        "focus distance {} vs the depth of {} along the camera's −Z, {depth}",
        dof.focus_distance,
        demo::FOCUS_OBJECT
    );
    assert_eq!(dof.focus_object.as_deref(), Some(demo::FOCUS_OBJECT));
    assert_eq!(dof.blades, demo::BLADES);
    assert!((dof.lens_mm - demo::LENS_MM as f32).abs() < 1e-4);

    // The loaded camera looks where the file says, and the scene is what the builder made.
    let forward = camera.world_from_camera.transform_vector3(Vec3::NEG_Z);
    let focus_node = vec3(&node_named(&json, demo::FOCUS_OBJECT)["translation"]);
    let origin = Vec3::from(camera.world_from_camera.translation);
    assert!(((focus_node - origin).dot(forward) - depth).abs() < 1e-4);
    assert_eq!(
        scene.drawn_triangle_count(),
        demo::build().stats.drawn_triangles
    );
    assert_eq!(scene.lights.len(), 1);
    let sun = &scene.lights[0];
    assert!((sun.intensity.x - (demo::SUN_LUX / 683.0) as f32).abs() < 1e-3);
}
