//! Directional albedos of the single-scattering lobes, tabulated once per process (on first
//! use) by quadrature over visible normals: what energy compensation and albedo scaling need.
//!
//! - GGX reflection, split into Schlick's two terms (`E = f0·A + B`, the "split-sum" pair):
//!   `A + B` is the albedo of a lobe with F = 1, whose shortfall below 1 is the energy single
//!   scattering loses to masking (Kulla & Conty 2017; compensated as Turquin 2019 does).
//! - The Charlie sheen lobe (`KHR_materials_sheen`'s albedo scaling).
//! - A rough dielectric interface with exact Fresnel: reflected and transmitted albedo, by view
//!   cosine, roughness and relative IOR (Turquin 2019's table for glass).
//!
//! Tables are indexed by view cosine μ and perceptual roughness r = √α, bilinear (trilinear
//! with the IOR) between grid points.

use super::fresnel::{dielectric, refract, schlick_weight};
use super::ggx::{Ggx, MIN_ALPHA};
use super::sheen;
use glam::Vec3;
use std::f32::consts::PI;
use std::sync::OnceLock;

/// Grid points along the view cosine.
const N_MU: usize = 32;
/// Grid points along perceptual roughness.
const N_R: usize = 32;
/// Stratified quadrature points per axis for each GGX entry.
const N_Q: usize = 32;
/// The same for sheen entries (the lobe gathers at grazing angles when smooth).
const S_Q: usize = 64;
/// Anisotropic GGX table: view cosines, view azimuths over a quarter turn, roughness along
/// x and along y, quadrature points per axis.
const A_MU: usize = 16;
const A_PHI: usize = 8;
const A_R: usize = 16;
const A_Q: usize = 16;
/// IOR points of the average-Fresnel table.
const F_ETA: usize = 64;
/// Glass table: view cosines, roughnesses, IORs and quadrature points per axis.
const G_MU: usize = 24;
const G_R: usize = 16;
const G_ETA: usize = 64;
const G_Q: usize = 20;
/// The glass table's IOR range (log-spaced): interfaces from 1/2.6 to 2.6 (diamond from
/// outside, air from inside diamond; relative IORs beyond are clamped).
const ETA_MIN: f32 = 1.0 / 2.6;
const ETA_MAX: f32 = 2.6;
/// Smallest view cosine tabulated (the integrator keeps views above 0.02).
const MU_MIN: f32 = 0.01;

fn mu_at(i: usize, n: usize) -> f32 {
    (i as f32 / (n - 1) as f32).max(MU_MIN)
}

fn alpha_at(i: usize, n: usize) -> f32 {
    let r = i as f32 / (n - 1) as f32;
    (r * r).max(MIN_ALPHA)
}

