//! One BVH from boxes with obvhs (PLOC, reinsertion) collapsed to our nodes, and a
//! bottom-level BVH from triangles.

use super::collapse::{collapse, Decisions};
use crate::deform::Deform;
use crate::node::Node;
use crate::structure::Blas;
use crate::triangle::Tri;
use crate::types::BvhQuality;
use glam::Vec3;
use obvhs::{
    aabb::Aabb,
    bvh2::{reinsertion::ReinsertionOptimizer, Bvh2},
    ploc::PlocBuilder,
    BvhBuildParams,
};
use std::sync::Mutex;

/// Depth (levels of nodes) of a tree; children always follow their parent in `nodes`.
pub(super) fn tree_depth(nodes: &[Node]) -> usize {
    let mut depth = vec![0u32; nodes.len()];
    let mut max = 0u32;
    for i in 0..nodes.len() {
        let d = if i == 0 { 1 } else { depth[i] };
        depth[i] = d;
        max = max.max(d);
        let n = &nodes[i];
        let children = n.imask.count_ones();
        for c in 0..children {
            if let Some(slot) = depth.get_mut((n.child_base_idx + c) as usize) {
                *slot = d + 1;
            }
        }
    }
    max as usize
}

fn build_params(quality: BvhQuality) -> BvhBuildParams {
    // Chosen by measurement (BlenderIO-32bitIndices, Embree's 1 M thin-lens rays, one thread,
    // interleaved runs on the shared 2-core machine; 1 M-triangle terrain build from
    // `benches/benches/accel.rs`):
    //   obvhs preset      closest Mrays/s   build 130 k   build 1 M
    //   very_fast_build   2.9 - 3.1         47 - 62 ms    0.46 s
    //   fast_build        3.3 - 3.5         63 - 75 ms    0.53 s
    //   medium_build      2.0 - 3.0         62 - 110 ms   0.60 s
    //   slow_build        2.3 - 2.7         110 - 160 ms  (not benched)
    // Then refined with callgrind instruction counts of closest-hit queries (deterministic, unlike
    // timings on that machine; 10 k thin-lens rays x 3, same scene), from fast_build:
    //   as is (search depth threshold 2, reinsertion 0.02)   35.44 M   build  87 - 118 ms
    //   search depth threshold 0                             34.64 M           87 -  95 ms
    //   threshold 0, reinsertion 0.1                         34.39 M           95 - 119 ms
    //   threshold 0, reinsertion 0.3                         34.34 M          180 - 250 ms
    //   threshold 0, reinsertion 1.0                         34.19 M          380 - 395 ms
    //   reinsertion 0.3, search Minimum                      39.01 M
    //   medium_build (search Medium)                         40.37 M
    //   very_fast_build                                      42.17 M
    // so Medium and High start from fast_build with the threshold off (the full Low search from
    // the first PLOC pass: fewer nodes visited at no build cost here); Medium keeps the light
    // reinsertion, High reinserts every node once (4x the build for 1.3 % fewer instructions).
    // Fast stays very_fast_build, the quickest build. More PLOC search (medium_build, High's
    // preset before) made worse trees for this traversal.
    // Spatial pre-splits are never used: they clip triangle boxes with rounded planes, which
    // would void the conservative box test.
    let mut p = match quality {
        BvhQuality::Fast => BvhBuildParams::very_fast_build(),
        BvhQuality::Medium => BvhBuildParams::fast_build(),
        BvhQuality::High => BvhBuildParams {
            reinsertion_batch_ratio: 1.0,
            ..BvhBuildParams::fast_build()
        },
    };
    if quality != BvhQuality::Fast {
        p.search_depth_threshold = 0;
    }
    p.pre_split = false;
    p
}

/// obvhs' builder and binary tree and the collapse's cost table, kept between builds so that
/// many small builds (the pieces of a joined tree) reuse their allocations instead of faulting
/// fresh pages in each time; lent to one build at a time. Dropping it frees them.
#[derive(Default)]
pub(super) struct Scratch(Mutex<Vec<Lent>>);

/// What one build lends from a [`Scratch`]: obvhs' builder and binary tree, and the collapse's
/// cost table.
type Lent = (PlocBuilder, Bvh2, Decisions);

