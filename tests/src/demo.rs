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
//! through [`sin_cos`] and [`atan`] below (additions, multiplications, divisions and square roots
//! only, which IEEE 754 rounds exactly), so the platform's `libm` cannot change a single bit, and
//! the JSON is written with its keys sorted whatever features `serde_json` was built with.
//! `cargo run -p aperture-tests --example make_demo` writes the file; the test `demo_scene` checks
//! that the committed asset is exactly what this module builds.

use serde_json::{json, Map, Value};

/// Name of the camera node (and of the glTF camera).
pub const CAMERA_NAME: &str = "Camera";
/// The node the camera focuses on (`cameras[0].extras.focus_object`): the middle of the row.
pub const FOCUS_OBJECT: &str = "Row3_Sphere";
/// Focal length written to `extras.lens`, mm.
pub const LENS_MM: f64 = 50.0;
/// f-number written to `extras.aperture_fstop`.
pub const FSTOP: f64 = 1.4;
/// Blade count written to `extras.aperture_blades`.
pub const BLADES: u32 = 6;
/// Sensor width for the `lens`/`yfov` relation (Blender's default, `sensor_fit` AUTO), mm.
pub const SENSOR_WIDTH_MM: f64 = 36.0;
/// Image aspect ratio written to the camera (`aspectRatio`).
pub const ASPECT: f64 = 16.0 / 9.0;
/// Sun illuminance, lux (SPEC §4: 2200 / 683 ≈ 3.2 W/m²).
pub const SUN_LUX: f64 = 2200.0;

/// Camera position in the world, metres.
const CAMERA_POS: [f64; 3] = [0.0, 0.32, 0.0];
/// Camera pitch (rotation about +X), degrees: negative looks down.
const CAMERA_PITCH_DEG: f64 = -7.0;

const PI: f64 = std::f64::consts::PI;

