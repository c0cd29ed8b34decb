//! Ray queries over triangle meshes placed by instances: closest hit and occlusion.
//!
//! - **Build**: obvhs (PLOC, reinsertion, conversion to its compressed 8-wide CWBVH). A mesh drawn
//!   by several instances gets one bottom-level BVH in object space, stored once; meshes drawn
//!   once are flattened into one world-space BVH; a top-level obvhs BVH over instance bounds
//!   joins them. Triangles are stored in BVH order with their original index.
//! - **Traversal** is ours (obvhs' node layout and child ordering): the box test honours
//!   `tmin`/`tmax` and is widened by a bound on every rounding error involved, and the stack is
//!   sized from the measured tree depth. Rays enter instances through `object_from_world`
//!   without renormalising, so `t` is in world units everywhere.
//! - **Triangles**: watertight test of Woop, Benthin and Wald (2013) with an `f64` fallback for
//!   zero edge functions and pbrt-v4's bound rejecting hits not provably in front.
//! - **Secondary rays** start from [`SpawnPoint::origin`] (or [`offset_ray_origin`]).
//! - **Batches**: [`Accel::intersect_batch`] and [`Accel::occluded_batch`] answer exactly as the
//!   one-ray queries but walk [`BATCH_LANES`] rays at once, interleaved, which hides much of
//!   each walk's load-to-use latency (about 1.35× the rays per second on thin-lens primary rays).
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
pub use build::FrameHints;
mod node;
mod triangle;

pub use triangle::intersect_triangle;

use glam::{Affine3A, Vec3};
use node::BoxRay;
use obvhs::cwbvh::node::CwBvhNode;
use rayon::prelude::*;
use std::mem::MaybeUninit;
use triangle::TriRay;

/// A ray segment: points `origin + t * dir` for `tmin <= t <= tmax`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Direction (need not be unit length; `t` is measured in its units).
    pub dir: Vec3,
    /// Smallest accepted `t`.
    pub tmin: f32,
    /// Largest accepted `t`.
    pub tmax: f32,
}

impl Ray {
    /// A ray over `[0, ∞)`.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin,
            dir,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }
}

/// The closest intersection along a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Index of the instance hit (into the `instances` given to [`Accel::build`]).
    pub instance: u32,
    /// Index of the triangle within its mesh's `indices` (the original order, not BVH order).
    pub triangle: u32,
    /// Barycentric weight of the triangle's second vertex.
    pub u: f32,
    /// Barycentric weight of the triangle's third vertex (the first has `1 - u - v`).
    pub v: f32,
}

/// One mesh's geometry in object space, borrowed for the build.
#[derive(Debug, Clone, Copy)]
pub struct MeshInput<'a> {
    /// Vertex positions.
    pub positions: &'a [Vec3],
    /// Triangles as indices into `positions`.
    pub indices: &'a [[u32; 3]],
}

/// A placement of a mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InstanceInput {
    /// Index into the meshes given to [`Accel::build`].
    pub mesh: u32,
    /// Object-to-world transform.
    pub world_from_object: Affine3A,
}

/// Build-time/quality trade-off of the BVH (`--bvh-quality`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BvhQuality {
    /// Fastest build, slower traversal: previews.
    Fast,
    /// The default balance.
    #[default]
    Medium,
    /// Slowest build, fastest traversal: long renders.
    High,
}

impl BvhQuality {
    /// Every quality, fastest build first.
    pub const ALL: [BvhQuality; 3] = [BvhQuality::Fast, BvhQuality::Medium, BvhQuality::High];

    /// The lower-case name used on the command line (`fast`, `medium`, `high`).
    pub fn name(self) -> &'static str {
        match self {
            BvhQuality::Fast => "fast",
            BvhQuality::Medium => "medium",
            BvhQuality::High => "high",
        }
    }
}

impl std::fmt::Display for BvhQuality {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A `--bvh-quality` value that is not `fast`, `medium` or `high`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseBvhQualityError(pub String);

impl std::fmt::Display for ParseBvhQualityError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "unknown BVH quality {:?} (expected fast, medium or high)",
            self.0
        )
    }
}

impl std::error::Error for ParseBvhQualityError {}

impl std::str::FromStr for BvhQuality {
    type Err = ParseBvhQualityError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        BvhQuality::ALL
            .into_iter()
            .find(|q| q.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| ParseBvhQualityError(s.to_owned()))
    }
}