impl Scratch {
    fn take(&self) -> Lent {
        let lent = self.0.lock().ok().and_then(|mut v| v.pop());
        lent.unwrap_or_else(|| (PlocBuilder::new(), Bvh2::default(), Decisions::new()))
    }

    fn give(&self, lent: Lent) {
        if let Ok(mut v) = self.0.lock() {
            v.push(lent);
        }
    }
}

/// A CWBVH over `aabbs` with at most `leaf_size` primitives a leaf (1 to 3): its nodes and
/// the primitive order of its leaves.
pub(super) fn build_cwbvh(
    aabbs: &[Aabb],
    quality: BvhQuality,
    leaf_size: u32,
) -> (Vec<Node>, Vec<u32>) {
    build_cwbvh_in(aabbs, quality, leaf_size, &Scratch::default())
}

/// [`build_cwbvh`] with its allocations taken from `scratch` (the same tree).
pub(super) fn build_cwbvh_in(
    aabbs: &[Aabb],
    quality: BvhQuality,
    leaf_size: u32,
    scratch: &Scratch,
) -> (Vec<Node>, Vec<u32>) {
    if aabbs.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let mut p = build_params(quality);
    p.max_prims_per_leaf = leaf_size;
    let (mut builder, mut bvh2, mut decisions) = scratch.take();
    builder.build_with_bvh(
        &mut bvh2,
        p.ploc_search_distance,
        aabbs,
        (0..aabbs.len() as u32).collect(),
        p.sort_precision,
        p.search_depth_threshold,
    );
    ReinsertionOptimizer::default().run(&mut bvh2, p.reinsertion_batch_ratio, None);
    let (nodes, order) = collapse(&bvh2, p.max_prims_per_leaf, &mut decisions);
    scratch.give((builder, bvh2, decisions));
    (nodes, order)
}

/// [`build_cwbvh_in`] with leaves of up to three primitives, and the union of `aabbs`.
pub(super) fn build_ordered(
    aabbs: &[Aabb],
    quality: BvhQuality,
    scratch: &Scratch,
) -> (Vec<Node>, Vec<u32>, Option<(Vec3, Vec3)>) {
    let (nodes, order) = build_cwbvh_in(aabbs, quality, 3, scratch);
    let bounds = aabbs.iter().fold(None, |acc: Option<(Vec3, Vec3)>, b| {
        let (lo, hi) = (Vec3::from(b.min), Vec3::from(b.max));
        Some(acc.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))))
    });
    (nodes, order, bounds)
}

/// A triangle's box.
pub(super) fn aabb_of(p: &[Vec3; 3]) -> Aabb {
    let lo = p[0].min(p[1]).min(p[2]);
    let hi = p[0].max(p[1]).max(p[2]);
    Aabb::new(lo.into(), hi.into())
}

