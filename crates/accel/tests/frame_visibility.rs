//! Animation frames where instances come and go (keyed `KHR_node_visibility`): with the
//! previous frame's structure, `Accel::build_frame` takes over the world-space BVH of the
//! instances that stay (renumbered when one before them left) and the bottom-level BVH of a
//! mesh hidden for a frame, and answers every ray exactly as a build without it.

use aperture_accel::{Accel, BvhQuality, FrameHints, InstanceInput, MeshInput};
use glam::{Affine3A, Quat, Vec3};

mod common;
use common::{grid, view_rays as rays, Geometry};

fn meshes() -> Vec<Geometry> {
    vec![grid(12, 0.1), grid(9, 0.3), grid(7, 0.0)]
}

/// Frame `k`: mesh 2 drawn first, by an instance shown on even frames only (its visibility
/// keyed, so hinted as changing); meshes 1 and 0 drawn by still instances after it.
fn instances(k: usize) -> (Vec<InstanceInput>, Vec<bool>) {
    let at = |x: f32, y: f32, angle: f32| {
        Affine3A::from_rotation_translation(Quat::from_rotation_y(angle), Vec3::new(x, y, -4.0))
    };
    let mut out = Vec::new();
    let mut changing = Vec::new();
    if k % 2 == 0 {
        out.push(InstanceInput {
            mesh: 2,
            world_from_object: at(0.0, -1.6, 0.3),
        });
        changing.push(true);
    }
    for (mesh, place) in [(1, at(0.0, 1.6, 0.2)), (0, at(-1.5, 0.0, 0.0))] {
        out.push(InstanceInput {
            mesh,
            world_from_object: place,
        });
        changing.push(false);
    }
    (out, changing)
}

fn build(k: usize, previous: Option<Accel>) -> Accel {
    let geometry = meshes();
    let inputs: Vec<MeshInput<'_>> = (geometry.iter())
        .map(|(p, i)| MeshInput {
            positions: p,
            indices: i,
        })
        .collect();
    let (instances, changing) = instances(k);
    let hints = FrameHints {
        moving: &changing,
        deforming_from: 3,
        ..FrameHints::STILL
    };
    Accel::build_frame(&inputs, &instances, BvhQuality::Medium, hints, previous)
}

#[test]
fn instances_coming_and_going_rebuild_no_bottom_level_bvh() {
    let mut previous = Some(build(0, None));
    let mut per_instance = [0usize; 3];
    for k in 1..5 {
        let reused = build(k, previous.take());
        let fresh = build(k, None);
        let (r, f) = (reused.stats(), fresh.stats());
        // Shown: the world-space BVH of meshes 1 and 0 and mesh 2's own, both taken over;
        // hidden: the world-space one alone (mesh 2's kept aside for the frame after).
        let blases = if k % 2 == 0 { 2 } else { 1 };
        assert_eq!(
            (r.blas_count, r.reused_blases),
            (blases, blases),
            "frame {k}"
        );
        assert_eq!((f.blas_count, f.reused_blases), (blases, 0), "frame {k}");
        for ray in rays() {
            let (a, b) = (reused.intersect(&ray), fresh.intersect(&ray));
            assert_eq!(
                a, b,
                "frame {k}: the instance numbers follow the frame's list"
            );
            assert_eq!(reused.occluded(&ray), fresh.occluded(&ray));
            if let Some(h) = a {
                per_instance[h.instance as usize] += 1;
            }
        }
        previous = Some(reused);
    }
    // Every instance number is hit: 0 is mesh 2 on even frames and mesh 1 on odd ones.
    assert!(per_instance.iter().all(|&n| n > 100), "{per_instance:?}");
}
