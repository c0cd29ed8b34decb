//! Meshes that deform within the shutter (skins, morph targets), as Cycles' *motion steps*:
//! vertex positions keyed at evenly spaced times over `[0, 1]`, interpolated linearly at a
//! ray's time. Their bottom-level BVH bounds each triangle over every key (the swept box) and
//! its leaves test the triangle interpolated at the ray's time.
//!
//! Why the union of the keys' boxes holds every in-between triangle: between two keys each
//! vertex moves on the segment joining its two positions, which lies in the box of those two
//! positions; [`lerp_point`] clamps its result into that box, so rounding cannot step out.

use crate::triangle::Tri;
use glam::Vec3;

/// One mesh's vertex positions (object space) keyed at `n ≥ 2` evenly spaced times over
/// `[0, 1]` (the shutter, normalised); key `k` at `k / (n − 1)`.
#[derive(Debug, Clone, PartialEq)]
pub struct VertexMotion {
    /// Vertex-major: vertex `v`'s key `k` at `v * steps + k` (a vertex's two enclosing keys
    /// are neighbours).
    keys: Vec<Vec3>,
    steps: usize,
    vertices: usize,
}

impl VertexMotion {
    /// The positions of every vertex at each key time (`keys[k][v]`); `None` when there are
    /// fewer than two keys, their vertex counts differ, or a position is not finite.
    pub fn new(keys: &[&[Vec3]]) -> Option<Self> {
        let vertices = keys.first()?.len();
        if keys.len() < 2 || keys.iter().any(|k| k.len() != vertices) {
            return None;
        }
        let steps = keys.len();
        let mut flat = Vec::with_capacity(vertices * steps);
        for v in 0..vertices {
            for k in keys {
                let p = k[v];
                if !p.is_finite() {
                    return None;
                }
                flat.push(p);
            }
        }
        Some(Self {
            keys: flat,
            steps,
            vertices,
        })
    }

    /// Number of keys (motion steps).
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.vertices
    }

    /// True when every vertex stays where it is at every key (nothing deforms).
    pub fn is_still(&self) -> bool {
        self.keys
            .chunks_exact(self.steps)
            .all(|k| k.iter().all(|p| *p == k[0]))
    }

    /// The key interval holding normalised time `tau` (clamped to `[0, 1]`) and the fraction
    /// of the way through it: `(k, f)` interpolates keys `k` and `k + 1`.
    #[inline]
    pub fn segment(&self, tau: f32) -> (usize, f32) {
        segment(self.steps, tau)
    }

    /// Vertex `v` at key interval `(k, f)` ([`VertexMotion::segment`]); `None` out of range.
    #[inline]
    pub fn position(&self, v: usize, (k, f): (usize, f32)) -> Option<Vec3> {
        let i = v.checked_mul(self.steps)?.checked_add(k)?;
        let a = self.keys.get(i)?;
        let b = self.keys.get(i + 1).filter(|_| k + 1 < self.steps)?;
        Some(lerp_point(*a, *b, f))
    }

    /// Vertex `v`'s key `k`, if both exist.
    pub fn key(&self, v: usize, k: usize) -> Option<Vec3> {
        (k < self.steps && v < self.vertices).then(|| self.keys[v * self.steps + k])
    }

    /// The largest coordinate magnitude over every key (for rounding-error bounds).
    pub(crate) fn max_abs(&self) -> f32 {
        self.keys
            .iter()
            .fold(0.0f32, |m, p| m.max(p.abs().max_element()))
    }
}

/// [`VertexMotion::segment`] for `steps ≥ 2` keys.
#[inline(always)]
fn segment(steps: usize, tau: f32) -> (usize, f32) {
    let x = tau.clamp(0.0, 1.0) * (steps - 1) as f32;
    let k = (x as usize).min(steps - 2);
    (k, x - k as f32)
}

/// `a` moved the fraction `f` of the way to `b`, kept inside the box of `a` and `b` (so within
/// the swept box whatever the rounding). The same bits wherever it is computed: the accel's
/// triangles and a renderer's surface agree, and triangles sharing a vertex share its bits.
#[inline(always)]
pub fn lerp_point(a: Vec3, b: Vec3, f: f32) -> Vec3 {
    (a + (b - a) * f).clamp(a.min(b), a.max(b))
}

/// A bottom-level BVH's triangles keyed over the shutter: per triangle (BVH order), its three
/// vertices at each key, triangle-major (`tri * steps + k`).
#[derive(Debug, Clone)]
pub(crate) struct Deform {
    pub(crate) keys: Vec<[Vec3; 3]>,
    pub(crate) steps: usize,
}

impl Deform {
    /// Per kept triangle (`tris[i].prim` indexes `indices`), its vertices at every key of
    /// `motion`; `None` when an index is out of `motion`'s range.
    pub(crate) fn new(
        tris: &[(Tri, u32)],
        indices: &[[u32; 3]],
        motion: &VertexMotion,
    ) -> Option<Self> {
        let steps = motion.steps;
        let mut keys = Vec::with_capacity(tris.len() * steps);
        for (t, _) in tris {
            let tri = indices.get(t.prim as usize)?;
            for k in 0..steps {
                let p = [0, 1, 2].map(|c| motion.key(tri[c] as usize, k));
                keys.push([p[0]?, p[1]?, p[2]?]);
            }
        }
        Some(Self { keys, steps })
    }

