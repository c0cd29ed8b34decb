//! The acceleration structure's data: the bottom-level BVHs, the top level's entries and
//! [`Accel`] itself (its queries, builds and lookups live in their own modules).

use crate::deform::Deform;
use crate::motion::MotionTransform;
use crate::node::Node;
use crate::triangle::Tri;
use crate::types::AccelStats;
use glam::{Affine3A, Vec3};

/// A bottom-level BVH over one mesh (object space) or over all flattened meshes (world space).
#[derive(Debug, Clone, Default)]
pub(crate) struct Blas {
    pub(crate) nodes: Vec<Node>,
    pub(crate) tris: Vec<Tri>,
    /// For the flattened BVH only: the instance of each triangle (BVH order). Empty otherwise.
    pub(crate) tri_instance: Vec<u32>,
    pub(crate) depth: usize,
    pub(crate) bounds: Option<(Vec3, Vec3)>,
    /// `bounds`, or a zero box for an empty tree (sizes the box test's rounding slack).
    pub(crate) box_bounds: (Vec3, Vec3),
    /// For a mesh deforming within the shutter: its triangles keyed over it (the nodes then
    /// bound the swept triangles, and `tris` holds the frame's, for lookups only).
    pub(crate) deform: Option<Box<Deform>>,
    /// How many pieces it was joined from (`build::join`; 0: built as one tree).
    pub(crate) pieces: usize,
}

/// One leaf of the top-level BVH: a BVH placed in the world.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Entry {
    pub(crate) blas: u32,
    /// The instance, or `FLATTENED` when the triangles carry their own.
    pub(crate) instance: u32,
    pub(crate) object_from_world: Affine3A,
    /// The flattened BVH is already in world space: skip the ray transform.
    pub(crate) identity: bool,
    /// Index into [`Accel::motions`] of a moving instance, or [`NO_MOTION`].
    pub(crate) motion: u32,
}

/// [`Entry::motion`] of an entry that stays put.
pub(crate) const NO_MOTION: u32 = u32::MAX;

pub(crate) const FLATTENED: u32 = u32::MAX;

/// The acceleration structure: answers ray queries from many threads at once.
///
/// Layout: a top-level obvhs CWBVH over instance bounds whose leaves point at bottom-level CWBVHs
/// (one per mesh drawn more than once, stored once however many instances draw it), plus one
/// world-space CWBVH holding every mesh that is drawn exactly once. Rays are moved into object
/// space per instance with `object_from_world` without renormalising the direction, so `t` stays
/// in world units.
#[derive(Debug, Clone)]
pub struct Accel {
    pub(crate) blases: Vec<Blas>,
    /// In top-level BVH order.
    pub(crate) entries: Vec<Entry>,
    pub(crate) tlas: Vec<Node>,
    pub(crate) tlas_depth: usize,
    /// Bounds of all instance bounds.
    pub(crate) tlas_bounds: (Vec3, Vec3),
    pub(crate) max_blas_depth: usize,
    /// Per input instance: a bound on the magnitudes met when moving its points between object
    /// and world space (`|T| + |M| max|p_obj|`), for [`Accel::spawn_point`].
    pub(crate) instance_magnitude: Vec<f32>,
    /// Node tests take the 8-wide AVX2 path (detected at build time; the x86_64 baseline is SSE2,
    /// 4 wide). Both compute the same operations: the same node masks, the same hits. On aarch64
    /// it selects the NEON kernels (else the scalar walk, which other architectures take).
    #[cfg_attr(
        not(any(target_arch = "x86_64", target_arch = "aarch64")),
        allow(dead_code)
    )]
    pub(crate) avx2: bool,
    pub(crate) stats: AccelStats,
    /// Per input mesh: its bottom-level BVH in `blases`, or `u32::MAX` (flattened, or not drawn).
    pub(crate) blas_of_mesh: Vec<u32>,
    /// The world-space BVH's key and its instances (ascending), when there is one (`blases[0]`).
    pub(crate) flat: Option<(u64, Vec<u32>)>,
    /// Triangles that only became degenerate in world space when flattened.
    pub(crate) flat_degenerate: usize,
    /// Bottom-level BVHs of unchanged meshes this frame does not use (by mesh), kept for the
    /// next frame's [`Accel::build_frame`]: a mesh keyed hidden for a while is not rebuilt
    /// when shown again. Never walked.
    pub(crate) spare: Vec<(u32, Blas)>,
    /// The transforms of moving entries ([`Entry::motion`]).
    pub(crate) motions: Vec<MotionTransform>,
}