/// Facts about a built acceleration structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct AccelStats {
    /// Triangles left out because they have zero area or non-finite vertices (counted per mesh).
    pub degenerate_triangles: usize,
    /// Triangles kept, counted once per mesh (meshes no valid instance draws are not counted).
    pub unique_triangles: usize,
    /// Triangles left out because an index is out of range of the mesh's positions (per mesh).
    pub invalid_index_triangles: usize,
    /// Instances left out: mesh index out of range, or a transform that is non-finite or not
    /// invertible.
    pub skipped_instances: usize,
    /// Triangles drawn: kept triangles summed over instances.
    pub drawn_triangles: usize,
    /// Instances whose mesh is used only once, flattened into one world-space BVH.
    pub flattened_instances: usize,
    /// Bottom-level BVHs (one per mesh drawn more than once, plus one for all flattened meshes).
    pub blas_count: usize,
    /// Entries of the top-level BVH (instances of shared meshes, plus one for the flattened BVH).
    pub tlas_entries: usize,
    /// Wide (8-child) BVH nodes over all levels.
    pub bvh_nodes: usize,
    /// Deepest bottom-level BVH, in nodes (the traversal stack adapts to it).
    pub max_blas_depth: usize,
    /// Bytes held by the structure (nodes, triangles, instances).
    pub memory_bytes: usize,
    /// Wall time of [`Accel::build`].
    pub build_time: std::time::Duration,
    /// Bottom-level BVHs taken from the previous frame instead of built
    /// ([`Accel::build_frame`]).
    pub reused_blases: usize,
}

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
    nodes: Vec<CwBvhNode>,
    tris: Vec<Tri>,
    /// For the flattened BVH only: the instance of each triangle (BVH order). Empty otherwise.
    tri_instance: Vec<u32>,
    depth: usize,
    bounds: Option<(Vec3, Vec3)>,
    /// `bounds`, or a zero box for an empty tree (sizes the box test's rounding slack).
    box_bounds: (Vec3, Vec3),
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
}

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
    tlas: Vec<CwBvhNode>,
    tlas_depth: usize,
    /// Bounds of all instance bounds.
    tlas_bounds: (Vec3, Vec3),
    max_blas_depth: usize,
    /// Per input instance: a bound on the magnitudes met when moving its points between object
    /// and world space (`|T| + |M| max|p_obj|`), for [`Accel::spawn_point`].
    instance_magnitude: Vec<f32>,
    /// Node tests take the 8-wide AVX2 + FMA path (detected at build time; the x86_64 baseline
    /// is SSE2, 4 wide). Both are conservative and give identical hits; node masks may differ
    /// where a fused slab distance rounds differently.
    avx2: bool,
    stats: AccelStats,
    /// Per input mesh: its bottom-level BVH in `blases`, or `u32::MAX` (flattened, or not drawn).
    blas_of_mesh: Vec<u32>,
    /// The world-space BVH's key and instance count, when there is one (`blases[0]`).
    flat: Option<(u64, usize)>,
    /// Triangles that only became degenerate in world space when flattened.
    flat_degenerate: usize,
}

/// A hit's position in world space with a bound on its rounding error: where secondary rays
/// start from (see [`SpawnPoint::origin`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpawnPoint {
    /// The hit position, `origin + t * dir` of the ray that found it.
    pub p: Vec3,
    /// Bound on the distance from `p` to the exact surface point (world units, any direction).
    pub error: f32,
}

impl SpawnPoint {
    /// The origin of a ray leaving the surface on the side `n` points to (pass the geometric
    /// normal flipped towards the new ray's direction): `p` pushed past its error bound along `n`,
    /// then by a few ulps with [`offset_ray_origin`].
    ///
    /// Why not only `offset_ray_origin`: on instanced meshes the point's error comes from the
    /// transform's magnitudes (say a coordinate near 0 computed from terms near 1e4), which a
    /// few ulps of the point's own coordinates do not cover.
    ///
    /// Near zero (coordinates below 1/32) the last step is the error bound rather than
    /// `offset_ray_origin`'s fixed 1/65536 units: the bound already covers the rounding that
    /// fixed step guards against, and a fixed step is a large part of a scene measured in units
    /// of 1e-4 (it lost contact shadows there). An `error` of 0 means "not known": then the
    /// fixed step stays, exactly as `offset_ray_origin`.
    pub fn origin(&self, n: Vec3) -> Vec3 {
        let n = n.normalize_or_zero();
        if self.error > 0.0 {
            offset_ulps(self.p + n * (2.0 * self.error), n, self.error)
        } else {
            offset_ray_origin(self.p, n)
        }
    }
}

/// A traversal stack entry: a node group (obvhs encoding: child base index, hit mask).
type Group = (u32, u32);

/// Stacks up to this depth live on the call stack; deeper trees (degenerate input) get a heap
/// stack sized from the measured depth, so the stack can never overflow.
const INLINE_STACK: usize = 48;

/// An uninitialised inline stack.
type InlineStack = [MaybeUninit<Group>; INLINE_STACK];

