//! World bounds of object-space boxes, widened so that rounding cannot make them miss a hit.

use glam::{Affine3A, Vec3};
use obvhs::aabb::Aabb;

/// World bounds of an object-space box, widened by a relative margin so that rounding in the
/// transform (of the box here, of the ray at query time) cannot make the box miss a hit.
pub(super) fn world_bounds(world_from_object: &Affine3A, (lo, hi): (Vec3, Vec3)) -> Aabb {
    let mut wlo = Vec3::splat(f32::INFINITY);
    let mut whi = Vec3::splat(f32::NEG_INFINITY);
    for k in 0..8 {
        let c = Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let w = world_from_object.transform_point3(c);
        wlo = wlo.min(w);
        whi = whi.max(w);
    }
    let margin = 1e-5
        * wlo
            .abs()
            .max(whi.abs())
            .max_element()
            .max(f32::MIN_POSITIVE);
    Aabb::new((wlo - margin).into(), (whi + margin).into())
}
