//! The queries: closest hit and occlusion for one ray, a batch or many rays (on rayon's
//! threads), brute force for tests, and triangle lookup.

use crate::deform::Deformed;
use crate::node::BoxRay;
use crate::structure::{Accel, Blas, Entry, FLATTENED, NO_MOTION};
use crate::triangle::TriRay;
use crate::types::{AccelStats, Hit, Ray};
use crate::walk::*;
use glam::Vec3;
use rayon::prelude::*;
use std::mem::MaybeUninit;

impl Accel {
    /// Build statistics.
    pub fn stats(&self) -> AccelStats {
        self.stats
    }

    /// A box (world space) holding everything a ray can hit; `None` when nothing can be hit.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        (!self.entries.is_empty()).then_some(self.tlas_bounds)
    }

    /// The closest hit in `[ray.tmin, ray.tmax]`, if any.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only when `detect_avx2` found every feature it enables.
            return unsafe { self.intersect_avx2(ray) };
        }
        #[cfg(target_arch = "aarch64")]
        if self.avx2 {
            // The NEON kernels (`detect_avx2`).
            return self.intersect_impl::<true>(ray);
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
        #[cfg(target_arch = "aarch64")]
        if self.avx2 {
            // The NEON kernels (`detect_avx2`).
            return self.occluded_impl::<true>(ray);
        }
        self.occluded_impl::<false>(ray)
    }

    /// A hit in `[ray.tmin, ray.tmax]` if any: the first the any-hit walk meets, not the
    /// closest ([`Accel::occluded`] saying which). For shadow rays that must tell an occluder
    /// from a surface they pass (the back of a culled single-sided face).
    pub fn occluder(&self, ray: &Ray) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: as in `intersect`.
            return unsafe { self.occluder_avx2(ray) };
        }
        #[cfg(target_arch = "aarch64")]
        if self.avx2 {
            // The NEON kernels (`detect_avx2`).
            return self.occluder_impl::<true>(ray);
        }
        self.occluder_impl::<false>(ray)
    }

    /// [`Accel::intersect_avx2`] for [`Accel::occluder`].
    ///
    /// # Safety
    /// As for [`Accel::intersect_avx2`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,popcnt,lzcnt,bmi1,bmi2")]
    unsafe fn occluder_avx2(&self, ray: &Ray) -> Option<Hit> {
        self.occluder_impl::<true>(ray)
    }

    #[inline(always)]
    pub(crate) fn occluder_impl<const AVX2: bool>(&self, ray: &Ray) -> Option<Hit> {
        if self.misses_bounds(ray) {
            return None;
        }
        let mut inline: InlineStack = [MaybeUninit::uninit(); INLINE_STACK];
        let mut heap = Vec::new();
        let blas_stack = stack_for(self.max_blas_depth, &mut inline, &mut heap);
        let mut tmax = ray.tmax;
        let mut leaf = EntriesBlocker::<AVX2> {
            accel: self,
            ray,
            stack: blas_stack,
            found: None,
        };
        self.for_entries::<AVX2>(ray, &mut tmax, &mut leaf);
        leaf.found
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

    /// Whether `ray` provably meets nothing: it starts outside the scene's bounds and its
    /// `[tmin, tmax]` misses them, widened by the box test's rounding slack (so no hit the
    /// walk would find is lost). Rays starting inside pass at the cost of two comparisons.
    ///
    /// Why: rays that miss a lone asset (most primary rays of a product shot) then cost a few
    /// dozen instructions instead of a walk's setup and root test (Embree rejects them at its
    /// root node as cheaply).
    #[inline(always)]
    pub(crate) fn misses_bounds(&self, ray: &Ray) -> bool {
        if self.starts_inside(ray) {
            return false;
        }
        let (lo, hi) = self.tlas_bounds;
        let o = ray.origin;
        if !(o.is_finite() && ray.dir.is_finite()) {
            return false;
        }
        let inv = crate::node::clamped_inv(ray.dir);
        let o = glam::Vec3A::from(o);
        let slack = inv.abs() * crate::node::reach(o, (lo, hi));
        let t0 = (glam::Vec3A::from(lo) - o) * inv;
        let t1 = (glam::Vec3A::from(hi) - o) * inv;
        let near = t0.min(t1) - slack;
        let far = t0.max(t1) + slack;
        // `f32::max`/`min` pass over a NaN `tmin`/`tmax`: a wider segment, never a false miss.
        let enter = near.max_element().max(ray.tmin);
        let exit = far.min_element().min(ray.tmax);
        enter > exit
    }

    /// Whether `ray` starts inside the scene's bounds (then [`Accel::misses_bounds`] is false).
    #[inline(always)]
    pub(crate) fn starts_inside(&self, ray: &Ray) -> bool {
        let (lo, hi) = self.tlas_bounds;
        let o = glam::Vec3A::from(ray.origin);
        (o.cmpge(lo.into()) & o.cmple(hi.into())).all()
    }

    #[inline(always)]
    pub(crate) fn intersect_impl<const AVX2: bool>(&self, ray: &Ray) -> Option<Hit> {
        if self.misses_bounds(ray) {
            return None;
        }
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
    pub(crate) fn occluded_impl<const AVX2: bool>(&self, ray: &Ray) -> bool {
        if self.misses_bounds(ray) {
            return false;
        }
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
    /// of `intersect` calls (one walk's dependent loads leave the core idle; several fill it).
    pub fn intersect_batch(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only when `detect_avx2` found every feature it enables.
            return unsafe { self.intersect_batch_avx2(rays, out) };
        }
        #[cfg(target_arch = "aarch64")]
        if self.avx2 {
            // The NEON kernels (`detect_avx2`).
            return self.batch_impl::<true, ClosestLeaf<true>>(rays, out);
        }
        self.batch_impl::<false, ClosestLeaf<false>>(rays, out)
    }

    /// [`Accel::occluded`] for each of `rays` on the calling thread, interleaved as
    /// [`Accel::intersect_batch`].
    pub fn occluded_batch(&self, rays: &[Ray], out: &mut [bool]) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: as in `intersect_batch`.
            return unsafe { self.occluded_batch_avx2(rays, out) };
        }
        #[cfg(target_arch = "aarch64")]
        if self.avx2 {
            // The NEON kernels (`detect_avx2`).
            return self.batch_impl::<true, AnyLeaf<true>>(rays, out);
        }
        self.batch_impl::<false, AnyLeaf<false>>(rays, out)
    }

    /// [`Accel::intersect_batch`] compiled for AVX2.
    ///
    /// # Safety
    /// As for [`Accel::intersect_avx2`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,popcnt,lzcnt,bmi1,bmi2")]
    unsafe fn intersect_batch_avx2(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        self.batch_impl::<true, ClosestLeaf<true>>(rays, out)
    }

    /// [`Accel::occluded_batch`] compiled for AVX2.
    ///
    /// # Safety
    /// As for [`Accel::intersect_avx2`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,popcnt,lzcnt,bmi1,bmi2")]
    unsafe fn occluded_batch_avx2(&self, rays: &[Ray], out: &mut [bool]) {
        self.batch_impl::<true, AnyLeaf<true>>(rays, out)
    }

    /// The one bottom-level tree every ray walks, when interleaving applies: a scene of one
    /// entry whose stack fits inline. Other scenes (instanced, or degenerate depths) go ray by
    /// ray.
    pub(crate) fn single_entry(&self) -> Option<(&Entry, &Blas)> {
        match self.entries.as_slice() {
            // A moving entry is placed per ray: walked ray by ray.
            [entry]
                if stack_len(self.max_blas_depth) <= INLINE_STACK && entry.motion == NO_MOTION =>
            {
                // A deforming tree's triangles are interpolated per ray: ray by ray too.
                self.blases
                    .get(entry.blas as usize)
                    .filter(|b| !b.nodes.is_empty() && b.deform.is_none())
                    .map(|b| (entry, b))
            }
            _ => None,
        }
    }

    /// The batch queries: [`interleave`]d walks of `rays` with leaves of type `L`, one answer per
    /// ray into `out`; ray by ray (`L::one`) where interleaving does not apply.
    #[inline(always)]
    pub(crate) fn batch_impl<'s, const AVX2: bool, L: BlasLeaf<'s>>(
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
        // Only the rays that may meet something are walked. A batch whose first ray starts
        // inside the scene (bounce and shadow rays, a camera inside) is walked whole, without
        // the indirection: culling only saves work, and the batches that gain start outside.
        if rays.first().is_none_or(|r| self.starts_inside(r)) {
            return Self::interleave_rays::<AVX2, L>(entry, blas, rays, out, n, Direct);
        }
        let mut walked = Vec::with_capacity(n);
        for (i, (ray, o)) in rays.iter().zip(out.iter_mut()).enumerate() {
            if self.misses_bounds(ray) {
                *o = L::miss();
            } else {
                walked.push(i);
            }
        }
        Self::interleave_rays::<AVX2, L>(entry, blas, rays, out, walked.len(), Listed(&walked));
    }

    /// The [`interleave`]d walks of `count` of `rays` over `blas`: walk `j` is ray
    /// `map.ray(j)`, its answer goes to `out[map.ray(j)]`. Monomorphised per mapping, so that
    /// the batch without culling pays no indirection.
    #[inline(always)]
    fn interleave_rays<'s, const AVX2: bool, L: BlasLeaf<'s>>(
        entry: &Entry,
        blas: &'s Blas,
        rays: &[Ray],
        out: &mut [L::Answer],
        count: usize,
        map: impl RayMap,
    ) {
        let mut walks = BatchWalks::<L, _, AVX2> {
            entry,
            blas,
            rays,
            out,
            map,
        };
        interleave::<AVX2, L>(&blas.nodes, count, &mut walks);
    }

    /// [`Accel::intersect`] for many rays, in parallel on the current rayon pool, each thread
    /// running [`Accel::intersect_batch`] on runs of 256 rays (one job each, so that threads
    /// finish together). `out` receives one result per ray
    /// (extra slots on either side are left alone).
    pub fn intersect_many(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        rays.par_chunks(256)
            .zip(out.par_chunks_mut(256))
            .with_max_len(1)
            .for_each(|(r, o)| self.intersect_batch(r, o));
    }

    /// [`Accel::occluded`] for many rays, in parallel on the current rayon pool (through
    /// [`Accel::occluded_batch`], as [`Accel::intersect_many`]).
    pub fn occluded_many(&self, rays: &[Ray], out: &mut [bool]) {
        rays.par_chunks(256)
            .zip(out.par_chunks_mut(256))
            .with_max_len(1)
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
                traverse::<AVX2, _>(&self.tlas, &r, tmax, stack, leaf)
            }
        }
    }

    /// `entry` placed at `ray`'s time: itself when it stays put, else a copy whose
    /// `object_from_world` is the moving instance's at that time.
    #[inline(always)]
    pub(crate) fn entry_at(&self, entry: &Entry, ray: &Ray) -> Entry {
        match self.motions.get(entry.motion as usize) {
            None => *entry,
            Some(m) => Entry {
                object_from_world: m.at(ray.time).inverse(),
                ..*entry
            },
        }
    }

    #[inline(always)]
    pub(crate) fn object_ray(entry: &Entry, ray: &Ray) -> (Vec3, Vec3) {
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
    pub(crate) fn make_hit(
        blas: &Blas,
        entry: &Entry,
        i: usize,
        (t, u, v): (f32, f32, f32),
    ) -> Hit {
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
    pub(crate) fn walk_entry<'s, const AVX2: bool, L: BlasLeaf<'s>>(
        &'s self,
        entry: &Entry,
        ray: &Ray,
        tmax: &mut f32,
        stack: &mut [MaybeUninit<Group>],
    ) -> Option<L::Answer> {
        let blas = self.blases.get(entry.blas as usize)?;
        let (br, mut leaf) = Self::walk_start::<AVX2, L>(entry, blas, ray);
        let stopped = match &blas.deform {
            None => traverse::<AVX2, _>(&blas.nodes, &br, tmax, stack, &mut leaf),
            Some(d) => {
                let deformed = Deformed::<_, AVX2>::new(&mut leaf, d, ray.time);
                traverse::<AVX2, _>(&blas.nodes, &br, tmax, stack, deformed)
            }
        };
        Some(leaf.answer(blas, entry, stopped))
    }

    /// What a walk of `blas` (drawn by `entry`) for `ray` starts from: the ray in the tree's
    /// space prepared for box tests, and a fresh leaf with its triangle-test constants.
    /// With `AVX2` it must be inlined into a function compiled for AVX2 (the triangle-test
    /// constants come from [`TriRay::new_avx`]).
    #[inline(always)]
    pub(crate) fn walk_start<'s, const AVX2: bool, L: BlasLeaf<'s>>(
        entry: &Entry,
        blas: &'s Blas,
        ray: &Ray,
    ) -> (BoxRay, L) {
        let (o, d) = Self::object_ray(entry, ray);
        // SAFETY: `AVX2` only in the queries compiled for AVX2 (see above).
        let tri_ray = unsafe { TriRay::new_for::<AVX2>(o, d) };
        (
            BoxRay::new(o, d, ray.tmin, blas.box_bounds),
            L::start(&blas.tris, tri_ray, ray.tmin),
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
            let entry = &self.entry_at(entry, ray);
            let (o, d) = Self::object_ray(entry, ray);
            let tr = TriRay::new(o, d);
            for (i, tri) in blas.tris.iter().enumerate() {
                let tri = match &blas.deform {
                    None => *tri,
                    Some(def) => match def.triangle(i, def.segment(ray.time)) {
                        Some(t) => t,
                        None => continue,
                    },
                };
                if let Some(h) = crate::triangle::intersect::<false>(&tr, &tri, ray.tmin, tmax) {
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
                // The instance may be drawn by another entry: look on.
                let found = (0..blas.tris.len())
                    .find(|&i| blas.tri_instance[i] == instance && blas.tris[i].prim == triangle);
                if let Some(i) = found {
                    return Some(blas.tris[i].p);
                }
                continue;
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

/// Which ray walk `j` of a batch is: [`Direct`] (ray `j`) or [`Listed`] (the `j`-th of a list).
/// A trait, not a closure, for the reason of [`Walks`].
trait RayMap {
    fn ray(&self, j: usize) -> usize;
}

/// Walk `j` is ray `j`.
struct Direct;

impl RayMap for Direct {
    #[inline(always)]
    fn ray(&self, j: usize) -> usize {
        j
    }
}

/// Walk `j` is ray `self.0[j]`.
struct Listed<'a>(&'a [usize]);

impl RayMap for Listed<'_> {
    #[inline(always)]
    fn ray(&self, j: usize) -> usize {
        self.0[j]
    }
}

/// The walks of one batch over a single entry's tree: their starts, and their answers into
/// `out`. With `AVX2` only inside the queries compiled for AVX2 ([`Accel::walk_start`]).
struct BatchWalks<'s, 'a, L: BlasLeaf<'s>, M: RayMap, const AVX2: bool> {
    entry: &'a Entry,
    blas: &'s Blas,
    rays: &'a [Ray],
    out: &'a mut [L::Answer],
    map: M,
}

impl<'s, L: BlasLeaf<'s>, M: RayMap, const AVX2: bool> Walks<L> for BatchWalks<'s, '_, L, M, AVX2> {
    #[inline(always)]
    fn start(&mut self, j: usize) -> (BoxRay, f32, L) {
        let ray = &self.rays[self.map.ray(j)];
        let (br, leaf) = Accel::walk_start::<AVX2, L>(self.entry, self.blas, ray);
        (br, ray.tmax, leaf)
    }

    #[inline(always)]
    fn finish(&mut self, j: usize, leaf: &L, stopped: bool) {
        self.out[self.map.ray(j)] = leaf.answer(self.blas, self.entry, stopped);
    }
}