/// The traversal stack for a tree of `depth` levels: `inline` when it fits, else `heap` sized to
/// the depth. A plain function rather than a closure-taking one so that the query stays one
/// function after inlining (closures were separate calls per ray).
///
/// Slots start uninitialised: zeroing 48 entries per query (a `memset` call) cost about 3 % of the
/// instructions of a primary ray. [`traverse`] reads a slot only below its stack pointer, that
/// is, only after writing it.
#[inline(always)]
fn stack_for<'a>(
    depth: usize,
    inline: &'a mut InlineStack,
    heap: &'a mut Vec<MaybeUninit<Group>>,
) -> &'a mut [MaybeUninit<Group>] {
    if depth < INLINE_STACK {
        inline
    } else {
        *heap = vec![MaybeUninit::<Group>::uninit(); depth + 1];
        heap
    }
}

/// What [`traverse`] does with each primitive of a hit leaf. A trait with `#[inline(always)]`
/// implementations rather than a closure: the compiler left the occlusion closure as a call per
/// triangle once the traversal was inlined into the query.
trait Leaf {
    /// Visits `primitive`; may shrink `tmax`; returns `true` to stop the traversal.
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool;
}

impl<L: Leaf> Leaf for &mut L {
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        (**self).visit(primitive, tmax)
    }
}

/// The top level's leaf for closest hit: each entry is a walk of its bottom-level tree. A
/// struct with an `#[inline(always)]` visit, not a closure: closures do not take the query's
/// target features, and once the walk became a stepped state the compiler kept the closure
/// (and the 8-wide node test inside it) a call (+10 % instructions per instanced query).
struct EntriesClosest<'a, const AVX2: bool> {
    accel: &'a Accel,
    ray: &'a Ray,
    stack: &'a mut [MaybeUninit<Group>],
    best: Option<Hit>,
}

impl<const AVX2: bool> Leaf for EntriesClosest<'_, AVX2> {
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        if let Some(entry) = self.accel.entries.get(primitive as usize) {
            let hit = self
                .accel
                .walk_entry::<AVX2, ClosestLeaf>(entry, self.ray, tmax, self.stack);
            if let Some(Some(hit)) = hit {
                self.best = Some(hit);
            }
        }
        false
    }
}

/// The top level's leaf for occlusion ([`EntriesClosest`] for any hit): stops at the first entry
/// that occludes.
struct EntriesAny<'a, const AVX2: bool> {
    accel: &'a Accel,
    ray: &'a Ray,
    stack: &'a mut [MaybeUninit<Group>],
}

impl<const AVX2: bool> Leaf for EntriesAny<'_, AVX2> {
    #[inline(always)]
    fn visit(&mut self, primitive: u32, _: &mut f32) -> bool {
        let mut tmax = self.ray.tmax;
        self.accel
            .entries
            .get(primitive as usize)
            .is_some_and(|entry| {
                self.accel
                    .walk_entry::<AVX2, AnyLeaf>(entry, self.ray, &mut tmax, self.stack)
                    == Some(true)
            })
    }
}

/// Closest hit over a bottom-level BVH's triangles: `(triangle index, (t, u, v))`.
#[derive(Clone, Copy)]
struct ClosestLeaf<'a> {
    tris: &'a [Tri],
    ray: TriRay,
    tmin: f32,
    best: Option<(usize, (f32, f32, f32))>,
}

impl Leaf for ClosestLeaf<'_> {
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        if let Some(tri) = self.tris.get(primitive as usize) {
            if let Some(h) =
                triangle::intersect(&self.ray, tri.p[0], tri.p[1], tri.p[2], self.tmin, *tmax)
            {
                *tmax = h.0;
                self.best = Some((primitive as usize, h));
            }
        }
        false
    }
}

/// Any hit over a bottom-level BVH's triangles: stops at the first.
#[derive(Clone, Copy)]
struct AnyLeaf<'a> {
    tris: &'a [Tri],
    ray: TriRay,
    tmin: f32,
}

impl Leaf for AnyLeaf<'_> {
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        self.tris.get(primitive as usize).is_some_and(|tri| {
            triangle::intersect(&self.ray, tri.p[0], tri.p[1], tri.p[2], self.tmin, *tmax).is_some()
        })
    }
}

/// A bottom-level leaf (closest or any hit): how a ray's leaf starts and what its answer is,
/// for the one-ray walks ([`Accel::walk_entry`]) and the batches ([`Accel::batch_impl`]).
trait BlasLeaf<'a>: Leaf + Copy {
    /// One ray's answer.
    type Answer;
    /// The leaf of a ray with triangle-test constants `ray`, before any visit.
    fn start(tris: &'a [Tri], ray: TriRay, tmin: f32) -> Self;
    /// The answer once the walk has ended (`stopped`: the leaf stopped it).
    fn answer(&self, blas: &Blas, entry: &Entry, stopped: bool) -> Self::Answer;
    /// The one-ray query, for scenes that interleaving does not cover.
    fn one<const AVX2: bool>(accel: &Accel, ray: &Ray) -> Self::Answer;
}

