//! The BSDFs' checks: reciprocity, energy, sampling densities against evaluation.

use super::*;
use std::f32::consts::TAU;

fn grid(n: u32) -> impl Iterator<Item = [f32; 2]> {
    (0..n * n).map(move |i| {
        [
            ((i % n) as f32 + 0.5) / n as f32,
            ((i / n) as f32 + 0.5) / n as f32,
        ]
    })
}

/// Albedo estimated by importance sampling: ∫ f cos dω ≈ mean(f cos / pdf).
fn albedo_is(b: &Bsdf, wo: Vec3) -> Vec3 {
    let mut sum = Vec3::ZERO;
    let n = 128;
    for (k, u) in grid(n).enumerate() {
        let lobe = ((k as u32).wrapping_mul(2654435761) >> 8) as f32 / (1u32 << 24) as f32;
        if let Some(s) = b.sample(wo, lobe, u) {
            sum += s.f * s.wi.z / s.pdf;
        }
    }
    sum / (n * n) as f32
}

/// The same integral by brute-force uniform hemisphere quadrature.
fn albedo_quadrature(b: &Bsdf, wo: Vec3) -> Vec3 {
    let n = 512;
    let mut sum = Vec3::ZERO;
    for u in grid(n) {
        let z = u[0];
        let r = (1.0 - z * z).sqrt();
        let phi = TAU * u[1];
        let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
        sum += b.eval(wo, wi).0 * wi.z;
    }
    sum * TAU / (n * n) as f32
}

/// A dielectric without a specular layer is Lambert: the same values, and pure cosine
/// sampling.
#[test]
fn no_specular_layer_is_lambert() {
    let base = Vec3::new(0.8, 0.5, 0.2);
    let no_spec = Dielectric {
        specular: 0.0,
        ..Dielectric::default()
    };
    let b = Bsdf::metal_rough_dielectric(base, 0.0, 0.4, &no_spec);
    assert!(
        matches!(b, Bsdf::Lambert { albedo } if albedo == base),
        "{b:?}"
    );
    // The general form with the same factors evaluates to the same value.
    let general = Bsdf::MetalRough(MetalRough {
        base,
        metallic: 0.0,
        alpha: 0.16,
        f0: Vec3::splat(0.04),
        spec_weight: 0.0,
        compensation: None,
    });
    let (wo, wi) = (
        Vec3::new(0.3, 0.1, 0.9).normalize(),
        Vec3::new(-0.5, 0.2, 0.6).normalize(),
    );
    assert!(
        (b.eval(wo, wi).0 - general.eval(wo, wi).0)
            .abs()
            .max_element()
            < 1e-6
    );
    // Any metal, or any specular weight, keeps the microfacet lobe.
    assert!(matches!(
        Bsdf::metal_rough_dielectric(base, 0.01, 0.4, &no_spec),
        Bsdf::MetalRough(_)
    ));
    assert!(matches!(
        Bsdf::metal_rough(base, 0.0, 0.4),
        Bsdf::MetalRough(_)
    ));
}

#[test]
fn lambert_white_reflects_everything() {
    let b = Bsdf::Lambert { albedo: Vec3::ONE };
    let a = albedo_is(&b, Vec3::new(0.3, 0.1, 0.9).normalize());
    assert!((a - Vec3::ONE).abs().max_element() < 1e-3, "{a}");
}

#[test]
fn sampling_agrees_with_evaluation() {
    let wo = Vec3::new(0.5, -0.2, 0.6).normalize();
    for b in [
        Bsdf::metal_rough(Vec3::new(0.8, 0.5, 0.2), 0.0, 0.5),
        Bsdf::metal_rough(Vec3::new(0.9, 0.6, 0.3), 1.0, 0.6),
        Bsdf::metal_rough(Vec3::new(0.2, 0.7, 0.4), 0.5, 0.8),
    ] {
        let is = albedo_is(&b, wo);
        let q = albedo_quadrature(&b, wo);
        assert!((is - q).abs().max_element() < 0.01, "{b:?}: {is} vs {q}");
        // Energy is not created.
        assert!(q.max_element() <= 1.0, "{q}");
    }
}

/// The density over the upper hemisphere integrates to the probability that sampling
/// succeeds (visible normals may reflect below the horizon; those samples are rejected).
#[test]
fn pdf_integrates_to_the_acceptance_rate() {
    let wo = Vec3::new(0.1, 0.4, 0.5).normalize();
    let b = Bsdf::metal_rough(Vec3::new(0.5, 0.5, 0.5), 0.3, 0.7);
    let m = 256;
    let mut accepted = 0;
    for (k, u) in grid(m).enumerate() {
        let lobe = (k % 97) as f32 / 97.0;
        accepted += usize::from(b.sample(wo, lobe, u).is_some());
    }
    let rate = accepted as f32 / (m * m) as f32;
    assert!(rate > 0.5);
    let n = 512;
    let mut sum = 0.0;
    for u in grid(n) {
        let z = u[0];
        let r = (1.0 - z * z).sqrt();
        let phi = TAU * u[1];
        sum += b.eval(wo, Vec3::new(r * phi.cos(), r * phi.sin(), z)).1;
    }
    let total = sum * TAU / (n * n) as f32;
    assert!((total - rate).abs() < 0.01, "{total} vs {rate}");
}

