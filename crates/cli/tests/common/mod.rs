//! What the farm tests share: the binary, the test scene, scratch folders, requirements that
//! skip outside CI and fail under `CI=true`, and pixel comparisons.

#![allow(dead_code)] // each test binary uses its own part of this

use aperture_imageio::{read_exr, Image};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `aperture` binary cargo built for these tests.
pub fn aperture() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_aperture"))
}

/// The repository's root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("repository root")
}

/// The scene the farm tests render: the README's demo, shipped in the repository.
pub fn demo_scene() -> PathBuf {
    repo().join("assets/demo.glb")
}

/// Options every farm render shares: small, with every pass.
pub const SMALL: [&str; 6] = ["--width", "96", "--height", "54", "--passes", "all"];

/// A requirement that is missing: outside CI the test skips with `why`; under `CI=true`
/// it fails, since a silent skip would hide that the test never ran.
pub fn missing(why: &str) {
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "CI=true but {why}"
    );
    eprintln!("skipping: {why}");
}

/// A scratch folder, removed when dropped.
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("aperture-farm-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Renders the demo scene on this machine with `args` into `out` and reads it back.
pub fn local_render(out: &Path, args: &[&str]) -> Image {
    local_render_of(&demo_scene(), out, args);
    read_exr(out).unwrap()
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|f| f.to_bits()).collect()
}

/// Every pixel of `expected` (beauty and each of its layers) equals `merged`'s bit for bit;
/// returns how many values were compared.
pub fn assert_same_pixels(merged: &Image, expected: &Image) -> usize {
    assert_eq!(
        (merged.width, merged.height, merged.placement),
        (expected.width, expected.height, expected.placement)
    );
    assert!(
        bits(merged.rgba.as_flattened()) == bits(expected.rgba.as_flattened()),
        "beauty differs"
    );
    let mut n = merged.rgba.len() * 4;
    for layer in &expected.layers {
        let m = merged
            .layer(&layer.name)
            .unwrap_or_else(|| panic!("the merged file has no {}", layer.name));
        assert!(
            bits(&m.data) == bits(&layer.data),
            "layer {} differs",
            layer.name
        );
        n += layer.data.len();
    }
    n
}

/// Largest difference of two pixels' values relative to the largest magnitude among them.
fn rel_px(a: &[f32], b: &[f32]) -> f64 {
    let scale = a
        .iter()
        .chain(b)
        .map(|v| f64::from(*v).abs())
        .fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| (f64::from(*x) - f64::from(*y)).abs())
        .fold(0.0, f64::max);
    if diff == 0.0 {
        0.0
    } else {
        diff / scale
    }
}

/// The largest relative difference between `merged` and `expected` over the beauty (per
/// channel) and every averaged layer (per pixel), with where it was; Depth, Position and
/// Cryptomatte IDs must be equal.
pub fn largest_relative_difference(merged: &Image, expected: &Image) -> (f64, String) {
    assert_eq!(
        (merged.width, merged.height),
        (expected.width, expected.height)
    );
    let mut worst = (0.0, String::new());
    let mut note = |d: f64, what: &str| {
        if d > worst.0 {
            worst = (d, what.to_string());
        }
    };
    for (m, e) in merged.rgba.iter().zip(&expected.rgba) {
        for c in 0..4 {
            note(rel_px(&[m[c]], &[e[c]]), "beauty");
        }
    }
    for layer in &expected.layers {
        let m = &merged.layer(&layer.name).expect("layer").data;
        let n = layer.channels.len();
        if matches!(layer.name.as_str(), "Depth" | "Position") {
            assert!(bits(m) == bits(&layer.data), "{}", layer.name);
        } else if layer.name.starts_with("Crypto") {
            for (i, (a, b)) in m.iter().zip(&layer.data).enumerate() {
                if i % 2 == 0 {
                    assert_eq!(a.to_bits(), b.to_bits(), "{} id", layer.name);
                } else {
                    note(rel_px(&[*a], &[*b]), &layer.name);
                }
            }
        } else {
            for (a, b) in m.chunks_exact(n).zip(layer.data.chunks_exact(n)) {
                note(rel_px(a, b), &layer.name);
            }
        }
    }
    worst
}

/// A glTF sample from the samples folder (`APERTURE_SAMPLES`, else `../shared/gltf-samples`
/// beside the repository), or `None` after [`missing`].
pub fn sample(relative: &str) -> Option<PathBuf> {
    let samples = std::env::var_os("APERTURE_SAMPLES")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join("../shared/gltf-samples"));
    let path = samples.join(relative);
    if path.is_file() {
        Some(path)
    } else {
        missing(&format!("the glTF sample {} is missing", path.display()));
        None
    }
}

/// Renders `scene` on this machine with `args` (an output pattern with `#` for `--frames`).
pub fn local_render_of(scene: &Path, out: &Path, args: &[&str]) {
    let status = Command::new(aperture())
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .arg("--quiet")
        .args(args)
        .status()
        .unwrap();
    assert!(status.success(), "local render {args:?}");
}

/// Runs `aperture ARGS` in `dir` and returns what it printed and its status.
pub fn run_in(args: &[&str], dir: &Path) -> Output {
    Command::new(aperture())
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// A run's standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The scene crate's GLB writer (one writer for every test that builds a file).
#[path = "../../../scene/tests/common/glb.rs"]
pub mod glb;

/// A GLB of `doc` whose buffer 0 holds a unit quad in z = 0 facing +Z: positions
/// (accessor 0, 4 × VEC3 float, bytes 0..48) and its two triangles' indices (accessor 1,
/// 6 × u16, bytes 48..60); `doc` may add accessors after these.
pub fn quad_glb(doc: &serde_json::Value) -> Vec<u8> {
    quad_glb_with(doc, &[])
}

/// [`quad_glb`] with `tail` (what `doc`'s added accessors read) from byte 60 of buffer 0.
pub fn quad_glb_with(doc: &serde_json::Value, tail: &[u8]) -> Vec<u8> {
    let mut bin = Vec::new();
    for v in [
        -1.0f32, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
    ] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    bin.extend_from_slice(tail);
    glb::glb(doc, &bin)
}

/// The JSON of [`quad_glb`]'s buffer, views and two accessors.
pub fn quad_json() -> serde_json::Value {
    serde_json::json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": 60}],
        "bufferViews": [
            {"buffer": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-1.0, -1.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    })
}
