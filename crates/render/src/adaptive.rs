//! Adaptive sampling after Blender Cycles: every pixel takes `min_spp` samples, then the image is
//! rendered in rounds that double each pixel's sample count; between rounds a pixel whose
//! estimated relative error is below the noise threshold stops, and, as in Cycles, a pixel keeps
//! sampling while any of its eight neighbours does, so no isolated unconverged holes remain.
//!
//! The error estimate differs from Cycles' on purpose. Cycles takes the difference between the
//! mean of all samples and the mean of the odd-indexed half (one degree of freedom per channel)
//! and divides it by the square root of the pixel's brightness. We take the standard error of the
//! pixel mean from the samples' variance (n − 1 degrees of freedom) and divide it by the mean
//! itself, `√(mean_rgb s²/n / (μ² + ε))`: the relative error that compositors see after grading
//! and that `aperture bench` measures. Dividing by `√μ` stops dark pixels at a relative error of
//! `t/√μ` (5× the threshold at μ = 0.04); on the demo scene those dark pixels held most of the
//! error left at relative MSE 1e-3 (BENCHMARKS.md, "Adaptive sampling").
//!
//! Determinism: a pixel's samples are always a prefix `0..n` of its own sequence (so Sobol's
//! strata stay intact for power-of-two counts), and decisions happen between rounds over the
//! whole image from the film alone, so the image does not depend on the thread count.

use crate::film::PixelSum;

/// Adaptive sampling settings (`--noise-threshold`, `--min-spp`). The render's `spp` is the most
/// samples any pixel takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveOptions {
    /// A pixel stops when its estimated relative error is below this (Cycles' "noise
    /// threshold"; 0.01 is Cycles' default, smaller is cleaner and slower). Finite and > 0.
    pub threshold: f32,
    /// Samples every pixel takes before it may stop (1 ..= spp). A power of two keeps every
    /// round's count a power of two, which Sobol stratifies best.
    pub min_spp: u32,
}

impl AdaptiveOptions {
    /// The automatic minimum for a budget of `spp`: `2√spp` (twice Cycles' `√spp`), rounded up to
    /// a power of two, at least 4 and at most `spp`. Twice, because a pixel whose light arrives
    /// by rare paths (a sun in glossy metal, seen through a defocused lens) must see some before
    /// it is judged: on the demo scene, pixels stopped dark at `√spp` held 40% of the error left
    /// at relative MSE 1e-3, and the doubled minimum cut the time to reach it by about 40%.
    pub fn auto_min_spp(spp: u32) -> u32 {
        let twice_root = (2.0 * (spp as f64).sqrt()).ceil() as u32;
        twice_root.next_power_of_two().max(4).min(spp.max(1))
    }

    /// The per-pixel sample counts after each round: `min_spp`, doubling, capped at `spp`.
    pub fn rounds(&self, spp: u32) -> Vec<u32> {
        let mut out = Vec::new();
        let mut n = self.min_spp.clamp(1, spp.max(1));
        loop {
            out.push(n);
            if n >= spp {
                return out;
            }
            n = n.saturating_mul(2).min(spp);
        }
    }
}

/// The ε of the relative error's denominator `μ² + ε`, as in the relative MSE of `aperture
/// bench` (`aperture_imageio::RELATIVE_MSE_EPSILON`): below a mean of about 0.1 the error is
/// measured in absolute terms, so near-black pixels do not sample forever.
pub const RELATIVE_ERROR_EPSILON: f64 = 1e-2;

/// A pixel's estimated relative error: the standard error of its mean from the sample variance,
/// over the mean, `√(mean over RGB of (s²/n) / (μ² + ε))`. `sq` holds the sums of squared
/// samples per channel. Infinite below two samples.
pub fn pixel_error(sum: &PixelSum, sq: &[f64; 3]) -> f64 {
    let n = sum.count;
    if n < 2.0 {
        return f64::INFINITY;
    }
    let e2: f64 = (0..3)
        .map(|c| {
            let mean = sum.rgb[c] / n;
            // Rounding can take the difference slightly below zero when all samples are equal.
            let var_of_mean = (sq[c] / n - mean * mean).max(0.0) / (n - 1.0);
            var_of_mean / (mean * mean + RELATIVE_ERROR_EPSILON)
        })
        .sum::<f64>()
        / 3.0;
    e2.sqrt()
}