/// `(sin x, cos x)` from a Taylor series after reduction to `[-π/4, π/4]`: bit-identical everywhere.
pub fn sin_cos(x: f64) -> (f64, f64) {
    let quadrant = (x / (PI / 2.0)).round();
    let r = x - quadrant * (PI / 2.0);
    let r2 = r * r;
    // Taylor series to the 19th power: the error at |r| = π/4 is below 1e-17.
    let (mut s, mut c) = (0.0, 0.0);
    let (mut ts, mut tc) = (r, 1.0);
    for k in 0..10 {
        s += ts;
        c += tc;
        let k2 = 2.0 * k as f64;
        ts *= -r2 / ((k2 + 2.0) * (k2 + 3.0));
        tc *= -r2 / ((k2 + 1.0) * (k2 + 2.0));
    }
    match (quadrant as i64).rem_euclid(4) {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// `atan x` by argument halving and a Taylor series: bit-identical everywhere.
pub fn atan(x: f64) -> f64 {
    // atan x = 2 atan(x / (1 + sqrt(1 + x²))); four halvings bring |x| ≤ 1 below tan(π/64).
    let mut y = x;
    for _ in 0..4 {
        y /= 1.0 + (1.0 + y * y).sqrt();
    }
    let y2 = y * y;
    let (mut sum, mut term) = (0.0, y);
    for k in 0..24 {
        sum += term / (2 * k + 1) as f64;
        term *= -y2;
    }
    16.0 * sum
}

/// The vertical field of view that matches [`LENS_MM`] on a [`SENSOR_WIDTH_MM`] sensor fitted to
/// the wider side of a [`ASPECT`] image, as Blender computes it (radians).
pub fn yfov() -> f64 {
    2.0 * atan(SENSOR_WIDTH_MM / 2.0 / LENS_MM / ASPECT)
}

type V3 = [f64; 3];

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// A unit quaternion `[x, y, z, w]`.
type Quat = [f64; 4];

fn quat_axis_angle(axis: V3, degrees: f64) -> Quat {
    let (s, c) = sin_cos(degrees.to_radians() / 2.0);
    [axis[0] * s, axis[1] * s, axis[2] * s, c]
}

fn quat_mul(a: Quat, b: Quat) -> Quat {
    [
        a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
        a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
        a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
        a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
    ]
}

fn quat_rotate(q: Quat, v: V3) -> V3 {
    // v' = v + 2w (u × v) + 2 u × (u × v), u = q.xyz
    let u = [q[0], q[1], q[2]];
    let cross = |a: V3, b: V3| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let t = scale(cross(u, v), 2.0);
    add(add(v, scale(t, q[3])), cross(u, t))
}

/// Rounds to 6 decimals so the JSON stays readable (and stays exactly what it says).
fn r6(x: f64) -> f64 {
    let y = (x * 1e6).round() / 1e6;
    if y == 0.0 {
        0.0 // no "-0.0"
    } else {
        y
    }
}

fn jv3(v: V3) -> Value {
    json!([r6(v[0]), r6(v[1]), r6(v[2])])
}

fn jq(q: Quat) -> Value {
    json!([r6(q[0]), r6(q[1]), r6(q[2]), r6(q[3])])
}

/// Triangle geometry with per-vertex normals.
#[derive(Default)]
struct Geometry {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    indices: Vec<u32>,
}

impl Geometry {
    fn vertex(&mut self, p: V3, n: V3) -> u32 {
        let i = self.positions.len() as u32;
        self.positions.push(p.map(|x| x as f32));
        self.normals.push(n.map(|x| x as f32));
        i
    }

    fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// A unit-radius UV sphere centred at the origin, counter-clockwise from outside.
    fn uv_sphere(segments: u32, rings: u32) -> Self {
        let mut g = Self::default();
        for ring in 0..=rings {
            let (st, ct) = sin_cos(PI * ring as f64 / rings as f64);
            for seg in 0..=segments {
                let (sp, cp) = sin_cos(2.0 * PI * seg as f64 / segments as f64);
                let n = [st * cp, ct, -st * sp];
                g.vertex(n, n);
            }
        }
        let row = segments + 1;
        for ring in 0..rings {
            for seg in 0..segments {
                let a = ring * row + seg;
                let (b, c, d) = (a + row, a + row + 1, a + 1);
                if ring != 0 {
                    g.indices.extend([a, b, d]);
                }
                if ring != rings - 1 {
                    g.indices.extend([d, b, c]);
                }
            }
        }
        g
    }

    /// An axis-aligned unit cube centred at the origin, flat-shaded.
    fn cube() -> Self {
        let mut g = Self::default();
        // Each face: normal, and two tangent axes u, v with u × v = normal.
        let faces: [(V3, V3, V3); 6] = [
            ([1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
            ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
            ([0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]),
            ([0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            ([0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ];
        for (n, u, v) in faces {
            let base = g.positions.len() as u32;
            for (su, sv) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
                let p = add(add(scale(n, 0.5), scale(u, su)), scale(v, sv));
                g.vertex(p, n);
            }
            g.indices
                .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
        g
    }

    /// A capped cylinder of radius 1 from y = 0 to y = 1: smooth sides, flat caps.
    fn cylinder(segments: u32) -> Self {
        let mut g = Self::default();
        let ring: Vec<(f64, f64)> = (0..=segments)
            .map(|s| sin_cos(2.0 * PI * s as f64 / segments as f64))
            .collect();
        for &(s, c) in &ring {
            let n = [c, 0.0, -s];
            g.vertex([c, 0.0, -s], n);
            g.vertex([c, 1.0, -s], n);
        }
        for k in 0..segments {
            let (a, b, c, d) = (2 * k, 2 * k + 2, 2 * k + 3, 2 * k + 1);
            g.indices.extend([a, b, c, a, c, d]);
        }
        for (y, n) in [(1.0, [0.0, 1.0, 0.0]), (0.0, [0.0, -1.0, 0.0])] {
            let centre = g.vertex([0.0, y, 0.0], n);
            let first = g.positions.len() as u32;
            for &(s, c) in &ring[..segments as usize] {
                g.vertex([c, y, -s], n);
            }
            for k in 0..segments {
                let (a, b) = (first + k, first + (k + 1) % segments);
                if y > 0.5 {
                    g.indices.extend([centre, a, b]);
                } else {
                    g.indices.extend([centre, b, a]);
                }
            }
        }
        g
    }

    /// A unit quad in the XY plane facing +Z, centred at the origin.
    fn quad() -> Self {
        let mut g = Self::default();
        let n = [0.0, 0.0, 1.0];
        for (x, y) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
            g.vertex([x, y, 0.0], n);
        }
        g.indices.extend([0, 1, 2, 0, 2, 3]);
        g
    }

    /// The checkered ground at y = 0: `(light tiles, dark tiles)`.
    fn ground(x0: f64, x1: f64, z0: f64, z1: f64, tile: f64) -> (Self, Self) {
        let (mut light, mut dark) = (Self::default(), Self::default());
        let nx = ((x1 - x0) / tile).round() as i64;
        let nz = ((z1 - z0) / tile).round() as i64;
        for iz in 0..nz {
            for ix in 0..nx {
                let g = if (ix + iz) % 2 == 0 {
                    &mut light
                } else {
                    &mut dark
                };
                let (xa, xb) = (x0 + ix as f64 * tile, x0 + (ix + 1) as f64 * tile);
                let (za, zb) = (z0 + iz as f64 * tile, z0 + (iz + 1) as f64 * tile);
                let n = [0.0, 1.0, 0.0];
                let base = g.positions.len() as u32;
                // Seen from above (+Y), x right and −z forward: counter-clockwise.
                for (x, z) in [(xa, zb), (xb, zb), (xb, za), (xa, za)] {
                    g.vertex([x, 0.0, z], n);
                }
                g.indices
                    .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
            }
        }
        (light, dark)
    }
}

/// The binary buffer with its buffer views and accessors.
#[derive(Default)]
struct Bin {
    data: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while self.data.len() % 4 != 0 {
            self.data.push(0);
        }
        self.views.push(json!({
            "buffer": 0,
            "byteOffset": self.data.len(),
            "byteLength": bytes.len(),
            "target": target,
        }));
        self.data.extend_from_slice(bytes);
        self.views.len() - 1
    }

    fn vec3(&mut self, v: &[[f32; 3]], with_bounds: bool) -> usize {
        let bytes: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, 34962);
        let mut acc = json!({
            "bufferView": view,
            "componentType": 5126,
            "count": v.len(),
            "type": "VEC3",
        });
        if with_bounds {
            let mut min = [f32::INFINITY; 3];
            let mut max = [f32::NEG_INFINITY; 3];
            for p in v {
                for k in 0..3 {
                    min[k] = min[k].min(p[k]);
                    max[k] = max[k].max(p[k]);
                }
            }
            // f32 → f64 is exact, and serde_json prints the shortest form that reads back as it.
            acc["min"] = json!(min.map(f64::from));
            acc["max"] = json!(max.map(f64::from));
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// Indices as u16 when every index fits, else as u32 (or u32 when `force_u32`).
    fn indices(&mut self, idx: &[u32], force_u32: bool) -> usize {
        let wide = force_u32 || idx.iter().any(|&i| i > u32::from(u16::MAX - 1));
        let (bytes, component): (Vec<u8>, u32) = if wide {
            (idx.iter().flat_map(|i| i.to_le_bytes()).collect(), 5125)
        } else {
            (
                idx.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect(),
                5123,
            )
        };
        let view = self.view(&bytes, 34963);
        self.accessors.push(json!({
            "bufferView": view,
            "componentType": component,
            "count": idx.len(),
            "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }

    /// Stores a geometry; returns the accessors `(POSITION, NORMAL, indices)`.
    fn geometry(&mut self, g: &Geometry, force_u32: bool) -> (usize, usize, usize) {
        (
            self.vec3(&g.positions, true),
            self.vec3(&g.normals, false),
            self.indices(&g.indices, force_u32),
        )
    }
}

fn primitive(acc: (usize, usize, usize), material: usize) -> Value {
    json!({
        "attributes": { "POSITION": acc.0, "NORMAL": acc.1 },
        "indices": acc.2,
        "material": material,
        "mode": 4,
    })
}

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

/// Rebuilds every object with its keys inserted in sorted order, so the output is the same
/// whether `serde_json::Map` is a `BTreeMap` or (feature `preserve_order`) an `IndexMap`.
fn sorted(v: Value) -> Value {
    match v {
        Value::Object(map) => {
            let mut entries: Vec<(String, Value)> = map.into_iter().collect();
            entries.sort_by(|a, b| a.0.cmp(&b.0));
            let mut out = Map::new();
            for (k, v) in entries {
                out.insert(k, sorted(v));
            }
            Value::Object(out)
        }
        Value::Array(items) => Value::Array(items.into_iter().map(sorted).collect()),
        other => other,
    }
}

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
    let mut nodes: Vec<Value> = Vec::new();
    let mut meshes: Vec<Value> = Vec::new();
    let mut drawn_triangles = 0;

    // Camera frame: pitch about +X; looks down its local −Z.
    let cam_rot = quat_axis_angle([1.0, 0.0, 0.0], CAMERA_PITCH_DEG);
    let tan_y = SENSOR_WIDTH_MM / 2.0 / LENS_MM / ASPECT; // tan(yfov / 2)
    let tan_x = tan_y * ASPECT;
    // World point at normalised image position (nx, ny) ∈ [−1, 1]² and depth d along the view axis.
    let at_image = |nx: f64, ny: f64, d: f64| -> V3 {
        let local = [nx * tan_x * d, ny * tan_y * d, -d];
        add(CAMERA_POS, quat_rotate(cam_rot, local))
    };

    // Materials.
    let materials = vec![
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
    ];
    const WARM: usize = 9;
    const COOL: usize = 10;
    const PANEL: usize = 11;

    // Shared geometry: every mesh that draws a shape points at the same accessors.
    let sphere = Geometry::uv_sphere(48, 24);
    let small_sphere = Geometry::uv_sphere(16, 8);
    let cube = Geometry::cube();
    let cylinder = Geometry::cylinder(40);
    let quad = Geometry::quad();
    let (light_tiles, dark_tiles) = Geometry::ground(-3.0, 3.0, -15.0, 0.6, 0.15);
    let sphere_acc = bin.geometry(&sphere, false);
    let small_acc = bin.geometry(&small_sphere, false);
    let cube_acc = bin.geometry(&cube, false);
    let cylinder_acc = bin.geometry(&cylinder, false);
    let quad_acc = bin.geometry(&quad, false);
    // The ground uses 32-bit indices on purpose, so the file exercises both index widths.
    let light_acc = bin.geometry(&light_tiles, true);
    let dark_acc = bin.geometry(&dark_tiles, true);

    // Ground.
    meshes.push(json!({
        "name": "Ground",
        "primitives": [primitive(light_acc, 0), primitive(dark_acc, 1)],
    }));
    nodes.push(json!({ "name": "Ground", "mesh": meshes.len() - 1 }));
    drawn_triangles += light_tiles.triangle_count() + dark_tiles.triangle_count();

    // The row: eight table-top objects from 1 m to 3.24 m deep, from the lower right of the image
    // to its upper left.
    #[derive(Clone, Copy)]
    enum Shape {
        Sphere,
        Box,
        Column,
    }
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
        let x = nx * tan_x * depth;
        let z = CAMERA_POS[2] - depth;
        let (kind, acc, tris, translation, rotation, size) = match shape {
            Shape::Sphere => {
                let r = 0.09;
                (
                    "Sphere",
                    sphere_acc,
                    sphere.triangle_count(),
                    [x, r, z],
                    None,
                    [r; 3],
                )
            }
            Shape::Box => {
                let s = 0.15;
                let yaw = quat_axis_angle([0.0, 1.0, 0.0], 20.0 + 25.0 * i as f64);
                (
                    "Box",
                    cube_acc,
                    cube.triangle_count(),
                    [x, s / 2.0, z],
                    Some(yaw),
                    [s; 3],
                )
            }
            Shape::Column => (
                "Column",
                cylinder_acc,
                cylinder.triangle_count(),
                [x, 0.0, z],
                None,
                [0.04, 0.34, 0.04],
            ),
        };
        let name = format!("Row{i}_{kind}");
        meshes.push(json!({ "name": name, "primitives": [primitive(acc, material)] }));
        let mut node = json!({
            "name": name,
            "mesh": meshes.len() - 1,
            "translation": jv3(translation),
            "scale": jv3(size),
        });
        if let Some(q) = rotation {
            node["rotation"] = jq(q);
        }
        nodes.push(node);
        drawn_triangles += tris;
    }

    // Bokeh lights: (image x, image y, depth along the view axis, warm?).
    let front: [(f64, f64, f64, bool); 4] = [
        (-0.78, 0.62, 0.6, true),
        (-0.4, 0.82, 0.7, false),
        (0.62, 0.74, 0.65, true),
        (-0.72, -0.5, 0.55, false),
    ];
    let behind: [(f64, f64, f64, bool); 8] = [
        (-0.86, 0.66, 6.0, true),
        (-0.56, 0.86, 8.0, false),
        (-0.24, 0.72, 10.0, true),
        (0.04, 0.9, 7.0, true),
        (0.3, 0.66, 11.0, false),
        (0.54, 0.82, 9.0, true),
        (0.78, 0.62, 12.0, false),
        (0.92, 0.9, 6.5, true),
    ];
    let warm_mesh = meshes.len();
    meshes.push(json!({ "name": "WarmBulb", "primitives": [primitive(small_acc, WARM)] }));
    let cool_mesh = meshes.len();
    meshes.push(json!({ "name": "CoolBulb", "primitives": [primitive(small_acc, COOL)] }));
    for (k, &(nx, ny, depth, warm)) in front.iter().chain(behind.iter()).enumerate() {
        let radius = if depth < 2.0 { 0.003 } else { 0.009 };
        let p = at_image(nx, ny, depth);
        assert!(p[1] > 2.0 * radius, "bokeh light {k} is under the ground");
        nodes.push(json!({
            "name": format!("Bulb{k}"),
            "mesh": if warm { warm_mesh } else { cool_mesh },
            "translation": jv3(p),
            "scale": jv3([radius; 3]),
        }));
        drawn_triangles += small_sphere.triangle_count();
    }

    // Soft fill: a 1.6 m × 0.6 m emissive panel behind and above the camera, tilted to face the row.
    meshes.push(json!({ "name": "FillPanel", "primitives": [primitive(quad_acc, PANEL)] }));
    nodes.push(json!({
        "name": "FillPanel",
        "mesh": meshes.len() - 1,
        "translation": jv3([0.0, 0.9, 1.0]),
        // Face −Z (turn 180° about Y), then tip down 30° towards the ground.
        "rotation": jq(quat_mul(
            quat_axis_angle([0.0, 1.0, 0.0], 180.0),
            quat_axis_angle([1.0, 0.0, 0.0], 30.0),
        )),
        "scale": jv3([1.6, 0.6, 1.0]),
    }));
    drawn_triangles += quad.triangle_count();

    // Sun: travels along its node's −Z; from the upper left, a little behind the camera.
    nodes.push(json!({
        "name": "Sun",
        "rotation": jq(quat_mul(
            quat_axis_angle([0.0, 1.0, 0.0], -45.0),
            quat_axis_angle([1.0, 0.0, 0.0], -50.0),
        )),
        "extensions": { "KHR_lights_punctual": { "light": 0 } },
    }));

    // Camera.
    nodes.push(json!({
        "name": CAMERA_NAME,
        "camera": 0,
        "translation": jv3(CAMERA_POS),
        "rotation": jq(cam_rot),
    }));

    let node_count = nodes.len();
    let json = json!({
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
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    let mut json = sorted(json);
    while bin.data.len() % 4 != 0 {
        bin.data.push(0);
    }
    json["buffers"][0]["byteLength"] = json!(bin.data.len());
    Demo {
        json,
        bin: bin.data,
        stats: DemoStats {
            drawn_triangles,
            nodes: node_count,
            bokeh_lights: (front.len(), behind.len()),
        },
    }
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
