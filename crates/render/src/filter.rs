//! Pixel reconstruction filters by importance sampling (filter importance sampling): a sample's
//! film position is drawn from the filter's shape around its pixel's centre, it gets weight 1
//! and lands in that one pixel only. Tiles therefore never write each other's pixels.

use std::f32::consts::TAU;

/// Entries of the tabulated 1-D distribution of a filter.
const TABLE: usize = 256;

/// Cells of the guide table that starts the search for a sample's bin (pbrt's lookup
/// acceleration): the search then takes about one step on average (the table holds 257
/// edges) instead of a binary search of nine.
const GUIDE: usize = 256;

/// Which filter (`--filter`; the first paragraph of each value's comment is its help there).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum FilterKind {
    /// The 1-pixel box.
    Box,
    /// Gaussian, 1.5 px wide (as Cycles).
    ///
    /// The width as Cycles defines it: the profile over ±0.75 px.
    Gaussian,
    /// Blackman-Harris, 1.5 px wide (Cycles' default).
    #[default]
    BlackmanHarris,
}

/// A filter ready to sample: separable, so each axis uses the same 1-D table.
#[derive(Debug, Clone)]
pub enum Filter {
    /// Uniform over the pixel.
    Box,
    /// A non-negative tabulated 1-D profile over `[−width/2, width/2]`.
    Tabulated {
        /// Total width in pixels.
        width: f32,
        /// Cumulative distribution at the `TABLE + 1` bin edges, from 0 to 1.
        cdf: Vec<f32>,
        /// Per cell `g` of `[0, 1)` cut in `GUIDE`, the number of edges whose cdf is at most
        /// `g / GUIDE`: where the search for a `u` in that cell starts.
        guide: Vec<u32>,
    },
}

/// Cycles' Gaussian profile over `x ∈ [−width/2, width/2]`.
fn gaussian(width: f32, x: f32) -> f32 {
    let x = x * 6.0 / width;
    (-2.0 * x * x).exp()
}

/// Cycles' Blackman-Harris profile over `x ∈ [−width/2, width/2]`.
fn blackman_harris(width: f32, x: f32) -> f32 {
    let x = TAU * (x / width + 0.5);
    0.35875 - 0.48829 * x.cos() + 0.14128 * (2.0 * x).cos() - 0.01168 * (3.0 * x).cos()
}

impl Filter {
    /// Builds the filter's sampling table.
    pub fn new(kind: FilterKind) -> Self {
        let width = 1.5;
        let profile: fn(f32, f32) -> f32 = match kind {
            FilterKind::Box => return Self::Box,
            FilterKind::Gaussian => gaussian,
            FilterKind::BlackmanHarris => blackman_harris,
        };
        let mut cdf = Vec::with_capacity(TABLE + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0f64);
        for i in 0..TABLE {
            let x = ((i as f32 + 0.5) / TABLE as f32 - 0.5) * width;
            acc += profile(width, x).max(0.0) as f64;
            cdf.push(acc);
        }
        let cdf: Vec<f32> = cdf.into_iter().map(|c| (c / acc) as f32).collect();
        let guide = (0..GUIDE)
            .map(|g| cdf.partition_point(|&c| c <= g as f32 / GUIDE as f32) as u32)
            .collect();
        Self::Tabulated { width, cdf, guide }
    }

    /// The largest offset from the pixel centre [`Filter::sample`] gives along an axis, in
    /// pixels.
    pub fn half_width(&self) -> f32 {
        match self {
            Self::Box => 0.5,
            Self::Tabulated { width, .. } => 0.5 * width,
        }
    }

    /// Offset from the pixel centre, in pixels, for `u ∈ [0, 1)` along one axis.
    pub fn sample_1d(&self, u: f32) -> f32 {
        match self {
            Self::Box => u - 0.5,
            Self::Tabulated { width, cdf, guide } => {
                // The last edge whose cdf ≤ u, then linear within the bin (piecewise-constant pdf).
                let i = Self::edges_at_most(cdf, guide, u).clamp(1, TABLE) - 1;
                let (c0, c1) = (cdf[i], cdf[i + 1]);
                let t = if c1 > c0 { (u - c0) / (c1 - c0) } else { 0.5 };
                ((i as f32 + t.clamp(0.0, 1.0)) / TABLE as f32 - 0.5) * width
            }
        }
    }