impl<'a> BlasLeaf<'a> for ClosestLeaf<'a> {
    type Answer = Option<Hit>;

    #[inline(always)]
    fn start(tris: &'a [Tri], ray: TriRay, tmin: f32) -> Self {
        Self {
            tris,
            ray,
            tmin,
            best: None,
        }
    }

    #[inline(always)]
    fn answer(&self, blas: &Blas, entry: &Entry, _: bool) -> Option<Hit> {
        self.best.map(|(i, h)| Accel::make_hit(blas, entry, i, h))
    }

    #[inline(always)]
    fn one<const AVX2: bool>(accel: &Accel, ray: &Ray) -> Option<Hit> {
        accel.intersect_impl::<AVX2>(ray)
    }
}

impl<'a> BlasLeaf<'a> for AnyLeaf<'a> {
    type Answer = bool;

    #[inline(always)]
    fn start(tris: &'a [Tri], ray: TriRay, tmin: f32) -> Self {
        Self { tris, ray, tmin }
    }

    #[inline(always)]
    fn answer(&self, _: &Blas, _: &Entry, stopped: bool) -> bool {
        stopped
    }

    #[inline(always)]
    fn one<const AVX2: bool>(accel: &Accel, ray: &Ray) -> bool {
        accel.occluded_impl::<AVX2>(ray)
    }
}

/// A walk of a CWBVH (obvhs layout) in progress, front to back: the traversal of one ray as a
/// state that advances one step at a time, so that several rays' walks can be interleaved on
/// one thread (see [`Accel::intersect_batch`]). [`traverse`] runs one walk to its end.
///
/// Each stack entry holds the unvisited siblings of one level of the current path, so the stack
/// needs one entry per tree level (the depth measured at build time).
#[derive(Clone, Copy)]
struct Walk {
    sp: usize,
    current: Group,
    prims: Group,
}

impl Walk {
    /// A walk from the root.
    #[inline(always)]
    fn new() -> Self {
        Self {
            sp: 0,
            // The root as a group of one internal child at priority 7 (obvhs convention).
            current: (0, 0x8000_0000),
            prims: (0, 0),
        }
    }

    /// Visits the pending primitives of the current leaf (`leaf.visit(primitive, &mut tmax)`
    /// each), then tests the next node. `Some(stopped)` once the walk has ended, where
    /// `stopped` says whether `leaf` stopped it.
    ///
    /// With `AVX2` it must be inlined into a function compiled for AVX2 (`Accel::intersect_avx2`
    /// and its kin), so that the node test and `count_ones`/`leading_zeros` become inline vector
    /// and bit instructions.
    #[inline(always)]
    fn step<const AVX2: bool>(
        &mut self,
        nodes: &[CwBvhNode],
        r: &BoxRay,
        tmax: &mut f32,
        stack: &mut [MaybeUninit<Group>],
        leaf: &mut impl Leaf,
    ) -> Option<bool> {
        while self.prims.1 != 0 {
            let local = 31 - self.prims.1.leading_zeros();
            self.prims.1 &= !(1u32 << local);
            if leaf.visit(self.prims.0 + local, tmax) {
                return Some(true);
            }
        }
        if self.current.1 & 0xff00_0000 != 0 {
            let hits = self.current.1;
            let offset = 31 - hits.leading_zeros();
            self.current.1 &= !(1u32 << offset);
            if self.current.1 & 0xff00_0000 != 0 {
                stack[self.sp] = MaybeUninit::new(self.current);
                self.sp += 1;
            }
            let slot = (offset - 24) ^ (r.oct_inv4 & 0xff);
            let relative = (hits & !(u32::MAX << slot)).count_ones();
            let Some(node) = nodes.get((self.current.0 + relative) as usize) else {
                // Unreachable for a well-formed tree (and for an empty one, whose root group is
                // never read); never read out of bounds.
                self.current.1 = 0;
                return None;
            };
            let mask = if AVX2 {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `AVX2` is true only when `detect_avx2` found AVX2 on this CPU.
                unsafe {
                    node::intersect_node_avx2(node, r, *tmax)
                }
                #[cfg(not(target_arch = "x86_64"))]
                node::intersect_node(node, r, *tmax)
            } else {
                node::intersect_node(node, r, *tmax)
            };
            self.current = (
                node.child_base_idx,
                (mask & 0xff00_0000) | node.imask as u32,
            );
            self.prims = (node.primitive_base_idx, mask & 0x00ff_ffff);
        } else {
            self.current = (0, 0);
        }
        if self.prims.1 == 0 && self.current.1 & 0xff00_0000 == 0 {
            if self.sp == 0 {
                return Some(false);
            }
            self.sp -= 1;
            // SAFETY: slots below `sp` were written by the push above before `sp` passed them
            // (`sp` only grows right after a write), so slot `sp` holds an initialised group.
            self.current = unsafe { stack[self.sp].assume_init() };
        }
        None
    }
}

