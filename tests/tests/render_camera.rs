//! Thin-lens acceptance: bokeh size and shape against SPEC §2, the pinhole limit, and Sobol's
//! advantage over independent samples on a depth-of-field scene.

use aperture_render::{Camera, Film, FilterKind, RenderOptions, SamplerKind};
use aperture_scene::{Dof, Scene};
use aperture_shading::test_scenes;

const SIZE: u32 = 64;
/// tan(yfov/2) = 0.5.
fn yfov() -> f32 {
    2.0 * 0.5f32.atan()
}

fn render_scene(scene: &Scene, spp: u32, sampler: SamplerKind, seed: u32) -> Film {
    let opts = RenderOptions {
        width: SIZE,
        height: SIZE,
        spp,
        seed,
        max_bounces: 0,
        filter: FilterKind::Box,
        sampler,
        ..RenderOptions::default()
    };
    aperture_tests::render_checked(scene, &opts)
}

/// Energy-weighted moments of the red channel about its centroid: (total, E[r²], the 6th
/// angular harmonic of r⁴, i.e. Σ v r⁴ cos 6φ / Σ v r⁴), positions at pixel centres with +y up.
fn moments(film: &Film) -> (f64, f64, f64) {
    let mut total = 0.0;
    let (mut cx, mut cy) = (0.0, 0.0);
    for y in 0..film.height() {
        for x in 0..film.width() {
            let v = film.pixel(x, y)[0] as f64;
            total += v;
            cx += v * (x as f64 + 0.5);
            cy += v * (y as f64 + 0.5);
        }
    }
    cx /= total;
    cy /= total;
    let (mut m2, mut m4, mut h6) = (0.0, 0.0, 0.0);
    for y in 0..film.height() {
        for x in 0..film.width() {
            let v = film.pixel(x, y)[0] as f64;
            let dx = x as f64 + 0.5 - cx;
            let dy = -(y as f64 + 0.5 - cy);
            let r2 = dx * dx + dy * dy;
            m2 += v * r2;
            m4 += v * r2 * r2;
            h6 += v * r2 * r2 * (6.0 * dy.atan2(dx)).cos();
        }
    }
    (total, m2 / total, h6 / m4)
}

struct Bokeh {
    /// Side of the emitter's pinhole image, pixels.
    emitter_px: f64,
    /// SPEC §2's circle of confusion, pixels.
    coc_formula: f64,
    film: Film,
}

fn bokeh(blades: u32, rotation: f32, spp: u32) -> Bokeh {
    let (f, z, radius, size) = (2.0f32, 4.0f32, 0.75f32, 0.25f32);
    let dof = Dof {
        enabled: true,
        aperture_radius: radius,
        focus_distance: f,
        blades,
        rotation,
        ..Dof::default()
    };
    let scene = test_scenes::bokeh(size, z, yfov(), dof, 50.0);
    let cam = Camera::new(&scene.cameras[0], SIZE, SIZE);
    let coc_formula = cam.coc_pixels(z) as f64;
    let formula_by_hand = radius * (1.0 / f - 1.0 / z) * SIZE as f32 / 0.5;
    assert!((coc_formula as f32 - formula_by_hand).abs() < 1e-3);
    let emitter_px = (size * SIZE as f32 / (2.0 * z * 0.5)) as f64;
    Bokeh {
        emitter_px,
        coc_formula,
        film: render_scene(&scene, spp, SamplerKind::Sobol, 7),
    }
}

/// The disc's diameter from its second moment: a uniform disc of diameter c has E[r²] = c²/8;
/// the emitter's square image (side w) adds w²/6 and sampling at pixel centres removes 1/6.
#[test]
fn defocused_point_renders_as_a_disc_of_the_coc_diameter() {
    let b = bokeh(0, 0.0, 256);
    let (total, m2, h6) = moments(&b.film);
    assert!(total > 0.0);
    let c = (8.0 * (m2 + 1.0 / 6.0 - b.emitter_px * b.emitter_px / 6.0)).sqrt();
    let err = (c - b.coc_formula).abs() / b.coc_formula;
    println!(
        "disc: measured {c:.3} px, formula {:.3} px, error {:.2}%, hexagonal harmonic {h6:.4}",
        b.coc_formula,
        100.0 * err
    );
    assert!(err < 0.05);
    // Round: no six-fold structure.
    assert!(h6.abs() < 0.02, "{h6}");
    // A pinhole renders the same emitter far smaller.
    let mut scene = test_scenes::bokeh(0.25, 4.0, yfov(), Dof::default(), 50.0);
    scene.cameras[0].dof.focus_distance = 2.0;
    let (_, m2_pin, _) = moments(&render_scene(&scene, 16, SamplerKind::Sobol, 7));
    assert!(m2_pin < 0.1 * m2, "{m2_pin} vs {m2}");
}

