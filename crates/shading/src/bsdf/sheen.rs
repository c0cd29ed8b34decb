//! The "Charlie" sheen lobe of `KHR_materials_sheen` (Estevez & Kulla 2017): the distribution
//! and the visibility fit the extension's reference implementation uses.

use std::f32::consts::PI;

/// Smallest perceptual sheen roughness (the reference clamps to keep the distribution finite).
const MIN_ROUGHNESS: f32 = 0.07;

/// α = roughness², roughness clamped to what the distribution can represent.
pub fn alpha(roughness: f32) -> f32 {
    let r = roughness.clamp(MIN_ROUGHNESS, 1.0);
    r * r
}

/// The Charlie distribution for `nh = n·h` (α = roughness²).
pub fn d(alpha: f32, nh: f32) -> f32 {
    let inv = 1.0 / alpha;
    let sin2 = (1.0 - nh * nh).max(0.0);
    (2.0 + inv) * sin2.powf(0.5 * inv) / (2.0 * PI)
}

fn lambda_helper(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let mix = |a: f32, b: f32| a + (b - a) * t;
    let a = mix(21.5473, 25.3245);
    let b = mix(3.82987, 3.32435);
    let c = mix(0.19823, 0.16801);
    let dd = mix(-1.97760, -1.27393);
    let e = mix(-4.32054, -4.85967);
    a / (1.0 + b * x.powf(c)) + dd * x + e
}

fn lambda(cos: f32, alpha: f32) -> f32 {
    let c = cos.abs();
    if c < 0.5 {
        lambda_helper(c, alpha).exp()
    } else {
        (2.0 * lambda_helper(0.5, alpha) - lambda_helper(1.0 - c, alpha)).exp()
    }
}

/// The sheen visibility `V = 1 / ((1 + Λ(v) + Λ(l)) 4 n·v n·l)`, clamped to [0, 1] as the
/// reference does.
pub fn v(nl: f32, nv: f32, alpha: f32) -> f32 {
    let denom = (1.0 + lambda(nv, alpha) + lambda(nl, alpha)) * 4.0 * nv * nl;
    if denom > 0.0 {
        (1.0 / denom).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// The sheen BRDF for white sheen colour: `D · V` at half-vector cosine `nh`.
pub fn brdf(alpha: f32, nh: f32, nl: f32, nv: f32) -> f32 {
    d(alpha, nh) * v(nl, nv, alpha)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// D is a distribution of normals: ∫ D(h) cos θh dω = 1.
    #[test]
    fn charlie_is_normalised() {
        for r in [0.1f32, 0.5, 1.0] {
            let a = alpha(r);
            let n = 4000;
            let sum: f64 = (0..n)
                .map(|i| {
                    let z = (i as f32 + 0.5) / n as f32;
                    (d(a, z) * z) as f64
                })
                .sum();
            let total = sum * std::f64::consts::TAU / n as f64;
            assert!((total - 1.0).abs() < 0.01, "r {r}: {total}");
        }
    }
}
