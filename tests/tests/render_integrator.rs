//! Path tracer acceptance: white furnace, an integrating sphere (multiple bounces, NEE + MIS on
//! emissive triangles, Russian roulette), and a plane under a point light against E = I cos θ / r².

use aperture_render::{
    build_accel, render, Camera, CameraSample, Clamp, FilterKind, RenderOptions,
};
use aperture_scene::{Dof, Light, LightKind, Scene};
use aperture_shading::{test_scenes, MaterialOverride};
use glam::{Affine3A, Vec2, Vec3};

fn opts(size: u32, spp: u32) -> RenderOptions {
    RenderOptions {
        width: size,
        height: size,
        spp,
        seed: 3,
        filter: FilterKind::Box,
        ..RenderOptions::default()
    }
}

/// A diffuse white sphere in a uniform environment of radiance 1 reflects exactly 1 everywhere.
#[test]
fn white_furnace_renders_one() {
    let scene = test_scenes::furnace();
    let accel = build_accel(&scene, Default::default());
    let o = RenderOptions {
        env: aperture_shading::Environment::Constant(Vec3::ONE),
        max_bounces: 64,
        material_override: MaterialOverride::Diffuse,
        ..opts(32, 16)
    };
    let film = render(&scene, &accel, &o, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    let (mut sum, mut n) = (0.0f64, 0usize);
    for p in film.to_rgba() {
        // Pixels fully on the sphere.
        if p[3] == 1.0 {
            sum += (p[0] + p[1] + p[2]) as f64 / 3.0;
            n += 1;
        }
    }
    let mean = sum / n as f64;
    println!("furnace: mean over {n} sphere pixels = {mean:.6}");
    assert!(n > 200);
    assert!((mean - 1.0).abs() < 0.005);
    assert_eq!(film.dropped_samples(), 0);
}

/// Inside a closed sphere whose walls emit Le = 1 and reflect diffusely with albedo a = 0.5,
/// radiance is Le / (1 − a) = 2 everywhere: every bounce counts, light sampling and BSDF sampling
/// are combined by MIS, and Russian roulette must stay unbiased.
#[test]
fn integrating_sphere_renders_le_over_one_minus_albedo() {
    let (scene, o) = integrating_sphere();
    let accel = build_accel(&scene, Default::default());
    let film = render(&scene, &accel, &o, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    let px = film.to_rgba();
    let mean = px.iter().map(|p| p[1] as f64).sum::<f64>() / px.len() as f64;
    println!("integrating sphere: mean {mean:.5} (expected 2)");
    assert!((mean - 2.0).abs() < 0.02, "{mean}");
    // Direct light only: Le (seen) + a·Le (one bounce) = 1.5.
    let direct = RenderOptions {
        max_bounces: 0,
        ..o
    };
    let film = render(&scene, &accel, &direct, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    let px = film.to_rgba();
    let mean0 = px.iter().map(|p| p[1] as f64).sum::<f64>() / px.len() as f64;
    println!("integrating sphere, max bounces 0: mean {mean0:.5} (expected 1.5)");
    assert!((mean0 - 1.5).abs() < 0.015, "{mean0}");
}

/// A closed sphere of radius 3 whose walls emit Le = 1 and reflect diffusely with albedo 0.5,
/// seen from its centre, and the options its tests render it with (64 bounces: the series
/// Σ aⁿ is then complete to 5e-20).
fn integrating_sphere() -> (Scene, RenderOptions) {
    let cam =
        test_scenes::look_at_camera(Vec3::ZERO, Vec3::new(0.3, 0.1, -1.0), 1.2, Dof::default());
    let mut wall = test_scenes::matte(Vec3::splat(0.5));
    wall.emissive_factor = Vec3::ONE;
    let scene = test_scenes::scene(
        vec![(
            test_scenes::icosphere(2, 0),
            Affine3A::from_scale(Vec3::splat(3.0)),
        )],
        vec![wall],
        cam,
    );
    let opts = RenderOptions {
        max_bounces: 64,
        material_override: MaterialOverride::Diffuse,
        ..opts(24, 16)
    };
    (scene, opts)
}

/// Cycles' clamps in the integrating sphere: an indirect limit near 0 leaves only light that
/// scattered at most once (Le + a·Le = 1.5, as `max_bounces` 0 gives), a limit no sample reaches
/// changes no bit, and a direct limit caps what the walls show.
#[test]
fn clamping_cuts_only_the_light_it_is_meant_to() {
    let (scene, o) = integrating_sphere();
    let accel = build_accel(&scene, Default::default());
    let mean = |o: &RenderOptions| {
        let film = render(&scene, &accel, o, &|_, _| {}).unwrap();
        assert_eq!(film.dropped_samples(), 0);
        let px = film.to_rgba();
        px.iter().map(|p| p[1] as f64).sum::<f64>() / px.len() as f64
    };
    let clamp = |direct, indirect| RenderOptions {
        clamp: Clamp { direct, indirect },
        ..o.clone()
    };
    let unclamped = render(&scene, &accel, &o, &|_, _| {}).unwrap();
    assert_eq!(unclamped.dropped_samples(), 0);
    let loose = render(&scene, &accel, &clamp(1e9, 1e9), &|_, _| {}).unwrap();
    assert_eq!(loose.dropped_samples(), 0);
    assert_eq!(unclamped.to_rgba(), loose.to_rgba());
    // Same tolerance as the unclamped test: 1 % noise at 16 spp over 576 pixels.
    let only_direct = mean(&clamp(0.0, 1e-9));
    println!("clamp indirect ~0: mean {only_direct:.5} (expected 1.5)");
    assert!((only_direct - 1.5).abs() < 0.015, "{only_direct}");
    // The walls' own emission (R + G + B = 3 per sample) is capped at 1.5: 0.5 per channel
    // remains. Their direct lighting (mean a·Le = 0.5) loses its samples above the cap, so it
    // lies in (0, 0.5); light that scattered twice or more (mean 0.5) is untouched. Without the
    // clamp the mean is 2.
    let capped = mean(&clamp(1.5, 0.0));
    println!("clamp direct 1.5: mean {capped:.5}");
    assert!(capped < 1.5 && capped > 1.0, "{capped}");
}

/// A diffuse plane under a point light: L = albedo/π · I cos θ / r² at every pixel.
#[test]
fn point_light_on_a_plane_matches_inverse_square_cosine() {
    let intensity = 5.0;
    let scene: Scene = test_scenes::lit_plane(intensity);
    let accel = build_accel(&scene, Default::default());
    let size = 48;
    let o = RenderOptions {
        max_bounces: 0,
        material_override: MaterialOverride::Diffuse,
        ..opts(size, 16)
    };
    let film = render(&scene, &accel, &o, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    let cam = Camera::new(&scene.cameras[0], size, size);
    let light = Vec3::new(0.0, test_scenes::LIT_PLANE_LIGHT_HEIGHT, 0.0);
    let mut worst = 0.0f32;
    let mut checked = 0;
    for y in (2..size).step_by(5) {
        for x in (2..size).step_by(5) {
            let ray = cam
                .generate_ray(&CameraSample {
                    p_film: Vec2::new(x as f32 + 0.5, y as f32 + 0.5),
                    p_lens: Vec2::ZERO,
                    time: 0.0,
                })
                .unwrap();
            let t = -ray.origin.y / ray.dir.y;
            let q = ray.origin + t * ray.dir;
            let d = light - q;
            let e = intensity * (d.y / d.length()) / d.length_squared();
            let want = 0.8 / std::f32::consts::PI * e;
            let got = film.pixel(x, y)[0];
            worst = worst.max((got - want).abs() / want);
            checked += 1;
        }
    }
    println!(
        "point light: {checked} probes, worst relative error {:.4}%",
        100.0 * worst
    );
    assert!(checked > 50);
    assert!(worst < 0.01);
}

/// Directional and spot lights land where SPEC §4 says: irradiance E (W/m²) from a directional
/// light at normal incidence gives L = albedo/π · E; a spot's outer cone cuts the light off.
#[test]
fn directional_and_spot_lights() {
    let mut scene = test_scenes::lit_plane(1.0);
    scene.lights[0] = Light {
        name: None,
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(2.0),
    };
    let accel = build_accel(&scene, Default::default());
    let o = RenderOptions {
        max_bounces: 0,
        material_override: MaterialOverride::Diffuse,
        ..opts(16, 4)
    };
    let film = render(&scene, &accel, &o, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    let want = 0.8 / std::f32::consts::PI * 2.0;
    for p in film.to_rgba() {
        assert!((p[0] - want).abs() < 1e-4 * want, "{} vs {want}", p[0]);
    }
    scene.lights[0] = Light {
        name: None,
        kind: LightKind::Spot {
            inner_cone: 0.1,
            outer_cone: 0.2,
        },
        position: Vec3::new(0.0, 2.0, 1.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(5.0),
    };
    let film = render(&scene, &accel, &o, &|_, _| {}).unwrap();
    assert_eq!(film.dropped_samples(), 0);
    let px = film.to_rgba();
    let lit = px.iter().filter(|p| p[0] > 0.0).count();
    assert!(lit > 0 && lit < px.len() / 2, "{lit}");
}