    /// The box triangle `i` sweeps over the shutter: the union of its boxes at every key.
    pub(crate) fn swept_box(&self, i: usize) -> (Vec3, Vec3) {
        let keys = &self.keys[i * self.steps..(i + 1) * self.steps];
        keys.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| {
                (
                    lo.min(p[0]).min(p[1]).min(p[2]),
                    hi.max(p[0]).max(p[1]).max(p[2]),
                )
            },
        )
    }

    /// The key interval of normalised time `tau` ([`VertexMotion::segment`]).
    #[inline(always)]
    pub(crate) fn segment(&self, tau: f32) -> (usize, f32) {
        segment(self.steps, tau)
    }

    /// Triangle `i` at key interval `(k, f)`; `None` out of range.
    #[inline(always)]
    pub(crate) fn triangle(&self, i: usize, at: (usize, f32)) -> Option<Tri> {
        triangle_at(&self.keys, self.steps, i, at)
    }

    /// The keys in the order `order` (BVH order) gives the triangles.
    pub(crate) fn reorder(&self, order: &[u32]) -> Self {
        let mut keys = Vec::with_capacity(self.keys.len());
        for &i in order {
            let i = i as usize * self.steps;
            keys.extend_from_slice(&self.keys[i..i + self.steps]);
        }
        Self {
            keys,
            steps: self.steps,
        }
    }
}

/// A bottom-level leaf over a deforming BVH: each visited triangle is interpolated at the
/// ray's time and tested as the still leaf `inner` tests its own, which records the hit (so
/// ties, stops and answers are exactly the still leaf's).
pub(crate) struct Deformed<'a, L, const AVX: bool> {
    pub(crate) inner: L,
    pub(crate) keys: &'a [[Vec3; 3]],
    pub(crate) steps: usize,
    /// The ray's key interval ([`segment`]).
    pub(crate) at: (usize, f32),
}

impl<'a, L, const AVX: bool> Deformed<'a, L, AVX> {
    /// The leaf of a ray at normalised time `tau` over `deform`'s keys.
    #[inline(always)]
    pub(crate) fn new(inner: L, deform: &'a Deform, tau: f32) -> Self {
        Self {
            inner,
            keys: &deform.keys,
            steps: deform.steps,
            at: segment(deform.steps, tau),
        }
    }

    /// Triangle `i` at the ray's time.
    #[inline(always)]
    pub(crate) fn triangle(&self, i: usize) -> Option<Tri> {
        triangle_at(self.keys, self.steps, i, self.at)
    }
}

/// Triangle `i` of triangle-major `keys` (`steps` a triangle) at key interval `(k, f)`.
#[inline(always)]
fn triangle_at(keys: &[[Vec3; 3]], steps: usize, i: usize, (k, f): (usize, f32)) -> Option<Tri> {
    let base = i.checked_mul(steps)?.checked_add(k)?;
    let (a, b) = (keys.get(base)?, keys.get(base + 1)?);
    Some(Tri {
        p: [0, 1, 2].map(|c| lerp_point(a[c], b[c], f)),
        prim: i as u32,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_met_and_the_middle_is_between() {
        let a = [Vec3::ZERO, Vec3::X];
        let b = [Vec3::new(0.0, 2.0, 0.0), Vec3::X];
        let m = VertexMotion::new(&[&a, &b]).unwrap();
        assert!(!m.is_still());
        assert_eq!(m.position(0, m.segment(0.0)), Some(Vec3::ZERO));
        assert_eq!(
            m.position(0, m.segment(1.0)),
            Some(Vec3::new(0.0, 2.0, 0.0))
        );
        assert_eq!(
            m.position(0, m.segment(0.25)),
            Some(Vec3::new(0.0, 0.5, 0.0))
        );
        assert_eq!(m.position(1, m.segment(0.7)), Some(Vec3::X));
        assert_eq!(m.position(2, m.segment(0.7)), None);
        assert!(VertexMotion::new(&[&a]).is_none());
        assert!(VertexMotion::new(&[&a, &b[..1]]).is_none());
        assert!(VertexMotion::new(&[&a, &[Vec3::NAN, Vec3::X]]).is_none());
        assert!(VertexMotion::new(&[&a, &a, &a]).unwrap().is_still());
    }

    #[test]
    fn interpolation_stays_in_the_box_of_its_ends() {
        // Values whose difference rounds: the clamped result never leaves [min, max].
        let pairs = [
            (1e-8f32, 1.0f32),
            (-1e-8, 1.0),
            (0.1, 0.3),
            (-3.7e5, 2.9e-3),
        ];
        for (a, b) in pairs {
            for i in 0..=64 {
                let f = i as f32 / 64.0;
                let p = lerp_point(Vec3::splat(a), Vec3::splat(b), f);
                assert!(p.x >= a.min(b) && p.x <= a.max(b), "{a} {b} {f}: {}", p.x);
            }
        }
    }
}
