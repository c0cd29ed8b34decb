//! Meshes deforming within the shutter (motion steps): a ray at time `t` meets the triangle
//! interpolated at `t`, not where another key has it, and the tree over the swept triangles
//! finds every hit a test of every interpolated triangle finds.

use aperture_accel::{Accel, BvhQuality, FrameHints, InstanceInput, MeshInput, Ray, VertexMotion};
use glam::{Affine3A, Vec3};

mod common;
use common::grid_indices;

/// A unit square in the plane z = 0 (two triangles) shifted by `dx` along x.
fn square(dx: f32) -> Vec<Vec3> {
    [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)]
        .map(|(x, y)| Vec3::new(x + dx, y, 0.0))
        .to_vec()
}

const SQUARE: [[u32; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

/// The square's `x` at normalised time `t` when keyed at x = −2, 0 and 3 (uneven speeds, so a
/// single straight line from the first key to the last would be wrong).
fn x_at(t: f32) -> f32 {
    if t <= 0.5 {
        -2.0 + 4.0 * t
    } else {
        6.0 * (t - 0.5)
    }
}

#[test]
fn a_ray_meets_the_square_where_its_time_puts_it() {
    let frame = square(0.0);
    let (k0, k1, k2) = (square(-2.0), square(0.0), square(3.0));
    let keys = [VertexMotion::new(&[&k0, &k1, &k2])];
    let meshes = [MeshInput {
        positions: &frame,
        indices: &SQUARE,
    }];
    let at = |z: f32| Affine3A::from_translation(Vec3::new(0.0, 0.0, z));
    // One instance (the tree alone), then two (a top level above it, and a still neighbour
    // drawing the same mesh without motion: it is the deforming one too, since the keys are
    // the mesh's).
    for n in [1usize, 2] {
        let instances: Vec<InstanceInput> = (0..n)
            .map(|i| InstanceInput {
                mesh: 0,
                world_from_object: at(-5.0 - 5.0 * i as f32),
            })
            .collect();
        let hints = FrameHints {
            deforming: &keys,
            ..FrameHints::STILL
        };
        let accel = Accel::build_frame(&meshes, &instances, BvhQuality::Medium, hints, None);
        for k in 0..=20 {
            let time = k as f32 / 20.0;
            let ray = Ray {
                time,
                ..Ray::new(Vec3::new(x_at(time), 0.1, 0.0), Vec3::NEG_Z)
            };
            let hit = accel.intersect(&ray).expect("the square at its time");
            assert_eq!(hit.instance, 0, "time {time}");
            assert!((hit.t - 5.0).abs() < 1e-5, "time {time}: t = {}", hit.t);
            assert_eq!(Some(hit), accel.intersect_brute_force(&ray), "time {time}");
            assert!(accel.occluded(&ray), "time {time}");
            // At a time where the square is more than its width away, the ray misses it.
            let away = Ray {
                time: if time < 0.5 { 1.0 } else { 0.0 },
                ..ray
            };
            if (x_at(away.time) - x_at(time)).abs() > 1.2 {
                assert_eq!(accel.intersect(&away), None, "time {time}");
                assert!(!accel.occluded(&away), "time {time}");
            }
            let mut batch = [None; 2];
            accel.intersect_batch(&[ray, away], &mut batch);
            assert_eq!(batch, [accel.intersect(&ray), accel.intersect(&away)]);
            let mut packets = [None; 2];
            accel.intersect_packets(&[ray, away], &mut packets);
            assert_eq!(packets, batch);
        }
    }
}

/// A wavy `n × n` grid over [−1, 1]² in z = 0: its vertices, triangles and the vertices with
/// a bump of height `h` travelling along x to `shift`.
fn grid(n: u32, shift: f32, h: f32) -> Vec<Vec3> {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (
                2.0 * i as f32 / n as f32 - 1.0,
                2.0 * j as f32 / n as f32 - 1.0,
            );
            let z = h * (-8.0 * ((x - shift) * (x - shift) + y * y)).exp();
            p.push(Vec3::new(x, y + 0.3 * shift * x, z));
        }
    }
    p
}

#[test]
fn the_swept_tree_finds_every_interpolated_hit() {
    let n = 24;
    let frame = grid(n, 0.0, 0.0);
    let indices = grid_indices(n);
    let steps: Vec<Vec<Vec3>> = (0..4)
        .map(|k| grid(n, -0.6 + 0.4 * k as f32, 0.8))
        .collect();
    let refs: Vec<&[Vec3]> = steps.iter().map(Vec::as_slice).collect();
    let keys = [VertexMotion::new(&refs)];
    let meshes = [MeshInput {
        positions: &frame,
        indices: &indices,
    }];
    let instances = [InstanceInput {
        mesh: 0,
        world_from_object: Affine3A::from_rotation_x(-0.3),
    }];
    let hints = FrameHints {
        deforming: &keys,
        ..FrameHints::STILL
    };
    let accel = Accel::build_frame(&meshes, &instances, BvhQuality::Medium, hints, None);
    let still = Accel::build(&meshes, &instances, BvhQuality::Medium);
    let (mut hits, mut differ) = (0, 0);
    let mut state = 12345u32;
    let mut rand = || {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (state >> 8) as f32 / (1u32 << 24) as f32
    };
    for _ in 0..3000 {
        let o = Vec3::new(2.4 * rand() - 1.2, 2.4 * rand() - 1.2, 3.0);
        let d = Vec3::new(0.4 * rand() - 0.2, 0.4 * rand() - 0.2, -1.0);
        let ray = Ray {
            time: rand(),
            ..Ray::new(o, d)
        };
        let want = accel.intersect_brute_force(&ray);
        assert_eq!(accel.intersect(&ray), want, "{ray:?}");
        assert_eq!(accel.occluded(&ray), want.is_some(), "{ray:?}");
        hits += usize::from(want.is_some());
        // The bump lifts the grid off the frame's flat one: most hits are elsewhere.
        differ += usize::from(want.map(|h| h.t) != still.intersect(&ray).map(|h| h.t));
    }
    assert!(
        hits > 1000 && differ > hits / 4,
        "{hits} hits, {differ} moved"
    );
}

#[test]
fn keys_for_another_vertex_count_leave_the_mesh_still() {
    let frame = square(0.0);
    let (k0, k1) = (square(-2.0)[..3].to_vec(), square(2.0)[..3].to_vec());
    let keys = [VertexMotion::new(&[&k0, &k1])];
    let meshes = [MeshInput {
        positions: &frame,
        indices: &SQUARE,
    }];
    let instances = [InstanceInput {
        mesh: 0,
        world_from_object: Affine3A::from_translation(Vec3::new(0.0, 0.0, -5.0)),
    }];
    let hints = FrameHints {
        deforming: &keys,
        ..FrameHints::STILL
    };
    let accel = Accel::build_frame(&meshes, &instances, BvhQuality::Medium, hints, None);
    for time in [0.0, 0.5, 1.0] {
        let ray = Ray {
            time,
            ..Ray::new(Vec3::new(0.1, 0.1, 0.0), Vec3::NEG_Z)
        };
        assert!(accel.intersect(&ray).is_some_and(|h| h.t == 5.0));
    }
}
