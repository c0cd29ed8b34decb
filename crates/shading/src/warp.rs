//! Sampling warps, each in one place: uniform numbers to points on the disc and the regular
//! polygon (the lens), to cosine-weighted directions (diffuse lobes), to outcomes of a
//! discrete distribution (the alias table of lights and environment texels), and the power
//! heuristic that weighs two strategies' samples.

use glam::{Vec2, Vec3, Vec4};
use std::f32::consts::{FRAC_PI_4, PI, TAU};

/// Shirley–Chiu concentric mapping of the unit square onto the unit disc: continuous and
/// area-preserving, so strata of the square stay compact strata of the disc.
///
/// Written without a data-dependent branch and with the quarter-range `sin`/`cos` kernels for
/// the one angle in `[-π/4, π/4]` the mapping needs: the lens and every diffuse bounce go
/// through here, and a 50/50 branch plus libm's `sincosf` cost more than the mapping itself.
/// It runs the lane version in one lane, because LLVM compiles a scalar `if` on the wedge test
/// into exactly that branch (7 % of a render's time sat in `Bsdf::sample` behind it).
#[inline(always)]
pub fn concentric_disc(u: Vec2) -> Vec2 {
    let (x, y) = concentric_disc_lanes([Vec4::splat(u.x), Vec4::splat(u.y)]);
    Vec2::new(x.x, y.x)
}

/// `(sin x, cos x)` for `|x| ≤ π/4`: Cephes' single-precision minimax kernels (within about
/// 1 ulp there), without the range reduction and branches of a general `sin_cos`. One macro
/// for the scalar and the lane version, so that both evaluate the same terms in the same order.
macro_rules! sin_cos_quarter_terms {
    ($x:expr) => {{
        let x = $x;
        let z = x * x;
        let s = x + x * z * ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1);
        let c =
            1.0 - 0.5 * z + z * z * ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2);
        (s, c)
    }};
}

/// `(sin x, cos x)` for `|x| ≤ π/4` in four lanes (`sin_cos_quarter_terms`).
#[inline(always)]
pub fn sin_cos_quarter_lanes(x: Vec4) -> (Vec4, Vec4) {
    sin_cos_quarter_terms!(x)
}

/// [`concentric_disc`] in four lanes (`u` as its x and y lanes), its branches as selects: the
/// same bits per lane. The camera's lanes (`camera_lanes.rs`) map four lens samples at once.
#[inline(always)]
pub fn concentric_disc_lanes(u: [Vec4; 2]) -> (Vec4, Vec4) {
    let ox = 2.0 * u[0] - Vec4::ONE;
    let oy = 2.0 * u[1] - Vec4::ONE;
    let swap = ox.abs().cmple(oy.abs());
    let num = Vec4::select(swap, ox, oy);
    let r = Vec4::select(swap, oy, ox);
    let (s, c) = sin_cos_quarter_lanes(FRAC_PI_4 * (num / r));
    // At the centre (`r` = 0) the point is the origin.
    let centre = r.cmpeq(Vec4::ZERO);
    let x = Vec4::select(centre, Vec4::ZERO, r * Vec4::select(swap, s, c));
    let y = Vec4::select(centre, Vec4::ZERO, r * Vec4::select(swap, c, s));
    (x, y)
}

/// The `k`-th corner of a regular `n`-gon inscribed in the unit circle, placed as Cycles places
/// blades: at angle `rotation + π/n + 2πk/n`.
pub fn polygon_corner(k: u32, n: u32, rotation: f32) -> Vec2 {
    let a = rotation + PI / n as f32 + TAU * k as f32 / n as f32;
    Vec2::new(a.cos(), a.sin())
}

/// Uniform point in the regular `n`-gon inscribed in the unit circle: `u.x` picks one of the `n`
/// equal-area wedges of the fan around the centre (its fractional part is reused), then a
/// uniform point in that triangle.
pub fn uniform_polygon(u: Vec2, n: u32, rotation: f32) -> Vec2 {
    let scaled = u.x * n as f32;
    let k = (scaled as u32).min(n - 1);
    let a = scaled - k as f32;
    let c0 = polygon_corner(k, n, rotation);
    let c1 = polygon_corner((k + 1) % n, n, rotation);
    // Uniform in the triangle (0, c0, c1): sqrt(a) spreads along the wedge's depth.
    let s = a.sqrt();
    s * ((1.0 - u.y) * c0 + u.y * c1)
}

/// Cosine-weighted hemisphere direction.
pub fn cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let d = concentric_disc(Vec2::new(u[0], u[1]));
    Vec3::new(d.x, d.y, (1.0 - d.length_squared()).max(0.0).sqrt())
}

/// The largest f32 below 1.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Walker/Vose alias table: O(1) sampling of a discrete distribution.
#[derive(Debug, Clone)]
pub struct AliasTable {
    /// Probability of keeping bin `i` (else take `alias[i]`).
    prob: Vec<f32>,
    alias: Vec<u32>,
    /// Normalised probability of each outcome.
    pmf: Vec<f32>,
}

