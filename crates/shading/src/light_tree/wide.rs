//! A node of the tree as the descent reads it: up to four children side by side, each field
//! one 4-lane vector (structure of arrays), so that one pass of 4-wide arithmetic weighs all
//! of them at a vertex. Against the binary tree it is built from, the descent takes half the
//! levels and reads one node's consecutive cache lines per level instead of two scattered
//! nodes (1,000 lights + 2,000 panels: the descent was 46 % of the render time).

use crate::light_bounds::LightBounds;
use crate::light_choice::{remap, walk};
use glam::{BVec4A, Vec3, Vec4};

/// A child: a node's index, or a leaf's index with this bit set.
pub(super) const LEAF_BIT: u32 = 1 << 31;

/// An unused lane's child.
pub(super) const EMPTY: u32 = u32::MAX;

/// Up to four children's bounds, lane by lane (a [`LightBounds`] as its importance reads it:
/// sphere, cone with its sine, spread, power, sides), and who they are.
#[derive(Debug, Clone, Copy)]
pub(super) struct Wide {
    cx: Vec4,
    cy: Vec4,
    cz: Vec4,
    radius2: Vec4,
    ax: Vec4,
    ay: Vec4,
    az: Vec4,
    cos_o: Vec4,
    sin_o: Vec4,
    cos_e: Vec4,
    phi: Vec4,
    /// 1 in the lanes of two-sided emitters, else 0.
    two_sided: Vec4,
    /// Each lane's child ([`LEAF_BIT`], [`EMPTY`]).
    pub children: [u32; 4],
    /// Lanes whose child is a spot light's leaf, weighed exactly (their cone's falloff).
    pub spots: u8,
}

impl Wide {
    /// A node of up to four children (more are ignored): their bounds and child codes.
    pub(super) fn new(lanes: &[(LightBounds, u32)], spots: u8) -> Self {
        let mut f = [[0.0f32; 4]; 12];
        let mut children = [EMPTY; 4];
        for (k, (b, child)) in lanes.iter().take(4).enumerate() {
            let v = lanes_of(b);
            for (field, x) in f.iter_mut().zip(v) {
                field[k] = x;
            }
            children[k] = *child;
        }
        let v = |i: usize| Vec4::from_array(f[i]);
        Self {
            cx: v(0),
            cy: v(1),
            cz: v(2),
            radius2: v(3),
            ax: v(4),
            ay: v(5),
            az: v(6),
            cos_o: v(7),
            sin_o: v(8),
            cos_e: v(9),
            phi: v(10),
            two_sided: v(11),
            children,
            spots,
        }
    }

    /// Each lane's [`LightBounds::importance`] at `p` with normal `n` (both sides when
    /// `two_sided`): the same bound, four at a time; 0 in unused lanes.
    #[inline]
    pub(super) fn importance(&self, p: Vec3, n: Vec3, two_sided: bool) -> Vec4 {
        let (zero, one) = (Vec4::ZERO, Vec4::ONE);
        let dx = Vec4::splat(p.x) - self.cx;
        let dy = Vec4::splat(p.y) - self.cy;
        let dz = Vec4::splat(p.z) - self.cz;
        let d2 = dx * dx + dy * dy + dz * dz;
        // Inside the bounding sphere every direction is possible: no cone, no falloff.
        let inside = d2.cmple(self.radius2);
        let inv = sqrt4(d2).recip();
        let (tx, ty, tz) = (dx * inv, dy * inv, dz * inv);
        // Directions from `p` into the bounding sphere: a cone of half-angle θ_b.
        let sin2_b = self.radius2 / d2;
        let (sin_b, cos_b) = (sqrt4(sin2_b), sqrt4((one - sin2_b).max(zero)));
        let nd = Vec4::splat(n.x) * tx + Vec4::splat(n.y) * ty + Vec4::splat(n.z) * tz;
        let cos_i = if two_sided { nd.abs() } else { -nd };
        let sin_i = sqrt4((one - cos_i * cos_i).max(zero));
        let cos_recv = less_cos(sin_i, cos_i, sin_b, cos_b);
        let aw = self.ax * tx + self.ay * ty + self.az * tz;
        let cos_w = Vec4::select(self.two_sided.cmpgt(zero), aw.abs(), aw);
        let sin_w = sqrt4((one - cos_w * cos_w).max(zero));
        // The angle to the cone's edge, then less the bounding sphere's.
        let within = cos_w.cmpgt(self.cos_o);
        let sin_x = Vec4::select(within, zero, sin_w * self.cos_o - cos_w * self.sin_o);
        let cos_x = Vec4::select(within, one, cos_w * self.cos_o + sin_w * self.sin_o);
        let cos_emit = less_cos(sin_x, cos_x, sin_b, cos_b);
        // NaN fails both tests, as it ends the scalar bound at zero.
        let lit: BVec4A = cos_recv.cmpgt(zero) & cos_emit.cmpgt(self.cos_e);
        let outside = Vec4::select(lit, self.phi * cos_emit.max(zero) * cos_recv / d2, zero);
        // Inside, the receiver's cosine less θ_b = π: 1, or −cos θ_i where rounding took
        // cos θ_i to −1 or below (a point at the centre, whose direction is NaN here and zero
        // in the scalar bound, takes 1 as there).
        let recv_inside = Vec4::select(cos_i.cmple(-one), -cos_i, one);
        let v = Vec4::select(inside, self.phi * recv_inside / self.radius2, outside);
        // NaN and negatives are zero, an overflow the largest weight.
        Vec4::select(v.cmpgt(zero), v.min(Vec4::splat(f32::MAX)), zero)
    }
}

