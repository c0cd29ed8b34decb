//! The Depth, Position and Vector passes' first surfaces found a row at a time
//! (`Integrator::first_surfaces`, packets) against one ray at a time (`first_surface`):
//! the same answers, through culled backs and see-through masks too.

use super::job::{geometry, integrator};
use crate::frame_accel::build_accel;
use crate::frame_lights::FrameLights;
use crate::options::RenderOptions;
use aperture_accel::Ray;
use aperture_scene::{AlphaMode, Instance, Scene};
use aperture_shading::convention::Convention;
use aperture_shading::test_scenes;
use glam::{Affine3A, Quat, Vec3};

/// A plane and a ball, over them a see-through mask (alpha 0.3, cutoff 0.5), an opaque one
/// (alpha 0.8) and a single-sided quad turned away from the camera.
fn layered() -> Scene {
    let mut s = test_scenes::lit_plane(3.0);
    let mut add = |mesh: aperture_scene::Mesh, world_from_object| {
        s.instances.push(Instance {
            mesh: s.meshes.len() as u32,
            world_from_object,
            node: s.instances.len() as u32,
            materials: 0,
        });
        s.meshes.push(mesh.into());
    };
    add(
        test_scenes::icosphere(2, 0),
        Affine3A::from_translation(Vec3::new(0.5, 0.6, 1.5)),
    );
    let at = |x: f32, y: f32| Affine3A::from_translation(Vec3::new(x, y, 2.0));
    add(test_scenes::quad(2.0, 1), at(-1.2, 2.0));
    add(test_scenes::quad(2.0, 2), at(0.0, 1.2));
    let away = Affine3A::from_quat(Quat::from_rotation_x(std::f32::consts::PI));
    add(test_scenes::quad(2.0, 3), at(1.2, 1.6) * away);
    let masked = |alpha: f32| aperture_scene::Material {
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        double_sided: true,
        base_color_factor: Vec3::ONE.extend(alpha),
        ..test_scenes::matte(Vec3::ONE)
    };
    let single = aperture_scene::Material {
        double_sided: false,
        ..test_scenes::matte(Vec3::ONE)
    };
    s.materials.extend([masked(0.3), masked(0.8), single]);
    s
}

#[test]
fn first_surfaces_of_a_row_are_each_rays_own() {
    let scene = layered();
    let opts = RenderOptions {
        single_sided: Convention::Gltf,
        ..RenderOptions::default()
    };
    let accel = build_accel(&scene, Default::default());
    let lit = FrameLights::build(&geometry(&scene, &opts), None);
    let tracer = integrator(geometry(&scene, &opts), &accel, &lit, &opts);
    let eye = Vec3::new(0.0, 6.0, 6.0);
    let (mut hits, mut batch) = (Vec::new(), Vec::new());
    let (mut past_first, mut found) = (0, 0);
    for row in 0..48 {
        // A row of rays fanning across the layers (some of its packets coherent, one ray
        // missing everything).
        let rays: Vec<Ray> = (0..64)
            .map(|col| {
                let target = Vec3::new(col as f32 * 0.08 - 2.56, 0.0, row as f32 * 0.08 - 0.5);
                let dir = if row == 0 && col == 0 {
                    Vec3::Y
                } else {
                    target - eye
                };
                Ray {
                    time: 0.0,
                    ..Ray::new(eye, dir.normalize())
                }
            })
            .collect();
        tracer.first_surfaces(&rays, &mut hits, &mut batch);
        assert_eq!(batch.len(), rays.len());
        for (r, got) in rays.iter().zip(&batch) {
            let alone = tracer.first_surface(r.origin, r.dir, r.time);
            assert_eq!(*got, alone, "row {row}, ray {r:?}");
            let first = accel.intersect(r);
            found += usize::from(alone.is_some());
            past_first += usize::from(alone.map(|a| a.1) != first && alone.is_some());
        }
    }
    // Both kinds of ray were met: those seen at their first hit and those that went on
    // through a culled back or a see-through mask.
    assert!(
        past_first > 0 && found > past_first,
        "{past_first} of {found}"
    );
}
