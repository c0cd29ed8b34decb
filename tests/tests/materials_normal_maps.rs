//! Normal maps end to end: the tangent frame from MikkTSpace (no `TANGENT` given) follows glTF's
//! convention (+X of the map along +u, +Y up the image), and a mapped normal facing away from the
//! viewer never gives black or NaN pixels.

use aperture_render::{build_accel, render, FilterKind, RenderOptions};
use aperture_scene::{
    Camera, ColorSpace, Dof, Filter, Light, LightKind, Material, Projection, Sampler, Scene,
    Texels, Texture, TextureRef, Wrap,
};
use aperture_shading::test_scenes;
use glam::{Affine3A, Vec3};

/// A constant normal map: one texel holding `n` (tangent space) encoded as glTF stores it.
fn normal_map(n: Vec3) -> Texture {
    let n = n.normalize();
    let enc = (n * 0.5 + Vec3::splat(0.5)) * 255.0;
    Texture {
        name: Some("normal".into()),
        width: 1,
        height: 1,
        texels: Texels::Rgba8(vec![[
            enc.x.round() as u8,
            enc.y.round() as u8,
            enc.z.round() as u8,
            255,
        ]]),
        color_space: ColorSpace::Linear,
        sampler: Sampler {
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
            mag_filter: Filter::Nearest,
        },
    }
}

/// A white dielectric unit quad at the origin facing +Z, uv (0,0) at its top-left (so +u is
/// world +X and "up the image" is world +Y), with a normal map holding `n`, no `TANGENT`, under a
/// directional light arriving from `to_light`, seen by `camera`.
fn mapped_quad(n: Option<Vec3>, to_light: Vec3, camera: Camera) -> Scene {
    let material = Material {
        metallic_factor: 0.0,
        roughness_factor: 1.0,
        normal_texture: n.map(|_| TextureRef {
            texture: 0,
            tex_coord: 0,
            transform: None,
        }),
        ..Material::default()
    };
    let mut s = test_scenes::scene(
        vec![(
            test_scenes::quad(1.0, 0),
            Affine3A::from_rotation_x(std::f32::consts::FRAC_PI_2),
        )],
        vec![material],
        camera,
    );
    if let Some(n) = n {
        s.textures.push(normal_map(n));
    }
    s.lights.push(Light {
        name: None,
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: -to_light.normalize(),
        intensity: Vec3::splat(2.0),
    });
    // What the loader does for a file without TANGENT.
    aperture_scene::generate_missing_tangents(&mut s);
    s
}

fn front_camera() -> Camera {
    Camera {
        name: "ortho".into(),
        node: None,
        index: None,
        world_from_camera: Affine3A::from_translation(Vec3::new(0.0, 0.0, 5.0)),
        projection: Projection::Orthographic {
            xmag: 0.5,
            ymag: 0.5,
        },
        dof: Dof::default(),
    }
}

fn opts() -> RenderOptions {
    RenderOptions {
        width: 8,
        height: 8,
        spp: 4,
        filter: FilterKind::Box,
        max_bounces: 0,
        ..RenderOptions::default()
    }
}

/// Mean red of the centre 4 × 4 pixels.
fn centre(scene: &Scene, opts: &RenderOptions) -> f32 {
    let film = aperture_tests::render_checked(scene, opts);
    let mut sum = 0.0;
    for y in 2..6 {
        for x in 2..6 {
            sum += film.pixel(x, y)[0];
        }
    }
    sum / 16.0
}

#[test]
fn mapped_normals_tilt_along_tangent_and_bitangent() {
    let tilt = 0.6;
    // Light from +X: the map tilted towards +X (its +X channel) is brighter than towards −X.
    let light_x = Vec3::new(1.0, 0.0, 0.5);
    let towards = centre(
        &mapped_quad(Some(Vec3::new(tilt, 0.0, 1.0)), light_x, front_camera()),
        &opts(),
    );
    let away = centre(
        &mapped_quad(Some(Vec3::new(-tilt, 0.0, 1.0)), light_x, front_camera()),
        &opts(),
    );
    assert!(towards > 1.3 * away, "+X {towards} vs −X {away}");
    // Light from up the image (+Y): the map's +Y channel points there.
    let light_y = Vec3::new(0.0, 1.0, 0.5);
    let up = centre(
        &mapped_quad(Some(Vec3::new(0.0, tilt, 1.0)), light_y, front_camera()),
        &opts(),
    );
    let down = centre(
        &mapped_quad(Some(Vec3::new(0.0, -tilt, 1.0)), light_y, front_camera()),
        &opts(),
    );
    assert!(up > 1.3 * down, "+Y {up} vs −Y {down}");
    // A flat map (0.5, 0.5, 1) shades like no map at all.
    let flat = centre(
        &mapped_quad(Some(Vec3::Z), light_x, front_camera()),
        &opts(),
    );
    let none = centre(&mapped_quad(None, light_x, front_camera()), &opts());
    assert!(
        (flat - none).abs() < 0.02 * none,
        "flat {flat} vs none {none}"
    );
}

#[test]
fn normals_facing_away_from_the_viewer_are_never_black_or_nan() {
    // Seen at a grazing angle from +X, with the mapped normal leaning hard towards −X: the
    // shading normal points away from the viewer.
    let camera =
        test_scenes::look_at_camera(Vec3::new(4.0, 0.0, 0.6), Vec3::ZERO, 0.15, Dof::default());
    let scene = mapped_quad(
        Some(Vec3::new(-1.0, 0.0, 0.15)),
        Vec3::new(0.3, 0.0, 1.0),
        camera,
    );
    let o = RenderOptions {
        width: 16,
        height: 16,
        spp: 8,
        max_bounces: 2,
        env: aperture_shading::Environment::Constant(Vec3::ONE),
        ..RenderOptions::default()
    };
    let accel = build_accel(&scene, Default::default());
    let film = render(&scene, &accel, &o, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    let mut covered = 0;
    for y in 0..16 {
        for x in 0..16 {
            let p = film.pixel(x, y);
            assert!(p.iter().all(|c| c.is_finite()), "({x}, {y}): {p:?}");
            if p[3] == 1.0 {
                covered += 1;
                // Lit by a white sky of radiance 1 and a light: a white surface is far from black.
                assert!(p[0] > 0.05, "black pixel at ({x}, {y}): {p:?}");
            }
        }
    }
    assert!(covered > 20, "the quad covers only {covered} pixels");
}