    /// The number of `cdf` entries at most `u` (`cdf.partition_point(|&c| c <= u)`, exactly):
    /// from the guide's start, a step or two either way (either way, so that a start off by
    /// the rounding of `u * GUIDE` still ends at the same count).
    #[inline]
    fn edges_at_most(cdf: &[f32], guide: &[u32], u: f32) -> usize {
        if u.is_nan() {
            // No edge is at most NaN (the binary search's answer).
            return 0;
        }
        let g = ((u * GUIDE as f32) as usize).min(GUIDE - 1);
        let mut k = guide.get(g).map_or(0, |&k| k as usize).min(cdf.len());
        while k > 0 && cdf[k - 1] > u {
            k -= 1;
        }
        // Two steps without branches (almost every search ends within them), then the rest.
        for _ in 0..2 {
            k += usize::from(cdf.get(k).is_some_and(|&c| c <= u));
        }
        while k < cdf.len() && cdf[k] <= u {
            k += 1;
        }
        k
    }

    /// Offset from the pixel centre for a 2-D sample.
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> glam::Vec2 {
        match self {
            // The box inline (what `sample_1d` does for it): two subtractions, not two calls.
            Self::Box => glam::Vec2::new(u[0] - 0.5, u[1] - 0.5),
            Self::Tabulated { .. } => glam::Vec2::new(self.sample_1d(u[0]), self.sample_1d(u[1])),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_covers_the_pixel() {
        let f = Filter::new(FilterKind::Box);
        assert_eq!(f.sample_1d(0.0), -0.5);
        assert!((f.sample_1d(0.75) - 0.25).abs() < 1e-7);
    }

    #[test]
    fn samples_stay_within_the_half_width() {
        for kind in [
            FilterKind::Box,
            FilterKind::Gaussian,
            FilterKind::BlackmanHarris,
        ] {
            let f = Filter::new(kind);
            let h = f.half_width();
            let widest = (0..=10_000)
                .map(|i| (i as f32 / 10_000.0).min(1.0f32.next_down()))
                .map(|u| f.sample_1d(u).abs())
                .fold(0.0f32, f32::max);
            assert!(
                widest <= h && widest > 0.9 * h,
                "{kind:?}: {widest} against {h}"
            );
        }
    }

    #[test]
    fn guided_search_matches_the_binary_search() {
        for kind in [FilterKind::Gaussian, FilterKind::BlackmanHarris] {
            let Filter::Tabulated { cdf, guide, .. } = Filter::new(kind) else {
                panic!("{kind:?} is tabulated");
            };
            // Every edge, its neighbours in f32, cell boundaries and a fine sweep; and NaN.
            let mut us: Vec<f32> = cdf
                .iter()
                .flat_map(|&c| [c, c.next_down(), c.next_up()])
                .collect();
            us.extend((0..=GUIDE).flat_map(|g| {
                let b = g as f32 / GUIDE as f32;
                [b, b.next_down(), b.next_up()]
            }));
            us.extend((0..100_000).map(|i| i as f32 / 100_000.0));
            us.extend([0.0, 1.0f32.next_down(), f32::NAN, -1.0, 2.0]);
            for u in us {
                assert_eq!(
                    Filter::edges_at_most(&cdf, &guide, u),
                    cdf.partition_point(|&c| c <= u),
                    "{kind:?} u = {u:e}"
                );
            }
        }
    }

    #[test]
    fn tabulated_filters_follow_their_profile() {
        for (kind, profile) in [
            (FilterKind::Gaussian, gaussian as fn(f32, f32) -> f32),
            (FilterKind::BlackmanHarris, blackman_harris),
        ] {
            let f = Filter::new(kind);
            let n = 20000;
            let xs: Vec<f32> = (0..n)
                .map(|i| f.sample_1d((i as f32 + 0.5) / n as f32))
                .collect();
            assert!(xs.iter().all(|x| x.abs() <= 0.75));
            assert!(xs.windows(2).all(|w| w[0] <= w[1]), "monotone");
            // Mean 0 (symmetric) and variance matches the profile's.
            let mean: f32 = xs.iter().sum::<f32>() / n as f32;
            assert!(mean.abs() < 1e-3, "{mean}");
            let var: f32 = xs.iter().map(|x| x * x).sum::<f32>() / n as f32;
            let (mut num, mut den) = (0.0f64, 0.0f64);
            for i in 0..10000 {
                let x = (i as f32 + 0.5) / 10000.0 * 1.5 - 0.75;
                let w = profile(1.5, x) as f64;
                num += w * (x * x) as f64;
                den += w;
            }
            let want = (num / den) as f32;
            assert!(
                (var - want).abs() < 0.01 * want,
                "{kind:?}: {var} vs {want}"
            );
            // Narrower than the box of the same support.
            assert!(var < 1.5f32.powi(2) / 12.0);
        }
    }
}
