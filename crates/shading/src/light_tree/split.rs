//! Where the build splits a node: pbrt-v4's surface area orientation heuristic (SAOH) over 12
//! buckets per axis, costing each side by power × the solid angle its cone lights × its box's
//! area; the median of the longest axis when buckets cannot separate the lights or when the
//! tree would grow too deep (a leaf's probability gathers at most 64 levels).

use super::tree::Leaf;
use crate::light_bounds::LightBounds;
use glam::Vec3;
use std::f32::consts::PI;

/// Buckets per axis.
const BUCKETS: usize = 12;

/// Depth from which only medians are taken, so that the binary tree stays under 64 levels
/// (31 + ⌈log2 n⌉ for any count of lights a `u32` indexes) and the wide tree under 32.
pub(super) const MEDIAN_DEPTH: u32 = 31;

/// A leaf waiting for its place: its bound, light and the centre it is sorted by.
pub(super) type Item = (LightBounds, Leaf, Vec3);

/// A split: along `axis`, the `count` items of smallest centre coordinate go first.
pub(super) struct Split {
    pub axis: usize,
    pub count: usize,
}

/// The split of `items` (bounds and centres, two or more) at `depth`.
pub(super) fn choose(items: &[Item], depth: u32) -> Split {
    let (lo, hi) = items.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), it| (lo.min(it.2), hi.max(it.2)),
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
fn best_on_axis(items: &[Item], axis: usize, lo: f32, extent: Vec3) -> Option<(f32, Split)> {
    let bucket =
        |c: Vec3| (((c[axis] - lo) / extent[axis] * BUCKETS as f32) as usize).min(BUCKETS - 1);
    let (buckets, counts) = bucket_bounds(items, bucket);
    // Costs of the boundaries from both ends; an empty bucket changes no bound (small nodes
    // leave most buckets empty).
    let mut below = [0.0f32; BUCKETS];
    let mut acc: Option<LightBounds> = None;
    for k in 0..BUCKETS - 1 {
        below[k] = match buckets[k] {
            None if k > 0 => below[k - 1],
            b => {
                acc = union(acc, b);
                acc.map_or(0.0, |b| cost(&b))
            }
        };
    }
    let mut above: Option<LightBounds> = None;
    let mut above_cost = 0.0;
    let mut best: Option<(f32, usize)> = None;
    for k in (1..BUCKETS).rev() {
        if buckets[k].is_some() {
            above = union(above, buckets[k]);
            above_cost = above.map_or(0.0, |b| cost(&b));
        }
        let left: usize = counts[..k].iter().sum();
        if left == 0 || left == items.len() {
            continue;
        }
        let c = below[k - 1] + above_cost;
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

/// Each bucket's bound (for costs only: a node's own bound is its children's exact union)
/// and item count. A bucket's cone is centred on its lights' mean axis and holds every
/// light's cone, found in two passes of dot products instead of one exact cone union (three
/// inverse cosines) per light and axis: the build's costliest part.
fn bucket_bounds(
    items: &[Item],
    bucket: impl Fn(Vec3) -> usize,
) -> ([Option<LightBounds>; BUCKETS], [usize; BUCKETS]) {
    let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
    let mut counts = [0usize; BUCKETS];
    for (b, _, c) in items {
        let k = bucket(*c);
        counts[k] += 1;
        buckets[k] = Some(match buckets[k] {
            None => *b,
            Some(x) => {
                // Two-sided emitters light the same way along either normal.
                let axis = if b.two_sided && x.axis.dot(b.axis) < 0.0 {
                    -b.axis
                } else {
                    b.axis
                };
                LightBounds {
                    lo: x.lo.min(b.lo),
                    hi: x.hi.max(b.hi),
                    phi: x.phi + b.phi,
                    axis: x.axis + axis,
                    cos_o: 1.0,
                    cos_e: x.cos_e.min(b.cos_e),
                    two_sided: x.two_sided || b.two_sided,
                }
            }
        });
    }
    for x in buckets.iter_mut().flatten() {
        x.axis = x.axis.normalize_or(Vec3::Z);
        x.cos_o = 1.0;
    }
    for (b, _, c) in items {
        if let Some(x) = buckets[bucket(*c)].as_mut() {
            let d = x.axis.dot(b.axis);
            let d = if b.two_sided { d.abs() } else { d };
            x.cos_o = x.cos_o.min(cos_sum(d.clamp(-1.0, 1.0), b.cos_o));
        }
    }
    (buckets, counts)
}

/// `cos(α + β)` for angles in `[0, π]` given by their cosines, −1 past π.
fn cos_sum(cos_a: f32, cos_b: f32) -> f32 {
    if cos_b < -cos_a {
        return -1.0;
    }
    let sin = |c: f32| (1.0 - c * c).max(0.0).sqrt();
    (cos_a * cos_b - sin(cos_a) * sin(cos_b)).max(-1.0)
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
