//! No self-intersection: rays leaving a surface through `offset_ray_origin` at grazing angles
//! never hit their own triangle, on tiny, unit, large and far-from-origin scenes, flattened and
//! instanced. The surfaces are closed convex icospheres, so a ray leaving outwards must hit
//! nothing at all, and a ray leaving inwards must hit some other triangle.

#[path = "accel_util.rs"]
mod util;

use aperture_accel::{offset_ray_origin, Accel, BvhQuality, Ray, SpawnPoint};
use glam::Vec3;
use util::{sphere_scene, Rng};

/// A direction at `angle` radians above the plane with normal `n` (unit), in a random tangent
/// direction.
fn grazing(rng: &mut Rng, n: Vec3, angle: f32) -> Vec3 {
    let t = (rng.unit_vector() - n * n.dot(rng.unit_vector()))
        .cross(n)
        .normalize();
    (t * angle.cos() + n * angle.sin()).normalize()
}

fn run(scale: f32, center: Vec3, instanced: bool) {
    let scene = sphere_scene(4, scale, center, instanced);
    let accel: Accel = scene.build(BvhQuality::default());
    let sphere_center = if instanced {
        scene.instances[0]
            .world_from_object
            .transform_point3(Vec3::ZERO)
    } else {
        center
    };
    let mut rng = Rng(scale.to_bits() as u64 + instanced as u64);
    let n_tris = scene.meshes[0].1.len();
    let (mut outward, mut inward) = (0, 0);
    for k in 0..4000 {
        let tri = rng.index(n_tris) as u32;
        let p = scene.world_triangle(0, tri);
        let normal = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        let outwards = if normal.dot(p[0] - sphere_center) > 0.0 {
            normal
        } else {
            -normal
        };
        // Two ways a renderer gets the surface point: barycentric interpolation, or o + t d of
        // the ray that found it.
        // Two ways a renderer gets a ray origin: on flattened meshes (world vertices exactly as
        // the BVH stores them), barycentric interpolation plus `offset_ray_origin`; on any mesh,
        // `Accel::spawn_point` of the ray that found the hit.
        let from_ray = instanced || k % 2 == 1;
        let spawn = if !from_ray {
            let (mut u, mut v) = (rng.f32(), rng.f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            SpawnPoint {
                p: p[0] * (1.0 - u - v) + p[1] * u + p[2] * v,
                error: 0.0,
            }
        } else {
            let target = (p[0] + p[1] + p[2]) / 3.0;
            let eye = target + outwards * scale * 3.0 + grazing(&mut rng, outwards, 0.5) * scale;
            let ray = Ray::new(eye, target - eye);
            match accel.intersect(&ray) {
                Some(h) if h.instance == 0 && h.triangle == tri => accel.spawn_point(&ray, &h),
                _ => continue,
            }
        };
        let point = spawn.p;
        let angle = [1e-1f32, 1e-2, 1e-3, 1e-4][k % 4];

        // Leaving outwards: a convex closed surface cannot be hit again.
        let o = spawn.origin(outwards);
        let ray = Ray::new(o, grazing(&mut rng, outwards, angle));
        if let Some(h) = accel.intersect(&ray) {
            assert!(
                h.instance != 0,
                "scale {scale} centre {center} instanced {instanced}: outward ray from triangle {tri} \
                 at angle {angle} hit triangle {} at t {} (point {point} origin {o} dir {} outwards {outwards} k {k} hit tri {:?})",
                h.triangle,
                h.t, ray.dir, scene.world_triangle(0, h.triangle)
            );
        }
        outward += 1;

        // Leaving inwards: hits the sphere again, never the triangle it left.
        let o = spawn.origin(-outwards);
        let ray = Ray::new(o, grazing(&mut rng, -outwards, angle));
        let h = accel.intersect(&ray);
        assert!(
            h.is_some_and(|h| h.instance == 0 && h.triangle != tri),
            "scale {scale} centre {center} instanced {instanced}: inward ray from triangle {tri} \
             at angle {angle}: {h:?}"
        );
        inward += 1;
    }
    assert!(outward > 2000 && inward > 2000, "{outward} {inward}");
}

#[test]
fn tiny_scene() {
    run(1e-4, Vec3::ZERO, false);
    run(1e-4, Vec3::splat(0.5), true);
}

#[test]
fn unit_scene() {
    run(1.0, Vec3::ZERO, false);
    run(1.0, Vec3::new(3.0, -2.0, 1.0), true);
}

#[test]
fn large_scene() {
    run(1e4, Vec3::ZERO, false);
    run(1e4, Vec3::splat(1e4), true);
}

#[test]
fn far_from_origin() {
    run(10.0, Vec3::splat(1e5), false);
    run(10.0, Vec3::new(-1e5, 1e5, 3e4), true);
}

#[test]
fn offset_moves_along_the_normal_at_every_magnitude() {
    let mut rng = Rng(9);
    for _ in 0..10_000 {
        let mag = 10f32.powf(rng.range(-8.0, 8.0));
        let p = rng.unit_vector() * mag;
        let n = rng.unit_vector();
        let o = offset_ray_origin(p, n);
        assert!(o.is_finite());
        assert!((o - p).dot(n) > 0.0, "p {p} n {n} -> {o}");
    }
    // Zero and signed zero coordinates do not overflow or panic.
    for p in [Vec3::ZERO, Vec3::new(-0.0, 0.0, -0.0)] {
        assert!(offset_ray_origin(p, Vec3::X).x > 0.0);
    }
}