impl AliasTable {
    /// A table for non-negative weights with a positive sum.
    pub fn new(weights: &[f64]) -> Self {
        let n = weights.len();
        let total: f64 = weights.iter().sum();
        let pmf: Vec<f32> = weights.iter().map(|w| (w / total) as f32).collect();
        let mut scaled: Vec<f64> = weights.iter().map(|w| w / total * n as f64).collect();
        let mut prob = vec![1.0f32; n];
        let mut alias: Vec<u32> = (0..n as u32).collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) =
            (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
            prob[s] = scaled[s] as f32;
            alias[s] = l as u32;
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // Leftovers (rounding) keep themselves with probability 1.
        Self { prob, alias, pmf }
    }

    /// Picks an outcome for `u ∈ [0, 1)`.
    pub fn sample(&self, u: f32) -> usize {
        let n = self.prob.len();
        let x = u * n as f32;
        let i = (x as usize).min(n - 1);
        let frac = x - i as f32;
        if frac < self.prob[i] {
            i
        } else {
            self.alias[i] as usize
        }
    }

    /// Picks an outcome for `u ∈ [0, 1)` and returns with it a fresh uniform number in
    /// `[0, 1)` recovered from the part of `u` the choice did not use.
    pub fn sample_remap(&self, u: f32) -> (usize, f32) {
        let n = self.prob.len();
        let x = u * n as f32;
        let i = (x as usize).min(n - 1);
        let frac = (x - i as f32).clamp(0.0, 1.0);
        let p = self.prob[i];
        if frac < p {
            (i, (frac / p).min(ONE_MINUS_EPSILON))
        } else {
            let rest = ((frac - p) / (1.0 - p)).clamp(0.0, ONE_MINUS_EPSILON);
            (self.alias[i] as usize, rest)
        }
    }

    /// Probability of outcome `i`.
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }
}

