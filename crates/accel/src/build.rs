//! Building the structure: bottom-level BVHs per shared mesh plus one world-space BVH of the
//! meshes drawn once, a top-level BVH over them, and, for animation, reusing the bottom-level
//! BVHs of meshes that did not change since the previous frame.

mod bounds;
mod check;
mod collapse;
mod counts;
mod join;
mod placement;
mod tree;

use crate::deform::Deform;
use crate::deform::VertexMotion;
use crate::motion::MotionTransform;
use crate::node::Node;
use crate::structure::{Accel, Blas, Entry, FLATTENED, NO_MOTION};
use crate::triangle::Tri;
use crate::types::{AccelStats, BvhQuality, InstanceInput, MeshInput};
use crate::walk::detect_avx2;
use bounds::world_bounds;
use check::{check_mesh, flatten, Checked};
use glam::{Affine3A, Vec3};
use join::build_joined;
use obvhs::aabb::Aabb;
use placement::{deform_of, flat_key, placement, Placement};
pub use placement::{FrameHints, FLATTEN_SHARED_LIMIT, JOIN_FROM};
use rayon::prelude::*;
use tree::{build_blas, build_cwbvh, tree_depth};

/// Structures built by [`Accel::build_frame`] in this process ([`builds`]).
static BUILDS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// How many structures [`Accel::build`] and [`Accel::build_frame`] have built in this process
/// so far: what a command that needs no ray queries (`aperture info`) shows it did not pay for.
pub fn builds() -> usize {
    BUILDS.load(std::sync::atomic::Ordering::Relaxed)
}

/// A usable instance: its index, its input and its `object_from_world`.
type Usable = (u32, InstanceInput, Affine3A);

/// [`world_bounds`] of an object-space box over every time of a moving instance's interval.
fn swept_world_bounds(motion: &MotionTransform, object: (Vec3, Vec3)) -> Aabb {
    let (lo, hi) = motion.swept_bounds(object);
    let margin = 1e-5 * lo.abs().max(hi.abs()).max_element().max(f32::MIN_POSITIVE);
    Aabb::new((lo - margin).into(), (hi + margin).into())
}

/// A bound on the magnitudes met when moving an instance's points between object and world
/// space, `|T| + |M| max|p_obj|`, for [`Accel::spawn_point`]; `max|p_obj|` over every key
/// of a deforming mesh too.
fn magnitude(mesh: &MeshInput<'_>, deform: Option<&VertexMotion>, m: &Affine3A) -> f32 {
    let obj = mesh
        .positions
        .iter()
        .filter(|p| p.is_finite())
        .fold(0.0f32, |m, p| m.max(p.abs().max_element()))
        .max(deform.map_or(0.0, VertexMotion::max_abs));
    let rows = m.matrix3.transpose();
    let norm = [rows.x_axis, rows.y_axis, rows.z_axis]
        .iter()
        .map(|r| r.abs().element_sum())
        .fold(0.0f32, f32::max);
    m.translation.abs().max_element() + norm * obj
}

