//! Zero leaks: rays from inside closed, finely tessellated icospheres, aimed exactly at vertices,
//! at points on edges and at random points on triangles, all hit the sphere where they aim, at
//! scales 1e-4, 1 and 1e4 and at an offset of 1e5, flattened into world space and instanced.

#[path = "accel_util.rs"]
mod util;

use aperture_accel::{Accel, BvhQuality, Hit, Ray};
use glam::Vec3;
use util::{sphere_scene, Rng};

/// Counts rays that do not hit instance 0 near their target (t = 1, as `dir = target - origin`).
fn leaks(accel: &Accel, origin: Vec3, targets: &[Vec3]) -> Vec<(Vec3, Option<Hit>)> {
    targets
        .iter()
        .filter_map(|&target| {
            let ray = Ray::new(origin, target - origin);
            let hit = accel.intersect(&ray);
            // Far from the origin the vertices and targets sit on a coarse float grid, so the
            // surface is bumpy at that grid's scale: allow a few grid steps in t.
            let grid = f32::EPSILON * target.abs().max_element();
            let tol = 1e-3 + 8.0 * grid / (target - origin).length();
            let ok = hit.is_some_and(|h| h.instance == 0 && (h.t - 1.0).abs() < tol)
                && accel.occluded(&ray);
            (!ok).then_some((target, hit))
        })
        .collect()
}

fn run(scale: f32, center: Vec3, instanced: bool) {
    let sub = 5; // 20,480 triangles
    let scene = sphere_scene(sub, scale, center, instanced);
    let accel = scene.build(BvhQuality::default());
    let n_tris = scene.meshes[0].1.len();
    assert_eq!(
        accel.stats().unique_triangles + accel.stats().degenerate_triangles,
        n_tris
    );

    // World-space vertices exactly as the BVH sees them for flattened scenes (and as the
    // renderer would compute them for instanced ones).
    let inst = scene.instances[0];
    let (pos, idx) = &scene.meshes[0];
    let world: Vec<Vec3> = pos
        .iter()
        .map(|p| inst.world_from_object.transform_point3(*p))
        .collect();

    let mut rng = Rng(scale.to_bits() as u64 ^ center.x.to_bits() as u64 ^ instanced as u64);
    let mut targets: Vec<Vec3> = world.clone();
    for [a, b, c] in idx.iter().copied() {
        let (a, b, c) = (world[a as usize], world[b as usize], world[c as usize]);
        // Edge midpoints and random points along edges.
        targets.push((a + b) * 0.5);
        targets.push(a + (c - a) * rng.f32());
        // A random point inside.
        let (mut u, mut v) = (rng.f32(), rng.f32());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        targets.push(a + (b - a) * u + (c - a) * v);
    }
    let to_world = |p: Vec3| {
        if instanced {
            inst.world_from_object.transform_point3(p)
        } else {
            center + p * scale
        }
    };
    let mut origins = vec![to_world(Vec3::ZERO)];
    for _ in 0..3 {
        origins.push(to_world(rng.unit_vector() * rng.range(0.0, 0.6)));
    }
    for (k, o) in origins.iter().enumerate() {
        // All targets from the centre; a quarter of them from the other origins.
        let ts: Vec<Vec3> = if k == 0 {
            targets.clone()
        } else {
            targets
                .iter()
                .copied()
                .filter(|_| rng.f32() < 0.25)
                .collect()
        };
        let bad = leaks(&accel, *o, &ts);
        let brute: Vec<_> = bad
            .iter()
            .take(3)
            .map(|(t, _)| accel.intersect_brute_force(&Ray::new(*o, *t - *o)))
            .collect();
        assert!(
            bad.is_empty(),
            "scale {scale} centre {center} instanced {instanced}: {} of {} rays from {o} leaked, e.g. {:?}; brute force: {brute:?}",
            bad.len(),
            ts.len(),
            &bad[..bad.len().min(3)]
        );
    }
}

#[test]
fn no_leaks_at_scale_1e_minus_4() {
    run(1e-4, Vec3::ZERO, false);
    run(1e-4, Vec3::ZERO, true);
}

#[test]
fn no_leaks_at_scale_1() {
    run(1.0, Vec3::ZERO, false);
    run(1.0, Vec3::ZERO, true);
}

#[test]
fn no_leaks_at_scale_1e4() {
    run(1e4, Vec3::ZERO, false);
    run(1e4, Vec3::ZERO, true);
}

#[test]
fn no_leaks_at_offset_1e5() {
    run(1.0, Vec3::splat(1e5), false);
    run(1.0, Vec3::splat(1e5), true);
    run(1e3, Vec3::new(1e5, -1e5, 3e4), false);
}