fn view(mu: f32) -> Vec3 {
    Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

/// Stratified points of the unit square.
fn grid(n: usize) -> impl Iterator<Item = [f32; 2]> {
    (0..n * n).map(move |k| {
        [
            ((k % n) as f32 + 0.5) / n as f32,
            ((k / n) as f32 + 0.5) / n as f32,
        ]
    })
}

/// Visible-normal sample points with weights (summing to 1): the radial coordinate is
/// stretched towards 1, where GGX's long tail (steep facets that mask and shadow) puts what
/// single scattering loses, so a small grid still resolves it: `u = 1 − (1 − t)³`.
fn tail_grid(n: usize) -> impl Iterator<Item = ([f32; 2], f64)> {
    grid(n).map(move |[t, v]| {
        let s = 1.0 - t;
        ([1.0 - s * s * s, v], 3.0 * (s * s) as f64 / (n * n) as f64)
    })
}

/// `(A, B)` for view cosine `mu` and GGX `alpha`: reflection albedo with F = 1 − w and F = w,
/// w = Schlick's weight.
fn ggx_entry(mu: f32, alpha: f32) -> [f32; 2] {
    split_sum(Ggx::isotropic(alpha), view(mu), N_Q)
}

/// `(A, B)` of distribution `g` seen from `wo`, by `n × n` visible normals.
fn split_sum(g: Ggx, wo: Vec3, n: usize) -> [f32; 2] {
    let g1 = g.g1(wo);
    let (mut a, mut b) = (0.0f64, 0.0f64);
    for (u, q) in tail_grid(n) {
        let m = g.sample_vndf(wo, u);
        let wi = 2.0 * wo.dot(m) * m - wo;
        if wi.z <= 0.0 {
            continue;
        }
        let weight = q * (g.g2(wo, wi) / g1) as f64;
        let w = schlick_weight(wo.dot(m)) as f64;
        a += (1.0 - w) * weight;
        b += w * weight;
    }
    [a as f32, b as f32]
}

/// The anisotropic table's entry `k`: view cosine, azimuth, roughness along x and y.
fn aniso_entry(k: usize) -> [f32; 2] {
    let mu = mu_at(k % A_MU, A_MU);
    let phi = (k / A_MU % A_PHI) as f32 / (A_PHI - 1) as f32 * std::f32::consts::FRAC_PI_2;
    let ax = alpha_at(k / (A_MU * A_PHI) % A_R, A_R);
    let ay = alpha_at(k / (A_MU * A_PHI * A_R), A_R);
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    let wo = Vec3::new(s * phi.cos(), s * phi.sin(), mu);
    split_sum(Ggx { ax, ay }, wo, A_Q)
}

/// Sheen albedo (white sheen colour) by cosine-weighted quadrature: mean of `f · π`.
fn sheen_entry(mu: f32, alpha: f32) -> f32 {
    let wo = view(mu);
    let mut sum = 0.0f64;
    for u in grid(S_Q) {
        let r = u[0].sqrt();
        let phi = 2.0 * PI * u[1];
        let wi = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u[0]).max(0.0).sqrt());
        if wi.z <= 0.0 {
            continue;
        }
        let h = (wo + wi).normalize();
        sum += (sheen::brdf(alpha, h.z, wi.z, wo.z) * PI) as f64;
    }
    (sum / (S_Q * S_Q) as f64) as f32
}

/// Reflected and transmitted albedo of a rough dielectric interface (flux, no radiance
/// scaling) for view cosine `mu`, GGX `alpha` and relative IOR `eta`.
fn glass_entry(mu: f32, alpha: f32, eta: f32) -> [f32; 2] {
    let g = Ggx::isotropic(alpha);
    let wo = view(mu);
    let g1 = g.g1(wo);
    let (mut r, mut t) = (0.0f64, 0.0f64);
    for (u, q) in tail_grid(G_Q) {
        let m = g.sample_vndf(wo, u);
        let om = wo.dot(m);
        let f = q * dielectric(om, eta) as f64;
        let wr = 2.0 * om * m - wo;
        if wr.z > 0.0 {
            r += f * (g.g2(wo, wr) / g1) as f64;
        }
        if let Some(wt) = refract(wo, m, eta) {
            if wt.z < 0.0 {
                t += (q - f) * (g.g2(wo, wt) / g1) as f64;
            }
        }
    }
    [r as f32, t as f32]
}

/// `f(0..n)` computed on plain OS threads (never rayon: these run inside a `OnceLock`
/// initialiser that render workers may reach, and a rayon thread waiting in a parallel loop
/// steals other jobs, which could re-enter the initialiser and deadlock). The calling thread
/// takes the first share; the others go to at most `threads() - 1` new threads.
fn parallel_map<T: Send + Default + Clone>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let mut out = vec![T::default(); n];
    let chunk = n.div_ceil(threads()).max(1);
    let fill = |c: usize, part: &mut [T]| {
        for (i, o) in part.iter_mut().enumerate() {
            *o = f(c * chunk + i);
        }
    };
    std::thread::scope(|scope| {
        let mut parts = out.chunks_mut(chunk).enumerate();
        let first = parts.next();
        for (c, part) in parts {
            let fill = &fill;
            scope.spawn(move || fill(c, part));
        }
        if let Some((c, part)) = first {
            fill(c, part);
        }
    });
    out
}

/// How many threads may compute a table: the size of the rayon pool the caller runs in (the
/// `--threads` bound: a render's workers reach the tables), else one per core, at most 16.
fn threads() -> usize {
    if rayon::current_thread_index().is_some() {
        return rayon::current_num_threads().clamp(1, 16);
    }
    std::thread::available_parallelism()
        .map_or(1, |t| t.get())
        .min(16)
}

