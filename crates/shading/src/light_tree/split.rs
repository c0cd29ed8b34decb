//! Where the build splits a node: pbrt-v4's surface area orientation heuristic (SAOH) over 12
//! buckets per axis, costing each side by power × the solid angle its cone lights × its box's
//! area; the median of the longest axis when buckets cannot separate the lights or when the
//! tree would grow too deep for the 64-bit trails.

use super::LightBounds;
use glam::Vec3;
use std::f32::consts::PI;

/// Buckets per axis.
const BUCKETS: usize = 12;

/// Depth from which only medians are taken: below it the trails' 64 bits still hold
/// ⌈log2 n⌉ more levels for any count of lights a `u32` indexes.
pub(super) const MEDIAN_DEPTH: u32 = 31;

/// A split: along `axis`, the `count` items of smallest centre coordinate go first.
pub(super) struct Split {
    pub axis: usize,
    pub count: usize,
}

/// The split of `items` (bounds and centres, two or more) at `depth`.
pub(super) fn choose(items: &[(LightBounds, Vec3)], depth: u32) -> Split {
    let (lo, hi) = items.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), it| (lo.min(it.1), hi.max(it.1)),
    );
    let extent = hi - lo;
    let longest = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let median = Split {
        axis: longest,
        count: items.len() / 2,
    };
    if depth >= MEDIAN_DEPTH {
        return median;
    }
    let mut best: Option<(f32, Split)> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 || !extent[axis].is_finite() {
            continue;
        }
        let Some((cost, split)) = best_on_axis(items, axis, lo[axis], extent) else {
            continue;
        };
        if best.as_ref().is_none_or(|b| cost < b.0) {
            best = Some((cost, split));
        }
    }
    best.map_or(median, |b| b.1)
}

/// The cheapest bucket boundary along `axis`: its cost and split.
fn best_on_axis(
    items: &[(LightBounds, Vec3)],
    axis: usize,
    lo: f32,
    extent: Vec3,
) -> Option<(f32, Split)> {
    let bucket =
        |c: Vec3| (((c[axis] - lo) / extent[axis] * BUCKETS as f32) as usize).min(BUCKETS - 1);
    let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
    let mut counts = [0usize; BUCKETS];
    for (b, c) in items {
        let k = bucket(*c);
        counts[k] += 1;
        buckets[k] = Some(buckets[k].map_or(*b, |x| x.union(b)));
    }
    // Costs of the boundaries from both ends.
    let mut below = [0.0f32; BUCKETS];
    let mut acc: Option<LightBounds> = None;
    for k in 0..BUCKETS - 1 {
        acc = union(acc, buckets[k]);
        below[k] = acc.map_or(0.0, |b| cost(&b));
    }
    let mut above: Option<LightBounds> = None;
    let mut best: Option<(f32, usize)> = None;
    for k in (1..BUCKETS).rev() {
        above = union(above, buckets[k]);
        let left: usize = counts[..k].iter().sum();
        if left == 0 || left == items.len() {
            continue;
        }
        let c = below[k - 1] + above.map_or(0.0, |b| cost(&b));
        if best.is_none_or(|b| c < b.0) {
            best = Some((c, k));
        }
    }
    let (c, k) = best?;
    // pbrt's regularisation: thin slabs across the longest axis cost more.
    let kr = extent.max_element() / extent[axis];
    let count = counts[..k].iter().sum();
    Some((c * kr, Split { axis, count }))
}

fn union(a: Option<LightBounds>, b: Option<LightBounds>) -> Option<LightBounds> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.union(&b)),
        (a, None) => a,
        (None, b) => b,
    }
}

/// A node's cost: power × the solid-angle measure of its cone (pbrt's `M_Ω`) × its box's area.
fn cost(b: &LightBounds) -> f32 {
    let theta_o = b.cos_o.clamp(-1.0, 1.0).acos();
    let theta_e = b.cos_e.clamp(-1.0, 1.0).acos();
    let theta_w = (theta_o + theta_e).min(PI);
    let sin_o = theta_o.sin();
    let m_omega = 2.0 * PI * (1.0 - b.cos_o)
        + PI / 2.0
            * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                + b.cos_o);
    let d = b.hi - b.lo;
    let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
    let c = b.phi * m_omega * area;
    if c.is_finite() {
        c
    } else {
        f32::MAX
    }
}
