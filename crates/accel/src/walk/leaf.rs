//! The leaf visitors: what a walk does with the primitives of each leaf its ray hits, for
//! closest and any hit, at the top level (entries, each a walk of a bottom-level tree) and the
//! bottom level (triangles).

use super::stack::Group;
use crate::deform::Deformed;
use crate::structure::{Accel, Blas, Entry};
use crate::triangle::{Tri, TriRay};
use crate::types::{Hit, Ray};
use std::mem::MaybeUninit;

/// What [`traverse`](super::traverse) does with each primitive of a hit leaf. A trait with `#[inline(always)]`
/// implementations rather than a closure: the compiler left the occlusion closure as a call per
/// triangle once the traversal was inlined into the query.
pub(crate) trait Leaf {
    /// Whether the walk looks for the closest hit (nearest child first, pops beyond `tmax`
    /// skipped) rather than any hit.
    const CLOSEST: bool;
    /// Visits `primitive`; may shrink `tmax`; returns `true` to stop the traversal.
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool;
}

impl<L: Leaf> Leaf for &mut L {
    const CLOSEST: bool = L::CLOSEST;
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        (**self).visit(primitive, tmax)
    }
}

/// The top level's leaf for closest hit: each entry is a walk of its bottom-level tree. A
/// struct with an `#[inline(always)]` visit, not a closure: closures do not take the query's
/// target features, and once the walk became a stepped state the compiler kept the closure
/// (and the 8-wide node test inside it) a call (+10 % instructions per instanced query).
pub(crate) struct EntriesClosest<'a, const AVX2: bool> {
    pub(crate) accel: &'a Accel,
    pub(crate) ray: &'a Ray,
    pub(crate) stack: &'a mut [MaybeUninit<Group>],
    pub(crate) best: Option<Hit>,
}

impl<const AVX2: bool> Leaf for EntriesClosest<'_, AVX2> {
    const CLOSEST: bool = true;
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        if let Some(entry) = self.accel.entries.get(primitive as usize) {
            let entry = &self.accel.entry_at(entry, self.ray);
            let hit = self
                .accel
                .walk_entry::<AVX2, ClosestLeaf<AVX2>>(entry, self.ray, tmax, self.stack);
            if let Some(Some(hit)) = hit {
                self.best = Some(hit);
            }
        }
        false
    }
}

/// The top level's leaf for occlusion ([`EntriesClosest`] for any hit): stops at the first entry
/// that occludes.
pub(crate) struct EntriesAny<'a, const AVX2: bool> {
    pub(crate) accel: &'a Accel,
    pub(crate) ray: &'a Ray,
    pub(crate) stack: &'a mut [MaybeUninit<Group>],
}

impl<const AVX2: bool> Leaf for EntriesAny<'_, AVX2> {
    const CLOSEST: bool = false;
    #[inline(always)]
    fn visit(&mut self, primitive: u32, _: &mut f32) -> bool {
        let mut tmax = self.ray.tmax;
        self.accel
            .entries
            .get(primitive as usize)
            .is_some_and(|entry| {
                let entry = &self.accel.entry_at(entry, self.ray);
                self.accel
                    .walk_entry::<AVX2, AnyLeaf<AVX2>>(entry, self.ray, &mut tmax, self.stack)
                    == Some(true)
            })
    }
}

/// The top level's leaf for an any hit that says which ([`EntriesAny`] keeping the hit): stops
/// at the first entry with a hit.
pub(crate) struct EntriesBlocker<'a, const AVX2: bool> {
    pub(crate) accel: &'a Accel,
    pub(crate) ray: &'a Ray,
    pub(crate) stack: &'a mut [MaybeUninit<Group>],
    pub(crate) found: Option<Hit>,
}

impl<const AVX2: bool> Leaf for EntriesBlocker<'_, AVX2> {
    const CLOSEST: bool = false;
    #[inline(always)]
    fn visit(&mut self, primitive: u32, _: &mut f32) -> bool {
        let mut tmax = self.ray.tmax;
        let Some(entry) = self.accel.entries.get(primitive as usize) else {
            return false;
        };
        let entry = &self.accel.entry_at(entry, self.ray);
        let hit = self
            .accel
            .walk_entry::<AVX2, BlockerLeaf<AVX2>>(entry, self.ray, &mut tmax, self.stack);
        self.found = hit.flatten();
        self.found.is_some()
    }
}

