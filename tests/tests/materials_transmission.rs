//! Transmission, volumes and nested dielectrics (SPEC §5, issue 14) against closed forms:
//! - a thin-walled pane from a file that is not Blender's transmits glTF's `(1 − F) · base
//!   colour` to camera rays and to shadow rays (a straight line), within 1 %;
//! - `--transmission auto` reads Blender's exporter in `asset.generator` and then makes a
//!   closed transmissive mesh refract;
//! - slabs of glass and liquid at normal incidence transmit what the incoherent adding of their
//!   interfaces (Fresnel of each *relative* IOR, Beer–Lambert inside) predicts: a liquid
//!   overlapping its glass counts one glass–liquid interface, not two air gaps.

use aperture_render::{build_accel, render, FilterKind, RenderOptions};
use aperture_scene::{
    Camera, Dof, Light, LightKind, LoadOptions, Material, Projection, Scene, Transmission, Volume,
};
use aperture_shading::{
    test_scenes, transmissive_meshes, Convention, Environment, TransmissionModel,
};
use aperture_tests::gltf_writer::GltfWriter;
use aperture_tests::render_checked;
use glam::{Affine3A, Mat4, Quat, Vec3, Vec4};
use serde_json::json;

/// Schlick's Fresnel of glTF's default IOR 1.5.
fn schlick(cos: f32) -> f32 {
    0.04 + 0.96 * (1.0 - cos).powi(5)
}

/// The mean of every pixel of a render, per channel.
fn mean(scene: &Scene, opts: &RenderOptions) -> Vec3 {
    let film = render_checked(scene, opts);
    let px = film.to_rgba();
    px.iter().map(|p| Vec3::new(p[0], p[1], p[2])).sum::<Vec3>() / px.len() as f32
}

fn ortho(z: f32, half: f32) -> Camera {
    Camera {
        name: "ortho".into(),
        node: None,
        index: None,
        world_from_camera: Affine3A::from_translation(Vec3::new(0.0, 0.0, z)),
        projection: Projection::Orthographic {
            xmag: half,
            ymag: half,
        },
        dof: Dof::default(),
    }
}

fn opts(spp: u32) -> RenderOptions {
    RenderOptions {
        width: 24,
        height: 24,
        spp,
        max_bounces: 32,
        filter: FilterKind::Box,
        ..RenderOptions::default()
    }
}

/// A glTF file: an emissive 4 × 4 wall (radiance 1) at z = −5 facing +Z, a 20 × 20 pane at the
/// origin turned `theta` about +Y with `pane`'s material, an orthographic camera at z = 5
/// seeing 2 × 2 units. What the pane reflects towards the camera misses the wall (black).
fn pane_file(theta: f32, pane: serde_json::Value, generator: &str) -> Vec<u8> {
    let mut w = GltfWriter::new(generator, &["KHR_materials_transmission"]);
    w.materials = vec![
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]}, "emissiveFactor": [1, 1, 1]}),
        pane,
    ];
    let facing_z = Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2);
    w.mesh(
        "wall",
        &test_scenes::quad(4.0, 0),
        Mat4::from_translation(Vec3::new(0.0, 0.0, -5.0)) * facing_z,
    );
    w.mesh(
        "pane",
        &test_scenes::quad(20.0, 1),
        Mat4::from_rotation_y(theta) * facing_z,
    );
    w.cameras = vec![
        json!({"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.01, "zfar": 100}}),
    ];
    w.camera_node(0, Mat4::from_translation(Vec3::new(0.0, 0.0, 5.0)));
    w.to_bytes()
}

fn glass(base: [f32; 3]) -> serde_json::Value {
    json!({
        "pbrMetallicRoughness": {"baseColorFactor": [base[0], base[1], base[2], 1], "metallicFactor": 0, "roughnessFactor": 0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}},
    })
}

fn load(bytes: &[u8]) -> Scene {
    aperture_scene::load_bytes(bytes, std::path::Path::new("."), &LoadOptions::default())
        .expect("loads")
}

#[test]
fn thin_pane_transmits_the_gltf_formula_to_camera_rays() {
    let base = [0.9f32, 0.6, 0.3];
    for theta_deg in [0.0f32, 45.0, 70.0] {
        let theta = theta_deg.to_radians();
        let scene = load(&pane_file(theta, glass(base), "a tool that is not Blender"));
        assert_eq!(
            Convention::Auto.resolve::<TransmissionModel>(&scene).0,
            TransmissionModel::Gltf
        );
        let got = mean(&scene, &opts(256));
        let want = (1.0 - schlick(theta.cos())) * Vec3::from(base);
        let err = ((got - want) / want).abs().max_element();
        println!("pane at {theta_deg}°: {got} vs glTF {want} (relative error {err:.4})");
        assert!(err < 0.01, "pane at {theta_deg}°: {got} vs {want}");
    }
}

