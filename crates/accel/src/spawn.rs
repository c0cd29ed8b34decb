//! Where secondary rays start: hit points with error bounds, and offsets off the surface.

use crate::{Accel, Hit, Ray};
use glam::Vec3;

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
