//! Degenerate input is left out and counted, never a panic: NaN and infinite vertices, zero-area
//! triangles, out-of-range indices, empty meshes, zero instances, bad mesh indices, singular and
//! non-finite transforms, and rays with zero or NaN directions.

#[path = "accel_util.rs"]
mod util;

use aperture_accel::{Accel, BvhQuality, InstanceInput, MeshInput, Ray};
use glam::{Affine3A, Vec3};
use util::{soup, Rng};

#[test]
fn zero_instances_and_empty_meshes() {
    let empty = Accel::build(&[], &[], BvhQuality::default());
    assert_eq!(empty.intersect(&Ray::new(Vec3::ZERO, Vec3::X)), None);
    assert!(!empty.occluded(&Ray::new(Vec3::ZERO, Vec3::X)));
    let mesh = MeshInput {
        positions: &[],
        indices: &[],
    };
    let inst = InstanceInput {
        mesh: 0,
        world_from_object: Affine3A::IDENTITY,
    };
    let a = Accel::build(&[mesh], &[inst, inst], BvhQuality::default());
    assert_eq!(a.stats().unique_triangles, 0);
    assert_eq!(a.intersect(&Ray::new(Vec3::ZERO, Vec3::X)), None);
}

#[test]
fn bad_triangles_and_instances_are_counted_and_skipped() {
    let positions = [
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(0.0, 1.0, -1.0),
        Vec3::new(2.0, 0.0, -1.0), // collinear with 0 and 1
        Vec3::new(f32::NAN, 0.0, -1.0),
        Vec3::new(f32::INFINITY, 0.0, -1.0),
    ];
    let indices = [
        [0, 1, 2],  // good
        [0, 1, 3],  // zero area (collinear)
        [0, 0, 2],  // zero area (repeated vertex)
        [0, 4, 2],  // NaN
        [5, 1, 2],  // infinite
        [0, 1, 99], // out of range
        [2, 1, 0],  // good (other winding)
    ];
    let meshes = [MeshInput {
        positions: &positions,
        indices: &indices,
    }];
    let good = InstanceInput {
        mesh: 0,
        world_from_object: Affine3A::IDENTITY,
    };
    let instances = [
        good,
        InstanceInput { mesh: 7, ..good },
        InstanceInput {
            world_from_object: Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0)),
            ..good
        },
        InstanceInput {
            world_from_object: Affine3A::from_translation(Vec3::NAN),
            ..good
        },
    ];
    let a = Accel::build(&meshes, &instances, BvhQuality::default());
    let s = a.stats();
    assert_eq!(s.degenerate_triangles, 4);
    assert_eq!(s.invalid_index_triangles, 1);
    assert_eq!(s.unique_triangles, 2);
    assert_eq!(s.skipped_instances, 3);
    assert_eq!(s.drawn_triangles, 2);
    let hit = a
        .intersect(&Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::NEG_Z))
        .expect("hit");
    assert!(hit.triangle == 0 || hit.triangle == 6, "{hit:?}");
    assert_eq!(hit.instance, 0);
    // Rays with no direction or NaN do not panic.
    for dir in [Vec3::ZERO, Vec3::NAN, Vec3::new(0.0, 0.0, f32::INFINITY)] {
        let r = Ray::new(Vec3::ZERO, dir);
        let _ = a.intersect(&r);
        let _ = a.occluded(&r);
    }
    let _ = a.intersect(&Ray::new(Vec3::NAN, Vec3::X));
}

#[test]
fn stacks_of_identical_and_nested_triangles_match_brute_force() {
    // Many identical boxes and boxes shrinking by powers of two: the shapes that make BVHs deep.
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for k in 0..2000u32 {
        let s = if k < 1000 {
            1.0
        } else {
            0.5f32.powi((k - 1000) as i32 / 8)
        };
        let z = -1.0 - (k % 7) as f32 * 1e-3;
        let b = positions.len() as u32;
        positions.extend([
            Vec3::new(0.0, 0.0, z) * 1.0,
            Vec3::new(s, 0.0, z),
            Vec3::new(0.0, s, z),
        ]);
        indices.push([b, b + 1, b + 2]);
    }
    let meshes = [MeshInput {
        positions: &positions,
        indices: &indices,
    }];
    let inst = InstanceInput {
        mesh: 0,
        world_from_object: Affine3A::IDENTITY,
    };
    let a = Accel::build(&meshes, &[inst], BvhQuality::High);
    let mut rng = Rng(5);
    for _ in 0..500 {
        let o = Vec3::new(rng.range(-0.1, 0.6), rng.range(-0.1, 0.6), 1.0);
        let ray = Ray::new(
            o,
            Vec3::new(rng.range(-0.1, 0.1), rng.range(-0.1, 0.1), -1.0),
        );
        let (x, y) = (a.intersect(&ray), a.intersect_brute_force(&ray));
        assert_eq!(x.map(|h| h.t), y.map(|h| h.t));
    }
}

#[test]
fn many_instances_of_a_soup() {
    let mut rng = Rng(6);
    let (p, i) = soup(&mut rng, 50, Vec3::splat(-1.0), Vec3::splat(1.0), 0.5);
    let meshes = [MeshInput {
        positions: &p,
        indices: &i,
    }];
    let instances: Vec<InstanceInput> = (0..2000)
        .map(|k| InstanceInput {
            mesh: 0,
            world_from_object: Affine3A::from_translation(
                Vec3::new((k % 50) as f32, (k / 50) as f32, 0.0) * 2.5,
            ),
        })
        .collect();
    let a = Accel::build(&meshes, &instances, BvhQuality::Fast);
    assert_eq!(a.stats().drawn_triangles, 100_000);
    for _ in 0..300 {
        let ray = Ray::new(
            Vec3::new(rng.range(0.0, 125.0), rng.range(0.0, 100.0), 5.0),
            Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), -1.0),
        );
        assert_eq!(a.intersect(&ray), a.intersect_brute_force(&ray));
    }
}
