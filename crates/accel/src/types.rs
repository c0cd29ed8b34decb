//! The public value types: rays, hits, build inputs, quality and statistics.

use glam::{Affine3A, Vec3};

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
    /// Normalised time in the shutter, `[0, 1]`: where moving instances are
    /// ([`crate::FrameHints::motion`]); still ones ignore it.
    pub time: f32,
}

impl Ray {
    /// A ray over `[0, ∞)`.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin,
            dir,
            tmin: 0.0,
            tmax: f32::INFINITY,
            time: 0.0,
        }
    }
}

/// The closest intersection along a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Index of the instance hit (into the `instances` given to [`Accel::build`](crate::Accel::build)).
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
    /// Index into the meshes given to [`Accel::build`](crate::Accel::build).
    pub mesh: u32,
    /// Object-to-world transform.
    pub world_from_object: Affine3A,
}

/// Build-time/quality trade-off of the BVH (`--bvh-quality`; the first paragraph of each
/// value's comment is its help there).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum BvhQuality {
    /// Fastest build.
    ///
    /// Slower traversal: previews.
    Fast,
    /// Balanced.
    ///
    /// The default.
    #[default]
    Medium,
    /// Fastest traversal.
    ///
    /// Slowest build: long renders.
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
    /// Bytes held by the structure (nodes, triangles, instances): the sum of
    /// `node_bytes`, `triangle_bytes` and `instance_bytes`.
    pub memory_bytes: usize,
    /// Bytes of the BVH nodes, every level (the wide nodes of the bottom-level BVHs and of the
    /// top level).
    pub node_bytes: usize,
    /// Bytes of the triangle store: each kept triangle's three points and its index, in BVH
    /// order (one copy per bottom-level BVH), plus the keyed triangles of deforming meshes.
    pub triangle_bytes: usize,
    /// Bytes placing triangles in instances: the world-space BVH's instance of each triangle
    /// and the top level's entries.
    pub instance_bytes: usize,
    /// Wall time of [`Accel::build`](crate::Accel::build).
    pub build_time: std::time::Duration,
    /// Pieces the world-space BVH was built in, one per instance in parallel, and joined under
    /// a tree over their boxes (0: built as one tree; see
    /// [`FrameHints::join_from`](crate::FrameHints::join_from)).
    pub joined_pieces: usize,
    /// Bottom-level BVHs taken from the previous frame instead of built
    /// ([`Accel::build_frame`](crate::Accel::build_frame)).
    pub reused_blases: usize,
}
