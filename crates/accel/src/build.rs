//! Building the structure: bottom-level BVHs per shared mesh plus one world-space BVH of the
//! meshes drawn once, a top-level BVH over them, and, for animation, reusing the bottom-level
//! BVHs of meshes that did not change since the previous frame.

use crate::node::{layout::nodes_from_cwbvh, Node};
use crate::{
    detect_avx2, Accel, AccelStats, Blas, BvhQuality, Entry, InstanceInput, MeshInput, Tri,
    FLATTENED,
};
use glam::{Affine3A, Vec3};
use obvhs::{
    aabb::Aabb, bvh2::reinsertion::ReinsertionOptimizer, cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh,
    ploc::PlocBuilder, BvhBuildParams,
};
use rayon::prelude::*;

/// Depth (levels of nodes) of a tree; children always follow their parent in `nodes`.
fn tree_depth(nodes: &[Node]) -> usize {
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
    p.max_prims_per_leaf = 3;
    p
}

fn build_cwbvh(aabbs: &[Aabb], quality: BvhQuality) -> (Vec<Node>, Vec<u32>) {
    if aabbs.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let p = build_params(quality);
    let mut bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
        p.ploc_search_distance,
        aabbs,
        (0..aabbs.len() as u32).collect(),
        p.sort_precision,
        p.search_depth_threshold,
    );
    ReinsertionOptimizer::default().run(&mut bvh2, p.reinsertion_batch_ratio, None);
    let cw = bvh2_to_cwbvh(&bvh2, p.max_prims_per_leaf, true, false);
    let nodes = nodes_from_cwbvh(&cw.nodes, &cw.primitive_indices, aabbs);
    (nodes, cw.primitive_indices)
}

/// Why a triangle is left out.
#[derive(Debug, Clone, Copy, PartialEq)]
enum TriCheck {
    Ok([Vec3; 3]),
    OutOfRange,
    Degenerate,
}

fn check_triangle(positions: &[Vec3], tri: [u32; 3]) -> TriCheck {
    let mut p = [Vec3::ZERO; 3];
    for k in 0..3 {
        match positions.get(tri[k] as usize) {
            Some(v) => p[k] = *v,
            None => return TriCheck::OutOfRange,
        }
    }
    classify(p)
}

fn classify(p: [Vec3; 3]) -> TriCheck {
    if !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()) {
        return TriCheck::Degenerate;
    }
    // In f64 the edges of f32 points and their products are exact, so this is exactly "the
    // three points are collinear", without a tolerance that would depend on the scene's scale.
    let [a, b, c] = p.map(|v| v.as_dvec3());
    if (b - a).cross(c - a) == glam::DVec3::ZERO {
        return TriCheck::Degenerate;
    }
    TriCheck::Ok(p)
}

fn aabb_of(p: &[Vec3; 3]) -> Aabb {
    let lo = p[0].min(p[1]).min(p[2]);
    let hi = p[0].max(p[1]).max(p[2]);
    Aabb::new(lo.into(), hi.into())
}

/// Builds one bottom-level BVH from kept triangles (`(vertices, original index, instance)`).
fn build_blas(tris: Vec<(Tri, u32)>, quality: BvhQuality, keep_instance: bool) -> Blas {
    let aabbs: Vec<Aabb> = tris.iter().map(|(t, _)| aabb_of(&t.p)).collect();
    let (nodes, order) = build_cwbvh(&aabbs, quality);
    drop(aabbs);
    let bounds = tris.iter().fold(None, |acc: Option<(Vec3, Vec3)>, (t, _)| {
        let (lo, hi) = (
            t.p[0].min(t.p[1]).min(t.p[2]),
            t.p[0].max(t.p[1]).max(t.p[2]),
        );
        Some(acc.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))))
    });
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
    }
}

