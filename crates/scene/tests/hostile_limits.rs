//! Inputs built to exhaust the loader — deep hierarchies, huge JSON arrays, counts near
//! `u32::MAX`, sparse accessors with millions of indices, one texture behind ten thousand
//! materials — each loaded in a child process under `setrlimit` (data segment and CPU time,
//! via the shell's `ulimit`): a stack overflow, an allocation past the ceiling or a quadratic
//! loop kills the child, and the test fails saying which limit it hit. No wall-clock
//! assertion: the ceilings are the kernel's.
// The limits are bash's `ulimit` and the deaths Unix signals: Unix only.
#![cfg(unix)]

use std::io::Cursor;
use std::path::Path;
use std::process::Command;

use aperture_scene::{Animated, Error, LoadOptions, Scene};
use serde_json::{json, Value};

/// Set in the child: the name of the test it runs.
const CHILD: &str = "APERTURE_LIMITED_CHILD";

/// Runs `body` in a child process (this test binary, this test only) with at most
/// `data_mib` MiB of data segment (heap and anonymous mappings, RLIMIT_DATA) and `cpu_s`
/// seconds of CPU time (RLIMIT_CPU), and fails unless it exits cleanly.
fn limited(test: &str, data_mib: u64, cpu_s: u64, body: impl FnOnce()) {
    if std::env::var(CHILD).as_deref() == Ok(test) {
        body();
        return;
    }
    let exe = std::env::current_exe().expect("test binary");
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "ulimit -d {} && ulimit -t {cpu_s} && exec \"$0\" \"$@\"",
            data_mib * 1024
        ))
        .arg(exe)
        .args([test, "--exact", "--nocapture", "--test-threads=1"])
        .env(CHILD, test)
        .env("RAYON_NUM_THREADS", "2")
        .output()
        .expect("running the child");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    use std::os::unix::process::ExitStatusExt as _;
    let why = match out.status.signal() {
        Some(24) => format!("killed at the CPU ceiling of {cpu_s} s (SIGXCPU)"),
        Some(9) => format!("killed (SIGKILL: the CPU ceiling of {cpu_s} s, hard limit)"),
        Some(11) => "crashed (SIGSEGV: a stack overflow?)".into(),
        Some(6) if stderr.contains("memory allocation") => {
            format!("ran out of its {data_mib} MiB data ceiling")
        }
        Some(s) => format!("died of signal {s}"),
        None => format!("exited with {:?}", out.status.code()),
    };
    assert!(
        out.status.success() && stdout.contains("1 passed"),
        "{test}: {why}\n--- stdout\n{stdout}\n--- stderr\n{stderr}"
    );
}

/// Bytes of a GLB file.
fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = json.to_string().into_bytes();
    j.resize(j.len().next_multiple_of(4), b' ');
    let mut b = bin.to_vec();
    b.resize(b.len().next_multiple_of(4), 0);
    let total = 12 + 8 + j.len() + if b.is_empty() { 0 } else { 8 + b.len() };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    if !b.is_empty() {
        out.extend_from_slice(&(b.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&b);
    }
    out
}

fn load(bytes: &[u8], options: &LoadOptions) -> Result<Scene, Error> {
    aperture_scene::load_bytes(bytes, Path::new("/nonexistent"), options)
}

/// One triangle: positions (36 bytes) at the start of the BIN chunk.
fn triangle() -> (Vec<u8>, Value, Value) {
    let bin: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let accessor = json!({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
        "min": [0, 0, 0], "max": [1, 1, 0]});
    let view = json!({"buffer": 0, "byteOffset": 0, "byteLength": 36});
    (bin, accessor, view)
}

#[test]
fn a_node_chain_200000_deep_loads_without_recursion() {
    limited(
        "a_node_chain_200000_deep_loads_without_recursion",
        1024,
        60,
        || {
            let n = 200_000;
            let (bin, acc, view) = triangle();
            let nodes: Vec<Value> = (0..n)
                .map(|i| {
                    let mut node = json!({"translation": [0.0, 1e-4, 0.0]});
                    if i + 1 < n {
                        node["children"] = json!([i + 1]);
                    }
                    if i % 1000 == 999 {
                        node["mesh"] = json!(0);
                    }
                    node
                })
                .collect();
            let doc = json!({"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}],
                "nodes": nodes, "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
                "accessors": [acc], "bufferViews": [view], "buffers": [{"byteLength": 36}]});
            let s = load(&glb(&doc, &bin), &LoadOptions::default()).expect("loads");
            assert_eq!(s.instances.len(), 200);
            assert_eq!(s.stats.nodes, n);
        },
    );
}

