//! Animation frames: `Accel::build_frame` with the previous frame's structure reuses the
//! bottom-level BVHs of unchanged meshes and answers every ray exactly as a build without it.

use aperture_accel::{Accel, BvhQuality, FrameHints, InstanceInput, MeshInput};
use glam::{Affine3A, Quat, Vec3};

mod common;
use common::{grid, view_rays as rays, Geometry};

/// Mesh 0: static, drawn twice (one moving instance); mesh 1: static, drawn once by a still
/// instance (flattened); mesh 2: static, drawn once by a moving instance; mesh 3: deforming.
fn frame(t: f32) -> (Vec<Geometry>, Vec<InstanceInput>) {
    let meshes = vec![grid(12, 0.1), grid(9, 0.3), grid(7, 0.0), grid(10, 0.2 + t)];
    let at = |x: f32, y: f32, angle: f32| {
        Affine3A::from_rotation_translation(Quat::from_rotation_y(angle), Vec3::new(x, y, -4.0))
    };
    let instances = vec![
        InstanceInput {
            mesh: 0,
            world_from_object: at(-1.5, 0.0, 0.0),
        },
        InstanceInput {
            mesh: 0,
            world_from_object: at(1.5, 0.3 * t, t),
        },
        InstanceInput {
            mesh: 1,
            world_from_object: at(0.0, 1.6, 0.2),
        },
        InstanceInput {
            mesh: 2,
            world_from_object: at(0.0, -1.6 + t, -t),
        },
        InstanceInput {
            mesh: 3,
            world_from_object: at(0.0, 0.0, 0.1),
        },
    ];
    (meshes, instances)
}

fn inputs(meshes: &[Geometry]) -> Vec<MeshInput<'_>> {
    meshes
        .iter()
        .map(|(p, i)| MeshInput {
            positions: p,
            indices: i,
        })
        .collect()
}

fn build(t: f32, previous: Option<Accel>) -> Accel {
    let (meshes, instances) = frame(t);
    let inputs = inputs(&meshes);
    let hints = FrameHints {
        moving: &[false, true, false, true, false],
        deforming_from: 3,
        ..FrameHints::STILL
    };
    Accel::build_frame(&inputs, &instances, BvhQuality::Medium, hints, previous)
}

#[test]
fn reused_frames_answer_like_fresh_builds() {
    let mut previous = Some(build(0.0, None));
    let mut hits = 0;
    for k in 1..5 {
        let t = k as f32 * 0.15;
        let reused = build(t, previous.take());
        let fresh = build(t, None);
        // Mesh 0, mesh 2 and the world-space BVH of mesh 1 come from the previous frame;
        // the deforming mesh 3 is rebuilt.
        assert_eq!(reused.stats().reused_blases, 3, "frame {k}");
        assert_eq!(fresh.stats().reused_blases, 0);
        assert_eq!(reused.stats().blas_count, fresh.stats().blas_count);
        assert_eq!(
            reused.stats().drawn_triangles,
            fresh.stats().drawn_triangles
        );
        for ray in rays() {
            let (a, b) = (reused.intersect(&ray), fresh.intersect(&ray));
            assert_eq!(a, b, "frame {k}");
            assert_eq!(reused.occluded(&ray), fresh.occluded(&ray));
            hits += usize::from(a.is_some());
        }
        previous = Some(reused);
    }
    assert!(hits > 1000, "{hits}");
}

#[test]
fn still_scenes_flatten_as_before_and_moving_instances_do_not() {
    let (meshes, instances) = frame(0.0);
    let inputs = inputs(&meshes);
    // A scene this small flattens its shared mesh 0 too: one world-space BVH holds all five.
    let still = Accel::build(&inputs, &instances, BvhQuality::Medium);
    assert_eq!(still.stats().flattened_instances, 5);
    assert_eq!(still.stats().blas_count, 1);
    // Keeping shared meshes instanced: meshes 1, 2 and 3 are drawn once and flattened; mesh 0
    // has its own BVH.
    let keep = FrameHints {
        flatten_shared_up_to: 0,
        ..FrameHints::STILL
    };
    let instanced = Accel::build_frame(&inputs, &instances, BvhQuality::Medium, keep, None);
    assert_eq!(instanced.stats().flattened_instances, 3);
    assert_eq!(instanced.stats().blas_count, 2);
    let framed = build(0.0, None);
    // The still instances of static meshes (mesh 0's first, mesh 1's) are flattened; mesh 0's
    // moving instance and meshes 2 and 3 get BVHs of their own.
    assert_eq!(framed.stats().flattened_instances, 2);
    assert_eq!(framed.stats().blas_count, 4);
    let mut hits = 0;
    for ray in rays() {
        let a = still.intersect(&ray).map(|h| (h.instance, h.triangle));
        assert_eq!(
            a,
            instanced.intersect(&ray).map(|h| (h.instance, h.triangle))
        );
        assert_eq!(a, framed.intersect(&ray).map(|h| (h.instance, h.triangle)));
        hits += usize::from(a.is_some());
    }
    assert!(hits > 1000, "{hits}");
}
