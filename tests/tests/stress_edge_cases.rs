//! Edge cases of issue 6, part 3, each written as a glTF file and rendered through the loader:
//! cameras inside geometry or exactly on a surface, rays grazing surfaces, degenerate
//! triangles, normals of zero length, textures of 1×1 and odd sizes. The renders must be finite
//! with no sample dropped (checked by `render_checked`), plus what each case implies about the
//! picture.

#[path = "stress_util.rs"]
mod util;

use aperture_imageio::Image;
use aperture_scene::Scene;
use aperture_shading::test_scenes::icosphere;
use glam::{Quat, Vec2, Vec3};
use serde_json::json;
use util::{mean, quat, render_checked, Gltf};

const SIZE: (u32, u32) = (32, 24);
const SPP: u32 = 8;

fn ground(g: &mut Gltf, half: f32, material: usize) -> usize {
    let h = half;
    g.mesh(
        &[
            Vec3::new(-h, 0.0, -h),
            Vec3::new(-h, 0.0, h),
            Vec3::new(h, 0.0, h),
            Vec3::new(h, 0.0, -h),
        ],
        Some(&[Vec3::Y; 4]),
        Some(&[
            Vec2::new(-3.5, -2.0),
            Vec2::new(-3.5, 4.25),
            Vec2::new(5.5, 4.25),
            Vec2::new(5.5, -2.0),
        ]),
        &[[0, 1, 2], [0, 2, 3]],
        material,
    )
}

