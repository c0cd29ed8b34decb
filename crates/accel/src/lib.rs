//! Ray queries over triangle meshes placed by instances: closest hit and occlusion.
//!
//! - **Build**: obvhs (PLOC, reinsertion, conversion to its 8-wide CWBVH), whose nodes we store
//!   with each child's exact box in floats (`node::layout`: Embree's BVH8 layout). A mesh drawn
//!   by several instances gets one bottom-level BVH in object space, stored once; meshes drawn
//!   once are flattened into one world-space BVH (and shared meshes too, in scenes drawing at
//!   most [`FLATTEN_SHARED_LIMIT`] triangles); a top-level obvhs BVH over instance bounds
//!   joins them. Triangles are stored in BVH order with their original index.
//! - **Traversal** is ours: the box test honours `tmin`/`tmax` and is
//!   widened by a bound on every rounding error involved, and the stack is sized from the
//!   measured tree depth. Closest hits visit children nearest entry first and skip those a hit
//!   has put beyond `tmax`; one-ray occlusion keeps obvhs' octant order. Rays enter instances
//!   through `object_from_world` without renormalising, so `t` is in world units everywhere.
//! - **Triangles**: watertight test of Woop, Benthin and Wald (2013) with an `f64` fallback for
//!   zero edge functions and pbrt-v4's bound rejecting hits not provably in front; hits that
//!   bound cannot prove are decided again in `f64` (close to the origin on large triangles).
//! - **Misses**: a ray starting outside the scene's bounds whose segment misses them (widened by
//!   the box test's slack) is answered without a walk, in every query.
//! - **Motion**: instances moving within a shutter ([`FrameHints::motion`]) are bounded over it
//!   and placed at each ray's [`Ray::time`]; meshes deforming within it
//!   ([`FrameHints::deforming`], [`VertexMotion`]) get a tree over their swept triangles whose
//!   leaves test each triangle interpolated at the ray's time. Both are walked ray by ray;
//!   still scenes keep every path above untouched.
//! - **Secondary rays** start from [`SpawnPoint::origin`] (or [`offset_ray_origin`]).
//! - **Batches**: [`Accel::intersect_batch`] and [`Accel::occluded_batch`] answer exactly as the
//!   one-ray queries but walk [`BATCH_LANES`] rays at once, interleaved, which hides much of
//!   each walk's load-to-use latency (about 1.35× the rays per second on thin-lens primary rays).
//! - **Packets**: [`Accel::intersect_packets`] and [`Accel::occluded_packets`] walk runs of
//!   [`PACKET_LANES`] coherent rays (a pixel's lens samples) as one packet, one AVX2 lane per
//!   ray, with the same per-ray answers; incoherent runs are interleaved as in the batches.
//! - **Ray files**: [`rayfile`] reads and writes the Embree anchor's raw `.rays` format.
//! - **Cover**: [`Accel::cover`] cuts the top of the trees into a few boxes that hold every
//!   triangle (a renderer finds from them the pixels that can only see the background).
//!
//! ```
//! use aperture_accel::{Accel, BvhQuality, InstanceInput, MeshInput, Ray};
//! use glam::{Affine3A, Vec3};
//! let positions = [Vec3::new(-1.0, -1.0, -2.0), Vec3::new(1.0, -1.0, -2.0), Vec3::new(0.0, 1.0, -2.0)];
//! let indices = [[0u32, 1, 2]];
//! let accel = Accel::build(
//!     &[MeshInput { positions: &positions, indices: &indices }],
//!     &[InstanceInput { mesh: 0, world_from_object: Affine3A::IDENTITY }],
//!     BvhQuality::default(),
//! );
//! let hit = accel.intersect(&Ray::new(Vec3::ZERO, Vec3::NEG_Z)).expect("the ray hits");
//! assert!((hit.t - 2.0).abs() < 1e-6);
//! ```

mod build;
mod cover;
mod deform;
mod motion;
mod node;
mod packet;
mod query;
pub mod rayfile;
mod spawn;
#[cfg(test)]
mod test_util;
mod triangle;
mod types;
mod walk;