#[test]
fn json_nested_100000_deep_is_an_error_not_a_stack_overflow() {
    limited(
        "json_nested_100000_deep_is_an_error_not_a_stack_overflow",
        256,
        20,
        || {
            let depth = 100_000;
            let doc = format!(
                r#"{{"asset":{{"version":"2.0"}},"extras":{}{}}}"#,
                "[".repeat(depth),
                "]".repeat(depth)
            );
            let e = load(doc.as_bytes(), &LoadOptions::default()).expect_err("refused");
            assert!(matches!(e, Error::Json { .. }), "{e}");
            assert!(e.to_string().contains("recursion"), "{e}");
        },
    );
}

#[test]
fn huge_json_arrays_load_in_bounded_memory() {
    limited("huge_json_arrays_load_in_bounded_memory", 1024, 60, || {
        // Half a million empty nodes in the scene and four million numbers in extras.
        let nodes = vec!["{}"; 500_000].join(",");
        let scene: Vec<String> = (0..500_000).map(|i| i.to_string()).collect();
        let extras = vec!["1.5"; 4_000_000].join(",");
        let doc = format!(
            r#"{{"asset":{{"version":"2.0"}},"extras":[{extras}],"scenes":[{{"nodes":[{}]}}],"nodes":[{nodes}]}}"#,
            scene.join(",")
        );
        let s = load(doc.as_bytes(), &LoadOptions::default()).expect("loads");
        assert_eq!(s.stats.nodes, 500_000);
        assert!(s.instances.is_empty());
    });
}

#[test]
fn accessor_counts_near_u32_max_are_errors_before_allocating() {
    limited(
        "accessor_counts_near_u32_max_are_errors_before_allocating",
        256,
        20,
        || {
            let (bin, _, view) = triangle();
            let huge = u64::from(u32::MAX);
            let cases = [
                // Backed by a 36-byte view.
                json!({"bufferView": 0, "componentType": 5126, "count": huge, "type": "VEC3",
                    "min": [0, 0, 0], "max": [1, 1, 1]}),
                // No view: zeros, capped by the file's bytes.
                json!({"componentType": 5126, "count": huge, "type": "VEC3",
                    "min": [0, 0, 0], "max": [1, 1, 1]}),
                // Sparse: more sparse values than the 36-byte views hold.
                json!({"componentType": 5126, "count": huge, "type": "VEC3",
                    "min": [0, 0, 0], "max": [1, 1, 1],
                    "sparse": {"count": huge, "indices": {"bufferView": 0, "componentType": 5125},
                        "values": {"bufferView": 0}}}),
                // Indices near u32::MAX.
                json!({"bufferView": 0, "componentType": 5125, "count": huge - 2, "type": "SCALAR"}),
            ];
            for (k, acc) in cases.into_iter().enumerate() {
                let prim = if k == 3 {
                    json!({"attributes": {"POSITION": 1}, "indices": 0})
                } else {
                    json!({"attributes": {"POSITION": 0}})
                };
                let doc = json!({"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}],
                    "nodes": [{"mesh": 0}], "meshes": [{"primitives": [prim]}],
                    "accessors": [acc, {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                        "min": [0, 0, 0], "max": [1, 1, 0]}],
                    "bufferViews": [view], "buffers": [{"byteLength": 36}]});
                let e = load(&glb(&doc, &bin), &LoadOptions::default()).expect_err("refused");
                assert!(e.to_string().contains("accessors["), "case {k}: {e}");
            }
        },
    );
}