/// World bounds of an object-space box, widened by a relative margin so that rounding in the
/// transform (of the box here, of the ray at query time) cannot make the box miss a hit.
fn world_bounds(world_from_object: &Affine3A, (lo, hi): (Vec3, Vec3)) -> Aabb {
    let mut wlo = Vec3::splat(f32::INFINITY);
    let mut whi = Vec3::splat(f32::NEG_INFINITY);
    for k in 0..8 {
        let c = Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let w = world_from_object.transform_point3(c);
        wlo = wlo.min(w);
        whi = whi.max(w);
    }
    let margin = 1e-5
        * wlo
            .abs()
            .max(whi.abs())
            .max_element()
            .max(f32::MIN_POSITIVE);
    Aabb::new((wlo - margin).into(), (whi + margin).into())
}

/// `object_from_world` for a usable instance transform, computed in f64 for accuracy.
fn invert(world_from_object: &Affine3A) -> Option<Affine3A> {
    let m = world_from_object;
    if !(m.matrix3.is_finite() && m.translation.is_finite()) {
        return None;
    }
    let d = glam::DAffine3::from_mat3_translation(m.matrix3.as_dmat3(), m.translation.as_dvec3());
    let det = d.matrix3.determinant();
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = d.inverse();
    let f = Affine3A::from_mat3_translation(inv.matrix3.as_mat3(), inv.translation.as_vec3());
    (f.matrix3.is_finite() && f.translation.is_finite()).then_some(f)
}

/// What an animation frame's structure may take from the previous frame's (see
/// [`Accel::build_frame`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct FrameHints<'a> {
    /// Per instance: its transform may change between frames, so it is kept out of the
    /// world-space BVH (moving it then only rebuilds the top level). Empty: none moves.
    pub moving: &'a [bool],
    /// Meshes from this index on deform between frames (skins, morph targets): kept out of the
    /// world-space BVH and rebuilt every frame; `meshes[..deforming_from]` are the same geometry
    /// in every frame, and their bottom-level BVHs are reused. `usize::MAX` (as
    /// [`FrameHints::STILL`]): nothing deforms and nothing is reused.
    pub deforming_from: usize,
    /// When the still instances draw at most this many triangles in all (each instance
    /// counted), every one of them goes into the world-space BVH, shared meshes too: one level
    /// to walk, no per-instance ray transform, and the interleaved queries apply. Above it, a
    /// mesh drawn more than once keeps one object-space BVH (memory bounded by the unique
    /// triangles). [`FLATTEN_SHARED_LIMIT`] by default; 0 keeps every shared mesh instanced.
    pub flatten_shared_up_to: usize,
}

/// The default of [`FrameHints::flatten_shared_up_to`]: 2^20 drawn triangles, so flattening
/// costs at most about 60 MB (a triangle takes about 60 bytes with its share of the nodes).
pub const FLATTEN_SHARED_LIMIT: usize = 1 << 20;

impl FrameHints<'_> {
    /// A still scene: no instance moves, no mesh deforms (what [`Accel::build`] assumes).
    pub const STILL: FrameHints<'static> = FrameHints {
        moving: &[],
        deforming_from: usize::MAX,
        flatten_shared_up_to: FLATTEN_SHARED_LIMIT,
    };
}