/// Per input instance, the bound on the magnitudes met moving its points between object and
/// world space ([`magnitude`]), for [`Accel::spawn_point`].
fn instance_magnitudes(
    meshes: &[MeshInput<'_>],
    instances: &[InstanceInput],
    usable: &[Usable],
    hints: &FrameHints<'_>,
) -> Vec<f32> {
    let mut out = vec![0.0f32; instances.len()];
    // Each reads every vertex of its mesh: in parallel (50 M triangles' vertices are 1.8 GB).
    let bounds: Vec<(u32, f32)> = usable
        .par_iter()
        .map(|(id, inst, _)| {
            let mesh = &meshes[inst.mesh as usize];
            let keys = deform_of(meshes, hints, inst.mesh as usize);
            (*id, magnitude(mesh, keys, &inst.world_from_object))
        })
        .collect();
    for (id, m) in bounds {
        out[id as usize] = m;
    }
    // A moving instance's points meet the magnitudes of every place it passes: the bound
    // at its keys and between them (sampled as its swept box is).
    for (id, keys) in hints.motion.iter().enumerate() {
        let (Some(keys), Some(inst)) = (keys, instances.get(id)) else {
            continue;
        };
        // An instance of no mesh is not drawn (counted as skipped).
        let Some(mesh) = meshes.get(inst.mesh as usize) else {
            continue;
        };
        let deform = deform_of(meshes, hints, inst.mesh as usize);
        let most = (0..=32)
            .map(|k| magnitude(mesh, deform, &keys.at(k as f32 / 32.0)))
            .fold(0.0f32, f32::max);
        let m = &mut out[id];
        *m = m.max(most);
    }
    out
}

/// A bottom-level BVH to make: built from triangles, or taken from the previous frame.
enum BlasJob {
    Build(Vec<(Tri, u32)>, bool, Option<Deform>),
    /// Built already (the world-space BVH of a large set, built in pieces in parallel).
    Built(Blas),
    Reuse(Blas),
}

/// What the previous frame offers.
struct Previous {
    /// Per mesh: its unchanged bottom-level BVH, for the meshes that need one now.
    taken: Vec<Option<Blas>>,
    /// The world-space BVH (with its count of triangles degenerate in world space) when it
    /// holds the same placements (`key`).
    flat_taken: Option<(Blas, usize)>,
    /// The unchanged bottom-level BVHs of meshes that need none now, kept for a later frame.
    spare: Vec<(u32, Blas)>,
}

/// What the previous frame offers (see [`Previous`]). The bottom-level BVH of a mesh no
/// instance draws in its own BVH this frame (keyed hidden, say) is kept aside rather than
/// dropped, so a mesh that is shown again is not rebuilt.
fn take_previous(
    mut previous: Option<Accel>,
    mesh_count: usize,
    own_blas: &[bool],
    hints: &FrameHints<'_>,
    (key, flat): (u64, &[(u32, InstanceInput)]),
) -> Previous {
    let reusable = |m: usize| {
        m < hints.deforming_from
            && hints.deforming_from != usize::MAX
            && hints.deforming.get(m).is_none_or(Option::is_none)
    };
    let mut out = Previous {
        taken: vec![None; mesh_count],
        flat_taken: None,
        spare: Vec::new(),
    };
    let Some(prev) = previous.as_mut() else {
        return out;
    };
    let mut kept: Vec<Option<Blas>> = vec![None; mesh_count];
    for m in (0..mesh_count).filter(|&m| reusable(m)) {
        // A tree built over a shutter's swept triangles is no still mesh's.
        let still = |b: &&u32| {
            prev.blases
                .get(**b as usize)
                .is_some_and(|t| t.deform.is_none())
        };
        if let Some(&b) = prev.blas_of_mesh.get(m).filter(still) {
            kept[m] = Some(std::mem::take(&mut prev.blases[b as usize]));
        }
    }
    for (m, blas) in prev.spare.drain(..) {
        if let Some(k) = kept.get_mut(m as usize).filter(|_| reusable(m as usize)) {
            k.get_or_insert(blas);
        }
    }
    for (m, k) in kept.into_iter().enumerate() {
        match k {
            Some(blas) if own_blas[m] => out.taken[m] = Some(blas),
            Some(blas) => out.spare.push((m as u32, blas)),
            None => {}
        }
    }
    match prev.flat.take() {
        Some((k, ids)) if k == key && ids.len() == flat.len() && !flat.is_empty() => {
            let mut blas = std::mem::take(&mut prev.blases[0]);
            renumber(&mut blas.tri_instance, &ids, flat);
            out.flat_taken = Some((blas, prev.flat_degenerate));
        }
        _ => {}
    }
    out
}

/// The instance of each triangle of a world-space BVH built over `old` (its instances,
/// ascending) renamed to the instance at the same place of `flat` (the same placements).
fn renumber(tri_instance: &mut [u32], old: &[u32], flat: &[(u32, InstanceInput)]) {
    if old.iter().zip(flat).all(|(o, (n, _))| o == n) {
        return;
    }
    for id in tri_instance {
        if let Ok(k) = old.binary_search(id) {
            *id = flat[k].0;
        }
    }
}

/// The meshes' validity counts into `stats`, drawn triangles counted per use.
fn count_checked(stats: &mut AccelStats, checked: &[Checked], uses: &[u32]) {
    for (m, c) in checked.iter().enumerate() {
        stats.degenerate_triangles += c.degenerate;
        stats.invalid_index_triangles += c.out_of_range;
        if uses[m] > 0 {
            stats.unique_triangles += c.kept;
            stats.drawn_triangles += c.kept * uses[m] as usize;
        }
    }
}

/// The bottom-level BVHs to make, in order: index 0 is the world-space one (if any).
struct BlasJobs {
    jobs: Vec<BlasJob>,
    /// Per mesh: its index in `jobs`, or `u32::MAX`.
    blas_of_mesh: Vec<u32>,
    has_flat: bool,
    /// Triangles that only became degenerate in world space when flattened.
    flat_degenerate: usize,
}

/// The world-space BVH's job (taken from `flat_taken` or built from `flat`), then one per
/// mesh with a BVH of its own (taken from `taken` or built from its checked triangles).
fn blas_jobs(
    (meshes, hints, quality): (&[MeshInput<'_>], &FrameHints<'_>, BvhQuality),
    flat: &[(u32, InstanceInput)],
    flat_taken: Option<(Blas, usize)>,
    checked: Vec<Checked>,
    taken: Vec<Option<Blas>>,
    own_blas: &[bool],
) -> BlasJobs {
    let mut jobs: Vec<BlasJob> = Vec::new();
    let mut flat_degenerate = 0;
    if !flat.is_empty() {
        jobs.push(match flat_taken {
            Some((blas, degenerate)) => {
                flat_degenerate = degenerate;
                BlasJob::Reuse(blas)
            }
            None => match build_joined(meshes, flat, quality, hints.join_from) {
                Some((blas, degenerate)) => {
                    flat_degenerate = degenerate;
                    BlasJob::Built(blas)
                }
                None => {
                    let (tris, degenerate) = flatten(meshes, flat);
                    flat_degenerate = degenerate;
                    BlasJob::Build(tris, true, None)
                }
            },
        });
    }
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
                let deform = deform_of(meshes, hints, m)
                    .and_then(|keys| Deform::new(&c.shared, meshes[m].indices, keys));
                jobs.push(BlasJob::Build(c.shared, false, deform));
            }
            None => {}
        }
    }
    BlasJobs {
        jobs,
        blas_of_mesh,
        has_flat,
        flat_degenerate,
    }
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
        previous: Option<Accel>,
    ) -> Self {
        let start = std::time::Instant::now();
        BUILDS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
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

        let key = flat_key(&flat);
        let Previous {
            taken,
            flat_taken,
            spare,
        } = take_previous(previous, meshes.len(), &own_blas, &hints, (key, &flat));

        let checked: Vec<Checked> = meshes
            .par_iter()
            .enumerate()
            .map(|(m, mesh)| check_mesh(mesh, own_blas[m] && taken[m].is_none()))
            .collect();
        count_checked(&mut stats, &checked, &uses);

        let jobs = blas_jobs(
            (meshes, &hints, quality),
            &flat,
            flat_taken,
            checked,
            taken,
            &own_blas,
        );
        stats.degenerate_triangles += jobs.flat_degenerate;
        stats.reused_blases = jobs
            .jobs
            .iter()
            .filter(|j| matches!(j, BlasJob::Reuse(_)))
            .count();
        let blases: Vec<Blas> = jobs
            .jobs
            .into_par_iter()
            .map(|job| match job {
                BlasJob::Build(tris, keep_instance, deform) => {
                    build_blas(tris, quality, keep_instance, deform)
                }
                BlasJob::Built(blas) | BlasJob::Reuse(blas) => blas,
            })
            .collect();
        let has_flat = jobs.has_flat;
        let mut accel = Self::top_level(
            blases,
            has_flat,
            (&usable, hints.motion),
            &jobs.blas_of_mesh,
            quality,
        );
        accel.blas_of_mesh = jobs.blas_of_mesh;
        accel.flat = has_flat.then(|| (key, flat.iter().map(|(id, _)| *id).collect()));
        accel.flat_degenerate = jobs.flat_degenerate;
        accel.spare = spare;
        accel.instance_magnitude = instance_magnitudes(meshes, instances, &usable, &hints);
        accel.count_structure(&mut stats);
        stats.build_time = start.elapsed();
        accel.stats = stats;
        accel
    }

    /// The sizes of the built structure into `stats`: trees, entries, nodes, depth, memory.
    fn count_structure(&self, stats: &mut AccelStats) {
        stats.blas_count = self.blases.len();
        stats.tlas_entries = self.entries.len();
        stats.bvh_nodes =
            self.tlas.len() + self.blases.iter().map(|b| b.nodes.len()).sum::<usize>();
        stats.max_blas_depth = self.max_blas_depth;
        stats.joined_pieces = self.blases.iter().map(|b| b.pieces).sum();
        let blases = self.blases.iter();
        stats.node_bytes = (self.tlas.len() + blases.clone().map(|b| b.nodes.len()).sum::<usize>())
            * size_of::<Node>();
        stats.triangle_bytes = blases
            .clone()
            .map(|b| {
                b.tris.len() * size_of::<Tri>()
                    + b.deform
                        .as_ref()
                        .map_or(0, |d| d.keys.len() * size_of::<[Vec3; 3]>())
            })
            .sum();
        stats.instance_bytes = blases.map(|b| b.tri_instance.len() * 4).sum::<usize>()
            + self.entries.len() * size_of::<Entry>();
        stats.memory_bytes = stats.node_bytes + stats.triangle_bytes + stats.instance_bytes;
    }

    /// The top-level BVH over the world-space BVH (`blases[0]` when `has_flat`) and the
    /// instances of meshes with bottom-level BVHs of their own.
    fn top_level(
        blases: Vec<Blas>,
        has_flat: bool,
        (usable, motion): (&[Usable], &[Option<MotionTransform>]),
        blas_of_mesh: &[u32],
        quality: BvhQuality,
    ) -> Self {
        let mut entries = Vec::new();
        let mut bounds = Vec::new();
        let mut motions = Vec::new();
        if has_flat {
            if let Some(b) = blases[0].bounds {
                entries.push(Entry {
                    blas: 0,
                    instance: FLATTENED,
                    object_from_world: Affine3A::IDENTITY,
                    identity: true,
                    motion: NO_MOTION,
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
            let moving = motion.get(*id as usize).and_then(Option::as_ref);
            entries.push(Entry {
                blas: b,
                instance: *id,
                object_from_world: *inv,
                identity: false,
                motion: moving.map_or(NO_MOTION, |_| motions.len() as u32),
            });
            bounds.push(match moving {
                Some(m) => {
                    motions.push(m.clone());
                    swept_world_bounds(m, bb)
                }
                None => world_bounds(&inst.world_from_object, bb),
            });
        }
        let (tlas, order) = if entries.len() > 1 {
            build_cwbvh(&bounds, quality, 3)
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
            spare: Vec::new(),
            motions,
        }
    }
}
