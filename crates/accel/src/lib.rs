//! Ray queries over triangle meshes placed by instances: closest hit and occlusion.
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

/// Facts about a built acceleration structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct AccelStats {
    /// Triangles left out because they have zero area or non-finite vertices (counted per mesh).
    pub degenerate_triangles: usize,
    /// Triangles kept, counted once per mesh.
    pub unique_triangles: usize,
}

/// The acceleration structure: answers ray queries from many threads at once.
#[derive(Debug, Clone)]
pub struct Accel {
    meshes: Vec<(Vec<Vec3>, Vec<[u32; 3]>)>,
    instances: Vec<InstanceInput>,
    stats: AccelStats,
}

impl Accel {
    /// Builds the structure. Placeholder: brute force until the BVH lands.
    pub fn build(
        meshes: &[MeshInput<'_>],
        instances: &[InstanceInput],
        quality: BvhQuality,
    ) -> Self {
        let _ = quality;
        let meshes: Vec<_> = meshes
            .iter()
            .map(|m| (m.positions.to_vec(), m.indices.to_vec()))
            .collect();
        let unique_triangles = meshes.iter().map(|m| m.1.len()).sum();
        Self {
            meshes,
            instances: instances.to_vec(),
            stats: AccelStats {
                degenerate_triangles: 0,
                unique_triangles,
            },
        }
    }

    /// Build statistics.
    pub fn stats(&self) -> AccelStats {
        self.stats
    }

    /// The closest hit in `[ray.tmin, ray.tmax]`, if any.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut tmax = ray.tmax;
        for (ii, inst) in self.instances.iter().enumerate() {
            let Some((pos, idx)) = self.meshes.get(inst.mesh as usize) else {
                continue;
            };
            for (ti, tri) in idx.iter().enumerate() {
                let p = tri.map(|i| inst.world_from_object.transform_point3(pos[i as usize]));
                if let Some((t, u, v)) = moller_trumbore(ray, p, tmax) {
                    tmax = t;
                    best = Some(Hit {
                        t,
                        instance: ii as u32,
                        triangle: ti as u32,
                        u,
                        v,
                    });
                }
            }
        }
        best
    }

    /// True when anything lies in `[ray.tmin, ray.tmax]`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.intersect(ray).is_some()
    }
}

fn moller_trumbore(ray: &Ray, p: [Vec3; 3], tmax: f32) -> Option<(f32, f32, f32)> {
    let e1 = p[1] - p[0];
    let e2 = p[2] - p[0];
    let pv = ray.dir.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tv = ray.origin - p[0];
    let u = tv.dot(pv) * inv;
    let qv = tv.cross(e1);
    let v = ray.dir.dot(qv) * inv;
    let t = e2.dot(qv) * inv;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t >= ray.tmin && t <= tmax).then_some((t, u, v))
}

/// Moves a surface point off its surface along the geometric normal so that a ray leaving it
/// cannot hit the same surface again (Wächter and Binder, Ray Tracing Gems ch. 6): the offset is
/// a few float ulps of the point's magnitude, not a fixed epsilon. `n` need not face the ray;
/// pass the normal flipped to the side the new ray leaves on.
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let of_i = (INT_SCALE * n).to_array().map(|x| x as i32);
    let pa = p.to_array();
    let mut out = [0.0f32; 3];
    for k in 0..3 {
        let bits = pa[k].to_bits() as i32;
        let moved = bits + if pa[k] < 0.0 { -of_i[k] } else { of_i[k] };
        let p_i = f32::from_bits(moved as u32);
        out[k] = if pa[k].abs() < ORIGIN {
            pa[k] + FLOAT_SCALE * n[k]
        } else {
            p_i
        };
    }
    Vec3::from_array(out)
}
