//! What the demo scene holds and where: the materials, the ground, the row of objects, the bokeh
//! lights, the fill panel, the sun and the camera node.

use serde_json::{json, Value};

use super::bin::{primitive, Bin};
use super::geometry::Geometry;
use super::lens::{View, CAMERA_NAME, CAMERA_POS};
use super::math::{jq, jv3, quat_axis_angle, quat_mul, Quat, V3};

/// Index of the warm bulbs' material in [`materials`].
const WARM: usize = 9;
/// Index of the cool bulbs' material.
const COOL: usize = 10;
/// Index of the fill panel's material.
const PANEL: usize = 11;

fn pbr(name: &str, rgb: V3, metallic: f64, roughness: f64) -> Value {
    json!({
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [rgb[0], rgb[1], rgb[2], 1.0],
            "metallicFactor": metallic,
            "roughnessFactor": roughness,
        },
    })
}

fn emissive(name: &str, rgb: V3, strength: f64) -> Value {
    json!({
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [0.0, 0.0, 0.0, 1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": 1.0,
        },
        "emissiveFactor": rgb,
        "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": strength } },
        "doubleSided": true,
    })
}

/// The scene's materials, in glTF order.
pub(super) fn materials() -> Vec<Value> {
    vec![
        pbr("GroundLight", [0.62, 0.62, 0.6], 0.0, 0.85),
        pbr("GroundDark", [0.16, 0.16, 0.17], 0.0, 0.7),
        pbr("RedPlastic", [0.8, 0.06, 0.05], 0.0, 0.35),
        pbr("Gold", [1.0, 0.766, 0.336], 1.0, 0.25),
        pbr("BluePaint", [0.08, 0.2, 0.75], 0.0, 0.6),
        pbr("WhiteClay", [0.82, 0.82, 0.8], 0.0, 0.9),
        pbr("GreenGlaze", [0.12, 0.55, 0.18], 0.0, 0.2),
        pbr("Copper", [0.955, 0.638, 0.538], 1.0, 0.45),
        pbr("Chrome", [0.95, 0.95, 0.95], 1.0, 0.06),
        emissive("WarmLight", [1.0, 0.72, 0.38], 60.0),
        emissive("CoolLight", [0.55, 0.75, 1.0], 60.0),
        emissive("FillPanel", [1.0, 0.97, 0.92], 0.6),
    ]
}

/// A stored geometry: its accessors `(POSITION, NORMAL, indices)` and triangle count.
#[derive(Clone, Copy)]
struct Stored {
    acc: (usize, usize, usize),
    triangles: usize,
}

impl Stored {
    fn new(bin: &mut Bin, g: &Geometry, force_u32: bool) -> Self {
        Self {
            acc: bin.geometry(g, force_u32),
            triangles: g.triangle_count(),
        }
    }
}

/// Shared geometry: every mesh that draws a shape points at the same accessors.
pub(super) struct Shapes {
    sphere: Stored,
    small_sphere: Stored,
    cube: Stored,
    cylinder: Stored,
    quad: Stored,
    light_tiles: Stored,
    dark_tiles: Stored,
}

impl Shapes {
    /// Builds the shapes and stores them in `bin`, in this order.
    pub(super) fn store(bin: &mut Bin) -> Self {
        let (light_tiles, dark_tiles) = Geometry::ground(-3.0, 3.0, -15.0, 0.6, 0.15);
        Self {
            sphere: Stored::new(bin, &Geometry::uv_sphere(48, 24), false),
            small_sphere: Stored::new(bin, &Geometry::uv_sphere(16, 8), false),
            cube: Stored::new(bin, &Geometry::cube(), false),
            cylinder: Stored::new(bin, &Geometry::cylinder(40), false),
            quad: Stored::new(bin, &Geometry::quad(), false),
            // The ground uses 32-bit indices on purpose, so the file exercises both index widths.
            light_tiles: Stored::new(bin, &light_tiles, true),
            dark_tiles: Stored::new(bin, &dark_tiles, true),
        }
    }
}

/// The kinds of object in the row.
#[derive(Clone, Copy)]
enum Shape {
    Sphere,
    Box,
    Column,
}