/// Walks a CWBVH (obvhs layout) front to back for `r`, calling `leaf.visit(primitive, &mut tmax)`
/// for every primitive in a hit leaf. Returns whether `leaf` stopped it. `stack` needs one entry
/// per tree level.
#[inline(always)]
fn traverse<const AVX2: bool>(
    nodes: &[CwBvhNode],
    r: &BoxRay,
    tmax: &mut f32,
    stack: &mut [MaybeUninit<Group>],
    mut leaf: impl Leaf,
) -> bool {
    if nodes.is_empty() {
        return false;
    }
    let mut walk = Walk::new();
    loop {
        if let Some(stopped) = walk.step::<AVX2>(nodes, r, tmax, stack, &mut leaf) {
            return stopped;
        }
    }
}

/// Rays walked at once, interleaved, by [`Accel::intersect_batch`] and [`Accel::occluded_batch`].
/// Measured on thin-lens primary rays (`benches/`, closest hit, 1 thread): 2 and 4 gain alike
/// in tile order, 4 gains more in random order, 8 less in tile order.
pub const BATCH_LANES: usize = 4;

/// Runs the walks of rays `0..n` over `nodes`, [`BATCH_LANES`] at a time, interleaved step by
/// step. `start(i)` gives ray `i`'s box ray, `tmax` and leaf; `finish(i, leaf, stopped)` takes
/// them back when its walk ends. Each ray's walk is exactly [`traverse`]'s, so the results are
/// too; only the order of work between rays changes.
///
/// Why: one ray's walk is a chain of dependent loads and tests (a node's address comes out of
/// its parent's test) that leaves most of the core idle; independent chains fill it.
#[inline(always)]
fn interleave<const AVX2: bool, L: Leaf + Copy>(
    nodes: &[CwBvhNode],
    n: usize,
    mut start: impl FnMut(usize) -> (BoxRay, f32, L),
    mut finish: impl FnMut(usize, &L, bool),
) {
    if n == 0 {
        return;
    }
    // Lanes are updated in place (no moves of whole lanes), and idle ones are marked by their
    // index: both measured faster than `Option`s of lanes.
    struct Lane<L> {
        /// The ray walked, or `usize::MAX` when the lane is idle.
        index: usize,
        walk: Walk,
        br: BoxRay,
        tmax: f32,
        leaf: L,
        stack: InlineStack,
    }
    let mut next = 0;
    let mut lanes: [Lane<L>; BATCH_LANES] = std::array::from_fn(|_| {
        // Lanes beyond `n` start idle, on a copy of the last ray.
        let index = if next < n { next } else { usize::MAX };
        let (br, tmax, leaf) = start(next.min(n - 1));
        next += 1;
        Lane {
            index,
            walk: Walk::new(),
            br,
            tmax,
            leaf,
            stack: [MaybeUninit::uninit(); INLINE_STACK],
        }
    });
    next = next.min(n);
    let mut active = lanes.iter().filter(|l| l.index != usize::MAX).count();
    while active > 0 {
        for lane in &mut lanes {
            if lane.index == usize::MAX {
                continue;
            }
            let done = lane.walk.step::<AVX2>(
                nodes,
                &lane.br,
                &mut lane.tmax,
                &mut lane.stack,
                &mut lane.leaf,
            );
            if let Some(stopped) = done {
                finish(lane.index, &lane.leaf, stopped);
                if next < n {
                    let (br, tmax, leaf) = start(next);
                    lane.index = next;
                    lane.walk = Walk::new();
                    lane.br = br;
                    lane.tmax = tmax;
                    lane.leaf = leaf;
                    next += 1;
                } else {
                    lane.index = usize::MAX;
                    active -= 1;
                }
            }
        }
    }
}