/// `cos(max(a − b, 0))` from the sines and cosines of `a` and `b` (lane by lane, as the
/// scalar bound's, pbrt-v4's `cosSubClamped`).
#[inline]
fn less_cos(sin_a: Vec4, cos_a: Vec4, sin_b: Vec4, cos_b: Vec4) -> Vec4 {
    Vec4::select(cos_a.cmpgt(cos_b), Vec4::ONE, cos_a * cos_b + sin_a * sin_b)
}

/// What [`Wide`] stores of `b` in its lanes: centre, squared radius, axis, `cos θ_o`,
/// `sin θ_o`, `cos θ_e`, power, two-sided (1 or 0).
fn lanes_of(b: &LightBounds) -> [f32; 12] {
    let (c, a) = (b.centre(), b.axis);
    [
        c.x,
        c.y,
        c.z,
        b.radius2(),
        a.x,
        a.y,
        a.z,
        b.cos_o,
        b.sin_o(),
        b.cos_e,
        b.phi,
        if b.two_sided { 1.0 } else { 0.0 },
    ]
}

/// Square roots of four lanes in one instruction (glam's `Vec4::sqrt` takes them one by one).
#[inline(always)]
fn sqrt4(v: Vec4) -> Vec4 {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE is part of every x86_64 target, so the instruction exists; it reads and
    // writes registers only.
    unsafe {
        std::arch::x86_64::_mm_sqrt_ps(v.into()).into()
    }
    #[cfg(target_arch = "aarch64")]
    // SAFETY: NEON is baseline on aarch64, so the instruction exists; it reads and writes
    // registers only.
    unsafe {
        std::arch::aarch64::vsqrtq_f32(v.into()).into()
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        v.sqrt()
    }
}

/// The choice among a node's children from their importances `w` and the uniform `u`: the
/// lane, its probability and `u` remapped; `None` when no child can light the vertex. The
/// probability is the same division [`lane_probability`] makes.
#[inline]
pub(super) fn choose(w: [f32; 4], u: f32) -> Option<(usize, f32, f32)> {
    let total = sum(w);
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let (k, wk, x) = walk(w.into_iter().enumerate(), u * total)?;
    Some((k, wk / total, remap(x, wk)))
}

/// The probability [`choose`] gives lane `k` of importances `w`.
#[inline]
pub(super) fn lane_probability(w: [f32; 4], k: usize) -> f32 {
    let total = sum(w);
    if !(total > 0.0 && total.is_finite()) {
        return 0.0;
    }
    w[k] / total
}

/// The lanes' sum, in one order for both the choice and the probability.
#[inline]
fn sum(w: [f32; 4]) -> f32 {
    ((w[0] + w[1]) + w[2]) + w[3]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 4-wide bound is the scalar one, lane by lane, at points inside and outside the
    /// bounds, on both sides, one- and two-sided.
    #[test]
    fn lanes_match_the_scalar_bound() {
        let spot = LightBounds {
            lo: Vec3::new(0.0, 2.0, 0.0),
            hi: Vec3::new(0.0, 2.0, 0.0),
            phi: 3.0,
            axis: Vec3::NEG_Y,
            cos_o: 0.9,
            cos_e: 0.8,
            two_sided: false,
        };
        let panel = LightBounds {
            lo: Vec3::new(-1.0, 0.5, -1.0),
            hi: Vec3::new(1.0, 0.6, 1.0),
            phi: 2.0,
            axis: Vec3::Y,
            cos_o: 0.95,
            cos_e: 0.0,
            two_sided: true,
        };
        let point = LightBounds {
            cos_o: -1.0,
            axis: Vec3::Z,
            lo: Vec3::new(3.0, 1.0, -2.0),
            hi: Vec3::new(3.0, 1.0, -2.0),
            ..spot
        };
        let bounds = [spot, panel, point];
        let lanes: Vec<(LightBounds, u32)> = bounds.iter().map(|b| (*b, 0)).collect();
        let wide = Wide::new(&lanes, 0);
        let points = [
            Vec3::ZERO,
            Vec3::new(0.2, 0.55, 0.1),
            Vec3::new(5.0, -1.0, 4.0),
        ];
        for p in points {
            for n in [Vec3::Y, Vec3::NEG_Y, Vec3::new(0.6, 0.0, 0.8)] {
                for two_sided in [false, true] {
                    let got = wide.importance(p, n, two_sided).to_array();
                    for (k, b) in bounds.iter().enumerate() {
                        let want = b.importance(p, n, two_sided);
                        let tol = 1e-5 * want.abs().max(1e-3);
                        assert!((got[k] - want).abs() <= tol, "{p} {n} {k}: {got:?} {want}");
                    }
                    assert_eq!(got[3], 0.0, "the unused lane");
                }
            }
        }
    }

    #[test]
    fn the_choice_follows_the_weights() {
        let w = [1.0, 0.0, 3.0, 0.0];
        assert_eq!(choose(w, 0.1).map(|c| c.0), Some(0));
        let (k, p, u) = choose(w, 0.5).unwrap();
        assert_eq!((k, p), (2, 0.75));
        assert!((u - (0.5 * 4.0 - 1.0) / 3.0).abs() < 1e-6);
        assert_eq!(lane_probability(w, 2), p);
        assert!(choose([0.0; 4], 0.5).is_none());
    }
}
