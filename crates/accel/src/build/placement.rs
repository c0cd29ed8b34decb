//! Where each instance goes: into the world-space BVH, or over a bottom-level BVH of its mesh
//! (and what an animation frame tells about that).

use crate::deform::VertexMotion;
use crate::motion::MotionTransform;
use crate::types::{InstanceInput, MeshInput};
use glam::Affine3A;

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
/// [`Accel::build_frame`](crate::Accel::build_frame)).
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
    /// When the world-space BVH's instances draw at least this many triangles (before
    /// checks), it is built per instance in parallel and joined under a tree over their boxes
    /// ([`JOIN_FROM`](crate::JOIN_FROM) by default; `usize::MAX`: always one build).
    pub join_from: usize,
    /// Per instance: how it moves within the shutter (`None`: it stays at
    /// `world_from_object`); empty: nothing moves. A moving instance is walked at each ray's
    /// [`Ray::time`](crate::Ray::time) and bounded over its whole interval.
    pub motion: &'a [Option<MotionTransform>],
    /// Per mesh: its vertices keyed over the shutter when it deforms within it (`None`, or a
    /// vertex count other than the mesh's: it stays as given); empty: nothing deforms. Such a
    /// mesh gets a bottom-level BVH of its own over its swept triangles, walked at each ray's
    /// [`Ray::time`](crate::Ray::time); the mesh's `positions` are the frame's (for lookups).
    pub deforming: &'a [Option<VertexMotion>],
}

/// The default of [`FrameHints::flatten_shared_up_to`]: 2^20 drawn triangles, so flattening
/// costs at most about 60 MB (a triangle takes about 60 bytes with its share of the nodes).
pub const FLATTEN_SHARED_LIMIT: usize = 1 << 20;

/// The default of [`FrameHints::join_from`]: world-space sets drawing at least 2^17 triangles
/// (before checks) are built per instance, in parallel, and joined, unless the instances' boxes
/// overlap much; smaller ones are built as one tree. From 2^17 joining pays on two cores: 16
/// tiles of 980 k triangles build in 0.21–0.24 s instead of 0.53–0.61 s, the 567 k interior
/// renders in 0.86× the wall time, the images the same bytes (BENCHMARKS.md, issue 63).
pub const JOIN_FROM: usize = 1 << 17;

impl FrameHints<'_> {
    /// A still scene: no instance moves, no mesh deforms (what [`Accel::build`](crate::Accel::build) assumes).
    pub const STILL: FrameHints<'static> = FrameHints {
        moving: &[],
        deforming_from: usize::MAX,
        flatten_shared_up_to: FLATTEN_SHARED_LIMIT,
        join_from: JOIN_FROM,
        motion: &[],
        deforming: &[],
    };
}

/// The keys of mesh `m` when it deforms within the shutter (`hints.deforming`, for as many
/// vertices as it has).
pub(super) fn deform_of<'h>(
    meshes: &[MeshInput<'_>],
    hints: &FrameHints<'h>,
    m: usize,
) -> Option<&'h VertexMotion> {
    let keys = hints.deforming.get(m)?.as_ref()?;
    (keys.vertex_count() == meshes.get(m)?.positions.len()).then_some(keys)
}

/// A key of the world-space BVH's contents: which meshes, with which transforms, in order.
/// Equal keys (and static meshes) mean an equal BVH but for the instance each triangle
/// names: instances that come and go before them (keyed visibility) renumber the same
/// placements, whose BVH is then taken over with its instance numbers changed.
pub(super) fn flat_key(flat: &[(u32, InstanceInput)]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |w: u32| {
        for b in w.to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for (_, inst) in flat {
        eat(inst.mesh);
        for v in inst.world_from_object.to_cols_array() {
            eat(v.to_bits());
        }
    }
    h
}

/// Where each instance goes: the usable ones (a mesh that exists, an invertible transform),
/// how often each mesh is drawn, which instances the world-space BVH holds, and which meshes
/// need a BVH of their own.
pub(super) struct Placement {
    pub(super) usable: Vec<(u32, InstanceInput, Affine3A)>,
    pub(super) uses: Vec<u32>,
    pub(super) flat: Vec<(u32, InstanceInput)>,
    pub(super) own_blas: Vec<bool>,
    pub(super) skipped: usize,
}

/// Flattens what neither moves nor deforms and is drawn once, or, in scenes drawing at most
/// `hints.flatten_shared_up_to` still triangles, everything that neither moves nor deforms.
pub(super) fn placement(
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
        !hints.moving.get(id as usize).copied().unwrap_or(false)
            && hints.motion.get(id as usize).is_none_or(Option::is_none)
            && m < hints.deforming_from
            && deform_of(meshes, hints, m).is_none()
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