struct Table2 {
    data: Vec<[f32; 2]>,
}

/// Bilinear weights of `x ∈ [0, 1]` on `n` grid points.
fn lerp_index(x: f32, n: usize) -> (usize, f32) {
    let f = (x.clamp(0.0, 1.0)) * (n - 1) as f32;
    let i = (f as usize).min(n - 2);
    (i, f - i as f32)
}

fn ggx_table() -> &'static Table2 {
    static T: OnceLock<Table2> = OnceLock::new();
    T.get_or_init(|| Table2 {
        data: parallel_map(N_R * N_MU, |k| {
            ggx_entry(mu_at(k % N_MU, N_MU), alpha_at(k / N_MU, N_R))
        }),
    })
}

fn sheen_table() -> &'static [f32] {
    static T: OnceLock<Vec<f32>> = OnceLock::new();
    T.get_or_init(|| {
        parallel_map(N_R * N_MU, |k| {
            let r = (k / N_MU) as f32 / (N_R - 1) as f32;
            sheen_entry(mu_at(k % N_MU, N_MU), sheen::alpha(r))
        })
    })
}

fn glass_table() -> &'static Table2 {
    static T: OnceLock<Table2> = OnceLock::new();
    T.get_or_init(|| Table2 {
        data: parallel_map(G_ETA * G_R * G_MU, |k| {
            let (mu, r, e) = (k % G_MU, (k / G_MU) % G_R, k / (G_MU * G_R));
            glass_entry(mu_at(mu, G_MU), alpha_at(r, G_R), eta_at(e))
        }),
    })
}

fn aniso_table() -> &'static [[f32; 2]] {
    static T: OnceLock<Vec<[f32; 2]>> = OnceLock::new();
    T.get_or_init(|| parallel_map(A_MU * A_PHI * A_R * A_R, aniso_entry))
}

/// Schlick's average of exact dielectric Fresnel over the cosine-weighted hemisphere,
/// `2 ∫ F(μ, η) μ dμ`, by IOR.
fn fresnel_average_table() -> &'static [f32] {
    static T: OnceLock<Vec<f32>> = OnceLock::new();
    T.get_or_init(|| {
        (0..F_ETA)
            .map(|i| {
                let t = i as f32 / (F_ETA - 1) as f32;
                let eta = ETA_MIN * (ETA_MAX / ETA_MIN).powf(t);
                let n = 1024;
                let sum: f64 = (0..n)
                    .map(|j| {
                        let mu = (j as f32 + 0.5) / n as f32;
                        (dielectric(mu, eta) * mu) as f64
                    })
                    .sum();
                (2.0 * sum / n as f64) as f32
            })
            .collect()
    })
}

fn eta_at(i: usize) -> f32 {
    let t = i as f32 / (G_ETA - 1) as f32;
    ETA_MIN * (ETA_MAX / ETA_MIN).powf(t)
}

/// Bilinear lookup in a table laid out `[r][mu]` with `n_r × n_mu` entries of `N` values.
fn bilinear<const N: usize>(
    data: &[[f32; N]],
    n_mu: usize,
    n_r: usize,
    mu: f32,
    alpha: f32,
) -> [f32; N] {
    let (i, fi) = lerp_index(mu, n_mu);
    let (j, fj) = lerp_index(alpha.max(0.0).sqrt(), n_r);
    let at = |j: usize, i: usize| data[j * n_mu + i];
    std::array::from_fn(|c| {
        let lo = at(j, i)[c] * (1.0 - fi) + at(j, i + 1)[c] * fi;
        let hi = at(j + 1, i)[c] * (1.0 - fi) + at(j + 1, i + 1)[c] * fi;
        lo * (1.0 - fj) + hi * fj
    })
}

/// GGX reflection albedo terms `(A, B)` at view cosine `mu` for roughness `alpha`: a lobe
/// with Schlick reflectance `f0` reflects `f0·A + B` of the light, `A + B` with F = 1.
pub fn ggx_albedo(mu: f32, alpha: f32) -> (f32, f32) {
    let [a, b] = bilinear(&ggx_table().data, N_MU, N_R, mu, alpha);
    (a, b)
}