/// Closest hit over a bottom-level BVH's triangles: `(triangle index, (t, u, v))`. With `AVX`
/// its triangle test takes the AVX path (`triangle::intersect`): such a leaf is only walked
/// inside the queries compiled for AVX2 (`AVX2` of the walks), as `AnyLeaf`'s.
#[derive(Clone, Copy)]
pub(crate) struct ClosestLeaf<'a, const AVX: bool> {
    pub(crate) tris: &'a [Tri],
    pub(crate) ray: TriRay,
    pub(crate) tmin: f32,
    pub(crate) best: Option<(usize, (f32, f32, f32))>,
}

impl<const AVX: bool> Leaf for ClosestLeaf<'_, AVX> {
    const CLOSEST: bool = true;
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        if let Some(tri) = self.tris.get(primitive as usize) {
            if let Some(h) = crate::triangle::intersect::<AVX>(&self.ray, tri, self.tmin, *tmax) {
                return self.record(primitive, h, tmax);
            }
        }
        false
    }
}

/// Any hit over a bottom-level BVH's triangles: stops at the first.
#[derive(Clone, Copy)]
pub(crate) struct AnyLeaf<'a, const AVX: bool> {
    pub(crate) tris: &'a [Tri],
    pub(crate) ray: TriRay,
    pub(crate) tmin: f32,
    /// The primitive that stopped the walk (meaningful once one has).
    pub(crate) blocker: u32,
}

impl<const AVX: bool> Leaf for AnyLeaf<'_, AVX> {
    const CLOSEST: bool = false;
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        let hit = self
            .tris
            .get(primitive as usize)
            .and_then(|tri| crate::triangle::intersect::<AVX>(&self.ray, tri, self.tmin, *tmax));
        hit.is_some_and(|h| self.record(primitive, h, tmax))
    }
}

/// [`AnyLeaf`] keeping the `(t, u, v)` of the hit that stopped the walk, its answer
/// ([`crate::Accel::occluder`]). A wrapper, not a field of `AnyLeaf`: the packets copy that
/// leaf eight at a time, and storing the hit there cost the occlusion batches 3–5 % on
/// `outdoor_dof`.
#[derive(Clone, Copy)]
pub(crate) struct BlockerLeaf<'a, const AVX: bool>(AnyLeaf<'a, AVX>, (f32, f32, f32));

impl<const AVX: bool> Leaf for BlockerLeaf<'_, AVX> {
    const CLOSEST: bool = false;
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        let (tris, ray, tmin) = self.0.triangles();
        let hit = (tris.get(primitive as usize))
            .and_then(|tri| crate::triangle::intersect::<AVX>(ray, tri, tmin, *tmax));
        hit.is_some_and(|h| self.record(primitive, h, tmax))
    }
}

/// A bottom-level leaf (closest or any hit): how a ray's leaf starts and what its answer is,
/// for the one-ray walks ([`Accel::walk_entry`]) and the batches ([`Accel::batch_impl`]).
pub(crate) trait BlasLeaf<'a>: Leaf + Copy {
    /// One ray's answer.
    type Answer;
    /// The leaf of a ray with triangle-test constants `ray`, before any visit.
    fn start(tris: &'a [Tri], ray: TriRay, tmin: f32) -> Self;
    /// The answer once the walk has ended (`stopped`: the leaf stopped it).
    fn answer(&self, blas: &Blas, entry: &Entry, stopped: bool) -> Self::Answer;
    /// The one-ray query, for scenes that interleaving does not cover.
    fn one<const AVX2: bool>(accel: &Accel, ray: &Ray) -> Self::Answer;
    /// The answer for a ray that meets nothing.
    fn miss() -> Self::Answer;
    /// The primitive that stopped the walk, for leaves whose answer any stopping primitive
    /// gives alike (any hit); `None` for the others. Used by the x86-64 packets only.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    fn blocker(&self) -> Option<u32>;
    /// The triangles the leaf tests, its ray's triangle-test constants and `tmin`: what a
    /// packet tests for several leaves at once ([`crate::triangle::lanes`]).
    fn triangles(&self) -> (&'a [Tri], &TriRay, f32);
    /// Takes hit `(t, b1, b2)` of `primitive`, found by the triangle test within
    /// `[tmin, tmax]` (the rest of [`Leaf::visit`]); `true` stops the walk.
    fn record(&mut self, primitive: u32, hit: (f32, f32, f32), tmax: &mut f32) -> bool;
}

impl<'a, const AVX: bool> BlasLeaf<'a> for ClosestLeaf<'a, AVX> {
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

    #[inline(always)]
    fn miss() -> Option<Hit> {
        None
    }

    #[inline(always)]
    fn blocker(&self) -> Option<u32> {
        None
    }

    #[inline(always)]
    fn triangles(&self) -> (&'a [Tri], &TriRay, f32) {
        (self.tris, &self.ray, self.tmin)
    }

    #[inline(always)]
    fn record(&mut self, primitive: u32, h: (f32, f32, f32), tmax: &mut f32) -> bool {
        // A tie in `t` goes to the lower primitive, so the answer does not depend on the
        // order of the visits (packets visit in another order than one ray).
        let first = self
            .best
            .is_none_or(|(best, _)| h.0 < *tmax || (primitive as usize) < best);
        if first {
            *tmax = h.0;
            self.best = Some((primitive as usize, h));
        }
        false
    }
}