/// One object of the row: its kind's name, geometry, translation, rotation and scale.
type Placed = (&'static str, Stored, V3, Option<Quat>, V3);

/// Object `i` of the row, of `shape`, at world `x`, `z`.
fn place(shapes: &Shapes, shape: Shape, i: usize, x: f64, z: f64) -> Placed {
    match shape {
        Shape::Sphere => {
            let r = 0.09;
            ("Sphere", shapes.sphere, [x, r, z], None, [r; 3])
        }
        Shape::Box => {
            let s = 0.15;
            let yaw = quat_axis_angle([0.0, 1.0, 0.0], 20.0 + 25.0 * i as f64);
            ("Box", shapes.cube, [x, s / 2.0, z], Some(yaw), [s; 3])
        }
        Shape::Column => (
            "Column",
            shapes.cylinder,
            [x, 0.0, z],
            None,
            [0.04, 0.34, 0.04],
        ),
    }
}

/// Bokeh lights: (image x, image y, depth along the view axis, warm?), in front of the focal
/// plane.
const FRONT: [(f64, f64, f64, bool); 4] = [
    (-0.78, 0.62, 0.6, true),
    (-0.4, 0.82, 0.7, false),
    (0.62, 0.74, 0.65, true),
    (-0.72, -0.5, 0.55, false),
];
/// Bokeh lights behind the focal plane.
const BEHIND: [(f64, f64, f64, bool); 8] = [
    (-0.86, 0.66, 6.0, true),
    (-0.56, 0.86, 8.0, false),
    (-0.24, 0.72, 10.0, true),
    (0.04, 0.9, 7.0, true),
    (0.3, 0.66, 11.0, false),
    (0.54, 0.82, 9.0, true),
    (0.78, 0.62, 12.0, false),
    (0.92, 0.9, 6.5, true),
];

/// The scene's nodes and meshes as they are added, and the triangles they draw.
#[derive(Default)]
pub(super) struct Assembly {
    pub(super) nodes: Vec<Value>,
    pub(super) meshes: Vec<Value>,
    pub(super) drawn_triangles: usize,
}

impl Assembly {
    /// The checkered ground.
    pub(super) fn add_ground(&mut self, shapes: &Shapes) {
        let (light, dark) = (shapes.light_tiles, shapes.dark_tiles);
        self.meshes.push(json!({
            "name": "Ground",
            "primitives": [primitive(light.acc, 0), primitive(dark.acc, 1)],
        }));
        self.nodes
            .push(json!({ "name": "Ground", "mesh": self.meshes.len() - 1 }));
        self.drawn_triangles += light.triangles + dark.triangles;
    }

    /// The row: eight table-top objects from 1 m to 3.24 m deep, from the lower right of the
    /// image to its upper left.
    pub(super) fn add_row(&mut self, shapes: &Shapes, view: &View) {
        let row: [(Shape, usize); 8] = [
            (Shape::Sphere, 2),
            (Shape::Box, 4),
            (Shape::Column, 5),
            (Shape::Sphere, 3),
            (Shape::Box, 6),
            (Shape::Column, 7),
            (Shape::Sphere, 8),
            (Shape::Box, 5),
        ];
        for (i, &(shape, material)) in row.iter().enumerate() {
            let depth = 1.0 + 0.32 * i as f64;
            let nx = 0.6 - 1.2 * i as f64 / 7.0;
            let x = nx * view.tan_x * depth;
            let z = CAMERA_POS[2] - depth;
            let (kind, stored, translation, rotation, size) = place(shapes, shape, i, x, z);
            let name = format!("Row{i}_{kind}");
            self.meshes
                .push(json!({ "name": name, "primitives": [primitive(stored.acc, material)] }));
            let mut node = json!({
                "name": name,
                "mesh": self.meshes.len() - 1,
                "translation": jv3(translation),
                "scale": jv3(size),
            });
            if let Some(q) = rotation {
                node["rotation"] = jq(q);
            }
            self.nodes.push(node);
            self.drawn_triangles += stored.triangles;
        }
    }

    /// Small bright spheres in front of and behind the focal plane; their counts.
    pub(super) fn add_bokeh_lights(&mut self, shapes: &Shapes, view: &View) -> (usize, usize) {
        let small = shapes.small_sphere;
        let warm_mesh = self.meshes.len();
        self.meshes
            .push(json!({ "name": "WarmBulb", "primitives": [primitive(small.acc, WARM)] }));
        let cool_mesh = self.meshes.len();
        self.meshes
            .push(json!({ "name": "CoolBulb", "primitives": [primitive(small.acc, COOL)] }));
        for (k, &(nx, ny, depth, warm)) in FRONT.iter().chain(BEHIND.iter()).enumerate() {
            let radius = if depth < 2.0 { 0.003 } else { 0.009 };
            let p = view.at_image(nx, ny, depth);
            assert!(p[1] > 2.0 * radius, "bokeh light {k} is under the ground");
            self.nodes.push(json!({
                "name": format!("Bulb{k}"),
                "mesh": if warm { warm_mesh } else { cool_mesh },
                "translation": jv3(p),
                "scale": jv3([radius; 3]),
            }));
            self.drawn_triangles += small.triangles;
        }
        (FRONT.len(), BEHIND.len())
    }

    /// Soft fill: a 1.6 m × 0.6 m emissive panel behind and above the camera, tilted to face the
    /// row.
    pub(super) fn add_fill_panel(&mut self, shapes: &Shapes) {
        self.meshes.push(
            json!({ "name": "FillPanel", "primitives": [primitive(shapes.quad.acc, PANEL)] }),
        );
        self.nodes.push(json!({
            "name": "FillPanel",
            "mesh": self.meshes.len() - 1,
            "translation": jv3([0.0, 0.9, 1.0]),
            // Face −Z (turn 180° about Y), then tip down 30° towards the ground.
            "rotation": jq(quat_mul(
                quat_axis_angle([0.0, 1.0, 0.0], 180.0),
                quat_axis_angle([1.0, 0.0, 0.0], 30.0),
            )),
            "scale": jv3([1.6, 0.6, 1.0]),
        }));
        self.drawn_triangles += shapes.quad.triangles;
    }

    /// The sun's node and the camera's.
    pub(super) fn add_sun_and_camera(&mut self, view: &View) {
        // Sun: travels along its node's −Z; from the upper left, a little behind the camera.
        self.nodes.push(json!({
            "name": "Sun",
            "rotation": jq(quat_mul(
                quat_axis_angle([0.0, 1.0, 0.0], -45.0),
                quat_axis_angle([1.0, 0.0, 0.0], -50.0),
            )),
            "extensions": { "KHR_lights_punctual": { "light": 0 } },
        }));
        self.nodes.push(json!({
            "name": CAMERA_NAME,
            "camera": 0,
            "translation": jv3(CAMERA_POS),
            "rotation": jq(view.rot),
        }));
    }
}