/// Whether this CPU can take the AVX2 (+ FMA) traversal. `APERTURE_NO_AVX2` forces the SSE2 path (to
/// compare the two, or to rule the AVX2 path out when debugging).
fn detect_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::env::var_os("APERTURE_NO_AVX2").is_none()
            && std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
            && std::arch::is_x86_feature_detected!("popcnt")
            && std::arch::is_x86_feature_detected!("lzcnt")
            && std::arch::is_x86_feature_detected!("bmi1")
            && std::arch::is_x86_feature_detected!("bmi2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

impl Accel {
    /// The world position of `hit` (found by `ray`) with a bound on its error, for spawning
    /// secondary rays with [`SpawnPoint::origin`].
    pub fn spawn_point(&self, ray: &Ray, hit: &Hit) -> SpawnPoint {
        let p = ray.origin + ray.dir * hit.t;
        let ray_part = ray.origin.abs().max_element() + (ray.dir * hit.t).abs().max_element();
        let transform_part = self.magnitude_of(hit.instance);
        // A few roundings of each magnitude: o + t d (2), the triangle test's t (a few), and the
        // object/world transforms of the ray and of the vertices (about 3 each).
        SpawnPoint {
            p,
            error: 16.0 * f32::EPSILON * (ray_part + transform_part),
        }
    }

    /// The bound on magnitudes met moving points of `instance` between object and world space.
    fn magnitude_of(&self, instance: u32) -> f32 {
        self.instance_magnitude
            .get(instance as usize)
            .copied()
            .unwrap_or(0.0)
    }

    /// A point `p` computed on a triangle of instance `instance` (say by interpolating its
    /// vertices, as a light sample is), with a bound on its rounding error: where a ray towards
    /// or from that point may start or end without meeting the triangle itself.
    pub fn surface_point(&self, instance: u32, p: Vec3) -> SpawnPoint {
        let transform_part = self.magnitude_of(instance);
        // Interpolation (a few roundings of the vertex magnitudes) and the object-to-world
        // transform (about 3 of the transform's).
        SpawnPoint {
            p,
            error: 16.0 * f32::EPSILON * (p.abs().max_element() + transform_part),
        }
    }

    /// Build statistics.
    pub fn stats(&self) -> AccelStats {
        self.stats
    }

    /// The closest hit in `[ray.tmin, ray.tmax]`, if any.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only when `detect_avx2` found every feature it enables.
            return unsafe { self.intersect_avx2(ray) };
        }
        self.intersect_impl::<false>(ray)
    }

    /// True when anything lies in `[ray.tmin, ray.tmax]`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: as in `intersect`.
            return unsafe { self.occluded_avx2(ray) };
        }
        self.occluded_impl::<false>(ray)
    }

    /// The whole query compiled for AVX2: the per-ray setup (reciprocals, shear, stack) and the
    /// traversal become one function, without a call boundary between them where the traversal
    /// had to spill its ray constants (about 60 instructions per ray).
    ///
    /// # Safety
    /// The CPU must support every feature enabled here (checked by `detect_avx2`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,popcnt,lzcnt,bmi1,bmi2")]
    unsafe fn intersect_avx2(&self, ray: &Ray) -> Option<Hit> {
        self.intersect_impl::<true>(ray)
    }

    /// [`Accel::intersect_avx2`] for occlusion.
    ///
    /// # Safety
    /// As for [`Accel::intersect_avx2`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,popcnt,lzcnt,bmi1,bmi2")]
    unsafe fn occluded_avx2(&self, ray: &Ray) -> bool {
        self.occluded_impl::<true>(ray)
    }

    #[inline(always)]
    fn intersect_impl<const AVX2: bool>(&self, ray: &Ray) -> Option<Hit> {
        let mut tmax = ray.tmax;
        let mut inline: InlineStack = [MaybeUninit::uninit(); INLINE_STACK];
        let mut heap = Vec::new();
        let blas_stack = stack_for(self.max_blas_depth, &mut inline, &mut heap);
        let mut leaf = EntriesClosest::<AVX2> {
            accel: self,
            ray,
            stack: blas_stack,
            best: None,
        };
        self.for_entries::<AVX2>(ray, &mut tmax, &mut leaf);
        leaf.best
    }

    #[inline(always)]
    fn occluded_impl<const AVX2: bool>(&self, ray: &Ray) -> bool {
        let mut inline: InlineStack = [MaybeUninit::uninit(); INLINE_STACK];
        let mut heap = Vec::new();
        let blas_stack = stack_for(self.max_blas_depth, &mut inline, &mut heap);
        let mut tmax = ray.tmax;
        let leaf = EntriesAny::<AVX2> {
            accel: self,
            ray,
            stack: blas_stack,
        };
        self.for_entries::<AVX2>(ray, &mut tmax, leaf)
    }

    /// [`Accel::intersect`] for each of `rays` on the calling thread, into `out` (one result per
    /// ray; extra slots on either side are left alone). The results are exactly `intersect`'s,
    /// ray by ray; the walks of [`BATCH_LANES`] rays are interleaved, which is faster than a loop
    /// of `intersect` calls (figures in `BENCHMARKS.md`).
    pub fn intersect_batch(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only when `detect_avx2` found every feature it enables.
            return unsafe { self.intersect_batch_avx2(rays, out) };
        }
        self.batch_impl::<false, ClosestLeaf>(rays, out)
    }

    /// [`Accel::occluded`] for each of `rays` on the calling thread, interleaved as
    /// [`Accel::intersect_batch`].
    pub fn occluded_batch(&self, rays: &[Ray], out: &mut [bool]) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: as in `intersect_batch`.
            return unsafe { self.occluded_batch_avx2(rays, out) };
        }
        self.batch_impl::<false, AnyLeaf>(rays, out)
    }

    /// [`Accel::intersect_batch`] compiled for AVX2.
    ///
    /// # Safety
    /// As for [`Accel::intersect_avx2`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,popcnt,lzcnt,bmi1,bmi2")]
    unsafe fn intersect_batch_avx2(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        self.batch_impl::<true, ClosestLeaf>(rays, out)
    }

    /// [`Accel::occluded_batch`] compiled for AVX2.
    ///
    /// # Safety
    /// As for [`Accel::intersect_avx2`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,popcnt,lzcnt,bmi1,bmi2")]
    unsafe fn occluded_batch_avx2(&self, rays: &[Ray], out: &mut [bool]) {
        self.batch_impl::<true, AnyLeaf>(rays, out)
    }

    /// The one bottom-level tree every ray walks, when interleaving applies: a scene of one
    /// entry whose stack fits inline. Other scenes (instanced, or degenerate depths) go ray by
    /// ray.
    fn single_entry(&self) -> Option<(&Entry, &Blas)> {
        match self.entries.as_slice() {
            [entry] if self.max_blas_depth < INLINE_STACK => self
                .blases
                .get(entry.blas as usize)
                .filter(|b| !b.nodes.is_empty())
                .map(|b| (entry, b)),
            _ => None,
        }
    }

    /// The batch queries: [`interleave`]d walks of `rays` with leaves of type `L`, one answer per
    /// ray into `out`; ray by ray (`L::one`) where interleaving does not apply.
    #[inline(always)]
    fn batch_impl<'s, const AVX2: bool, L: BlasLeaf<'s>>(
        &'s self,
        rays: &[Ray],
        out: &mut [L::Answer],
    ) {
        let n = rays.len().min(out.len());
        let (rays, out) = (&rays[..n], &mut out[..n]);
        let Some((entry, blas)) = self.single_entry() else {
            for (r, o) in rays.iter().zip(out.iter_mut()) {
                *o = L::one::<AVX2>(self, r);
            }
            return;
        };
        interleave::<AVX2, L>(
            &blas.nodes,
            n,
            |i| {
                let ray = &rays[i];
                let (br, leaf) = Self::walk_start::<L>(entry, blas, ray);
                (br, ray.tmax, leaf)
            },
            |i, leaf, stopped| out[i] = leaf.answer(blas, entry, stopped),
        );
    }

    /// [`Accel::intersect`] for many rays, in parallel on the current rayon pool, each thread
    /// running [`Accel::intersect_batch`] on runs of 256 rays. `out` receives one result per ray
    /// (extra slots on either side are left alone).
    pub fn intersect_many(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        rays.par_chunks(256)
            .zip(out.par_chunks_mut(256))
            .for_each(|(r, o)| self.intersect_batch(r, o));
    }

    /// [`Accel::occluded`] for many rays, in parallel on the current rayon pool (through
    /// [`Accel::occluded_batch`], as [`Accel::intersect_many`]).
    pub fn occluded_many(&self, rays: &[Ray], out: &mut [bool]) {
        rays.par_chunks(256)
            .zip(out.par_chunks_mut(256))
            .for_each(|(r, o)| self.occluded_batch(r, o));
    }

    /// Visits (`leaf.visit(entry index, &mut tmax)`) the top-level entries whose bounds the ray
    /// may cross.
    #[inline(always)]
    fn for_entries<const AVX2: bool>(
        &self,
        ray: &Ray,
        tmax: &mut f32,
        mut leaf: impl Leaf,
    ) -> bool {
        match self.entries.len() {
            0 => false,
            // One entry (a scene without shared meshes): no top-level walk.
            1 => leaf.visit(0, tmax),
            _ => {
                let r = BoxRay::new(ray.origin, ray.dir, ray.tmin, self.tlas_bounds);
                let mut inline: InlineStack = [MaybeUninit::uninit(); INLINE_STACK];
                let mut heap = Vec::new();
                let stack = stack_for(self.tlas_depth, &mut inline, &mut heap);
                traverse::<AVX2>(&self.tlas, &r, tmax, stack, leaf)
            }
        }
    }

    #[inline(always)]
    fn object_ray(entry: &Entry, ray: &Ray) -> (Vec3, Vec3) {
        if entry.identity {
            (ray.origin, ray.dir)
        } else {
            (
                entry.object_from_world.transform_point3(ray.origin),
                entry.object_from_world.transform_vector3(ray.dir),
            )
        }
    }

    #[inline(always)]
    fn make_hit(blas: &Blas, entry: &Entry, i: usize, (t, u, v): (f32, f32, f32)) -> Hit {
        let instance = if entry.instance == FLATTENED {
            blas.tri_instance.get(i).copied().unwrap_or(FLATTENED)
        } else {
            entry.instance
        };
        Hit {
            t,
            instance,
            triangle: blas.tris[i].prim,
            u,
            v,
        }
    }

    /// Walks the bottom-level tree of `entry` for `ray` (moved into its space) with a leaf of
    /// type `L`: `L`'s answer, or `None` for an entry without a tree.
    #[inline(always)]
    fn walk_entry<'s, const AVX2: bool, L: BlasLeaf<'s>>(
        &'s self,
        entry: &Entry,
        ray: &Ray,
        tmax: &mut f32,
        stack: &mut [MaybeUninit<Group>],
    ) -> Option<L::Answer> {
        let blas = self.blases.get(entry.blas as usize)?;
        let (br, mut leaf) = Self::walk_start::<L>(entry, blas, ray);
        let stopped = traverse::<AVX2>(&blas.nodes, &br, tmax, stack, &mut leaf);
        Some(leaf.answer(blas, entry, stopped))
    }

    /// What a walk of `blas` (drawn by `entry`) for `ray` starts from: the ray in the tree's
    /// space prepared for box tests, and a fresh leaf with its triangle-test constants.
    #[inline(always)]
    fn walk_start<'s, L: BlasLeaf<'s>>(entry: &Entry, blas: &'s Blas, ray: &Ray) -> (BoxRay, L) {
        let (o, d) = Self::object_ray(entry, ray);
        (
            BoxRay::new(o, d, ray.tmin, blas.box_bounds),
            L::start(&blas.tris, TriRay::new(o, d), ray.tmin),
        )
    }

    /// The closest hit by testing every triangle of every instance, with the same ray transform
    /// and triangle test as [`Accel::intersect`]. Slow: a reference for tests and debugging.
    pub fn intersect_brute_force(&self, ray: &Ray) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut tmax = ray.tmax;
        for entry in &self.entries {
            let Some(blas) = self.blases.get(entry.blas as usize) else {
                continue;
            };
            let (o, d) = Self::object_ray(entry, ray);
            let tr = TriRay::new(o, d);
            for (i, tri) in blas.tris.iter().enumerate() {
                if let Some(h) =
                    triangle::intersect(&tr, tri.p[0], tri.p[1], tri.p[2], ray.tmin, tmax)
                {
                    tmax = h.0;
                    best = Some(Self::make_hit(blas, entry, i, h));
                }
            }
        }
        best
    }

    /// The world-space vertices of `triangle` of `instance` as the structure stores them (for
    /// flattened meshes these are the exact world positions the intersection used).
    /// `None` if that triangle was left out or does not exist.
    pub fn triangle_world(&self, instance: u32, triangle: u32) -> Option<[Vec3; 3]> {
        for entry in &self.entries {
            let Some(blas) = self.blases.get(entry.blas as usize) else {
                continue;
            };
            if entry.instance == FLATTENED {
                let i = (0..blas.tris.len())
                    .find(|&i| blas.tri_instance[i] == instance && blas.tris[i].prim == triangle)?;
                return Some(blas.tris[i].p);
            }
            if entry.instance == instance {
                let world_from_object = entry.object_from_world.inverse();
                let t = blas.tris.iter().find(|t| t.prim == triangle)?;
                return Some(t.p.map(|p| world_from_object.transform_point3(p)));
            }
        }
        None
    }
}