pub use build::{FrameHints, FLATTEN_SHARED_LIMIT};
pub use deform::{lerp_point, VertexMotion};
pub use motion::MotionTransform;
pub use packet::{PACKET_CONE_COS, PACKET_LANES};
pub use rayfile::{read_rays, write_rays, RayFileError};
pub use spawn::{offset_ray_origin, SpawnPoint};
pub use triangle::intersect_triangle;
pub use types::{AccelStats, BvhQuality, Hit, InstanceInput, MeshInput, ParseBvhQualityError, Ray};
pub use walk::BATCH_LANES;

use crate::node::Node;
use glam::{Affine3A, Vec3};

/// A triangle in BVH order: its vertices exactly as given (shared vertices stay bitwise equal,
/// which the watertight test relies on) and its index in the mesh's original `indices`.
#[derive(Debug, Clone, Copy)]
#[repr(C)]
struct Tri {
    p: [Vec3; 3],
    prim: u32,
}

/// A bottom-level BVH over one mesh (object space) or over all flattened meshes (world space).
#[derive(Debug, Clone, Default)]
struct Blas {
    nodes: Vec<Node>,
    tris: Vec<Tri>,
    /// For the flattened BVH only: the instance of each triangle (BVH order). Empty otherwise.
    tri_instance: Vec<u32>,
    depth: usize,
    bounds: Option<(Vec3, Vec3)>,
    /// `bounds`, or a zero box for an empty tree (sizes the box test's rounding slack).
    box_bounds: (Vec3, Vec3),
    /// For a mesh deforming within the shutter: its triangles keyed over it (the nodes then
    /// bound the swept triangles, and `tris` holds the frame's, for lookups only).
    deform: Option<Box<deform::Deform>>,
}

/// One leaf of the top-level BVH: a BVH placed in the world.
#[derive(Debug, Clone, Copy)]
struct Entry {
    blas: u32,
    /// The instance, or `FLATTENED` when the triangles carry their own.
    instance: u32,
    object_from_world: Affine3A,
    /// The flattened BVH is already in world space: skip the ray transform.
    identity: bool,
    /// Index into [`Accel::motions`] of a moving instance, or [`NO_MOTION`].
    motion: u32,
}

/// [`Entry::motion`] of an entry that stays put.
const NO_MOTION: u32 = u32::MAX;

const FLATTENED: u32 = u32::MAX;

/// The acceleration structure: answers ray queries from many threads at once.
///
/// Layout: a top-level obvhs CWBVH over instance bounds whose leaves point at bottom-level CWBVHs
/// (one per mesh drawn more than once, stored once however many instances draw it), plus one
/// world-space CWBVH holding every mesh that is drawn exactly once. Rays are moved into object
/// space per instance with `object_from_world` without renormalising the direction, so `t` stays
/// in world units.
#[derive(Debug, Clone)]
pub struct Accel {
    blases: Vec<Blas>,
    /// In top-level BVH order.
    entries: Vec<Entry>,
    tlas: Vec<Node>,
    tlas_depth: usize,
    /// Bounds of all instance bounds.
    tlas_bounds: (Vec3, Vec3),
    max_blas_depth: usize,
    /// Per input instance: a bound on the magnitudes met when moving its points between object
    /// and world space (`|T| + |M| max|p_obj|`), for [`Accel::spawn_point`].
    instance_magnitude: Vec<f32>,
    /// Node tests take the 8-wide AVX2 path (detected at build time; the x86_64 baseline is SSE2,
    /// 4 wide). Both compute the same operations: the same node masks, the same hits.
    avx2: bool,
    stats: AccelStats,
    /// Per input mesh: its bottom-level BVH in `blases`, or `u32::MAX` (flattened, or not drawn).
    blas_of_mesh: Vec<u32>,
    /// The world-space BVH's key and its instances (ascending), when there is one (`blases[0]`).
    flat: Option<(u64, Vec<u32>)>,
    /// Triangles that only became degenerate in world space when flattened.
    flat_degenerate: usize,
    /// Bottom-level BVHs of unchanged meshes this frame does not use (by mesh), kept for the
    /// next frame's [`Accel::build_frame`]: a mesh keyed hidden for a while is not rebuilt
    /// when shown again. Never walked.
    spare: Vec<(u32, Blas)>,
    /// The transforms of moving entries ([`Entry::motion`]).
    motions: Vec<MotionTransform>,
}
