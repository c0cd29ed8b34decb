//! Single wavelengths for dispersion (`KHR_materials_dispersion`): a path that refracts through
//! a dispersive body follows one wavelength, drawn uniformly over the visible range, and
//! carries that wavelength's linear Rec.709 colour (the CIE 1931 observer, analytic fit of
//! Wyman, Sloan & Shirley 2013), normalised so that the colours average to white: in
//! expectation the path carries what an RGB path would, spread into a spectrum.

use glam::{Mat3, Vec3};
use std::sync::OnceLock;

/// The range wavelengths are drawn from, nm.
const LAMBDA_MIN: f32 = 380.0;
const LAMBDA_MAX: f32 = 720.0;

fn lobe(x: f32, mu: f32, s1: f32, s2: f32) -> f32 {
    let s = if x < mu { s1 } else { s2 };
    let t = (x - mu) / s;
    (-0.5 * t * t).exp()
}

/// CIE 1931 colour matching functions at `lambda` nm (multi-lobe Gaussian fit).
fn xyz(lambda: f32) -> Vec3 {
    Vec3::new(
        1.056 * lobe(lambda, 599.8, 37.9, 31.0) + 0.362 * lobe(lambda, 442.0, 16.0, 26.7)
            - 0.065 * lobe(lambda, 501.1, 20.4, 26.2),
        0.821 * lobe(lambda, 568.8, 46.9, 40.5) + 0.286 * lobe(lambda, 530.9, 16.3, 31.1),
        1.217 * lobe(lambda, 437.0, 11.8, 36.0) + 0.681 * lobe(lambda, 459.0, 26.0, 13.8),
    )
}

/// XYZ to linear Rec.709.
pub const XYZ_TO_REC709: Mat3 = Mat3::from_cols_array(&[
    3.240_454_2,
    -0.969_266,
    0.055_643_4,
    -1.537_138_5,
    1.876_010_8,
    -0.204_025_9,
    -0.498_531_4,
    0.041_556,
    1.057_225_2,
]);

/// Rec.709 colour of `lambda`, negatives (outside the gamut) clipped.
fn rgb(lambda: f32) -> Vec3 {
    (XYZ_TO_REC709 * xyz(lambda)).max(Vec3::ZERO)
}

/// Per-channel means of [`rgb`] over the range, so weights average to one.
fn normalisation() -> Vec3 {
    static N: OnceLock<Vec3> = OnceLock::new();
    *N.get_or_init(|| {
        let n = 2048;
        let sum: Vec3 = (0..n)
            .map(|i| rgb(LAMBDA_MIN + (LAMBDA_MAX - LAMBDA_MIN) * (i as f32 + 0.5) / n as f32))
            .sum();
        sum / n as f32
    })
}

/// A wavelength (nm) for uniform `u` and the RGB weight a path following it carries.
pub fn sample(u: f32) -> (f32, Vec3) {
    let lambda = LAMBDA_MIN + (LAMBDA_MAX - LAMBDA_MIN) * u.clamp(0.0, 1.0);
    (lambda, rgb(lambda) / normalisation())
}

/// Bins of [`sample_in_channel`]'s tables over the range.
const CHANNEL_BINS: usize = 1024;

/// Per Rec.709 channel (R, G, B), the CDF of that channel's colour-matching weight over the
/// range's bins (`CHANNEL_BINS + 1` values from 0 to 1).
fn channel_cdfs() -> &'static [Vec<f32>; 3] {
    static T: OnceLock<[Vec<f32>; 3]> = OnceLock::new();
    T.get_or_init(|| {
        std::array::from_fn(|c| {
            let w: Vec<f64> = (0..CHANNEL_BINS)
                .map(|i| {
                    let t = (i as f32 + 0.5) / CHANNEL_BINS as f32;
                    f64::from(rgb(LAMBDA_MIN + (LAMBDA_MAX - LAMBDA_MIN) * t)[c])
                })
                .collect();
            let total: f64 = w.iter().sum();
            let mut acc = 0.0;
            std::iter::once(0.0)
                .chain(w.iter().map(|x| {
                    acc += x;
                    (acc / total) as f32
                }))
                .collect()
        })
    })
}