impl<'a, const AVX: bool> BlasLeaf<'a> for AnyLeaf<'a, AVX> {
    type Answer = bool;

    #[inline(always)]
    fn start(tris: &'a [Tri], ray: TriRay, tmin: f32) -> Self {
        Self {
            tris,
            ray,
            tmin,
            blocker: 0,
        }
    }

    #[inline(always)]
    fn answer(&self, _: &Blas, _: &Entry, stopped: bool) -> bool {
        stopped
    }

    #[inline(always)]
    fn one<const AVX2: bool>(accel: &Accel, ray: &Ray) -> bool {
        accel.occluded_impl::<AVX2>(ray)
    }

    #[inline(always)]
    fn miss() -> bool {
        false
    }

    #[inline(always)]
    fn blocker(&self) -> Option<u32> {
        Some(self.blocker)
    }

    #[inline(always)]
    fn triangles(&self) -> (&'a [Tri], &TriRay, f32) {
        (self.tris, &self.ray, self.tmin)
    }

    #[inline(always)]
    fn record(&mut self, primitive: u32, _: (f32, f32, f32), _: &mut f32) -> bool {
        self.blocker = primitive;
        true
    }
}

impl<'a, const AVX: bool> BlasLeaf<'a> for BlockerLeaf<'a, AVX> {
    type Answer = Option<Hit>;

    #[inline(always)]
    fn start(tris: &'a [Tri], ray: TriRay, tmin: f32) -> Self {
        Self(AnyLeaf::start(tris, ray, tmin), (0.0, 0.0, 0.0))
    }

    #[inline(always)]
    fn answer(&self, blas: &Blas, entry: &Entry, stopped: bool) -> Option<Hit> {
        stopped.then(|| Accel::make_hit(blas, entry, self.0.blocker as usize, self.1))
    }

    #[inline(always)]
    fn one<const AVX2: bool>(accel: &Accel, ray: &Ray) -> Option<Hit> {
        accel.occluder_impl::<AVX2>(ray)
    }

    #[inline(always)]
    fn miss() -> Option<Hit> {
        None
    }

    #[inline(always)]
    fn blocker(&self) -> Option<u32> {
        // Which hit stops the walk changes the answer: not one a packet may share.
        None
    }

    #[inline(always)]
    fn triangles(&self) -> (&'a [Tri], &TriRay, f32) {
        self.0.triangles()
    }

    #[inline(always)]
    fn record(&mut self, primitive: u32, h: (f32, f32, f32), tmax: &mut f32) -> bool {
        self.1 = h;
        self.0.record(primitive, h, tmax)
    }
}

/// A deforming BVH's leaf ([`Deformed`]): the triangle interpolated at the ray's time, tested
/// and recorded as the still leaf `inner` does.
impl<'s, L: BlasLeaf<'s>, const AVX: bool> Leaf for Deformed<'_, &mut L, AVX> {
    const CLOSEST: bool = L::CLOSEST;
    #[inline(always)]
    fn visit(&mut self, primitive: u32, tmax: &mut f32) -> bool {
        let Some(tri) = self.triangle(primitive as usize) else {
            return false;
        };
        let (_, ray, tmin) = self.inner.triangles();
        match crate::triangle::intersect::<AVX>(ray, &tri, tmin, *tmax) {
            Some(h) => self.inner.record(primitive, h, tmax),
            None => false,
        }
    }
}
