//! An emissive rectangle over a diffuse plane against the closed-form form factor.

use aperture_render::{Camera, RenderOptions};
use aperture_scene::{Dof, Scene};
use aperture_shading::{test_scenes, MaterialOverride};
use glam::{Affine3A, Vec3};
use std::f64::consts::PI;

use aperture_tests::render_checked;

use crate::{hit_ground, opts, subpixel_rays};

/// Form factor from a differential area to a parallel rectangle `[0, a] × [0, b]` at height
/// `h` with one corner straight above it (Howell's catalogue of configuration factors, B-3):
/// F = 1/2π [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))], X = a/h, Y = b/h.
/// Signed in `a` and `b`, so rectangles not above the point are sums and differences of four.
fn corner_form_factor(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a.abs() / h, b.abs() / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    a.signum() * b.signum() * (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

/// Form factor from a differential area at `(px, 0, pz)` facing +Y to the rectangle
/// `[x0, x1] × [z0, z1]` at height `h` (superposition of four corner rectangles).
fn rect_form_factor(px: f64, pz: f64, [x0, x1, z0, z1]: [f64; 4], h: f64) -> f64 {
    let g = |x: f64, z: f64| corner_form_factor(x - px, z - pz, h);
    g(x1, z1) - g(x0, z1) - g(x1, z0) + g(x0, z0)
}

/// The test's scene: the plane of `albedo` at y = 0 and the emitter of `radiance` at height `h`.
fn rect_scene(albedo: f64, radiance: f32, h: f64) -> Scene {
    let cam = test_scenes::look_at_camera(
        Vec3::new(0.0, 3.5, 4.0),
        Vec3::new(0.0, 0.0, 0.3),
        0.9,
        Dof::default(),
    );
    test_scenes::scene(
        vec![
            (test_scenes::quad(40.0, 0), Affine3A::IDENTITY),
            (
                test_scenes::quad(1.0, 1),
                Affine3A::from_translation(Vec3::new(0.0, h as f32, 0.0))
                    * Affine3A::from_scale(Vec3::new(1.2, 1.0, 0.8)),
            ),
        ],
        vec![
            test_scenes::matte(Vec3::splat(albedo as f32)),
            test_scenes::emitter(Vec3::splat(radiance)),
        ],
        cam,
    )
}

/// A 40 × 40 diffuse plane (albedo 0.8) at y = 0 under an emissive 1.2 × 0.8 rectangle of
/// radiance `L` at height `h`, facing down (it emits on both sides; only one faces the plane).
/// With `max_bounces` 0 only direct light counts, so the plane's radiance is
/// albedo/π · E = albedo · L · F, F the form factor above. Probes: every pixel whose area
/// sees only the plane (the emitter hides part of it).
#[test]
fn emissive_rectangle_over_a_plane_matches_the_form_factor() {
    let (albedo, radiance, h) = (0.8f64, 3.0f32, 0.7f64);
    let rect = [-0.6, 0.6, -0.4, 0.4];
    let scene = rect_scene(albedo, radiance, h);
    let size = 32;
    let o = RenderOptions {
        material_override: MaterialOverride::Diffuse,
        ..opts(size, 256, 0)
    };
    let film = render_checked(&scene, &o);
    let cam = Camera::new(&scene.cameras[0], size, size);
    // The prediction per pixel; `None` where part of the pixel shows the emitter or no plane.
    let predict = |x: u32, y: u32| -> Option<f64> {
        let rays = subpixel_rays(&cam, x, y, 4);
        let mut want = 0.0;
        for &(o, d) in &rays {
            let t = (h - o.y) / d.y;
            let e = o + t * d;
            let (ex, ez) = (rect[0]..=rect[1], rect[2]..=rect[3]);
            if t > 0.0 && ex.contains(&e.x) && ez.contains(&e.z) {
                return None;
            }
            let q = hit_ground(o, d)?;
            if q.x.abs() >= 20.0 || q.z.abs() >= 20.0 {
                return None;
            }
            want += albedo * radiance as f64 * rect_form_factor(q.x, q.z, rect, h);
        }
        Some(want / rays.len() as f64)
    };
    let predicted: Vec<Option<f64>> = (0..size * size)
        .map(|i| predict(i % size, i / size))
        .collect();
    let (mut sum_got, mut sum_want) = (0.0f64, 0.0f64);
    let (mut worst, mut sq) = (0.0f64, 0.0f64);
    let mut n = 0usize;
    let mut peak = 0.0f64;
    for y in 0..size {
        for x in 0..size {
            // Sub-pixel positions can miss a sliver of the emitter's silhouette: a probe's
            // neighbours must see only the plane too.
            let clear = (y.saturating_sub(1)..(y + 2).min(size)).all(|ny| {
                (x.saturating_sub(1)..(x + 2).min(size))
                    .all(|nx| predicted[(ny * size + nx) as usize].is_some())
            });
            let Some(want) = predicted[(y * size + x) as usize].filter(|_| clear) else {
                continue;
            };
            let got = film.pixel(x, y)[0] as f64;
            let rel = (got - want) / want;
            worst = worst.max(rel.abs());
            sq += rel * rel;
            sum_got += got;
            sum_want += want;
            peak = peak.max(want);
            n += 1;
        }
    }
    let bias = sum_got / sum_want - 1.0;
    let rms = (sq / n as f64).sqrt();
    println!(
        "emissive rectangle: {n} probe pixels (peak {peak:.4}), mean ratio − 1 = {bias:+.5}, \
         per-pixel relative error rms {rms:.4}, worst {worst:.4}"
    );
    assert!(n > 500, "{n}");
    // Tolerances. The mean over all probes averages ~250 000 samples: its noise is well below
    // 0.1%, so 0.3% bounds a bias. Per pixel, 256 light samples (MIS with BSDF samples) leave
    // ~0.4% rms noise (measured), 2% in the worst of ~950 pixels.
    assert!(bias.abs() < 0.003, "{bias}");
    assert!(worst < 0.05, "{worst}");
}
