//! A 2-D piecewise-constant distribution over an image's texels, sampled by inverting its
//! marginal and conditional CDFs (pbrt's `PiecewiseConstant2D`): the bokeh image's warp
//! (issue 61, `aperture_image`). Beside `warp.rs` and `warp_lens.rs`.
//!
//! The warp is continuous inside each texel and monotone in each number (rows by `u.y`, then
//! columns by `u.x`), so strata of `u` stay strata of the image.

use glam::Vec2;

/// The largest f32 below 1.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A density over `[0, 1]²` proportional to non-negative texel weights, rows top to bottom
/// (`y` down, as images are stored), columns left to right.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageDistribution {
    width: usize,
    height: usize,
    /// Per row, the CDF of its columns: `width + 1` values from 0 to 1 (a black row: uniform).
    rows: Vec<f32>,
    /// The CDF of the rows: `height + 1` values from 0 to 1.
    marginal: Vec<f32>,
    /// Each texel's weight over the mean weight: the density at a point of it.
    density: Vec<f32>,
}

impl ImageDistribution {
    /// The distribution of `weights` (`width × height`, row-major, top row first); `None` when
    /// the sizes disagree or no weight is positive and finite. Negative or non-finite weights
    /// count as 0.
    pub fn new(width: usize, height: usize, weights: &[f32]) -> Option<Self> {
        if width == 0 || height == 0 || weights.len() != width.checked_mul(height)? {
            return None;
        }
        let w = |x: f32| {
            if x.is_finite() && x > 0.0 {
                x as f64
            } else {
                0.0
            }
        };
        let mut rows = Vec::with_capacity(height * (width + 1));
        let mut row_sums = Vec::with_capacity(height);
        for row in weights.chunks_exact(width) {
            let sum: f64 = row.iter().map(|&x| w(x)).sum();
            row_sums.push(sum);
            rows.extend(cdf(row.iter().map(|&x| w(x)), sum, width));
        }
        let total: f64 = row_sums.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let marginal = cdf(row_sums.iter().copied(), total, height).collect();
        let mean = total / (width * height) as f64;
        let density = weights.iter().map(|&x| (w(x) / mean) as f32).collect();
        Some(Self {
            width,
            height,
            rows,
            marginal,
            density,
        })
    }

    /// The point of `[0, 1]²` (x right, y down) for `u ∈ [0, 1)²`: the row by `u.y`, the column
    /// in it by `u.x`, each continuous inside its texel.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Vec2 {
        let (row, fy) = invert(&self.marginal, u.y);
        let cdf = &self.rows[row * (self.width + 1)..(row + 1) * (self.width + 1)];
        let (col, fx) = invert(cdf, u.x);
        Vec2::new(
            ((col as f32 + fx) / self.width as f32).min(ONE_MINUS_EPSILON),
            ((row as f32 + fy) / self.height as f32).min(ONE_MINUS_EPSILON),
        )
    }

    /// The density (with respect to area in `[0, 1]²`) at point `p`; 0 outside.
    pub fn pdf(&self, p: Vec2) -> f32 {
        if !(p.x >= 0.0 && p.x < 1.0 && p.y >= 0.0 && p.y < 1.0) {
            return 0.0;
        }
        let x = ((p.x * self.width as f32) as usize).min(self.width - 1);
        let y = ((p.y * self.height as f32) as usize).min(self.height - 1);
        self.density[y * self.width + x]
    }

    /// `(width, height)` in texels.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }
}

/// The `n + 1` CDF values of `n` weights summing to `sum`; uniform when `sum` is 0.
fn cdf(weights: impl Iterator<Item = f64>, sum: f64, n: usize) -> impl Iterator<Item = f32> {
    let mut acc = 0.0f64;
    let uniform = sum.is_nan() || sum <= 0.0;
    std::iter::once(0.0).chain(weights.enumerate().map(move |(i, x)| {
        if i + 1 == n {
            return 1.0;
        }
        acc += if uniform { 1.0 } else { x };
        let total = if uniform { n as f64 } else { sum };
        (acc / total) as f32
    }))
}

/// The bin of `cdf` (`n + 1` increasing values, 0 to 1) holding `u`, and where in it `u` falls
/// (0–1). Bins of zero width are never returned.
#[inline]
fn invert(cdf: &[f32], u: f32) -> (usize, f32) {
    let n = cdf.len() - 1;
    // The last index whose value is ≤ u, among 0..n (so a bin with a positive width).
    let i = cdf[1..n].partition_point(|&c| c <= u);
    let (lo, hi) = (cdf[i], cdf[i + 1]);
    let f = if hi > lo { (u - lo) / (hi - lo) } else { 0.5 };
    (i, f.clamp(0.0, ONE_MINUS_EPSILON))
}