/// Six blades: the bokeh is a hexagon inscribed in the CoC circle. Its second moment is
/// (5/12)·(c/2)², and its six-fold harmonic has the sign of the corners' orientation: corners
/// at rotation + π/6 + kπ/3 (rotation 0: a corner points up, cos 6φ = −1 there).
#[test]
fn six_blades_render_a_hexagon() {
    let b = bokeh(6, 0.0, 256);
    let (_, m2, h6) = moments(&b.film);
    let m2_shape = m2 + 1.0 / 6.0 - b.emitter_px * b.emitter_px / 6.0;
    let c = 2.0 * (m2_shape * 12.0 / 5.0).sqrt();
    let err = (c - b.coc_formula).abs() / b.coc_formula;
    // As a disc the same moment would give a diameter 9% short of the circle.
    let as_disc = (8.0 * m2_shape).sqrt();
    println!(
        "hexagon: circumscribed diameter {c:.3} px vs formula {:.3} px ({:.2}%), as-disc {as_disc:.3}, harmonic {h6:.4}",
        b.coc_formula,
        100.0 * err
    );
    assert!(err < 0.05);
    assert!((as_disc - b.coc_formula).abs() / b.coc_formula > 0.07);
    assert!(h6 < -0.05, "corners up: {h6}");
    // Rotated by 30°, corners point sideways (cos 6φ = +1 at φ = 0).
    let r = bokeh(6, std::f32::consts::FRAC_PI_6, 256);
    let (_, _, h6r) = moments(&r.film);
    println!("hexagon rotated 30°: harmonic {h6r:.4}");
    assert!(h6r > 0.05, "corners sideways: {h6r}");
}

/// Σ v r³ cos 3φ / Σ v r³ about the centroid: the sign says where a triangle's corners point.
fn third_harmonic(film: &Film) -> f64 {
    let (mut total, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for y in 0..film.height() {
        for x in 0..film.width() {
            let v = film.pixel(x, y)[0] as f64;
            total += v;
            cx += v * (x as f64 + 0.5);
            cy += v * (y as f64 + 0.5);
        }
    }
    let (cx, cy) = (cx / total, cy / total);
    let (mut m3, mut h3) = (0.0, 0.0);
    for y in 0..film.height() {
        for x in 0..film.width() {
            let v = film.pixel(x, y)[0] as f64;
            let (dx, dy) = (x as f64 + 0.5 - cx, -(y as f64 + 0.5 - cy));
            let r3 = (dx * dx + dy * dy).powf(1.5);
            m3 += v * r3;
            h3 += v * r3 * (3.0 * dy.atan2(dx)).cos();
        }
    }
    h3 / m3
}

/// SPEC §2: behind the focal plane a bokeh shows the aperture's orientation, in front of it the
/// shape is point-reflected. Three blades at rotation 0 have corners at 60°, 180° and 300°
/// (cos 3φ = −1 there); reflected, at 240°, 0° and 120° (cos 3φ = +1).
#[test]
fn bokeh_is_point_reflected_in_front_of_the_focal_plane() {
    let dof = Dof {
        enabled: true,
        aperture_radius: 0.75,
        focus_distance: 2.0,
        blades: 3,
        ..Dof::default()
    };
    let behind = test_scenes::bokeh(0.25, 4.0, yfov(), dof.clone(), 50.0);
    let in_front = test_scenes::bokeh(0.1, 1.5, yfov(), dof, 50.0);
    let h_behind = third_harmonic(&render_scene(&behind, 64, SamplerKind::Sobol, 3));
    let h_front = third_harmonic(&render_scene(&in_front, 64, SamplerKind::Sobol, 3));
    println!("triangle bokeh: behind {h_behind:.3}, in front {h_front:.3}");
    assert!(h_behind < -0.1, "{h_behind}");
    assert!(h_front > 0.1, "{h_front}");
}

/// `R = 0` with depth of field "on" is the pinhole, bit for bit.
#[test]
fn zero_radius_is_bit_identical_to_the_pinhole() {
    let on = Dof {
        enabled: true,
        aperture_radius: 0.0,
        focus_distance: 2.0,
        blades: 6,
        ..Dof::default()
    };
    let off = Dof {
        enabled: false,
        aperture_radius: 0.4,
        focus_distance: 2.0,
        ..Dof::default()
    };
    let a = render_scene(
        &test_scenes::bokeh(1.0, 4.0, yfov(), on, 3.0),
        4,
        SamplerKind::Sobol,
        1,
    );
    let b = render_scene(
        &test_scenes::bokeh(1.0, 4.0, yfov(), off, 3.0),
        4,
        SamplerKind::Sobol,
        1,
    );
    assert!(a.to_rgba().iter().any(|p| p[0] > 0.0));
    assert_eq!(a, b);
}

fn rmse(a: &Film, b: &Film) -> f64 {
    let (a, b) = (a.to_rgba(), b.to_rgba());
    let s: f64 = a
        .iter()
        .zip(&b)
        .map(|(p, q)| (p[0] as f64 - q[0] as f64).powi(2))
        .sum();
    (s / a.len() as f64).sqrt()
}

/// At equal spp, the Owen-scrambled Sobol points give a lower error than independent ones on a
/// depth-of-field scene (a defocused square: pixel and lens dimensions both matter).
#[test]
fn sobol_beats_random_on_a_dof_scene() {
    let dof = Dof {
        enabled: true,
        aperture_radius: 0.3,
        focus_distance: 2.0,
        ..Dof::default()
    };
    let scene = test_scenes::bokeh(1.2, 4.0, yfov(), dof, 1.0);
    let reference = render_scene(&scene, 1024, SamplerKind::Sobol, 99);
    let mut ratio_sum = 0.0;
    for seed in 0..2 {
        let sobol = rmse(
            &render_scene(&scene, 16, SamplerKind::Sobol, seed),
            &reference,
        );
        let random = rmse(
            &render_scene(&scene, 16, SamplerKind::Random, seed),
            &reference,
        );
        println!("seed {seed}: RMSE Sobol {sobol:.5}, random {random:.5}");
        assert!(sobol < random);
        ratio_sum += sobol / random;
    }
    assert!(ratio_sum / 2.0 < 0.8, "{}", ratio_sum / 2.0);
}