/// A directional light through a horizontal pane onto a white floor (direct light only): the
/// floor receives `(1 − F(cos θ)) · base colour` of what it receives without the pane.
#[test]
fn thin_pane_transmits_the_gltf_formula_to_shadow_rays() {
    let base = Vec3::new(0.8, 0.5, 0.2);
    let build = |with_pane: bool, theta: f32| {
        let floor = Material {
            specular_factor: 0.0,
            ..test_scenes::matte(Vec3::splat(0.8))
        };
        let pane = Material {
            base_color_factor: base.extend(1.0),
            metallic_factor: 0.0,
            roughness_factor: 0.0,
            transmission: Some(Transmission {
                factor: 1.0,
                texture: None,
            }),
            ..Material::default()
        };
        let camera = Camera {
            world_from_camera: Affine3A::from_rotation_translation(
                Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
                Vec3::new(0.0, 0.5, 0.0),
            ),
            ..ortho(0.0, 1.0)
        };
        let mut meshes = vec![(test_scenes::quad(40.0, 0), Affine3A::IDENTITY)];
        if with_pane {
            meshes.push((
                test_scenes::quad(400.0, 1),
                Affine3A::from_translation(Vec3::new(0.0, 1.0, 0.0)),
            ));
        }
        let mut s = test_scenes::scene(meshes, vec![floor, pane], camera);
        s.lights.push(Light {
            name: None,
            kind: LightKind::Directional,
            position: Vec3::ZERO,
            direction: Vec3::new(theta.sin(), -theta.cos(), 0.0),
            intensity: Vec3::splat(3.0),
        });
        s
    };
    for theta_deg in [0.0f32, 50.0] {
        let theta = theta_deg.to_radians();
        let o = RenderOptions {
            max_bounces: 0,
            ..opts(4)
        };
        let lit = mean(&build(true, theta), &o);
        let open = mean(&build(false, theta), &o);
        let want = (1.0 - schlick(theta.cos())) * base;
        let ratio = lit / open;
        println!("shadow rays through a pane at {theta_deg}°: {ratio} vs glTF {want}");
        assert!(
            ((ratio - want) / want).abs().max_element() < 0.01,
            "{ratio} vs {want}"
        );
    }
}

/// A glTF file with one closed transmissive sphere (no volume) written by `generator`.
fn sphere_file(generator: &str) -> Vec<u8> {
    let mut w = GltfWriter::new(generator, &["KHR_materials_transmission"]);
    w.materials = vec![
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}}),
        glass([1.0, 1.0, 1.0]),
    ];
    w.mesh(
        "ground",
        &test_scenes::quad(20.0, 0),
        Mat4::from_translation(Vec3::new(0.0, -1.0, 0.0)),
    );
    w.mesh("glass", &test_scenes::icosphere(3, 1), Mat4::IDENTITY);
    w.to_bytes()
}

#[test]
fn auto_mode_makes_blender_glass_refract() {
    let blender = load(&sphere_file("Khronos glTF Blender I/O v4.2.70"));
    let other = load(&sphere_file("three.js GLTFExporter"));
    assert_eq!(
        transmissive_meshes(&blender, Convention::Auto.resolve(&blender).0),
        (1, 0)
    );
    assert_eq!(
        transmissive_meshes(&other, Convention::Auto.resolve(&other).0),
        (0, 1)
    );
    let o = |mode| RenderOptions {
        transmission: mode,
        env: Environment::Constant(Vec3::new(0.3, 0.5, 0.8)),
        ..opts(8)
    };
    let accel = build_accel(&blender, Default::default());
    let img = |mode| {
        render(&blender, &accel, &o(mode), &|_, _| {})
            .expect("renders")
            .to_rgba()
    };
    let auto = img(Convention::Auto);
    assert_eq!(auto, img(Convention::Blender), "auto is blender here");
    assert_ne!(auto, img(Convention::Gltf), "and that refracts");
}

/// A stack of interfaces and layers at normal incidence, combined by the incoherent adding
/// method: `(R from above, T downwards, R from below, T upwards)`.
#[derive(Clone, Copy, Debug)]
struct Stack {
    rf: f64,
    tf: f64,
    rb: f64,
    tb: f64,
}

impl Stack {
    fn interface(n1: f64, n2: f64) -> Self {
        let r = ((n2 - n1) / (n2 + n1)).powi(2);
        Self {
            rf: r,
            tf: 1.0 - r,
            rb: r,
            tb: 1.0 - r,
        }
    }