/// Moves a surface point off its surface along the geometric normal so that a ray leaving it
/// cannot hit the same surface again (Wächter and Binder, Ray Tracing Gems ch. 6): the offset is
/// a few float ulps of the point's magnitude, not a fixed epsilon. `n` need not face the ray;
/// pass the normal flipped to the side the new ray leaves on.
///
/// It covers the rounding of a point computed from values of its own magnitude (barycentric
/// interpolation of world-space vertices). Points on instanced meshes, or computed as
/// `o + t d`, can carry more error; use [`Accel::spawn_point`] and [`SpawnPoint::origin`] there.
/// Coordinates below 1/32 move by a fixed `n / 65536` (as in the paper), which is large
/// compared with scenes of millimetre scale: harmless for self-intersection, but such scenes
/// are better modelled in larger units.
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    offset_ulps(p, n, 1.0 / 65536.0)
}

/// Wächter and Binder's offset: 256 ulps along `n` for coordinates of at least 1/32, and
/// `float_scale · n` for those below, whose ulps are too fine to cover a rounding error that
/// comes from larger magnitudes elsewhere.
fn offset_ulps(p: Vec3, n: Vec3, float_scale: f32) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const INT_SCALE: f32 = 256.0;
    let of_i = (INT_SCALE * n).to_array().map(|x| x as i32);
    let pa = p.to_array();
    let mut out = [0.0f32; 3];
    for k in 0..3 {
        // Wrapping: near zero (handled by the float branch below) or for huge normals the
        // integer step may overflow; the paper's C relies on two's complement wrapping too.
        let bits = pa[k].to_bits() as i32;
        let step = if pa[k] < 0.0 {
            of_i[k].wrapping_neg()
        } else {
            of_i[k]
        };
        let moved = bits.wrapping_add(step);
        let p_i = f32::from_bits(moved as u32);
        out[k] = if pa[k].abs() < ORIGIN {
            pa[k] + float_scale * n[k]
        } else {
            p_i
        };
    }
    Vec3::from_array(out)
}
