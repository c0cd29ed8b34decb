//! Fresnel reflectance: Schlick's approximation (glTF), the exact dielectric equations (for
//! refraction), refraction directions, and the thin-film interference of
//! `KHR_materials_iridescence` (Belcour & Barla 2017, as the extension's implementation notes
//! write it).

use crate::spectrum::XYZ_TO_REC709;
use glam::Vec3;
use std::f32::consts::PI;

/// Schlick's weight `(1 − cos)⁵`.
pub fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Schlick's Fresnel with reflectance `f0` at normal incidence.
pub fn schlick(f0: Vec3, cos: f32) -> Vec3 {
    f0 + (Vec3::ONE - f0) * schlick_weight(cos)
}

/// Reflectance at normal incidence of an interface of relative IOR `eta`.
pub fn f0_from_eta(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// Unpolarised Fresnel reflectance of a dielectric interface for incident cosine `cos_i`
/// (measured on the incident side, `0 ≤ cos_i ≤ 1`) and relative IOR `eta` = n(transmitted
/// side) / n(incident side); 1 under total internal reflection.
pub fn dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

/// The direction `wi` (unit, `wi·m > 0`) refracts into through a facet of normal `m` with
/// relative IOR `eta` (far side over `wi`'s side); `None` under total internal reflection.
pub fn refract(wi: Vec3, m: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = wi.dot(m);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-wi / eta + (cos_i / eta - cos_t) * m)
}

/// The spectral sensitivity of the thin-film phase term, integrated against the colour
/// matching functions in Fourier space (the extension's `evalSensitivity`).
fn sensitivity(opd: f32, shift: Vec3) -> Vec3 {
    let phase = 2.0 * PI * opd * 1.0e-9;
    let val = Vec3::new(5.4856e-13, 4.4201e-13, 5.2481e-13);
    let pos = Vec3::new(1.6810e+06, 1.7953e+06, 2.2084e+06);
    let var = Vec3::new(4.3278e+09, 9.3046e+09, 6.6121e+09);
    let cos = |v: Vec3| Vec3::new(v.x.cos(), v.y.cos(), v.z.cos());
    let exp = |v: Vec3| Vec3::new(v.x.exp(), v.y.exp(), v.z.exp());
    let sqrt = |v: Vec3| Vec3::new(v.x.sqrt(), v.y.sqrt(), v.z.sqrt());
    let mut xyz =
        val * sqrt(2.0 * PI * var) * cos(pos * phase + shift) * exp(-(phase * phase) * var);
    xyz.x += 9.7470e-14
        * (2.0 * PI * 4.5282e+09f32).sqrt()
        * (2.2399e+06 * phase + shift.x).cos()
        * (-4.5282e+09 * phase * phase).exp();
    XYZ_TO_REC709 * (xyz / 1.0685e-7)
}