#[test]
fn a_sparse_accessor_with_two_million_indices_loads_in_bounded_memory() {
    limited(
        "a_sparse_accessor_with_two_million_indices_loads_in_bounded_memory",
        1024,
        60,
        || {
            let n: u32 = 2_000_000;
            let mut bin = Vec::with_capacity(n as usize * 16);
            for i in 0..n {
                bin.extend_from_slice(&i.to_le_bytes());
            }
            for i in 0..n {
                let corner = [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]][(i % 3) as usize];
                let t = (i / 3) as f32;
                for c in [corner[0] + t, corner[1], corner[2]] {
                    bin.extend_from_slice(&c.to_le_bytes());
                }
            }
            let doc = json!({"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}],
                "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
                "accessors": [{"componentType": 5126, "count": n - 2, "type": "VEC3",
                    "min": [0, 0, 0], "max": [1e6, 1, 0],
                    "sparse": {"count": n - 2, "indices": {"bufferView": 0, "componentType": 5125},
                        "values": {"bufferView": 1}}}],
                "bufferViews": [{"buffer": 0, "byteLength": n * 4},
                    {"buffer": 0, "byteOffset": n * 4, "byteLength": n * 12}],
                "buffers": [{"byteLength": n * 16}]});
            let s = load(&glb(&doc, &bin), &LoadOptions::default()).expect("loads");
            assert_eq!(s.unique_triangle_count(), (n as usize - 2) / 3);
        },
    );
}

fn png(w: u32, h: u32) -> Vec<u8> {
    let img = image::RgbaImage::from_fn(w, h, |x, y| image::Rgba([x as u8, y as u8, 9, 255]));
    let mut out = Vec::new();
    image::DynamicImage::ImageRgba8(img)
        .write_to(&mut Cursor::new(&mut out), image::ImageFormat::Png)
        .expect("png");
    out
}

/// One mesh of `materials` primitives (the same triangle), material `i` on primitive `i`, each
/// material's base colour texture `texture_of(i)`; `textures` textures of image 0 (the PNG at
/// the end of the BIN chunk), texture `t` with sampler `t` when `samplers`.
fn textured(materials: usize, textures: usize, samplers: bool, image: &[u8]) -> Vec<u8> {
    let (mut bin, acc, view) = triangle();
    let image_at = bin.len();
    bin.extend_from_slice(image);
    let prims: Vec<Value> = (0..materials)
        .map(|i| json!({"attributes": {"POSITION": 0}, "material": i}))
        .collect();
    let mats: Vec<Value> = (0..materials)
        .map(|i| json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": i % textures}}}))
        .collect();
    let texs: Vec<Value> = (0..textures)
        .map(|t| {
            if samplers {
                json!({"source": 0, "sampler": t})
            } else {
                json!({"source": 0})
            }
        })
        .collect();
    let smps: Vec<Value> = (0..if samplers { textures } else { 0 })
        .map(|t| {
            let wrap = [33071u32, 33648, 10497][t % 3];
            json!({"wrapS": wrap})
        })
        .collect();
    let mut doc = json!({"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}], "meshes": [{"primitives": prims}], "materials": mats,
        "textures": texs, "images": [{"bufferView": 1, "mimeType": "image/png"}],
        "accessors": [acc],
        "bufferViews": [view, {"buffer": 0, "byteOffset": image_at, "byteLength": image.len()}],
        "buffers": [{"byteLength": bin.len()}]});
    if samplers {
        doc["samplers"] = json!(smps);
    }
    glb(&doc, &bin)
}

#[test]
fn a_texture_behind_ten_thousand_materials_is_decoded_once() {
    limited(
        "a_texture_behind_ten_thousand_materials_is_decoded_once",
        512,
        60,
        || {
            let file = textured(10_000, 1, false, &png(256, 256));
            let s = load(&file, &LoadOptions::default()).expect("loads");
            assert_eq!(s.materials.len(), 10_000);
            assert_eq!(s.textures.len(), 1);
        },
    );
}

#[test]
fn ten_thousand_textures_of_one_image_are_held_to_the_budget() {
    limited(
        "ten_thousand_textures_of_one_image_are_held_to_the_budget",
        512,
        60,
        || {
            // Each texture has its own sampler, so each holds its own copy of the texels:
            // 10,000 x 1 MiB, refused by a 256 MiB budget before any is decoded.
            let file = textured(10_000, 10_000, true, &png(512, 512));
            let options = LoadOptions {
                memory: aperture_budget::MemoryBudget::fixed(256 << 20),
                ..LoadOptions::default()
            };
            let e = load(&file, &options).expect_err("over budget");
            assert!(matches!(e, Error::OverBudget { .. }), "{e}");
            assert!(e.to_string().contains("used 10000 time(s)"), "{e}");
            // Animated::load_bytes checks the same before posing anything.
            assert!(Animated::load_bytes(&file, Path::new("/nonexistent"), &options).is_err());
        },
    );
}