/// Which pixels keep sampling: those not converged and their eight neighbours (Cycles' x and y
/// filter passes), limited to pixels that have budget left.
pub(crate) fn dilate(converged: &[bool], has_budget: &[bool], width: usize) -> Vec<bool> {
    let height = converged.len() / width;
    let mut row = vec![false; converged.len()];
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            row[i] = !converged[i]
                || (x > 0 && !converged[i - 1])
                || (x + 1 < width && !converged[i + 1]);
        }
    }
    let mut active = vec![false; converged.len()];
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            let busy = row[i] || (y > 0 && row[i - width]) || (y + 1 < height && row[i + width]);
            active[i] = busy && has_budget[i];
        }
    }
    active
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn rounds_double_from_the_minimum() {
        let a = AdaptiveOptions {
            threshold: 0.01,
            min_spp: 4,
        };
        assert_eq!(a.rounds(64), vec![4, 8, 16, 32, 64]);
        assert_eq!(a.rounds(48), vec![4, 8, 16, 32, 48]);
        assert_eq!(a.rounds(4), vec![4]);
        assert_eq!(a.rounds(2), vec![2]);
        assert_eq!(AdaptiveOptions::auto_min_spp(1024), 64);
        assert_eq!(AdaptiveOptions::auto_min_spp(4096), 128);
        assert_eq!(AdaptiveOptions::auto_min_spp(1000), 64);
        assert_eq!(AdaptiveOptions::auto_min_spp(16), 8);
        assert_eq!(AdaptiveOptions::auto_min_spp(8), 8);
        assert_eq!(AdaptiveOptions::auto_min_spp(2), 2);
    }

    /// Sums and squared sums of `samples` (grey).
    fn pixel(samples: &[f32]) -> (PixelSum, [f64; 3]) {
        let mut sum = PixelSum::default();
        let mut sq = [0.0; 3];
        for &v in samples {
            assert!(sum.add(Vec3::splat(v), true));
            sq.iter_mut()
                .for_each(|s| *s += f64::from(v) * f64::from(v));
        }
        (sum, sq)
    }

    #[test]
    fn error_is_the_relative_standard_error() {
        let (flat, sq) = pixel(&[0.5; 8]);
        assert_eq!(pixel_error(&flat, &sq), 0.0);
        // Samples 0 and 2 alternating: mean 1, s² = 8/7, standard error √(8/7/8) = 0.378,
        // relative to √(1 + ε).
        let (noisy, sq) = pixel(&[0.0, 2.0, 0.0, 2.0, 0.0, 2.0, 0.0, 2.0]);
        let expected = (1.0f64 / 7.0).sqrt() / (1.0 + RELATIVE_ERROR_EPSILON).sqrt();
        assert!((pixel_error(&noisy, &sq) - expected).abs() < 1e-12);
        assert_eq!(pixel_error(&PixelSum::default(), &[0.0; 3]), f64::INFINITY);
        assert_eq!(
            pixel_error(&pixel(&[3.0]).0, &pixel(&[3.0]).1),
            f64::INFINITY
        );
    }

    #[test]
    fn dark_and_bright_pixels_with_equal_relative_noise_score_alike() {
        // The point of dividing by μ rather than Cycles' √μ: a pixel 25× darker with the same
        // relative noise is not let off with a 5× smaller error.
        let bright: Vec<f32> = (0..64)
            .map(|i| if i % 4 == 0 { 4.0 } else { 0.0 })
            .collect();
        let dark: Vec<f32> = bright.iter().map(|v| v / 25.0).collect();
        let (b, bq) = pixel(&bright);
        let (d, dq) = pixel(&dark);
        let (eb, ed) = (pixel_error(&b, &bq), pixel_error(&d, &dq));
        // Mean 0.04 sits below the ε knee (√ε = 0.1), which scales the dark error to
        // 0.04/0.108 = 0.37 of the bright one's: still nearly 2× Cycles' √0.04 = 0.2.
        assert!(ed > 0.3 * eb && ed < eb, "dark {ed} bright {eb}");
        // Above the knee the error is scale-free.
        let brighter: Vec<f32> = bright.iter().map(|v| v * 10.0).collect();
        let (h, hq) = pixel(&brighter);
        let eh = pixel_error(&h, &hq);
        assert!((eh / eb - 1.0).abs() < 0.01, "mean 10: {eh}, mean 1: {eb}");
    }

    #[test]
    fn a_busy_pixel_keeps_its_neighbours_busy() {
        let w = 5;
        let mut converged = vec![true; 25];
        converged[12] = false; // the centre
        let budget = vec![true; 25];
        let active = dilate(&converged, &budget, w);
        let on: Vec<usize> = (0..25).filter(|&i| active[i]).collect();
        assert_eq!(on, vec![6, 7, 8, 11, 12, 13, 16, 17, 18]);
        let none = dilate(&[true; 25], &budget, w);
        assert!(none.iter().all(|a| !a));
        let mut no_budget = budget.clone();
        no_budget[12] = false;
        assert!(!dilate(&converged, &no_budget, w)[12]);
    }
}
