//! HDR environment images: a constant-colour image lights a white sphere exactly like the
//! constant `--env` colour, and importance sampling by luminance beats uniform sphere sampling
//! on a high-dynamic-range map (a small sun over a dim sky), at equal samples per pixel.

use aperture_render::{Film, FilterKind, RenderOptions};
use aperture_shading::{test_scenes, EnvImage, EnvSampling, Environment, MaterialOverride};
use glam::Vec3;
use std::sync::Arc;

fn opts(size: u32, spp: u32, env: Environment, max_bounces: u32) -> RenderOptions {
    RenderOptions {
        width: size,
        height: size,
        spp,
        seed: 5,
        filter: FilterKind::Box,
        max_bounces,
        env,
        material_override: MaterialOverride::Diffuse,
        ..RenderOptions::default()
    }
}

fn image(
    w: u32,
    h: u32,
    f: impl Fn(u32, u32) -> Vec3,
    rotation: f32,
    sampling: EnvSampling,
) -> Environment {
    Environment::Image(Arc::new(EnvImage {
        width: w,
        height: h,
        texels: (0..w * h).map(|i| f(i % w, i / w)).collect(),
        rotation,
        strength: 1.0,
        sampling,
    }))
}

fn render_furnace(o: &RenderOptions) -> Film {
    aperture_tests::render_checked(&test_scenes::furnace(), o)
}

#[test]
fn constant_hdr_image_matches_the_constant_colour() {
    let c = Vec3::new(0.5, 0.7, 0.9);
    let constant = render_furnace(&opts(24, 16, Environment::Constant(c), 8));
    let hdr = render_furnace(&opts(
        24,
        16,
        image(16, 8, |_, _| c, 0.4, EnvSampling::Importance),
        8,
    ));
    let (a, b) = (constant.to_rgba(), hdr.to_rgba());
    let (mut sum_a, mut sum_b) = (Vec3::ZERO, Vec3::ZERO);
    for (p, q) in a.iter().zip(&b) {
        assert_eq!(p[3], q[3], "coverage differs");
        sum_a += Vec3::new(p[0], p[1], p[2]);
        sum_b += Vec3::new(q[0], q[1], q[2]);
    }
    let n = a.len() as f32;
    let (ma, mb) = (sum_a / n, sum_b / n);
    let e = rmse(&constant, &hdr);
    println!("constant {ma} vs image {mb}, per-pixel RMSE {e:.4}");
    // A white furnace: every pixel (sphere or sky) is the environment colour.
    assert!(
        (mb - c).abs().max_element() < 0.01 * c.max_element(),
        "{mb} vs {c}"
    );
    assert!((ma - mb).abs().max_element() < 0.01, "{ma} vs {mb}");
    // Only sampling noise separates the two images.
    assert!(e < 0.04, "{e}");
}

fn rmse(a: &Film, b: &Film) -> f64 {
    let (a, b) = (a.to_rgba(), b.to_rgba());
    let se: f64 = a
        .iter()
        .zip(&b)
        .map(|(p, q)| (0..3).map(|k| ((p[k] - q[k]) as f64).powi(2)).sum::<f64>())
        .sum();
    (se / (3 * a.len()) as f64).sqrt()
}

#[test]
fn importance_sampling_lowers_rmse_against_uniform_sampling() {
    // A 64 × 32 map: a dim blue sky and a 2 × 2-texel sun of 2 000, 30° above the horizon
    // towards +Z, behind the camera, so the sphere's visible side is sunlit.
    let map = |sampling| {
        image(
            64,
            32,
            |x, y| {
                if (47..49).contains(&x) && (10..12).contains(&y) {
                    Vec3::new(2000.0, 1800.0, 1500.0)
                } else {
                    Vec3::new(0.05, 0.08, 0.15)
                }
            },
            0.0,
            sampling,
        )
    };
    let reference = render_furnace(&opts(16, 1024, map(EnvSampling::Importance), 0));
    let is = render_furnace(&opts(16, 8, map(EnvSampling::Importance), 0));
    let uniform = render_furnace(&opts(16, 8, map(EnvSampling::Uniform), 0));
    // The uniform estimator converges to the same image (a check that both are unbiased).
    let uniform_ref = render_furnace(&opts(16, 1024, map(EnvSampling::Uniform), 0));
    let (e_is, e_uni) = (rmse(&is, &reference), rmse(&uniform, &reference));
    let mean =
        |f: &Film| f.to_rgba().iter().map(|p| p[0] as f64).sum::<f64>() / f.to_rgba().len() as f64;
    let (m_ref, m_uni) = (mean(&reference), mean(&uniform_ref));
    println!(
        "8 spp RMSE: importance {e_is:.4}, uniform {e_uni:.4}; 1024-spp means {m_ref:.4} vs {m_uni:.4}"
    );
    assert!(e_is < 0.5 * e_uni, "importance {e_is} vs uniform {e_uni}");
    assert!((m_ref - m_uni).abs() < 0.05 * m_ref, "{m_ref} vs {m_uni}");
}