fn matte(g: &mut Gltf) -> usize {
    g.material(json!({"pbrMetallicRoughness": {
        "baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0, "roughnessFactor": 0.5}}))
}

fn point_light(g: &mut Gltf, at: Vec3) -> usize {
    let l = g.light(json!({"type": "point", "intensity": 683.0 * 8.0}));
    g.node(json!({"extensions": {"KHR_lights_punctual": {"light": l}},
        "translation": at.to_array()}))
}

/// A camera node at `eye` looking along `dir`.
fn camera(g: &mut Gltf, eye: Vec3, dir: Vec3, extras: serde_json::Value) -> usize {
    let c = g.camera(json!({"type": "perspective",
        "perspective": {"yfov": 0.9, "znear": 0.001}, "extras": extras}));
    let q = Quat::from_rotation_arc(Vec3::NEG_Z, dir.normalize());
    g.node(json!({"camera": c, "translation": eye.to_array(), "rotation": q.to_array()}))
}

fn render(scene: &Scene) -> [f64; 3] {
    mean(&render_checked(scene, SIZE, SPP, 0, 3))
}

#[test]
fn cameras_inside_geometry_and_on_surfaces() {
    for (eye, dir, lens) in [
        // Inside a closed ball lit from outside: everything it sees is in the ball's shadow.
        (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.3, -0.2, -1.0), 0.0),
        // The same with a lens wider than the ball: rays start inside and outside it.
        (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.3, -0.2, -1.0), 2.0),
        // Exactly on the ground, looking down into it and along it.
        (Vec3::new(0.5, 0.0, 2.0), Vec3::NEG_Y, 0.0),
        (Vec3::new(0.5, 0.0, 2.0), Vec3::new(0.0, 0.0, -1.0), 0.0),
        // Exactly on the ball's surface (a vertex of the icosphere, radius 0.5 at (0, 1, 0)).
        (
            Vec3::new(0.0, 1.0, 0.0) + 0.5 * icosphere(2, 0).positions[0],
            Vec3::new(0.0, -1.0, -1.0),
            0.1,
        ),
    ] {
        let mut g = Gltf::new();
        let m = matte(&mut g);
        let plane = ground(&mut g, 3.0, m);
        let s = icosphere(2, 0);
        let ball = g.mesh(&s.positions, Some(&s.normals), None, &s.indices, m);
        let nodes = [
            g.node(json!({"mesh": plane})),
            g.node(json!({"mesh": ball, "translation": [0, 1, 0], "scale": [0.5, 0.5, 0.5]})),
            point_light(&mut g, Vec3::new(1.5, 3.0, 1.5)),
            camera(
                &mut g,
                eye,
                dir,
                if lens > 0.0 {
                    json!({"aperture_radius": lens, "focus_distance": 1.0})
                } else {
                    json!({})
                },
            ),
        ];
        let m = render(&g.load(&nodes));
        if lens == 0.0 && eye == Vec3::new(0.0, 1.0, 0.0) {
            // The ball's inside faces the light only through the ball itself.
            assert_eq!(m, [0.0; 3], "inside the ball");
        }
    }
}

#[test]
fn grazing_rays_and_grazing_light() {
    for (eye, dir, light) in [
        // The eye in the ground's plane, looking along it; the light above.
        (
            Vec3::new(0.0, 0.0, 2.9),
            Vec3::NEG_Z,
            Vec3::new(0.0, 2.0, 0.0),
        ),
        // Just above the plane, looking along it; the light in the plane.
        (
            Vec3::new(0.0, 1e-6, 2.9),
            Vec3::new(0.0, -1e-7, -1.0),
            Vec3::new(0.5, 0.0, -1.0),
        ),
        // A light exactly in the plane and the eye above: every shadow ray grazes.
        (
            Vec3::new(0.0, 1.0, 2.9),
            Vec3::new(0.0, -0.5, -1.0),
            Vec3::new(0.0, 0.0, 0.0),
        ),
    ] {
        let mut g = Gltf::new();
        let m = matte(&mut g);
        let plane = ground(&mut g, 3.0, m);
        // A second plane along the view, edge-on to the camera.
        let wall = g.mesh(
            &[
                Vec3::new(0.0, 0.0, -3.0),
                Vec3::new(0.0, 0.0, 3.0),
                Vec3::new(0.0, 1.0, 3.0),
                Vec3::new(0.0, 1.0, -3.0),
            ],
            Some(&[Vec3::X; 4]),
            None,
            &[[0, 1, 2], [0, 2, 3]],
            m,
        );
        let nodes = [
            g.node(json!({"mesh": plane})),
            g.node(json!({"mesh": wall})),
            point_light(&mut g, light),
            camera(&mut g, eye, dir, json!({})),
        ];
        render(&g.load(&nodes));
    }
}

#[test]
fn degenerate_triangles_and_zero_normals() {
    let mut g = Gltf::new();
    let m = matte(&mut g);
    let plane = ground(&mut g, 3.0, m);
    let p = [
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::new(1.0, 0.5, 0.0),
        Vec3::new(0.0, 1.5, 0.0),
        Vec3::new(2.0, 0.5, 0.0), // collinear with 0 and 1
        Vec3::new(0.0, 0.5, 0.0), // coincides with 0
        Vec3::new(1.0, 1.5, 0.5),
    ];
    let tris = [
        [0, 1, 2], // a real triangle
        [0, 1, 3], // collinear: zero area
        [0, 4, 2], // two corners at one point
        [1, 1, 1], // one vertex three times
        [1, 5, 2], // a real triangle
    ];
    // Without NORMAL, the loader makes flat normals (of zero-area triangles too); with NORMAL,
    // some are zero-length and one points along the surface.
    let zero_normals = [
        Vec3::ZERO,
        Vec3::Z,
        Vec3::ZERO,
        Vec3::ZERO,
        Vec3::X,
        Vec3::ZERO,
    ];
    let flat = g.mesh(&p, None, None, &tris, m);
    let zeros = g.mesh(&p, Some(&zero_normals), None, &tris, m);
    let nodes = [
        g.node(json!({"mesh": plane})),
        g.node(json!({"mesh": flat})),
        g.node(json!({"mesh": zeros, "translation": [-1.5, 0, 0.5]})),
        // A node that scales one axis to zero: all its triangles are degenerate in the world.
        g.node(json!({"mesh": flat, "translation": [0, 0, 1], "scale": [1, 0, 1]})),
        point_light(&mut g, Vec3::new(1.5, 3.0, 1.5)),
        camera(
            &mut g,
            Vec3::new(0.0, 1.0, 4.0),
            Vec3::new(0.0, -0.2, -1.0),
            json!({"aperture_radius": 0.05, "focus_distance": 4.0}),
        ),
    ];
    let scene = g.load(&nodes);
    for mesh in &scene.meshes {
        assert!(
            mesh.normals.iter().all(|n| n.is_finite()),
            "non-finite normal"
        );
    }
    let m = render(&scene);
    assert!(m[0] > 0.0, "the lit ground is black: {m:?}");
}

/// An 8-bit texture of `w × h` texels of varying colour.
fn texture_image(w: u32, h: u32) -> Image {
    let mut im = Image::new(w, h);
    for (i, p) in im.rgba.iter_mut().enumerate() {
        let k = i as f32;
        *p = [(0.3 + 0.1 * k) % 1.0, (0.7 * k) % 1.0, 0.5, 1.0];
    }
    im
}

#[test]
fn textures_of_one_texel_and_odd_sizes() {
    // (width, height, sampler): nearest + clamp, linear + mirrored repeat, default repeat.
    let cases = [
        (
            1,
            1,
            json!({"magFilter": 9728, "wrapS": 33071, "wrapT": 33071}),
        ),
        (
            1,
            1,
            json!({"magFilter": 9729, "wrapS": 33648, "wrapT": 10497}),
        ),
        (3, 5, json!({"magFilter": 9729})),
        (
            7,
            1,
            json!({"magFilter": 9728, "wrapS": 33648, "wrapT": 33071}),
        ),
        (1, 9, json!({})),
    ];
    for (w, h, sampler) in cases {
        let mut g = Gltf::new();
        let t = g.png_texture(&texture_image(w, h), sampler);
        // Every texture slot at once, normal map included (MikkTSpace tangents are generated
        // for it from UVs that here cover several repeats).
        let mat = g.material(json!({
            "pbrMetallicRoughness": {"baseColorTexture": {"index": t},
                "metallicRoughnessTexture": {"index": t}},
            "normalTexture": {"index": t, "scale": 2.0},
            "emissiveTexture": {"index": t}, "emissiveFactor": [0.2, 0.2, 0.2],
            "occlusionTexture": {"index": t}}));
        let plane = ground(&mut g, 3.0, mat);
        let s = icosphere(1, 0);
        // The ball has UVs of huge magnitude, where f32 UV steps exceed a texel.
        let uv: Vec<Vec2> = s
            .positions
            .iter()
            .map(|p| Vec2::new(1e7 * p.x, -3e6 * p.y))
            .collect();
        let ball = g.mesh(&s.positions, Some(&s.normals), Some(&uv), &s.indices, mat);
        let nodes = [
            g.node(json!({"mesh": plane})),
            g.node(json!({"mesh": ball, "translation": [0, 0.5, 0], "scale": [0.5, 0.5, 0.5]})),
            point_light(&mut g, Vec3::new(1.5, 3.0, 1.5)),
            camera(
                &mut g,
                Vec3::new(0.0, 1.5, 4.0),
                Vec3::new(0.0, -0.3, -1.0),
                json!({}),
            ),
        ];
        let scene = g.load(&nodes);
        assert_eq!((scene.textures[0].width, scene.textures[0].height), (w, h));
        let m = render(&scene);
        assert!(m[0] > 0.0, "{w}x{h}: black");
    }
}

/// The rotation helper the other stress tests use, checked once: a quarter turn about X takes
/// −Z to +Y.
#[test]
fn quat_helper_turns_the_right_way() {
    let q = Quat::from_array(quat(Vec3::X, std::f32::consts::FRAC_PI_2));
    assert!((q * Vec3::NEG_Z - Vec3::Y).length() < 1e-6);
}

/// Each node's values are finite f32, but composed (in f64) they overflow f32: an error naming
/// the node, never an infinite instance, light or camera that would turn samples into NaN.
#[test]
fn a_hierarchy_that_overflows_float32_is_an_error_naming_the_node() {
    for (what, child) in [
        ("mesh", json!({"mesh": 0, "scale": [1e30, 1e30, 1e30]})),
        (
            "light",
            json!({"extensions": {"KHR_lights_punctual": {"light": 0}},
            "translation": [1e30, 0, 0]}),
        ),
        ("camera", json!({"camera": 0, "translation": [0, 0, 1e30]})),
    ] {
        let mut g = Gltf::new();
        let m = matte(&mut g);
        ground(&mut g, 1.0, m);
        g.light(json!({"type": "point", "intensity": 1.0}));
        g.camera(json!({"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.1}}));
        let c = g.node(child);
        let root = g.node(json!({"children": [c], "scale": [1e30, 1e30, 1e30]}));
        let bytes = g.to_bytes(&[root]);
        let e = aperture_scene::load_bytes(&bytes, std::path::Path::new("."), &Default::default())
            .expect_err(what);
        assert!(e.to_string().contains("nodes[0]"), "{what}: {e}");
    }
}
