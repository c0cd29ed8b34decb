//! Asking the cache ahead for what shading a hit reads first. A wavefront shades its paths'
//! hits one after another; each hit reads its triangle's corner indices, then three positions,
//! normals and texture coordinates: a few random reads, which miss in a large mesh. Asking for
//! them a few paths ahead overlaps those misses with the shading in between.

use crate::surface::Geometry;
use aperture_scene::Mesh;

impl Geometry<'_> {
    /// Asks the cache for the corner indices of `triangle` of `instance`'s mesh: the first
    /// read of [`Geometry::surface_at`], a few paths before it (see [`Geometry::prefetch`]).
    #[inline(always)]
    pub fn prefetch_corners(&self, instance: u32, triangle: u32) {
        if let Some(mesh) = self.mesh_of(instance) {
            prefetch(mesh.indices.as_ptr().wrapping_add(triangle as usize));
        }
    }

    /// Asks the cache for what [`Geometry::surface_at`] reads at the corners of `triangle` of
    /// `instance`'s mesh: positions, normals and the first texture coordinates. Reads only the
    /// corner indices (asked for earlier by [`Geometry::prefetch_corners`]); out-of-range
    /// indices ask for nothing that is read.
    #[inline(always)]
    pub fn prefetch(&self, instance: u32, triangle: u32) {
        let Some(mesh) = self.mesh_of(instance) else {
            return;
        };
        let Some(corners) = mesh.indices.get(triangle as usize) else {
            return;
        };
        for &i in corners {
            let i = i as usize;
            prefetch(mesh.positions.as_ptr().wrapping_add(i));
            if !mesh.normals.is_empty() {
                prefetch(mesh.normals.as_ptr().wrapping_add(i));
            }
            if !mesh.uv0.is_empty() {
                prefetch(mesh.uv0.as_ptr().wrapping_add(i));
            }
        }
    }

    fn mesh_of(&self, instance: u32) -> Option<&Mesh> {
        let inst = self.scene.instances.get(instance as usize)?;
        self.scene.meshes.get(inst.mesh as usize).map(|m| &**m)
    }
}

/// A hint to bring the cache line holding `p` closer; never reads `p` (any address is fine).
#[inline(always)]
fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is only a hint: it neither faults nor reads the address into the
    // program, so any pointer value, even out of bounds, is sound.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>(p as *const i8);
    }
    #[cfg(target_arch = "aarch64")]
    // SAFETY: `prfm` is only a hint, as above: it neither faults nor reads into the program
    // (`std::arch::aarch64::_prefetch` is not stable yet). No memory is written, no flags.
    unsafe {
        std::arch::asm!("prfm pldl1keep, [{p}]", p = in(reg) p, options(nostack, readonly, preserves_flags));
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    let _ = p;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::{prefetch_worth_it as worth_it, MaterialOverride, PREFETCH_ABOVE};
    use crate::test_scenes;

    #[test]
    fn hints_are_for_large_meshes_and_never_read_out_of_range() {
        let small = test_scenes::lit_plane(1.0);
        assert!(
            !worth_it(&small),
            "a test scene's few kilobytes are not worth hints"
        );
        let g = Geometry::new(&small, MaterialOverride::None);
        // Out-of-range instances, triangles and corner indices must be harmless.
        for (instance, triangle) in [(0, 0), (0, u32::MAX), (u32::MAX, 0), (7, 12345)] {
            g.prefetch_corners(instance, triangle);
            g.prefetch(instance, triangle);
        }
        let mut big = small.clone();
        let mesh = std::sync::Arc::make_mut(&mut big.meshes[0]);
        let n = PREFETCH_ABOVE / std::mem::size_of_val(&mesh.positions[0]) + 1;
        mesh.positions.resize(n, glam::Vec3::ZERO);
        mesh.indices.push([u32::MAX, 0, (n - 1) as u32]);
        assert!(worth_it(&big));
        let g = Geometry::new(&big, MaterialOverride::None);
        let last = big.meshes[0].indices.len() as u32 - 1;
        g.prefetch(0, last);
    }
}