/// Turquin's multiple-scattering factor for a GGX reflection lobe whose average Fresnel is
/// `f_avg`: `1 + F_avg (1 − E) / E`, E the F = 1 albedo at the view. Multiplying the
/// single-scattering lobe by it makes a white (F = 1) lobe reflect exactly everything.
pub fn multiple_scattering(mu: f32, alpha: f32, f_avg: Vec3) -> Vec3 {
    let (a, b) = ggx_albedo(mu, alpha);
    ms_factor(a + b, f_avg)
}

/// [`multiple_scattering`] from the F = 1 albedo `e`.
pub fn ms_factor(e: f32, f_avg: Vec3) -> Vec3 {
    let e = e.clamp(0.05, 1.0);
    Vec3::ONE + f_avg * ((1.0 - e) / e)
}

/// [`ggx_albedo`] of an anisotropic distribution seen from `wo` (local, x along `ax`):
/// the isotropic table when the two roughnesses (nearly) agree, else a table over view
/// cosine, view azimuth and both roughnesses (built on first use).
pub fn ggx_albedo_aniso(wo: Vec3, ax: f32, ay: f32) -> (f32, f32) {
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    if hi <= lo * 1.05 {
        return ggx_albedo(wo.z, (ax * ay).sqrt());
    }
    let data = aniso_table();
    let s = (wo.x * wo.x + wo.y * wo.y).sqrt();
    let phi = if s > 0.0 {
        wo.y.abs().atan2(wo.x.abs())
    } else {
        0.0
    };
    let coords = [
        lerp_index(wo.z, A_MU),
        lerp_index(phi / std::f32::consts::FRAC_PI_2, A_PHI),
        lerp_index(ax.max(0.0).sqrt(), A_R),
        lerp_index(ay.max(0.0).sqrt(), A_R),
    ];
    let strides = [1, A_MU, A_MU * A_PHI, A_MU * A_PHI * A_R];
    let mut out = [0.0f32; 2];
    for corner in 0..16usize {
        let mut index = 0;
        let mut weight = 1.0;
        for (d, ((i, f), stride)) in coords.iter().zip(strides).enumerate() {
            let up = corner >> d & 1 == 1;
            index += (i + usize::from(up)) * stride;
            weight *= if up { *f } else { 1.0 - f };
        }
        if weight > 0.0 {
            out[0] += weight * data[index][0];
            out[1] += weight * data[index][1];
        }
    }
    (out[0], out[1])
}

/// The average exact Fresnel reflectance of an interface of relative IOR `eta` over the
/// cosine-weighted hemisphere (total internal reflection included when `eta < 1`).
pub fn fresnel_average(eta: f32) -> f32 {
    let t =
        ((eta.clamp(ETA_MIN, ETA_MAX) / ETA_MIN).ln() / (ETA_MAX / ETA_MIN).ln()).clamp(0.0, 1.0);
    let (i, f) = lerp_index(t, F_ETA);
    let data = fresnel_average_table();
    data[i] * (1.0 - f) + data[i + 1] * f
}

/// Schlick's Fresnel averaged over the cosine-weighted hemisphere: `f0 + (1 − f0) / 21`.
pub fn schlick_average(f0: Vec3) -> Vec3 {
    f0 + (Vec3::ONE - f0) / 21.0
}

/// Albedo of the Charlie sheen lobe (white sheen colour) at view cosine `mu` for perceptual
/// sheen roughness `roughness`.
pub fn sheen_albedo(mu: f32, roughness: f32) -> f32 {
    let data = sheen_table();
    let (i, fi) = lerp_index(mu, N_MU);
    let (j, fj) = lerp_index(roughness.clamp(0.0, 1.0), N_R);
    let at = |j: usize, i: usize| data[j * N_MU + i];
    let lo = at(j, i) * (1.0 - fi) + at(j, i + 1) * fi;
    let hi = at(j + 1, i) * (1.0 - fi) + at(j + 1, i + 1) * fi;
    lo * (1.0 - fj) + hi * fj
}

