//! Packet occlusion tries the triangle that blocked the whole previous packet first: each ray's
//! answer stays its own, whether that triangle blocks all of the next packet, some of it, or
//! none of it.

use aperture_accel::{Accel, BvhQuality, InstanceInput, MeshInput, Ray, PACKET_LANES};
use glam::{Affine3A, Vec3};

/// A triangle at z = -2 covering x ≤ -0.3 around y = 0, a quad at z = -3 over y in [-1, -0.6],
/// and a triangle at z = -2.5 over y in [0.5, 1] (so that the scene's box covers the rays that
/// miss everything: they are walked, not culled).
fn scene() -> Accel {
    let positions = vec![
        Vec3::new(-2.0, -1.0, -2.0),
        Vec3::new(-0.3, -1.0, -2.0),
        Vec3::new(-0.3, 1.0, -2.0),
        Vec3::new(-1.0, -1.0, -3.0),
        Vec3::new(1.0, -1.0, -3.0),
        Vec3::new(1.0, -0.6, -3.0),
        Vec3::new(-1.0, -0.6, -3.0),
        Vec3::new(0.0, 0.5, -2.5),
        Vec3::new(1.0, 0.5, -2.5),
        Vec3::new(0.5, 1.0, -2.5),
    ];
    let indices = vec![[0, 1, 2], [3, 4, 5], [3, 5, 6], [7, 8, 9]];
    let meshes = [MeshInput {
        positions: &positions,
        indices: &indices,
    }];
    let instances = [InstanceInput {
        mesh: 0,
        world_from_object: Affine3A::IDENTITY,
    }];
    Accel::build(&meshes, &instances, BvhQuality::Medium)
}

/// A packet of rays down -z from z = 0 through `(x, y)` for each point.
fn packet(points: [(f32, f32); PACKET_LANES]) -> Vec<Ray> {
    points
        .iter()
        .map(|&(x, y)| Ray::new(Vec3::new(x, y, 0.0), Vec3::NEG_Z))
        .collect()
}

fn row(x0: f32, step: f32, y: f32) -> [(f32, f32); PACKET_LANES] {
    std::array::from_fn(|i| (x0 + step * i as f32, y))
}

#[test]
fn a_cached_blocker_leaves_every_answer_as_the_ray_alone() {
    let accel = scene();
    let mut partly = row(0.1, 0.1, 0.0);
    partly[0] = (-0.5, 0.0);
    let packets = [
        // Blocked whole by the triangle at z = -2: it becomes the packet's blocker.
        (row(-0.95, 0.05, 0.0), [true; PACKET_LANES]),
        // Its first ray blocked by that same triangle, the others meeting nothing.
        (partly, std::array::from_fn(|i| i == 0)),
        // Blocked whole again (first by the cached triangle), then whole by others.
        (row(-0.9, 0.05, 0.1), [true; PACKET_LANES]),
        (row(0.0, 0.1, -0.8), [true; PACKET_LANES]),
        // Nothing blocked, then blocked whole with nothing cached.
        (row(0.1, 0.1, 0.2), [false; PACKET_LANES]),
        (row(-0.9, 0.05, -0.8), [true; PACKET_LANES]),
    ];
    let rays: Vec<Ray> = packets.iter().flat_map(|(p, _)| packet(*p)).collect();
    let expected: Vec<bool> = packets.iter().flat_map(|(_, e)| *e).collect();
    let alone: Vec<bool> = rays.iter().map(|r| accel.occluded(r)).collect();
    assert_eq!(alone, expected, "the scene is as described");
    let mut packed = vec![false; rays.len()];
    accel.occluded_packets(&rays, &mut packed);
    assert_eq!(packed, expected);
}
