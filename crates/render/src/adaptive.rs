//! Adaptive sampling, as Blender Cycles does it: every pixel takes `min_spp` samples, then the
//! image is rendered in rounds that double each pixel's sample count; between rounds a pixel
//! whose estimated relative error is below the noise threshold stops.
//!
//! The error estimate is Cycles' (after Dammertz et al., "A hierarchical automatic stopping
//! condition for Monte Carlo global illumination"): the difference between the mean of all samples
//! and the mean of the odd-indexed half, summed over RGB, divided by the square root of the
//! pixel's mean RGB sum (noise relative to what the eye sees). As in Cycles, a pixel keeps
//! sampling while any of its eight neighbours does, so no isolated unconverged holes remain.
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
    /// Cycles' automatic minimum for a budget of `spp`: `√spp`, here rounded up to a power of
    /// two, at least 4 and at most `spp`.
    pub fn auto_min_spp(spp: u32) -> u32 {
        let root = (spp as f64).sqrt().ceil() as u32;
        root.next_power_of_two().max(4).min(spp.max(1))
    }

    /// A threshold that follows a budget of `spp`: `max(0.001, 1/√spp)`, the relative noise a
    /// pixel of unit variance reaches at `spp` samples. `aperture bench` sweeps budgets with it.
    pub fn auto_threshold(spp: u32) -> f32 {
        (1.0 / (spp.max(1) as f32).sqrt()).max(0.001)
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

/// Cycles' per-pixel relative error estimate from the sum of all samples and the sum of the
/// odd-indexed ones: `Σ_rgb |I − 2·A| / n  /  (10⁻⁴ + √(Σ_rgb I / n))`.
pub fn pixel_error(sum: &PixelSum, odd: &[f64; 3]) -> f64 {
    if sum.count < 2.0 {
        return f64::INFINITY;
    }
    let inv = 1.0 / sum.count;
    let diff: f64 = (0..3)
        .map(|c| (sum.rgb[c] - 2.0 * odd[c]).abs())
        .sum::<f64>()
        * inv;
    let norm = ((sum.rgb[0] + sum.rgb[1] + sum.rgb[2]) * inv)
        .max(0.0)
        .sqrt();
    diff / (1e-4 + norm)
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
        assert_eq!(AdaptiveOptions::auto_min_spp(1024), 32);
        assert_eq!(AdaptiveOptions::auto_min_spp(8), 4);
        assert_eq!(AdaptiveOptions::auto_min_spp(2), 2);
    }

    #[test]
    fn error_is_zero_for_constant_samples_and_grows_with_noise() {
        let mut flat = PixelSum::default();
        let mut odd = [0.0; 3];
        for i in 0..8 {
            flat.add(Vec3::splat(0.5), true);
            if i % 2 == 1 {
                odd.iter_mut().for_each(|o| *o += 0.5);
            }
        }
        assert_eq!(pixel_error(&flat, &odd), 0.0);
        let mut noisy = PixelSum::default();
        let mut odd = [0.0; 3];
        for i in 0..8 {
            let v: f64 = if i % 2 == 0 { 1.0 } else { 0.0 };
            noisy.add(Vec3::splat(v as f32), true);
            if i % 2 == 1 {
                odd.iter_mut().for_each(|o| *o += v);
            }
        }
        assert!(pixel_error(&noisy, &odd) > 0.5);
        assert_eq!(pixel_error(&PixelSum::default(), &[0.0; 3]), f64::INFINITY);
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
