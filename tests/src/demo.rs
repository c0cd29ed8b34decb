//! The demo scene `assets/demo.glb`, built in memory.
//!
//! A row of spheres, boxes and columns recedes in depth on a checkered ground; small bright
//! emissive spheres float in front of and behind the focal plane so their bokeh shows the
//! six-bladed aperture; a sun (`KHR_lights_punctual`, lux) is the key light and a soft emissive
//! panel behind the camera fills the shadows and shows in the metals. The camera's `extras` carry
//! Blender's depth-of-field keys (SPEC §3): f/1.4, a 50 mm lens and the focus on the middle of the
//! row.
//!
//! [`build_glb`] is a pure function: the same bytes on every run and machine. All trigonometry goes
//! through [`sin_cos`] and [`atan`] (in `demo/math.rs`: additions, multiplications, divisions and
//! square roots only, which IEEE 754 rounds exactly), so the platform's `libm` cannot change a
//! single bit, and the JSON is written with its keys sorted whatever features `serde_json` was
//! built with. The parts live beside this file: the camera (`lens.rs`), the meshes
//! (`geometry.rs`), the buffer (`bin.rs`) and what stands where (`layout.rs`).
//! `cargo run -p aperture-tests --example make_demo` writes the file; the test `demo_scene` checks
//! that the committed asset is exactly what this module builds.

mod bin;
mod geometry;
mod layout;
mod lens;
mod math;

use serde_json::{json, Value};

use bin::{sorted, Bin};
use layout::{materials, Assembly, Shapes};
use lens::View;
use math::r6;

pub use lens::{yfov, ASPECT, BLADES, CAMERA_NAME, FOCUS_OBJECT, FSTOP, LENS_MM, SENSOR_WIDTH_MM};
pub use math::{atan, sin_cos};

/// Sun illuminance, lux (SPEC §4: 2200 / 683 ≈ 3.2 W/m²).
pub const SUN_LUX: f64 = 2200.0;

/// What the scene is made of, for tests and the README.
#[derive(Debug, Clone, PartialEq)]
pub struct DemoStats {
    /// Triangles drawn (each mesh counted once per node that draws it).
    pub drawn_triangles: usize,
    /// Nodes in the scene.
    pub nodes: usize,
    /// Small emissive spheres placed for bokeh: `(in front of the focal plane, behind it)`.
    pub bokeh_lights: (usize, usize),
}

/// The demo scene as a glTF JSON document and its binary buffer.
pub struct Demo {
    /// The glTF JSON (keys sorted).
    pub json: Value,
    /// The binary buffer (a multiple of 4 bytes long).
    pub bin: Vec<u8>,
    /// Counts for tests.
    pub stats: DemoStats,
}

/// Builds the demo scene.
pub fn build() -> Demo {
    let mut bin = Bin::default();
    let view = View::new();
    let shapes = Shapes::store(&mut bin);
    let mut scene = Assembly::default();
    scene.add_ground(&shapes);
    scene.add_row(&shapes, &view);
    let bokeh_lights = scene.add_bokeh_lights(&shapes, &view);
    scene.add_fill_panel(&shapes);
    scene.add_sun_and_camera(&view);

    let node_count = scene.nodes.len();
    let mut json = sorted(document(
        scene.nodes,
        scene.meshes,
        bin.views,
        bin.accessors,
    ));
    while bin.data.len() % 4 != 0 {
        bin.data.push(0);
    }
    json["buffers"][0]["byteLength"] = json!(bin.data.len());
    Demo {
        json,
        bin: bin.data,
        stats: DemoStats {
            drawn_triangles: scene.drawn_triangles,
            nodes: node_count,
            bokeh_lights,
        },
    }
}

/// The glTF document around the nodes, meshes, buffer views and accessors (keys not yet sorted,
/// the buffer's length not yet known).
fn document(
    nodes: Vec<Value>,
    meshes: Vec<Value>,
    views: Vec<Value>,
    accessors: Vec<Value>,
) -> Value {
    let node_count = nodes.len();
    let materials = materials();
    json!({
        "asset": {
            "version": "2.0",
            "generator": "aperture make_demo (tests/src/demo.rs)",
            "copyright": "CC0 1.0: the aperture authors",
        },
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
        "extensions": {
            "KHR_lights_punctual": {
                "lights": [{
                    "name": "Sun",
                    "type": "directional",
                    "color": [1.0, 0.96, 0.9],
                    "intensity": SUN_LUX,
                }],
            },
        },
        "scene": 0,
        "scenes": [{ "name": "Demo", "nodes": (0..node_count).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{
            "name": CAMERA_NAME,
            "type": "perspective",
            "perspective": {
                "yfov": r6(yfov()),
                "aspectRatio": r6(ASPECT),
                "znear": 0.05,
                "zfar": 200.0,
            },
            "extras": {
                "use_dof": true,
                "aperture_fstop": FSTOP,
                "aperture_blades": BLADES,
                "aperture_rotation": 0.0,
                "lens": LENS_MM,
                "sensor_width": SENSOR_WIDTH_MM,
                "sensor_fit": "AUTO",
                "focus_object": FOCUS_OBJECT,
            },
        }],
        "buffers": [{ "byteLength": 0 }],
        "bufferViews": views,
        "accessors": accessors,
    })
}

/// Packs a glTF JSON document and its buffer into a GLB: 12-byte header, a JSON chunk padded with
/// spaces and a BIN chunk padded with zeros, both 4-byte aligned.
pub fn to_glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut text = serde_json::to_vec(json).expect("a serde_json::Value always serialises");
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let mut bin = bin.to_vec();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + text.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// The bytes of `assets/demo.glb`.
pub fn build_glb() -> Vec<u8> {
    let demo = build();
    to_glb(&demo.json, &demo.bin)
}

/// Path of the committed asset: `assets/demo.glb` at the workspace root.
pub fn asset_path() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/demo.glb")
}