/// Thin-film Fresnel (`F_iridescence`) for cosine `cos1` on the film, a film of IOR `film_ior`
/// and `thickness_nm` between a medium of IOR `outside_ior` and a base of reflectance
/// `base_f0`. A film of zero thickness is no film: the base's Schlick Fresnel.
pub fn iridescence(
    outside_ior: f32,
    film_ior: f32,
    cos1: f32,
    thickness_nm: f32,
    base_f0: Vec3,
) -> Vec3 {
    let cos1 = cos1.clamp(0.0, 1.0);
    if thickness_nm <= 0.0 {
        return schlick(base_f0, cos1);
    }
    // Fade the film's IOR to the outside's as it gets thin (the sample viewer's smoothstep):
    // a vanishing film must not keep a Fresnel of its own.
    let t = (thickness_nm / 30.0).clamp(0.0, 1.0);
    let film = outside_ior + (film_ior - outside_ior) * (t * t * (3.0 - 2.0 * t));
    let sin2_t2 = (outside_ior / film).powi(2) * (1.0 - cos1 * cos1);
    if sin2_t2 > 1.0 {
        return Vec3::ONE;
    }
    let cos2 = (1.0 - sin2_t2).sqrt();
    // First interface.
    let r0 = ((film - outside_ior) / (film + outside_ior)).powi(2);
    let r12 = r0 + (1.0 - r0) * schlick_weight(cos1);
    let t121 = 1.0 - r12;
    let phi12 = if film < outside_ior { PI } else { 0.0 };
    let phi21 = PI - phi12;
    // Second interface.
    let sq = (base_f0 + Vec3::splat(1e-4)).clamp(Vec3::ZERO, Vec3::splat(0.9999));
    let sq = Vec3::new(sq.x.sqrt(), sq.y.sqrt(), sq.z.sqrt());
    let base_ior = (Vec3::ONE + sq) / (Vec3::ONE - sq);
    let r1 = ((base_ior - Vec3::splat(film)) / (base_ior + Vec3::splat(film))).powf(2.0);
    let r23 = r1 + (Vec3::ONE - r1) * schlick_weight(cos2);
    let phi23 = Vec3::new(
        if base_ior.x < film { PI } else { 0.0 },
        if base_ior.y < film { PI } else { 0.0 },
        if base_ior.z < film { PI } else { 0.0 },
    );
    let opd = 2.0 * film * thickness_nm * cos2;
    let phi = Vec3::splat(phi21) + phi23;
    let r123 = (r12 * r23).clamp(Vec3::splat(1e-5), Vec3::splat(0.9999));
    let r123s = Vec3::new(r123.x.sqrt(), r123.y.sqrt(), r123.z.sqrt());
    let rs = t121 * t121 * r23 / (Vec3::ONE - r123);
    let mut i = Vec3::splat(r12) + rs;
    let mut cm = rs - Vec3::splat(t121);
    for m in 1..=2 {
        cm *= r123s;
        let sm = 2.0 * sensitivity(m as f32 * opd, m as f32 * phi);
        i += cm * sm;
    }
    i.max(Vec3::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_fresnel_known_values() {
        // Normal incidence: ((η − 1)/(η + 1))².
        assert!((dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((dielectric(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
        // Grazing: everything reflects.
        assert!((dielectric(0.0, 1.5) - 1.0).abs() < 1e-6);
        // Total internal reflection beyond the critical angle (sin θc = 1/1.5).
        let cos_c = (1.0f32 - 1.0 / 2.25).sqrt();
        assert_eq!(dielectric(cos_c - 0.01, 1.0 / 1.5), 1.0);
        assert!(dielectric(cos_c + 0.01, 1.0 / 1.5) < 1.0);
        // Brewster's angle: tan θB = η, the parallel part vanishes.
        let theta_b = 1.5f32.atan();
        let r = dielectric(theta_b.cos(), 1.5);
        let cos_t = (1.0 - theta_b.sin().powi(2) / 2.25).sqrt();
        let r_perp = (theta_b.cos() - 1.5 * cos_t) / (theta_b.cos() + 1.5 * cos_t);
        assert!((r - 0.5 * r_perp * r_perp).abs() < 1e-6);
    }

    #[test]
    fn refraction_obeys_snell() {
        let wi = Vec3::new(0.6, 0.0, 0.8);
        let t = refract(wi, Vec3::Z, 1.5).unwrap();
        assert!((t.length() - 1.0).abs() < 1e-6 && t.z < 0.0);
        assert!((0.6 - 1.5 * t.x.abs()).abs() < 1e-6, "{t}");
        // Leaving a denser medium at a steep angle: total internal reflection.
        assert!(refract(Vec3::new(0.9, 0.0, 0.436), Vec3::Z, 1.0 / 1.5).is_none());
    }

    /// A film of the outside's IOR, or of no thickness, changes nothing; a real film tints
    /// the reflection (the three channels differ) and stays within [0, 1].
    #[test]
    fn iridescence_limits() {
        let f0 = Vec3::splat(0.04);
        let plain = schlick(f0, 0.7);
        assert!(
            (iridescence(1.0, 1.3, 0.7, 0.0, f0) - plain)
                .abs()
                .max_element()
                < 1e-6
        );
        let film = iridescence(1.0, 1.3, 0.7, 400.0, f0);
        assert!(
            film.min_element() >= 0.0 && film.max_element() <= 1.0,
            "{film}"
        );
        assert!((film.x - film.z).abs() > 0.005, "{film}");
    }
}
