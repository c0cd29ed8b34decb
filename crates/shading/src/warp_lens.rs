//! Warps of the lens clipped by its barrel (optical vignetting, issue 61): uniform points in the
//! intersection of the aperture and a second, offset disc. Beside `warp.rs`, which is full.

use crate::warp::concentric_disc;
use glam::Vec2;
use std::f64::consts::{FRAC_PI_2, PI};

/// Uniform point in the intersection of the unit disc and the disc of `radius` around `centre`,
/// from `u ∈ [0,1)²`; `None` when they do not meet.
///
/// When the unit disc lies inside the other, this is [`concentric_disc`]`(u)` bit for bit (an
/// unclipped lens is unchanged). Otherwise the lens-shaped region is cut in chords across the
/// line of centres: `u.x` picks the chord by the inverse of the area on one side of it (two
/// circular segments meeting at the common chord, solved by safeguarded Newton in `f64`), `u.y`
/// the point along it. Continuous and area-preserving, so strata of `u` stay strata.
pub fn disc_in_disc(u: Vec2, centre: Vec2, radius: f32) -> Option<Vec2> {
    let d = centre.length();
    if !(d.is_finite() && radius > 0.0) || d >= 1.0 + radius {
        return None;
    }
    if d + 1.0 <= radius {
        return Some(concentric_disc(u));
    }
    if d + radius <= 1.0 {
        return Some(concentric_disc(u) * radius + centre);
    }
    let lens = Lens::new(f64::from(d), f64::from(radius));
    let lo = lens.d - lens.r;
    let w = if radius == 1.0 {
        first_guess(d, u.x)
    } else {
        f64::from(u.x)
    };
    let s = lens.invert(f64::from(u.x) * lens.total, lo + (1.0 - lo) * w);
    let t = (2.0 * f64::from(u.y) - 1.0) * lens.half_width(s);
    let e = centre / d;
    Some(e * s as f32 + e.perp() * t as f32)
}

/// The lens-shaped intersection of the unit disc and a disc of radius `r` at distance `d` along
/// +s, in chord coordinates: left of the common chord it is the second disc's cap, right of it
/// the unit disc's.
struct Lens {
    d: f64,
    r: f64,
    chord: f64,
    left: f64,
    /// The unit disc's area left of the chord (what its cap's area is measured from).
    unit_left: f64,
    total: f64,
}

impl Lens {
    fn new(d: f64, r: f64) -> Self {
        let chord = (d * d + 1.0 - r * r) / (2.0 * d);
        // Two unit discs (the camera's barrel): the chord halves the offset, and the unit
        // disc's part left of it is the mirror of the barrel's cap, `π − left`.
        let (left, unit_left) = if r == 1.0 {
            let left = segment(1.0, -0.5 * d);
            (left, PI - left)
        } else {
            (segment(r, chord - d), segment(1.0, chord))
        };
        let total = left + PI - unit_left;
        Self {
            d,
            r,
            chord,
            left,
            unit_left,
            total,
        }
    }

    /// Half the chord's length at `s`.
    fn half_width(&self, s: f64) -> f64 {
        let h2 = if s <= self.chord {
            let q = s - self.d;
            self.r * self.r - q * q
        } else {
            1.0 - s * s
        };
        h2.max(0.0).sqrt()
    }

    /// The region's area left of `s`.
    fn area_left_of(&self, s: f64) -> f64 {
        if s <= self.chord {
            segment(self.r, s - self.d)
        } else {
            self.left + segment(1.0, s) - self.unit_left
        }
    }

    /// The `s` whose left area is `target`: Halley's method (the area's derivatives are
    /// the chord's length `2h` and `−2q/h`, `q` the offset from the arc's centre), falling
    /// back to bisection whenever a step would leave the bracket, from `start`. It stops at
    /// the first step whose error estimate for the point it reaches, `C·step³` with
    /// `C = (q² + ρ²/6) / h⁴` (Halley's cubic term; `ρ` the arc's radius), is below 1e-10 and
    /// the step below 1e-3: far below the `f32` result's resolution (about 6e-8), without
    /// evaluating the area there once more (one `asin` a step).
    fn invert(&self, target: f64, start: f64) -> f64 {
        let (mut lo, mut hi) = (self.d - self.r, 1.0);
        let mut s = start.clamp(lo, hi);
        for _ in 0..48 {
            let g = self.area_left_of(s) - target;
            if g > 0.0 {
                hi = s;
            } else {
                lo = s;
            }
            let (q, rho) = if s <= self.chord {
                (s - self.d, self.r)
            } else {
                (s, 1.0)
            };
            let h = self.half_width(s);
            // f' = 2h, f'' = −2q/h: Halley's step 2 g f' / (2 f'² − g f'').
            let (f1, f2) = (2.0 * h, -2.0 * q / h);
            let mut next = s - 2.0 * g * f1 / (2.0 * f1 * f1 - g * f2);
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            let step = (next - s).abs();
            let h2 = h * h;
            let c = q * q + rho * rho / 6.0;
            if step <= 1e-8 || (step <= 1e-3 && c * step * step * step <= 1e-10 * h2 * h2) {
                return next;
            }
            s = next;
        }
        s
    }
}