/// Reflected and transmitted albedo `(R, T)` of a rough dielectric interface with exact
/// Fresnel at view cosine `mu`, roughness `alpha` and relative IOR `eta` (clamped to 1/2.6 … 2.6).
pub fn glass_albedo(mu: f32, alpha: f32, eta: f32) -> (f32, f32) {
    let data = &glass_table().data;
    let le =
        ((eta.clamp(ETA_MIN, ETA_MAX) / ETA_MIN).ln() / (ETA_MAX / ETA_MIN).ln()).clamp(0.0, 1.0);
    let (k, fk) = lerp_index(le, G_ETA);
    let slice = |k: usize| {
        let n = G_MU * G_R;
        bilinear(&data[k * n..(k + 1) * n], G_MU, G_R, mu, alpha)
    };
    let (lo, hi) = (slice(k), slice(k + 1));
    (
        lo[0] * (1.0 - fk) + hi[0] * fk,
        lo[1] * (1.0 - fk) + hi[1] * fk,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table against a brute-force hemisphere integral of the glTF lobe.
    #[test]
    fn ggx_albedo_matches_brute_force() {
        use super::super::ggx::{ggx_d, smith_v};
        for (mu, alpha) in [(0.9f32, 0.25f32), (0.4, 0.5), (0.2, 0.81)] {
            let wo = view(mu);
            let n = 700;
            let mut sum = 0.0f64;
            for u in grid(n) {
                let z = u[0];
                let r = (1.0 - z * z).sqrt();
                let phi = 2.0 * PI * u[1];
                let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                let h = (wo + wi).normalize();
                let a2 = alpha * alpha;
                sum += (ggx_d(h.z, a2) * smith_v(wi.z, wo.z, a2) * wi.z) as f64;
            }
            let e = (sum * 2.0 * std::f64::consts::PI / (n * n) as f64) as f32;
            let (a, b) = ggx_albedo(mu, alpha);
            assert!(
                (a + b - e).abs() < 0.01,
                "μ {mu} α {alpha}: table {} vs {e}",
                a + b
            );
        }
        // Smooth lobes lose nothing.
        let (a, b) = ggx_albedo(0.7, MIN_ALPHA);
        assert!((a + b - 1.0).abs() < 1e-3);
    }

    /// A smooth interface reflects Fresnel's share and transmits the rest; rough ones lose a
    /// little to masking, more at grazing.
    #[test]
    fn glass_albedo_limits() {
        let (r, t) = glass_albedo(1.0, MIN_ALPHA, 1.5);
        assert!(
            (r - 0.04).abs() < 2e-3 && (r + t - 1.0).abs() < 2e-3,
            "{r} {t}"
        );
        let (r, t) = glass_albedo(0.3, MIN_ALPHA, 1.0 / 1.5);
        assert!(r > 0.99 && t < 0.01, "total internal reflection: {r} {t}");
        let (r, t) = glass_albedo(0.5, 0.5, 1.5);
        assert!(r + t < 0.99 && r + t > 0.8, "{r} {t}");
    }

    /// The anisotropic table agrees with direct quadrature between its grid points, and with
    /// the isotropic table where the roughnesses agree.
    #[test]
    fn anisotropic_albedo_interpolates() {
        let wo = Vec3::new(0.5, 0.4, 0.6).normalize();
        for (ax, ay) in [(0.5f32, 0.05f32), (0.1, 0.7), (0.3, 0.3)] {
            let (a, b) = ggx_albedo_aniso(wo, ax, ay);
            let [da, db] = split_sum(Ggx { ax, ay }, wo, 48);
            assert!(
                (a + b - da - db).abs() < 0.01,
                "{ax} {ay}: {} vs {}",
                a + b,
                da + db
            );
        }
        // Fresnel's hemispherical average: 0.092 for glass from outside (≈ F0 + …), and most
        // light is reflected from inside (total internal reflection).
        assert!(
            (fresnel_average(1.5) - 0.092).abs() < 0.003,
            "{}",
            fresnel_average(1.5)
        );
        assert!(fresnel_average(1.0 / 1.5) > 0.55);
    }

    #[test]
    fn sheen_albedo_is_a_fraction() {
        for mu in [0.1, 0.5, 1.0] {
            for r in [0.0, 0.5, 1.0] {
                let e = sheen_albedo(mu, r);
                assert!((0.0..=1.0).contains(&e), "μ {mu} r {r}: {e}");
            }
        }
        // Rough sheen reflects more than smooth sheen at normal view.
        assert!(sheen_albedo(1.0, 1.0) > sheen_albedo(1.0, 0.2));
    }
}
