//! Ray queries over triangle meshes placed by instances: closest hit and occlusion.
//!
//! - **Build**: obvhs (PLOC, reinsertion, conversion to its 8-wide CWBVH), whose nodes we store
//!   with each child's exact box in floats (`node::layout`: Embree's BVH8 layout). A mesh drawn
//!   by several instances gets one bottom-level BVH in object space, stored once; meshes drawn
//!   once are flattened into one world-space BVH (and shared meshes too, in scenes drawing at
//!   most [`FLATTEN_SHARED_LIMIT`] triangles); a top-level obvhs BVH over instance bounds
//!   joins them. Triangles are stored in BVH order with their original index. A world-space
//!   set of at least [`JOIN_FROM`] triangles whose instances barely overlap is built per
//!   instance in parallel and joined under a tree over their boxes (one tree to walk; a
//!   fraction of one build's temporaries).
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
//!   [`PACKET_LANES`] coherent rays (a pixel's lens samples) as one packet, one AVX2 (x86-64)
//!   or NEON (aarch64) lane per ray, with the same per-ray answers; incoherent runs are
//!   interleaved as in the batches.
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

#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
mod avx;
mod build;
mod cover;
mod deform;
mod motion;
mod node;
mod packet;
mod prefetch;
mod query;
pub mod rayfile;
mod spawn;
mod structure;
#[cfg(test)]
mod test_util;
mod triangle;
mod types;
mod walk;

pub use build::{builds, FrameHints, FLATTEN_SHARED_LIMIT, JOIN_FROM};
pub use deform::{lerp_point, VertexMotion};
pub use motion::MotionTransform;
pub use packet::{PACKET_CONE_COS, PACKET_LANES};
pub use rayfile::{read_rays, write_rays, RayFileError};
pub use spawn::{offset_ray_origin, SpawnPoint};
pub use structure::Accel;
pub use triangle::intersect_triangle;
pub use types::{AccelStats, BvhQuality, Hit, InstanceInput, MeshInput, ParseBvhQualityError, Ray};
pub use walk::BATCH_LANES;