    fn layer(transmittance: f64) -> Self {
        Self {
            rf: 0.0,
            tf: transmittance,
            rb: 0.0,
            tb: transmittance,
        }
    }

    fn then(self, b: Self) -> Self {
        let k = 1.0 / (1.0 - self.rb * b.rf);
        Self {
            rf: self.rf + self.tf * b.rf * self.tb * k,
            tf: self.tf * b.tf * k,
            rb: b.rb + b.tb * self.rb * b.tf * k,
            tb: b.tb * self.tb * k,
        }
    }
}

/// A glass material of IOR `ior` with attenuation `colour` at distance 1 (a volume).
fn dielectric(ior: f32, colour: f32) -> Material {
    Material {
        base_color_factor: Vec4::ONE,
        metallic_factor: 0.0,
        roughness_factor: 0.0,
        ior,
        transmission: Some(Transmission {
            factor: 1.0,
            texture: None,
        }),
        volume: Some(Volume {
            thickness_factor: 1.0,
            thickness_texture: None,
            attenuation_distance: 1.0,
            attenuation_color: Vec3::splat(colour),
        }),
        ..Material::default()
    }
}

/// An emissive wall at z = −5 behind `bodies` (meshes with transforms), seen by an
/// orthographic camera at z = 5: the image mean is the stack's transmittance.
fn through(bodies: Vec<(aperture_scene::Mesh, Affine3A)>, materials: Vec<Material>) -> f32 {
    let mut all = materials;
    all.push(test_scenes::emitter(Vec3::ONE));
    let wall = all.len() as u32 - 1;
    let mut meshes = bodies;
    meshes.push((
        test_scenes::quad(40.0, wall),
        Affine3A::from_rotation_translation(
            Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
            Vec3::new(0.0, 0.0, -5.0),
        ),
    ));
    let scene = test_scenes::scene(meshes, all, ortho(5.0, 0.5));
    mean(&scene, &opts(512)).x
}

fn slab(z0: f32, z1: f32, half: f32, material: u32) -> (aperture_scene::Mesh, Affine3A) {
    (
        test_scenes::cuboid(Vec3::new(half, half, 0.5 * (z1 - z0)), material),
        Affine3A::from_translation(Vec3::new(0.0, 0.0, 0.5 * (z0 + z1))),
    )
}

#[test]
fn a_glass_block_absorbs_by_beer_lambert() {
    // σ = −ln(0.6) per unit, 2 units of glass.
    let got = through(vec![slab(-1.0, 1.0, 10.0, 0)], vec![dielectric(1.5, 0.6)]);
    let want = Stack::interface(1.0, 1.5)
        .then(Stack::layer(0.36))
        .then(Stack::interface(1.5, 1.0))
        .tf as f32;
    println!("glass block: {got} vs {want}");
    assert!((got - want).abs() < 0.005 * want, "{got} vs {want}");
}

/// Air | glass 1.5 | liquid 1.33, overlapping the glass by 0.05 | glass | air: one interface at
/// each boundary (glass–liquid at relative IOR 1.33/1.5), liquid absorbing over its 2.05.
#[test]
fn liquid_overlapping_its_glass_is_one_interface_per_boundary() {
    let (glass, liquid) = (0u32, 1u32);
    let bodies = vec![
        slab(1.0, 2.0, 10.0, glass),
        slab(-2.0, -1.0, 10.0, glass),
        slab(-1.05, 1.05, 9.0, liquid),
    ];
    let got = through(bodies, vec![dielectric(1.5, 1.0), dielectric(1.33, 0.7)]);
    let nested = Stack::interface(1.0, 1.5)
        .then(Stack::interface(1.5, 1.33))
        .then(Stack::layer(0.7f64.powf(2.05)))
        .then(Stack::interface(1.33, 1.5))
        .then(Stack::interface(1.5, 1.0))
        .tf as f32;
    // What counting each surface against air would give: six interfaces.
    let naive = Stack::interface(1.0, 1.5)
        .then(Stack::interface(1.5, 1.0))
        .then(Stack::interface(1.0, 1.33))
        .then(Stack::layer(0.7f64.powf(2.1)))
        .then(Stack::interface(1.33, 1.0))
        .then(Stack::interface(1.0, 1.5))
        .then(Stack::interface(1.5, 1.0))
        .tf as f32;
    println!("liquid in glass: {got} vs nested {nested} (naive {naive})");
    assert!((got - nested).abs() < 0.005 * nested, "{got} vs {nested}");
    assert!((got - naive).abs() > 5.0 * 0.005 * nested);
}