/// Power heuristic with β = 2.
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && a2.is_finite() {
        a2 / (a2 + b2)
    } else if a2.is_infinite() {
        1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(sin x, cos x)` for `|x| ≤ π/4` (`sin_cos_quarter_terms`), one value.
    fn sin_cos_quarter(x: f32) -> (f32, f32) {
        sin_cos_quarter_terms!(x)
    }

    /// The mapping written out one point at a time: the reference of the lane code.
    fn concentric_disc_scalar(u: Vec2) -> Vec2 {
        let o = 2.0 * u - Vec2::ONE;
        let swap = o.x.abs() <= o.y.abs();
        let (num, r) = if swap { (o.x, o.y) } else { (o.y, o.x) };
        if r == 0.0 {
            return Vec2::ZERO;
        }
        let (s, c) = sin_cos_quarter(FRAC_PI_4 * (num / r));
        r * if swap {
            Vec2::new(s, c)
        } else {
            Vec2::new(c, s)
        }
    }

    /// The lanes, and the one-lane [`concentric_disc`], give the scalar mapping's bits, lane
    /// by lane, over a grid with the centre, the wedge borders (|x| = |y|) and the square's
    /// edges on it.
    #[test]
    fn concentric_disc_lanes_are_the_scalar_mapping() {
        let n = 64;
        let values: Vec<f32> = (0..=n)
            .map(|i| i as f32 / n as f32)
            .map(|v| v.min(1.0 - f32::EPSILON / 2.0))
            .collect();
        let points: Vec<Vec2> = values
            .iter()
            .flat_map(|&x| values.iter().map(move |&y| Vec2::new(x, y)))
            .collect();
        assert!(
            points.contains(&Vec2::splat(0.5)),
            "the centre is on the grid"
        );
        for quad in points.chunks(4) {
            let lane = |k: usize| quad.get(k).copied().unwrap_or(quad[0]);
            let u = [
                Vec4::new(lane(0).x, lane(1).x, lane(2).x, lane(3).x),
                Vec4::new(lane(0).y, lane(1).y, lane(2).y, lane(3).y),
            ];
            let (x, y) = concentric_disc_lanes(u);
            for k in 0..4 {
                let want = concentric_disc_scalar(lane(k));
                let one = concentric_disc(lane(k));
                assert_eq!(
                    (x[k].to_bits(), y[k].to_bits()),
                    (want.x.to_bits(), want.y.to_bits()),
                    "{}",
                    lane(k)
                );
                assert_eq!(
                    (one.x.to_bits(), one.y.to_bits()),
                    (want.x.to_bits(), want.y.to_bits()),
                    "{}",
                    lane(k)
                );
            }
        }
    }

    fn grid(n: u32) -> impl Iterator<Item = Vec2> {
        (0..n * n).map(move |i| {
            Vec2::new(
                ((i % n) as f32 + 0.5) / n as f32,
                ((i / n) as f32 + 0.5) / n as f32,
            )
        })
    }

    #[test]
    fn polygon_sampling_is_uniform_over_the_polygon() {
        // Mean of |p|² over a regular hexagon of circumradius 1 is 5/12. A centred grid whose
        // columns split evenly among the 6 wedges.
        let n = 192;
        let mut sum = 0.0;
        let mut centroid = Vec2::ZERO;
        for i in 0..n * n {
            let u = Vec2::new(
                ((i % n) as f32 + 0.5) / n as f32,
                ((i / n) as f32 + 0.5) / n as f32,
            );
            let p = uniform_polygon(u, 6, 0.0);
            sum += p.length_squared();
            centroid += p;
        }
        let mean = sum / (n * n) as f32;
        assert!((mean - 5.0 / 12.0).abs() < 1e-3, "{mean}");
        assert!(centroid.length() / ((n * n) as f32) < 1e-3);
    }

    #[test]
    fn concentric_disc_is_uniform() {
        // Mean of r² over the unit disc is 1/2.
        let n = 128;
        let mean: f32 = grid(n)
            .map(|u| concentric_disc(u).length_squared())
            .sum::<f32>()
            / (n * n) as f32;
        assert!((mean - 0.5).abs() < 1e-3, "{mean}");
    }

    #[test]
    fn quarter_sin_cos_is_within_two_ulps() {
        // Every float of [-π/4, π/4] at a stride, and the ends.
        let end = FRAC_PI_4.to_bits();
        let xs = (0..=end).step_by(97).chain([end]).map(f32::from_bits);
        for x in xs.flat_map(|x| [x, -x]) {
            let (s, c) = sin_cos_quarter(x);
            let (ws, wc) = (f64::from(x).sin(), f64::from(x).cos());
            let ulp = |w: f64| f64::from(f32::EPSILON) * w.abs().max(f64::from(f32::MIN_POSITIVE));
            assert!(
                (f64::from(s) - ws).abs() <= 2.0 * ulp(ws),
                "sin {x}: {s} vs {ws}"
            );
            assert!(
                (f64::from(c) - wc).abs() <= 2.0 * ulp(wc),
                "cos {x}: {c} vs {wc}"
            );
        }
    }

    #[test]
    fn concentric_disc_is_shirley_chius_mapping() {
        // Against the mapping as written with two branches, in f64.
        let n = 97;
        for u in grid(n).chain([Vec2::splat(0.5), Vec2::ZERO, Vec2::new(0.5, 0.0)]) {
            let (x, y) = (2.0 * f64::from(u.x) - 1.0, 2.0 * f64::from(u.y) - 1.0);
            let want = if x == 0.0 && y == 0.0 {
                (0.0, 0.0)
            } else if x.abs() > y.abs() {
                let t = std::f64::consts::FRAC_PI_4 * (y / x);
                (x * t.cos(), x * t.sin())
            } else {
                let t = std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (x / y);
                (y * t.cos(), y * t.sin())
            };
            let d = concentric_disc(u);
            assert!(
                (f64::from(d.x) - want.0).abs() < 4e-7,
                "{u}: {d} vs {want:?}"
            );
            assert!(
                (f64::from(d.y) - want.1).abs() < 4e-7,
                "{u}: {d} vs {want:?}"
            );
            assert!(d.length() <= 1.0, "{u}: {d}");
        }
    }

    #[test]
    fn alias_table_reproduces_the_weights() {
        let w = [1.0, 0.0, 3.0, 0.5, 2.5];
        let t = AliasTable::new(&w);
        let n = 70000;
        let mut counts = [0usize; 5];
        for i in 0..n {
            counts[t.sample((i as f32 + 0.5) / n as f32)] += 1;
        }
        for i in 0..5 {
            let want = w[i] / 7.0;
            assert!((t.pmf(i) as f64 - want).abs() < 1e-6);
            let got = counts[i] as f64 / n as f64;
            assert!((got - want).abs() < 2e-3, "{i}: {got} vs {want}");
        }
        // The remapped number is uniform within each outcome: its mean is 1/2.
        let mut sums = [0.0f64; 5];
        for i in 0..n {
            let (k, r) = t.sample_remap((i as f32 + 0.5) / n as f32);
            assert!((0.0..1.0).contains(&r));
            sums[k] += r as f64;
        }
        for i in [0, 2, 3, 4] {
            let mean = sums[i] / (t.pmf(i) as f64 * n as f64);
            assert!((mean - 0.5).abs() < 0.01, "{i}: {mean}");
        }
    }

    #[test]
    fn power_heuristic_limits() {
        assert_eq!(power_heuristic(1.0, 0.0), 1.0);
        assert_eq!(power_heuristic(0.0, 1.0), 0.0);
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
        assert!((power_heuristic(1.0, 1.0) - 0.5).abs() < 1e-7);
        assert!((power_heuristic(3.0, 1.0) + power_heuristic(1.0, 3.0) - 1.0).abs() < 1e-7);
    }
}