/// Builds one bottom-level BVH from kept triangles (`(vertices, original index, instance)`);
/// with `deform` (their keys over the shutter, in the order of `tris`), over the boxes the
/// triangles sweep.
pub(super) fn build_blas(
    tris: Vec<(Tri, u32)>,
    quality: BvhQuality,
    keep_instance: bool,
    deform: Option<Deform>,
) -> Blas {
    let aabbs: Vec<Aabb> = match &deform {
        None => tris.iter().map(|(t, _)| aabb_of(&t.p)).collect(),
        Some(d) => (0..tris.len())
            .map(|i| {
                let (lo, hi) = d.swept_box(i);
                Aabb::new(lo.into(), hi.into())
            })
            .collect(),
    };
    let (nodes, order, bounds) = build_ordered(&aabbs, quality, &Scratch::default());
    drop(aabbs);
    let ordered: Vec<Tri> = order.iter().map(|&i| tris[i as usize].0).collect();
    let tri_instance = if keep_instance {
        order.iter().map(|&i| tris[i as usize].1).collect()
    } else {
        Vec::new()
    };
    let depth = tree_depth(&nodes);
    let box_bounds = bounds.unwrap_or((Vec3::ZERO, Vec3::ZERO));
    Blas {
        nodes,
        tris: ordered,
        tri_instance,
        depth,
        bounds,
        box_bounds,
        deform: deform.map(|d| Box::new(d.reorder(&order))),
        pieces: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` scattered boxes from `seed`.
    fn boxes(n: usize, seed: u32) -> Vec<Aabb> {
        let mut s = seed;
        let mut next = || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1u32 << 24) as f32
        };
        (0..n)
            .map(|_| {
                let c = Vec3::new(next(), next(), next()) * 40.0;
                let h = Vec3::new(next(), next(), next()) * 0.5;
                Aabb::new((c - h).into(), (c + h).into())
            })
            .collect()
    }

    /// obvhs' own one-shot build and CWBVH conversion (`PlocBuilder::with_capacity(..).build`,
    /// `bvh2_to_cwbvh`, as trees were built before the scratch pool and the collapse), with
    /// its nodes in our layout. It repeats `build_cwbvh_in`'s PLOC and reinsertion calls on
    /// purpose: the reference shares no code with what it checks.
    fn one_shot(aabbs: &[Aabb], quality: BvhQuality, leaf: u32) -> (Vec<Node>, Vec<u32>) {
        let mut p = build_params(quality);
        p.max_prims_per_leaf = leaf;
        let mut bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
            p.ploc_search_distance,
            aabbs,
            (0..aabbs.len() as u32).collect(),
            p.sort_precision,
            p.search_depth_threshold,
        );
        ReinsertionOptimizer::default().run(&mut bvh2, p.reinsertion_batch_ratio, None);
        let cw = obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh(&bvh2, leaf, true, false);
        let nodes = crate::node::layout::nodes_from_cwbvh(&cw.nodes, &cw.primitive_indices, aabbs);
        (nodes, cw.primitive_indices)
    }

    /// Every quality and leaf size: (quality, primitives a leaf).
    fn settings() -> impl Iterator<Item = (BvhQuality, u32)> {
        [BvhQuality::Fast, BvhQuality::Medium, BvhQuality::High]
            .into_iter()
            .flat_map(|q| (1..=3).map(move |l| (q, l)))
    }

    /// Asserts that `build_cwbvh_in` with `scratch` builds obvhs' one-shot tree over `b`, node
    /// for node, and the same primitive order.
    fn assert_obvhs_tree(b: &[Aabb], quality: BvhQuality, leaf: u32, scratch: &Scratch, at: &str) {
        let (fresh, fresh_order) = one_shot(b, quality, leaf);
        let (ours, order) = build_cwbvh_in(b, quality, leaf, scratch);
        let at = format!("{at}, {quality:?}, leaves of {leaf}");
        assert_eq!(fresh_order, order, "{at}");
        assert_eq!(fresh.len(), ours.len(), "{at}");
        let key = |n: &Node| {
            let links = (n.child_base_idx, n.primitive_base_idx, n.imask);
            (n.child_meta, links, n.bounds)
        };
        for (a, r) in fresh.iter().zip(&ours) {
            assert_eq!(key(a), key(r), "{at}");
        }
    }

    /// Unit boxes on a grid: equal costs everywhere, so the collapse must break ties as obvhs
    /// does (the first of equal splits) to build its tree.
    #[test]
    fn collapse_of_a_grid_breaks_ties_as_obvhs() {
        let b: Vec<Aabb> = (0..16 * 16 * 8)
            .map(|i| {
                let c = Vec3::new((i % 16) as f32, (i / 16 % 16) as f32, (i / 256) as f32);
                Aabb::new((c - 0.5).into(), (c + 0.5).into())
            })
            .collect();
        for (quality, leaf) in settings() {
            assert_obvhs_tree(&b, quality, leaf, &Scratch::default(), "grid");
        }
    }

    /// Every quality and leaf size, with allocations reused from bigger and smaller builds
    /// before: the tree is obvhs' one-shot build and conversion, node for node.
    #[test]
    fn collapse_with_reuse_builds_obvhs_trees() {
        let scratch = Scratch::default();
        let sizes = [
            (3000, 1),
            (40, 2),
            (700, 3),
            (1, 4),
            (2, 6),
            (3, 7),
            (2500, 5),
        ];
        for (quality, leaf) in settings() {
            for (n, seed) in sizes {
                let at = format!("{n} boxes");
                assert_obvhs_tree(&boxes(n, seed), quality, leaf, &scratch, &at);
            }
        }
        assert_eq!(scratch.0.lock().map(|v| v.len()).unwrap_or(0), 1);
    }
}