/// Resolution of [`first_guess`]'s table: offsets `d ∈ [0, 2]` by the number of areas.
const GUESS: (usize, usize) = (64, 64);

/// A first guess of [`Lens::invert`] for two unit discs `d` apart (the camera's case: the barrel
/// has the aperture's radius), as the fraction of the way from the region's left end to its
/// right: bilinear in a table of exact inverses, made once. Newton then needs about 2 steps
/// instead of 4; the result does not depend on the guess beyond the `f32` resolution.
fn first_guess(d: f32, u: f32) -> f64 {
    static TABLE: std::sync::OnceLock<Vec<f64>> = std::sync::OnceLock::new();
    let (nd, nu) = GUESS;
    let table = TABLE.get_or_init(|| {
        let mut t = Vec::with_capacity((nd + 1) * (nu + 1));
        for i in 0..=nd {
            let d = (2.0 * i as f64 / nd as f64).clamp(1e-4, 2.0 - 1e-4);
            let lens = Lens::new(d, 1.0);
            let lo = d - 1.0;
            for j in 0..=nu {
                let f = j as f64 / nu as f64;
                let s = lens.invert(f * lens.total, lo + (1.0 - lo) * f);
                t.push(((s - lo) / (1.0 - lo)).clamp(0.0, 1.0));
            }
        }
        t
    });
    let x = (f64::from(d) * 0.5 * nd as f64).clamp(0.0, nd as f64);
    let y = (f64::from(u) * nu as f64).clamp(0.0, nu as f64);
    let (i, j) = ((x as usize).min(nd - 1), (y as usize).min(nu - 1));
    let (fx, fy) = (x - i as f64, y - j as f64);
    let at = |i: usize, j: usize| table[i * (nu + 1) + j];
    let a = at(i, j) + (at(i, j + 1) - at(i, j)) * fy;
    let b = at(i + 1, j) + (at(i + 1, j + 1) - at(i + 1, j)) * fy;
    a + (b - a) * fx
}

/// Area of the disc of radius `rho` (centred at 0) left of `x`.
fn segment(rho: f64, x: f64) -> f64 {
    let q = (x / rho).clamp(-1.0, 1.0);
    rho * rho * (q.asin() + q * (1.0 - q * q).max(0.0).sqrt() + FRAC_PI_2)
}

/// Uniform point of a shape (`sample`, a uniform warp of `[0,1)²` onto it) that also lies in the
/// disc of `radius` around `centre`: the first of `u` and up to 63 numbers hashed from it whose
/// point is inside (rejection, deterministic in `u`). For shapes without a closed-form clipped
/// warp (the blade polygon). After 64 misses (when the two barely meet) the last point is pulled
/// into the disc.
pub fn clipped_by_disc(u: Vec2, sample: impl Fn(Vec2) -> Vec2, centre: Vec2, radius: f32) -> Vec2 {
    // A relative 1e-6 of slack: a point of a shape inscribed in the disc stays itself.
    let r2 = radius * radius * (1.0 + 2e-6);
    let (p, inside) = first_inside(u, sample, |p| (p - centre).length_squared() <= r2);
    let off = p - centre;
    let len = off.length();
    if !inside && len > radius {
        centre + off * (radius / len)
    } else {
        p
    }
}

/// Rejection deterministic in `u`: the point `sample` makes of the first of `u` and up to 63
/// numbers hashed from it (SplitMix64) that `inside` accepts, and `true`; after 63 misses the
/// 64th point, untested, and `false`. Every sample stays a pure function of its numbers.
pub fn first_inside(
    u: Vec2,
    sample: impl Fn(Vec2) -> Vec2,
    inside: impl Fn(Vec2) -> bool,
) -> (Vec2, bool) {
    let mut h = u64::from(u.x.to_bits()) | (u64::from(u.y.to_bits()) << 32);
    let mut p = sample(u);
    for _ in 0..63 {
        if inside(p) {
            return (p, true);
        }
        h = splitmix64(h);
        let unit = |b: u64| (b >> 40) as f32 * (1.0 / (1u64 << 24) as f32);
        p = sample(Vec2::new(unit(h), unit(h << 24)));
    }
    (p, false)
}

/// SplitMix64's step: a well-mixed 64-bit hash of `x`.
fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