/// IOR and specular change only the dielectric Fresnel term: the glTF default equals
/// IOR 1.5; a higher IOR reflects more at normal incidence; specular 0 leaves pure diffuse;
/// metals ignore both.
#[test]
fn ior_and_specular_change_the_dielectric_fresnel() {
    let base = Vec3::new(0.5, 0.4, 0.3);
    let wo = Vec3::Z;
    let mirror = Vec3::new(0.01, 0.0, 1.0).normalize();
    let d = |ior, specular, specular_color| Dielectric {
        ior,
        specular,
        specular_color,
    };
    let default = Bsdf::metal_rough(base, 0.0, 0.3);
    let ior15 = Bsdf::metal_rough_dielectric(base, 0.0, 0.3, &d(1.5, 1.0, Vec3::ONE));
    assert_eq!(default, ior15);
    let ior2 = Bsdf::metal_rough_dielectric(base, 0.0, 0.3, &d(2.0, 1.0, Vec3::ONE));
    assert!(ior2.eval(wo, mirror).0.x > default.eval(wo, mirror).0.x);
    if let Bsdf::MetalRough(MetalRough { f0, .. }) = ior2 {
        assert!((f0.x - 1.0 / 9.0).abs() < 1e-6, "{f0}");
    }
    // Specular weight 0: exactly Lambert of the base colour.
    let off = Bsdf::metal_rough_dielectric(base, 0.0, 0.3, &d(1.5, 0.0, Vec3::ONE));
    let wi = Vec3::new(0.3, 0.2, 0.9).normalize();
    assert!((off.eval(wo, wi).0 - base * FRAC_1_PI).abs().max_element() < 1e-6);
    // A red specular tint reflects red more than blue in the highlight.
    let tinted = Bsdf::metal_rough_dielectric(Vec3::ZERO, 0.0, 0.3, &d(1.5, 1.0, Vec3::X));
    let f = tinted.eval(wo, mirror).0;
    assert!(f.x > 0.0 && f.x > 100.0 * f.z, "{f}");
    // Energy is still conserved for a strong, tinted layer.
    let strong =
        Bsdf::metal_rough_dielectric(Vec3::ONE, 0.0, 0.5, &d(3.0, 1.0, Vec3::new(2.0, 1.0, 0.5)));
    let q = albedo_quadrature(&strong, Vec3::new(0.4, 0.0, 0.6).normalize());
    assert!(q.max_element() <= 1.0 + 1e-3, "{q}");
    let is = albedo_is(&strong, Vec3::new(0.4, 0.0, 0.6).normalize());
    assert!((is - q).abs().max_element() < 0.01, "{is} vs {q}");
    // Metals ignore the dielectric layer.
    let metal = Bsdf::metal_rough(base, 1.0, 0.3);
    let metal2 = Bsdf::metal_rough_dielectric(base, 1.0, 0.3, &d(2.5, 0.2, Vec3::X));
    assert_eq!(metal.eval(wo, wi).0, metal2.eval(wo, wi).0);
}

/// The lobe split sums to one and agrees with the pure cases; albedos stay in [0, 1] and
/// follow the material (a white metal's glossy albedo near 1 when smooth).
#[test]
fn lobes_split_and_albedos_are_sane() {
    let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
    let wi = Vec3::new(-0.4, 0.3, 0.8).normalize();
    let lambert = Bsdf::Lambert {
        albedo: Vec3::splat(0.5),
    };
    assert_eq!(lambert.lobe_split(wo, wi), LobeSplit::DIFFUSE);
    let metal = Bsdf::metal_rough(Vec3::ONE, 1.0, 0.05);
    let s = metal.lobe_split(wo, wi);
    assert_eq!(s.diffuse, Vec3::ZERO);
    assert!(metal.albedos(wo).glossy.min_element() > 0.9);
    assert!(!metal.glossy_is_rough());
    for b in [
        Bsdf::metal_rough(Vec3::new(0.8, 0.4, 0.1), 0.0, 0.5),
        Bsdf::metal_rough(Vec3::new(0.8, 0.4, 0.1), 0.4, 0.9),
    ] {
        let s = b.lobe_split(wo, wi);
        let sum = s.diffuse + s.glossy + s.transmission;
        assert!((sum - Vec3::ONE).abs().max_element() < 1e-6, "{s:?}");
        assert!(s.diffuse.min_element() > 0.0 && s.glossy.min_element() > 0.0);
        let a = b.albedos(wo);
        let total = a.diffuse + a.glossy;
        assert!(
            total.max_element() <= 1.0 && total.min_element() > 0.0,
            "{a:?}"
        );
        assert!(b.glossy_is_rough());
    }
}

#[test]
fn frame_is_orthonormal() {
    for n in [Vec3::Z, Vec3::NEG_Z, Vec3::new(0.3, -0.8, 0.2).normalize()] {
        let f = Frame::from_normal(n);
        assert!(f.t.dot(f.b).abs() < 1e-6 && f.t.dot(n).abs() < 1e-6);
        let v = Vec3::new(0.2, 0.5, -0.7);
        assert!((f.to_world(f.to_local(v)) - v).length() < 1e-6);
    }
}
