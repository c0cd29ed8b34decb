//! `aperture render --frames` over keyed `KHR_node_visibility` (issue 48): each frame of the
//! sequence is the single `--frame N` render bit for bit (every pass, Cryptomatte included),
//! and after the first frame no bottom-level BVH is built: quads come and go, their meshes'
//! BVHs are taken over and only the top level is rebuilt.

mod common;

use common::{run_in as aperture, stderr, Scratch};
use serde_json::json;

/// The quad of `common::quad_json` with key times at byte 60 (frame 0, and halfway to frames 2
/// and 4 at 24 fps) and two nodes' keys after them: "blink" hidden, shown, hidden; "parent"
/// shown, hidden, shown.
fn scene() -> Vec<u8> {
    let mut doc = common::quad_json();
    doc["buffers"][0]["byteLength"] = json!(78);
    let views = doc["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": 60, "byteLength": 18}));
    let accessors = doc["accessors"].as_array_mut().unwrap();
    accessors.push(json!({"bufferView": 2, "componentType": 5126, "count": 3,
        "type": "SCALAR", "min": [0.0], "max": [3.5 / 24.0]}));
    for offset in [12, 15] {
        accessors.push(
            json!({"bufferView": 2, "byteOffset": offset, "componentType": 5121,
            "count": 3, "type": "SCALAR"}),
        );
    }
    let pointer = |node: usize| {
        json!({"KHR_animation_pointer":
            {"pointer": format!("/nodes/{node}/extensions/KHR_node_visibility/visible")}})
    };
    let rest = json!({
        "extensionsUsed": ["KHR_node_visibility", "KHR_animation_pointer", "KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 40.0}]}},
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.1}}],
        "nodes": [
            {"name": "blink", "mesh": 0, "translation": [-1.2, 0.0, 0.0],
             "extensions": {"KHR_node_visibility": {"visible": false}}},
            {"name": "parent", "mesh": 0, "translation": [1.2, 0.0, 0.0], "children": [2]},
            {"name": "child", "mesh": 0, "translation": [0.0, 2.2, 0.5], "scale": [0.5, 0.5, 0.5],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "still", "mesh": 0, "translation": [0.0, -2.2, 0.0]},
            {"name": "eye", "camera": 0, "translation": [0.0, 0.0, 6.0]}
        ],
        "animations": [{"channels": [
            {"sampler": 0, "target": {"path": "pointer", "extensions": pointer(0)}},
            {"sampler": 1, "target": {"path": "pointer", "extensions": pointer(1)}}],
            "samplers": [{"input": 2, "output": 3, "interpolation": "STEP"},
                {"input": 2, "output": 4, "interpolation": "STEP"}]}],
        "scenes": [{"nodes": [0, 1, 3, 4]}]
    });
    for (k, v) in rest.as_object().unwrap() {
        doc[k] = v.clone();
    }
    let mut tail = Vec::new();
    for t in [0.0f32, 1.5 / 24.0, 3.5 / 24.0] {
        tail.extend_from_slice(&t.to_le_bytes());
    }
    tail.extend_from_slice(&[0, 1, 0, 1, 0, 1]);
    common::quad_glb_with(&doc, &tail)
}

/// The bottom-level BVHs built and reused, from a frame line's `BVH 0.4 ms: 1 built, 2 reused`.
fn bvh_work(line: &str) -> Option<(usize, usize)> {
    let rest = line.split("ms: ").nth(1)?;
    let mut words = rest.split([' ', ',', ')']).filter(|w| !w.is_empty());
    let built = words.next()?.parse().ok()?;
    let reused = words.nth(1)?.parse().ok()?;
    Some((built, reused))
}

#[test]
fn each_frame_of_a_visibility_sequence_is_its_single_frame_render() {
    let dir = Scratch::new("visibility-frames");
    std::fs::write(dir.path("blink.glb"), scene()).unwrap();
    let size = [
        "--width",
        "40",
        "--height",
        "30",
        "--spp",
        "4",
        "--env",
        "0.5,0.5,0.5",
        "--passes",
        "all",
    ];
    let mut a = vec!["render", "blink.glb", "-o", "seq_#.exr", "--frames", "0..4"];
    a.extend_from_slice(&size);
    let o = aperture(&a, &dir.0);
    assert!(o.status.success(), "{}", stderr(&o));
    let said = stderr(&o);
    let work: Vec<(usize, usize)> = said.lines().filter_map(bvh_work).collect();
    eprintln!("per-frame BVH work (built, reused): {work:?}");
    assert_eq!(work.len(), 5, "{said}");
    assert!(work[0].0 > 0, "{work:?}");
    for (f, &(built, reused)) in work.iter().enumerate().skip(1) {
        assert_eq!(built, 0, "frame {f} rebuilt a bottom-level BVH: {work:?}");
        assert!(reused > 0, "frame {f}: {work:?}");
    }
    let read = |n: &str| aperture_imageio::read_exr(&dir.path(n)).unwrap();
    for f in 0..5 {
        let (one, frame) = (format!("one_{f}.exr"), f.to_string());
        let mut a = vec![
            "render",
            "blink.glb",
            "-o",
            &one,
            "--frame",
            &frame,
            "--quiet",
        ];
        a.extend_from_slice(&size);
        let o = aperture(&a, &dir.0);
        assert!(o.status.success(), "{}", stderr(&o));
        let n = common::assert_same_pixels(&read(&format!("seq_{f}.exr")), &read(&one));
        eprintln!("frame {f}: {n} values bit-identical to --frame {f}");
    }
    // The blinking quad is drawn at frame 2 and not at 0: the frames differ.
    assert_ne!(read("seq_0.exr").rgba, read("seq_2.exr").rgba);
}
