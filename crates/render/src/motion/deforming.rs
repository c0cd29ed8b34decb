//! Meshes deforming within the shutter (skins, morph weights) by motion steps, as Cycles does:
//! each one's vertex positions at the steps ([`VertexMotion`], object space), interpolated
//! linearly at a ray's time by the accel and by the surface found there.

use aperture_accel::VertexMotion;
use aperture_shading::surface::Surface;
use glam::Affine3A;

/// Moves `s`, found on a deforming mesh with `keys` placed by `world_from_object` (the frame's
/// placement of its instance), to the triangle interpolated at normalised time `tau`: the
/// position, the geometric normal and the area from the interpolated vertices, exactly those
/// the accel intersected. The shading normal and tangent stay the frame's (interpolated vertex
/// attributes of the frame's pose: a shading-only approximation, as the texture coordinates,
/// which do not deform).
#[inline]
pub fn deform_surface(
    s: &mut Surface,
    keys: &VertexMotion,
    world_from_object: &Affine3A,
    tau: f32,
) {
    let (_, [i0, i1, i2], b) = s.corners;
    let at = keys.segment(tau);
    let p = [i0, i1, i2].map(|i| keys.position(i as usize, at));
    let [Some(p0), Some(p1), Some(p2)] = p else {
        return;
    };
    let m = world_from_object;
    s.p = m.transform_point3(b.x * p0 + b.y * p1 + b.z * p2);
    let cross = m
        .transform_vector3(p1 - p0)
        .cross(m.transform_vector3(p2 - p0));
    let len = cross.length();
    if len > 0.0 && len.is_finite() {
        // As `Geometry::surface_at`: the cross product flips under a mirroring placement.
        let mirrored = m.matrix3.determinant() < 0.0;
        s.ng = if mirrored { -cross / len } else { cross / len };
        s.area = 0.5 * len;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aperture_shading::surface::{Geometry, MaterialOverride};
    use aperture_shading::test_scenes::{emitter, look_at_camera, quad, scene};
    use aperture_shading::transmission::TransmissionModel;
    use glam::{Quat, Vec3};

    #[test]
    fn the_surface_is_the_interpolated_triangle() {
        let cam = look_at_camera(Vec3::ZERO, Vec3::NEG_Z, 0.5, Default::default());
        let place = Affine3A::from_scale_rotation_translation(
            Vec3::new(2.0, 1.0, -1.0),
            Quat::from_rotation_z(0.3),
            Vec3::new(0.0, 0.0, -5.0),
        );
        let sc = scene(vec![(quad(1.0, 0), place)], vec![emitter(Vec3::ONE)], cam);
        let frame = &sc.meshes[0].positions;
        // Key 1 lifts every vertex by 1 along y and tilts vertex 0 by 0.5 along x.
        let mut lifted: Vec<Vec3> = frame.iter().map(|p| *p + Vec3::Y).collect();
        lifted[0] += Vec3::new(0.5, 0.0, 0.0);
        let keys = VertexMotion::new(&[frame, &lifted]).unwrap();
        let geom =
            Geometry::with_transmission(&sc, MaterialOverride::None, TransmissionModel::Gltf);
        let (b1, b2) = (0.2, 0.3);
        for tau in [0.0f32, 0.25, 1.0] {
            let mut s = geom.surface(0, 0, b1, b2);
            let still_ng = s.ng;
            deform_surface(&mut s, &keys, &place, tau);
            let [i0, i1, i2] = sc.meshes[0].indices[0].map(|i| i as usize);
            let at = |i: usize| frame[i] + tau * (lifted[i] - frame[i]);
            let want = (1.0 - b1 - b2) * at(i0) + b1 * at(i1) + b2 * at(i2);
            assert!(
                (s.p - place.transform_point3(want)).length() < 1e-5,
                "tau {tau}"
            );
            let (e1, e2) = (at(i1) - at(i0), at(i2) - at(i0));
            let n = place
                .transform_vector3(e1)
                .cross(place.transform_vector3(e2))
                .normalize();
            // The placement mirrors (a negative scale): the normal is flipped back.
            assert!((s.ng + n).length() < 1e-5, "tau {tau}: {} {n}", s.ng);
            if tau == 0.0 {
                assert!((s.ng - still_ng).length() < 1e-6);
            }
        }
    }
}