/// A key of the world-space BVH's contents: which instances of which meshes, with which
/// transforms. Equal keys (and static meshes) mean an equal BVH.
fn flat_key(flat: &[(u32, InstanceInput)]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |w: u32| {
        for b in w.to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for (id, inst) in flat {
        eat(*id);
        eat(inst.mesh);
        for v in inst.world_from_object.to_cols_array() {
            eat(v.to_bits());
        }
    }
    h
}

/// Per mesh: validity counts, and the kept triangles if a bottom-level BVH is to be built.
struct Checked {
    shared: Vec<(Tri, u32)>,
    kept: usize,
    degenerate: usize,
    out_of_range: usize,
}

fn check_mesh(mesh: &MeshInput<'_>, keep: bool) -> Checked {
    let mut c = Checked {
        shared: Vec::new(),
        kept: 0,
        degenerate: 0,
        out_of_range: 0,
    };
    for (i, tri) in mesh.indices.iter().enumerate() {
        match check_triangle(mesh.positions, *tri) {
            TriCheck::Ok(p) => {
                c.kept += 1;
                if keep {
                    c.shared.push((Tri { p, prim: i as u32 }, 0));
                }
            }
            TriCheck::OutOfRange => c.out_of_range += 1,
            TriCheck::Degenerate => c.degenerate += 1,
        }
    }
    c
}

/// The flattened instances' triangles in world space, tagged with the instance, and how many
/// triangles only become degenerate there (rounding).
fn flatten(meshes: &[MeshInput<'_>], flat: &[(u32, InstanceInput)]) -> (Vec<(Tri, u32)>, usize) {
    let mut tris: Vec<(Tri, u32)> = Vec::new();
    let mut degenerate = 0;
    for (id, inst) in flat {
        let mesh = &meshes[inst.mesh as usize];
        let world: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|p| inst.world_from_object.transform_point3(*p))
            .collect();
        for (i, tri) in mesh.indices.iter().enumerate() {
            match check_triangle(&world, *tri) {
                TriCheck::Ok(p) => tris.push((Tri { p, prim: i as u32 }, *id)),
                TriCheck::Degenerate
                    if check_triangle(mesh.positions, *tri) != TriCheck::Degenerate =>
                {
                    degenerate += 1
                }
                _ => {}
            }
        }
    }
    (tris, degenerate)
}

/// A bound on the magnitudes met when moving an instance's points between object and world
/// space, `|T| + |M| max|p_obj|`, for [`Accel::spawn_point`].
fn magnitude(mesh: &MeshInput<'_>, m: &Affine3A) -> f32 {
    let obj = mesh
        .positions
        .iter()
        .filter(|p| p.is_finite())
        .fold(0.0f32, |m, p| m.max(p.abs().max_element()));
    let rows = m.matrix3.transpose();
    let norm = [rows.x_axis, rows.y_axis, rows.z_axis]
        .iter()
        .map(|r| r.abs().element_sum())
        .fold(0.0f32, f32::max);
    m.translation.abs().max_element() + norm * obj
}

/// Where each instance goes: the usable ones (a mesh that exists, an invertible transform),
/// how often each mesh is drawn, which instances the world-space BVH holds, and which meshes
/// need a BVH of their own.
struct Placement {
    usable: Vec<(u32, InstanceInput, Affine3A)>,
    uses: Vec<u32>,
    flat: Vec<(u32, InstanceInput)>,
    own_blas: Vec<bool>,
    skipped: usize,
}

/// Flattens what neither moves nor deforms and is drawn once, or, in scenes drawing at most
/// `hints.flatten_shared_up_to` still triangles, everything that neither moves nor deforms.
fn placement(
    meshes: &[MeshInput<'_>],
    instances: &[InstanceInput],
    hints: &FrameHints<'_>,
) -> Placement {
    let mut usable: Vec<(u32, InstanceInput, Affine3A)> = Vec::with_capacity(instances.len());
    let mut uses = vec![0u32; meshes.len()];
    let mut skipped = 0;
    for (i, inst) in instances.iter().enumerate() {
        let inv = invert(&inst.world_from_object);
        match (meshes.get(inst.mesh as usize), inv) {
            (Some(_), Some(inv)) => {
                uses[inst.mesh as usize] += 1;
                usable.push((i as u32, *inst, inv));
            }
            _ => skipped += 1,
        }
    }
    let is_static = |id: u32, m: usize| {
        !hints.moving.get(id as usize).copied().unwrap_or(false) && m < hints.deforming_from
    };
    let static_drawn: usize = usable
        .iter()
        .filter(|(id, inst, _)| is_static(*id, inst.mesh as usize))
        .map(|(_, inst, _)| meshes[inst.mesh as usize].indices.len())
        .sum();
    let flatten_all = static_drawn <= hints.flatten_shared_up_to;
    let flattened = |id: u32, m: usize| (uses[m] == 1 || flatten_all) && is_static(id, m);
    let flat: Vec<(u32, InstanceInput)> = usable
        .iter()
        .filter(|(id, inst, _)| flattened(*id, inst.mesh as usize))
        .map(|(id, inst, _)| (*id, *inst))
        .collect();
    let mut own_blas = vec![false; meshes.len()];
    for (id, inst, _) in &usable {
        let m = inst.mesh as usize;
        own_blas[m] |= !flattened(*id, m);
    }
    Placement {
        usable,
        uses,
        flat,
        own_blas,
        skipped,
    }
}

/// A bottom-level BVH to make: built from triangles, or taken from the previous frame.
enum BlasJob {
    Build(Vec<(Tri, u32)>, bool),
    Reuse(Blas),
}

impl Accel {
    /// Builds the structure with obvhs (PLOC, reinsertion, CWBVH conversion) for each mesh drawn
    /// more than once, one world-space BVH for the meshes drawn once, and a top-level BVH over the
    /// instances. Invalid input is left out and counted in [`Accel::stats`], never a panic.
    pub fn build(
        meshes: &[MeshInput<'_>],
        instances: &[InstanceInput],
        quality: BvhQuality,
    ) -> Self {
        Self::build_frame(meshes, instances, quality, FrameHints::STILL, None)
    }

    /// [`Accel::build`] for one frame of an animation: instances that `hints` says move, and
    /// meshes that deform, get bottom-level BVHs of their own (object space); the bottom-level
    /// BVHs of unchanged meshes, and the world-space BVH of unmoving instances, are taken from
    /// `previous` (the last frame's structure, built with the same hints) instead of being
    /// rebuilt; the top level is always rebuilt. The result does not depend on `previous`: it is
    /// exactly what a build without it makes, only faster ([`AccelStats::reused_blases`]).
    pub fn build_frame(
        meshes: &[MeshInput<'_>],
        instances: &[InstanceInput],
        quality: BvhQuality,
        hints: FrameHints<'_>,
        mut previous: Option<Accel>,
    ) -> Self {
        let start = std::time::Instant::now();
        let mut stats = AccelStats::default();

        let Placement {
            usable,
            uses,
            flat,
            own_blas,
            skipped,
        } = placement(meshes, instances, &hints);
        stats.skipped_instances = skipped;
        stats.flattened_instances = flat.len();

        // What the previous frame offers: unchanged meshes' BVHs and the world-space BVH.
        let reusable = |m: usize| m < hints.deforming_from && hints.deforming_from != usize::MAX;
        let key = flat_key(&flat);
        let mut taken = vec![None; meshes.len()];
        let mut flat_taken = None;
        if let Some(prev) = previous.as_mut() {
            for m in (0..meshes.len()).filter(|&m| own_blas[m] && reusable(m)) {
                if let Some(&b) = prev.blas_of_mesh.get(m).filter(|&&b| b != u32::MAX) {
                    taken[m] = Some(std::mem::take(&mut prev.blases[b as usize]));
                }
            }
            if prev.flat.is_some_and(|(k, _)| k == key) && !flat.is_empty() {
                flat_taken = Some((std::mem::take(&mut prev.blases[0]), prev.flat_degenerate));
            }
        }
        drop(previous);

        let checked: Vec<Checked> = meshes
            .par_iter()
            .enumerate()
            .map(|(m, mesh)| check_mesh(mesh, own_blas[m] && taken[m].is_none()))
            .collect();
        for (m, c) in checked.iter().enumerate() {
            stats.degenerate_triangles += c.degenerate;
            stats.invalid_index_triangles += c.out_of_range;
            if uses[m] > 0 {
                stats.unique_triangles += c.kept;
                stats.drawn_triangles += c.kept * uses[m] as usize;
            }
        }

        // Bottom-level BVHs, built in parallel: index 0 is the flattened one (if any).
        let mut jobs: Vec<BlasJob> = Vec::new();
        let mut flat_degenerate = 0;
        if !flat.is_empty() {
            jobs.push(match flat_taken {
                Some((blas, degenerate)) => {
                    flat_degenerate = degenerate;
                    BlasJob::Reuse(blas)
                }
                None => {
                    let (tris, degenerate) = flatten(meshes, &flat);
                    flat_degenerate = degenerate;
                    BlasJob::Build(tris, true)
                }
            });
        }
        stats.degenerate_triangles += flat_degenerate;
        let has_flat = !jobs.is_empty();
        let mut blas_of_mesh = vec![u32::MAX; meshes.len()];
        for ((m, c), reused) in checked.into_iter().enumerate().zip(taken) {
            if !own_blas[m] {
                continue;
            }
            match reused {
                Some(blas) => {
                    blas_of_mesh[m] = jobs.len() as u32;
                    jobs.push(BlasJob::Reuse(blas));
                }
                None if !c.shared.is_empty() => {
                    blas_of_mesh[m] = jobs.len() as u32;
                    jobs.push(BlasJob::Build(c.shared, false));
                }
                None => {}
            }
        }
        stats.reused_blases = jobs
            .iter()
            .filter(|j| matches!(j, BlasJob::Reuse(_)))
            .count();
        let blases: Vec<Blas> = jobs
            .into_par_iter()
            .map(|job| match job {
                BlasJob::Build(tris, keep_instance) => build_blas(tris, quality, keep_instance),
                BlasJob::Reuse(blas) => blas,
            })
            .collect();
        let mut accel = Self::top_level(blases, has_flat, &usable, &blas_of_mesh, quality);
        accel.blas_of_mesh = blas_of_mesh;
        accel.flat = has_flat.then_some((key, flat.len()));
        accel.flat_degenerate = flat_degenerate;
        accel.instance_magnitude = vec![0.0f32; instances.len()];
        for (id, inst, _) in &usable {
            let mesh = &meshes[inst.mesh as usize];
            accel.instance_magnitude[*id as usize] = magnitude(mesh, &inst.world_from_object);
        }
        stats.blas_count = accel.blases.len();
        stats.tlas_entries = accel.entries.len();
        stats.bvh_nodes =
            accel.tlas.len() + accel.blases.iter().map(|b| b.nodes.len()).sum::<usize>();
        stats.max_blas_depth = accel.max_blas_depth;
        stats.memory_bytes = accel
            .blases
            .iter()
            .map(|b| {
                b.nodes.len() * size_of::<Node>()
                    + b.tris.len() * size_of::<Tri>()
                    + b.tri_instance.len() * 4
            })
            .sum::<usize>()
            + accel.tlas.len() * size_of::<Node>()
            + accel.entries.len() * size_of::<Entry>();
        stats.build_time = start.elapsed();
        accel.stats = stats;
        accel
    }

    /// The top-level BVH over the world-space BVH (`blases[0]` when `has_flat`) and the
    /// instances of meshes with bottom-level BVHs of their own.
    fn top_level(
        blases: Vec<Blas>,
        has_flat: bool,
        usable: &[(u32, InstanceInput, Affine3A)],
        blas_of_mesh: &[u32],
        quality: BvhQuality,
    ) -> Self {
        let mut entries = Vec::new();
        let mut bounds = Vec::new();
        if has_flat {
            if let Some(b) = blases[0].bounds {
                entries.push(Entry {
                    blas: 0,
                    instance: FLATTENED,
                    object_from_world: Affine3A::IDENTITY,
                    identity: true,
                });
                bounds.push(world_bounds(&Affine3A::IDENTITY, b));
            }
        }
        for (id, inst, inv) in usable {
            let b = blas_of_mesh[inst.mesh as usize];
            if b == u32::MAX {
                continue;
            }
            let Some(bb) = blases[b as usize].bounds else {
                continue;
            };
            entries.push(Entry {
                blas: b,
                instance: *id,
                object_from_world: *inv,
                identity: false,
            });
            bounds.push(world_bounds(&inst.world_from_object, bb));
        }
        let (tlas, order) = if entries.len() > 1 {
            build_cwbvh(&bounds, quality)
        } else {
            (Vec::new(), (0..entries.len() as u32).collect())
        };
        let entries: Vec<Entry> = order.iter().map(|&i| entries[i as usize]).collect();
        let tlas_bounds = bounds
            .iter()
            .map(|b| (Vec3::from(b.min), Vec3::from(b.max)))
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
            .unwrap_or((Vec3::ZERO, Vec3::ZERO));
        let tlas_depth = tree_depth(&tlas);
        let max_blas_depth = blases.iter().map(|b| b.depth).max().unwrap_or(0);
        Self {
            blases,
            entries,
            tlas,
            tlas_depth,
            tlas_bounds,
            max_blas_depth,
            instance_magnitude: Vec::new(),
            avx2: detect_avx2(),
            stats: AccelStats::default(),
            blas_of_mesh: Vec::new(),
            flat: None,
            flat_degenerate: 0,
        }
    }
}
