//! `Accel::input_counts` reports what a build would, without building (issue 59: `aperture
//! info` builds no BVH), and `builds()` counts the builds that happen.

use aperture_accel::{builds, Accel, AccelStats, FrameHints, InstanceInput, MeshInput};
use glam::{Affine3A, Vec3};

/// The counts about the input, with the structure's sizes and build time cleared.
fn input_part(s: AccelStats) -> AccelStats {
    AccelStats {
        degenerate_triangles: s.degenerate_triangles,
        unique_triangles: s.unique_triangles,
        invalid_index_triangles: s.invalid_index_triangles,
        skipped_instances: s.skipped_instances,
        drawn_triangles: s.drawn_triangles,
        flattened_instances: s.flattened_instances,
        ..AccelStats::default()
    }
}

fn placed(mesh: u32, m: Affine3A) -> InstanceInput {
    InstanceInput {
        mesh,
        world_from_object: m,
    }
}

#[test]
fn input_counts_equal_the_builds_and_build_nothing() {
    let a = [
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::splat(f32::NAN),
    ];
    // Kept, collinear (0, 1, 3), out of range, non-finite.
    let ia = [[0u32, 1, 2], [0, 1, 3], [0, 1, 9], [0, 1, 4]];
    // Fine in object space, every point rounds to 0 in world space under `squash`.
    let b = [
        Vec3::ZERO,
        Vec3::new(1e-20, 0.0, 0.0),
        Vec3::new(0.0, 1e-20, 0.0),
    ];
    let ib = [[0u32, 1, 2]];
    let meshes = [
        MeshInput {
            positions: &a,
            indices: &ia,
        },
        MeshInput {
            positions: &b,
            indices: &ib,
        },
    ];
    let squash = Affine3A::from_scale(Vec3::new(1e-30, 1e-30, 1.0));
    let moved = Affine3A::from_translation(Vec3::new(0.0, 0.0, -5.0));
    let instances = [
        placed(0, Affine3A::IDENTITY),
        placed(0, moved),
        placed(1, squash),
        placed(7, Affine3A::IDENTITY),
        placed(0, Affine3A::from_scale(Vec3::ZERO)),
    ];
    // Sharing kept instanced (no flattening of shared meshes), and the default. Degenerate:
    // two in mesh 0, and mesh 1's triangle, which only world space (flattened) makes one.
    let instanced = FrameHints {
        flatten_shared_up_to: 0,
        ..FrameHints::STILL
    };
    for hints in [instanced, FrameHints::STILL] {
        let before = builds();
        let counts = Accel::input_counts(&meshes, &instances, hints);
        assert_eq!(builds(), before, "input_counts built a structure");
        let built = Accel::build_frame(
            &meshes,
            &instances,
            aperture_accel::BvhQuality::Fast,
            hints,
            None,
        );
        assert_eq!(builds(), before + 1, "a build is counted");
        assert_eq!(counts, input_part(built.stats()));
        assert_eq!(counts.skipped_instances, 2);
        assert_eq!(counts.invalid_index_triangles, 1);
        assert_eq!(counts.unique_triangles, 2);
        assert_eq!(counts.drawn_triangles, 3);
        assert_eq!(counts.degenerate_triangles, 3, "{counts:?}");
    }
}