/// A wavelength (nm) for a path that carries only Rec.709 channel `channel` (0 R, 1 G, 2 B,
/// chosen by the camera for chromatic aberration), drawn in proportion to that channel's
/// colour-matching weight, and the factor on the path's weight that keeps the channel's
/// estimate what [`sample`] gives it in expectation (1 up to the tabulation; exact with it).
pub fn sample_in_channel(channel: usize, u: f32) -> (f32, f32) {
    let c = channel.min(2);
    let cdf = &channel_cdfs()[c];
    let u = u.clamp(0.0, 1.0 - f32::EPSILON / 2.0);
    let i = cdf[1..CHANNEL_BINS].partition_point(|&v| v <= u);
    let (lo, hi) = (cdf[i], cdf[i + 1]);
    let f = if hi > lo { (u - lo) / (hi - lo) } else { 0.5 };
    let t = (i as f32 + f.clamp(0.0, 1.0)) / CHANNEL_BINS as f32;
    let lambda = LAMBDA_MIN + (LAMBDA_MAX - LAMBDA_MIN) * t;
    // The density of λ over the range (per unit of t) is the bin's probability × bins; the
    // uniform draw of [`sample`] weighs rgb(λ)[c] / normalisation[c] against density 1.
    let pdf = (hi - lo) * CHANNEL_BINS as f32;
    let weight = if pdf > 0.0 {
        rgb(lambda)[c] / normalisation()[c] / pdf
    } else {
        0.0
    };
    (lambda, weight)
}

/// The IOR at `lambda` of a material of IOR `ior` (at 587.6 nm) and dispersion `20 / V`
/// (`KHR_materials_dispersion`'s Cauchy form).
pub fn dispersed_ior(ior: f32, dispersion: f32, lambda: f32) -> f32 {
    if dispersion <= 0.0 {
        return ior;
    }
    let abbe = 20.0 / dispersion;
    (ior + (ior - 1.0) / abbe * (523_655.0 / (lambda * lambda) - 1.5168)).max(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_average_to_white() {
        let n = 1000;
        let mean: Vec3 = (0..n)
            .map(|i| sample((i as f32 + 0.5) / n as f32).1)
            .sum::<Vec3>()
            / n as f32;
        assert!((mean - Vec3::ONE).abs().max_element() < 0.01, "{mean}");
        // Red light is red, blue light blue.
        let (_, red) = sample(0.85);
        let (_, blue) = sample(0.2);
        assert!(red.x > red.z && blue.z > blue.x, "{red} {blue}");
    }

    #[test]
    fn dispersion_follows_the_abbe_number() {
        // At the d line the IOR is the material's; blue bends more than red.
        assert!((dispersed_ior(1.5, 1.0, 587.6) - 1.5).abs() < 1e-3);
        let (f, c) = (
            dispersed_ior(1.5, 1.0, 486.1),
            dispersed_ior(1.5, 1.0, 656.3),
        );
        // V = (n_d − 1) / (n_F − n_C) = 20.
        assert!(((1.5 - 1.0) / (f - c) - 20.0).abs() < 0.1, "{f} {c}");
        assert_eq!(dispersed_ior(1.5, 0.0, 400.0), 1.5);
    }

    #[test]
    fn channel_wavelengths_follow_their_channel() {
        // Red paths take long wavelengths, blue short ones; the weights average to 1.
        let n = 4000;
        for (c, lo, hi) in [(0, 560.0, 720.0), (2, 380.0, 520.0)] {
            let mut mean_w = 0.0;
            let mut mean_l = 0.0;
            for i in 0..n {
                let (l, w) = sample_in_channel(c, (i as f32 + 0.5) / n as f32);
                mean_w += w / n as f32;
                mean_l += l / n as f32;
            }
            assert!((mean_w - 1.0).abs() < 0.01, "{c}: {mean_w}");
            assert!(mean_l > lo && mean_l < hi, "{c}: {mean_l}");
        }
    }
}
