//! The BVH answers exactly as brute force over every triangle (same ray transform, same triangle
//! test), for flattened and instanced scenes, closest hit and occlusion; and every reported hit
//! lies on the triangle it names (checked against the input meshes, independently of the BVH).
//! The batch queries (interleaved walks) and the packet queries answer exactly as the one-ray
//! queries, so brute force checks them too. Scenes with instances
//! are checked both kept instanced and flattened into one world-space BVH.

#[path = "accel_util.rs"]
mod util;

use aperture_accel::{Accel, BvhQuality, Hit, InstanceInput, Ray, PACKET_CONE_COS, PACKET_LANES};
use glam::{Affine3A, Quat, Vec3};
use util::{icosphere, random_rays, random_transform, soup, Rng, Scene};

fn check(scene: &Scene, accel: &Accel, rays: &[Ray]) -> usize {
    let mut hits = 0;
    for (k, ray) in rays.iter().enumerate() {
        let bvh = accel.intersect(ray);
        let brute = accel.intersect_brute_force(ray);
        match (bvh, brute) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                hits += 1;
                assert_eq!(a.t, b.t, "ray {k} {ray:?}: bvh {a:?} brute {b:?}");
                // Different triangles at the same t are a tie on a shared edge or vertex; the
                // checks below still require the BVH's triangle to contain the hit point.
                let w = 1.0 - a.u - a.v;
                assert!(
                    [a.u, a.v, w]
                        .iter()
                        .all(|b| (-1e-6..=1.0 + 1e-6).contains(b)),
                    "ray {k}: barycentrics out of range: {a:?} (brute {b:?})"
                );
                // Independent check: the hit point lies on the named triangle.
                let p = scene.world_triangle(a.instance, a.triangle);
                let on_tri = p[0] * (1.0 - a.u - a.v) + p[1] * a.u + p[2] * a.v;
                let on_ray = ray.origin + ray.dir * a.t;
                let size = (p[1] - p[0]).length() + (p[2] - p[0]).length() + on_ray.length();
                assert!(
                    (on_tri - on_ray).length() <= 1e-4 * size,
                    "ray {k}: {a:?}: triangle point {on_tri} vs ray point {on_ray}"
                );
                assert!(
                    a.t >= ray.tmin && a.t <= ray.tmax,
                    "ray {k}: {a:?} outside range"
                );
            }
            (a, b) => panic!("ray {k} {ray:?}: bvh {a:?} brute {b:?}"),
        }
        assert_eq!(
            accel.occluded(ray),
            brute.is_some(),
            "occlusion of ray {k} {ray:?}"
        );
    }
    check_batches(accel, rays);
    check_packets(accel, rays);
    hits
}

/// `runs` runs of [`PACKET_LANES`] rays as a thin lens makes them: from points of a small disc
/// around the origin of each of `rays` in turn towards one point on the ray, half of them ending
/// there (a finite `tmax`, so occlusion answers differ within a run). Some runs are too wide:
/// the packet queries interleave those. Rays close to an axis plane are passed over (their runs
/// would straddle octants, which the incoherent rays cover); none when all are.
fn lens_runs(rays: &[Ray], runs: usize, rng: &mut Rng) -> Vec<Ray> {
    let mut out = Vec::new();
    let off_axis = rays
        .iter()
        .filter(|r| r.dir.abs().min_element() >= 0.2 * r.dir.length());
    for (k, ray) in off_axis.cycle().take(runs).enumerate() {
        let focus = ray.origin + ray.dir.normalize() * rng.range(2.0, 12.0);
        let radius = rng.range(0.0, 0.3);
        for _ in 0..PACKET_LANES {
            let origin = ray.origin + rng.unit_vector() * radius * rng.f32();
            let mut r = Ray::new(origin, focus - origin);
            if k % 2 == 1 {
                r.tmax = 1.0;
            }
            out.push(r);
        }
    }
    out
}

/// Runs whose directions differ only in the sign of a zero component: one octant in world
/// space, two in the box test (its reciprocals are ±1e20), so they must not be one packet.
fn signed_zero_runs(rays: &[Ray], runs: usize) -> Vec<Ray> {
    let mut out = Vec::new();
    for (k, ray) in rays.iter().take(runs).enumerate() {
        let axis = k % 3;
        for i in 0..PACKET_LANES {
            let mut dir = ray.dir;
            dir[axis] = if i % 2 == 0 { 0.0 } else { -0.0 };
            let jitter = Vec3::new(0.0, 1e-3, 2e-3) * i as f32;
            out.push(Ray::new(ray.origin + jitter, dir));
        }
    }
    out
}

/// The packet queries give, ray by ray, exactly the one-ray answers: on thin-lens runs (most of
/// them traced as packets, which the count checks) and on the incoherent `rays`, over the whole
/// set and over short calls that end mid-packet.
fn check_packets(accel: &Accel, rays: &[Ray]) {
    let lens = lens_runs(rays, 400, &mut Rng(7));
    let coherent = lens
        .chunks(PACKET_LANES)
        .filter(|run| {
            let d0 = run[0].dir.normalize();
            run.iter().all(|r| {
                r.dir.cmplt(Vec3::ZERO) == run[0].dir.cmplt(Vec3::ZERO)
                    && r.dir.normalize().dot(d0) >= PACKET_CONE_COS
            })
        })
        .count();
    let runs = lens.len() / PACKET_LANES;
    assert!(
        coherent >= runs / 2,
        "{coherent} of {runs} runs are packets"
    );
    let zeros = signed_zero_runs(rays, 100);
    for set in [&lens[..], &zeros[..], rays] {
        let single: Vec<Option<Hit>> = set.iter().map(|r| accel.intersect(r)).collect();
        let single_occ: Vec<bool> = set.iter().map(|r| accel.occluded(r)).collect();
        let occluded = single_occ.iter().filter(|&&o| o).count();
        if std::ptr::eq(set, &lens[..]) && !lens.is_empty() {
            // Both answers within runs, or the comparison proves little.
            assert!(occluded > 0 && occluded < set.len(), "{occluded} occluded");
        }
        for len in [set.len().max(1), 3, 8, 13] {
            let mut hits = vec![None; set.len()];
            let mut occ = vec![false; set.len()];
            for (k, chunk) in set.chunks(len).enumerate() {
                accel.intersect_packets(chunk, &mut hits[k * len..]);
                accel.occluded_packets(chunk, &mut occ[k * len..]);
            }
            assert_eq!(hits, single, "packets in calls of {len}");
            assert_eq!(occ, single_occ, "packets in calls of {len}");
        }
    }
}

/// The batch and many-ray queries give, ray by ray, exactly the one-ray answers: over the whole
/// set and over short batches (fewer rays than lanes, and lanes refilled mid-batch).
fn check_batches(accel: &Accel, rays: &[Ray]) {
    let single: Vec<Option<Hit>> = rays.iter().map(|r| accel.intersect(r)).collect();
    let single_occ: Vec<bool> = rays.iter().map(|r| accel.occluded(r)).collect();
    let mut hits = vec![None; rays.len()];
    let mut occ = vec![false; rays.len()];
    accel.intersect_many(rays, &mut hits);
    accel.occluded_many(rays, &mut occ);
    assert_eq!(hits, single, "intersect_many");
    assert_eq!(occ, single_occ, "occluded_many");
    for len in [1, 2, 3, 5, 9, 31] {
        for (k, chunk) in rays.chunks(len).enumerate() {
            let (at, end) = (k * len, k * len + chunk.len());
            // The batch's slots and a few past it, set to what the answers are not.
            let window = at..(end + 3).min(rays.len());
            hits[window.clone()].fill(Some(Hit {
                t: -1.0,
                instance: u32::MAX,
                triangle: u32::MAX,
                u: 0.0,
                v: 0.0,
            }));
            for (o, s) in occ[window.clone()]
                .iter_mut()
                .zip(&single_occ[window.clone()])
            {
                *o = !s;
            }
            accel.intersect_batch(chunk, &mut hits[at..]);
            accel.occluded_batch(chunk, &mut occ[at..]);
            assert_eq!(&hits[at..end], &single[at..end], "batch of {len} at {at}");
            assert_eq!(
                &occ[at..end],
                &single_occ[at..end],
                "batch of {len} at {at}"
            );
            // Slots past the batch are left alone.
            assert!(hits[end..window.end]
                .iter()
                .all(|h| h.is_some_and(|h| h.t == -1.0)));
            for (o, s) in occ[end..window.end]
                .iter()
                .zip(&single_occ[end..window.end])
            {
                assert_ne!(o, s, "slot past a batch of {len} at {at} written");
            }
        }
    }
    // An empty batch writes nothing.
    accel.intersect_batch(&[], &mut hits);
    accel.occluded_batch(&[], &mut occ);
}

fn assert_mixed(hits: usize, n: usize) {
    // Both outcomes must be exercised or the comparison proves little.
    assert!(hits > n / 10 && hits < n, "{hits} of {n} rays hit");
}

#[test]
fn flattened_random_soup() {
    let mut rng = Rng(1);
    let (lo, hi) = (Vec3::splat(-10.0), Vec3::splat(10.0));
    let mesh = soup(&mut rng, 20_000, lo, hi, 0.6);
    let scene = Scene {
        meshes: vec![mesh],
        instances: vec![InstanceInput {
            mesh: 0,
            world_from_object: Affine3A::IDENTITY,
        }],
    };
    let rays = random_rays(&mut rng, 2000, lo, hi);
    for q in BvhQuality::ALL {
        let accel = scene.build(q);
        assert_eq!(accel.stats().unique_triangles, 20_000);
        assert_mixed(check(&scene, &accel, &rays), rays.len());
    }
}

#[test]
fn instanced_meshes_with_mirrors_and_single_use_meshes() {
    let mut rng = Rng(2);
    let (lo, hi) = (Vec3::splat(-20.0), Vec3::splat(20.0));
    let sphere = icosphere(2);
    let blob = soup(&mut rng, 300, Vec3::splat(-1.0), Vec3::splat(1.0), 0.4);
    let once = soup(&mut rng, 2000, lo, hi, 0.8);
    let mut instances = Vec::new();
    for i in 0..150 {
        instances.push(InstanceInput {
            mesh: (i % 2) as u32,
            world_from_object: random_transform(&mut rng, lo, hi, i % 3 == 0),
        });
    }
    instances.push(InstanceInput {
        mesh: 2,
        world_from_object: random_transform(&mut rng, Vec3::ZERO, Vec3::ZERO, false),
    });
    let scene = Scene {
        meshes: vec![sphere, blob, once],
        instances,
    };
    let accel = scene.build(BvhQuality::default());
    let s = accel.stats();
    assert_eq!(s.flattened_instances, 1);
    assert_eq!(s.blas_count, 3);
    assert_eq!(s.tlas_entries, 151);
    assert_eq!(s.drawn_triangles, 75 * 320 + 75 * 300 + 2000);
    let rays = random_rays(&mut rng, 3000, lo, hi);
    assert_mixed(check(&scene, &accel, &rays), rays.len());
    // Built as `Accel::build` does, this small scene is one world-space BVH.
    let flat = scene.build_flattened(BvhQuality::default());
    assert_eq!(flat.stats().flattened_instances, 151);
    assert_eq!(flat.stats().blas_count, 1);
    assert_eq!(flat.stats().tlas_entries, 1);
    assert_mixed(check(&scene, &flat, &rays), rays.len());
}

#[test]
fn simple_instancing_shape_cube_grid() {
    // SimpleInstancing-like: one 12-triangle cube drawn 125 times on a grid.
    let c = [-0.4f32, 0.4];
    let pos: Vec<Vec3> = (0..8)
        .map(|i| Vec3::new(c[i & 1], c[(i >> 1) & 1], c[(i >> 2) & 1]))
        .collect();
    let idx = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    let mut instances = Vec::new();
    for x in 0..5 {
        for y in 0..5 {
            for z in 0..5 {
                instances.push(InstanceInput {
                    mesh: 0,
                    world_from_object: Affine3A::from_translation(Vec3::new(
                        x as f32, y as f32, z as f32,
                    )),
                });
            }
        }
    }
    let scene = Scene {
        meshes: vec![(pos, idx)],
        instances,
    };
    let accel = scene.build(BvhQuality::default());
    assert_eq!(accel.stats().drawn_triangles, 1500);
    assert_eq!(accel.stats().unique_triangles, 12);
    let mut rng = Rng(3);
    let rays = random_rays(&mut rng, 3000, Vec3::splat(-1.0), Vec3::splat(5.0));
    assert_mixed(check(&scene, &accel, &rays), rays.len());
    let flat = scene.build_flattened(BvhQuality::default());
    assert_eq!(flat.stats().flattened_instances, 125);
    assert_mixed(check(&scene, &flat, &rays), rays.len());
    // Axis-aligned rays along the grid lines and through the gaps (zero direction components).
    let mut hits = 0;
    for i in 0..200 {
        let o = Vec3::new(-2.0, rng.range(-0.5, 4.5), rng.range(-0.5, 4.5));
        let o = if i % 2 == 0 { o.round() } else { o };
        hits += check(&scene, &accel, &[Ray::new(o, Vec3::X)]);
    }
    assert_mixed(hits, 200);
}

#[test]
fn thin_lens_like_rays_from_outside() {
    let mut rng = Rng(4);
    let sphere = icosphere(4);
    let scene = Scene {
        meshes: vec![sphere],
        instances: vec![InstanceInput {
            mesh: 0,
            world_from_object: Affine3A::from_scale(Vec3::splat(3.0)),
        }],
    };
    let accel = scene.build(BvhQuality::default());
    let rays: Vec<Ray> = (0..2000)
        .map(|_| {
            let lens = Vec3::new(rng.range(-0.2, 0.2), rng.range(-0.2, 0.2), 10.0);
            let target = Vec3::new(rng.range(-4.0, 4.0), rng.range(-4.0, 4.0), 0.0);
            Ray::new(lens, target - lens)
        })
        .collect();
    assert_mixed(check(&scene, &accel, &rays), rays.len());
}

/// Rays from outside the scene that only graze its bounds: through an extreme vertex of the
/// mesh, within the face of the bounding box it touches, its target moved a few ulps in and
/// out, at several scales and far from the world origin. The bounds test that lets rays
/// missing everything skip the walk must never reject one that the walk (and brute force)
/// finds a hit for.
#[test]
fn rays_grazing_the_scene_bounds() {
    let mut rng = Rng(11);
    for (scale, offset) in [(1e-3, 0.0), (1.0, 0.0), (1.0, 1e4), (1e4, -3e5)] {
        let world_from_object = Affine3A::from_scale_rotation_translation(
            Vec3::splat(scale),
            Default::default(),
            Vec3::splat(offset),
        );
        let scene = Scene {
            meshes: vec![icosphere(2)],
            instances: vec![InstanceInput {
                mesh: 0,
                world_from_object,
            }],
        };
        let world: Vec<Vec3> = scene.meshes[0]
            .0
            .iter()
            .map(|&p| world_from_object.transform_point3(p))
            .collect();
        let mut rays = Vec::new();
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let extreme = world
                    .iter()
                    .copied()
                    .max_by(|a, b| (sign * a[axis]).total_cmp(&(sign * b[axis])))
                    .expect("vertices");
                for _ in 0..20 {
                    // A direction in the face plane (perpendicular to `axis`).
                    let mut tangent = rng.unit_vector();
                    tangent[axis] = 0.0;
                    let origin = extreme + tangent.normalize_or(Vec3::X) * (3.0 * scale);
                    for ulps in -2i32..=2 {
                        let mut target = extreme;
                        let bits = target[axis].to_bits() as i32;
                        target[axis] = f32::from_bits(
                            (bits + ulps * sign as i32 * target[axis].signum() as i32) as u32,
                        );
                        rays.push(Ray::new(origin, target - origin));
                    }
                }
            }
        }
        let hits = check(&scene, &accel(&scene), &rays);
        assert!(
            hits > 0 && hits < rays.len(),
            "scale {scale}: {hits} of {} hit",
            rays.len()
        );
    }
}

/// A floor of coplanar tiles (flat leaves), a sphere drawn twice and a soup.
fn floor_sphere_soup(rng: &mut Rng, scale: f32) -> Scene {
    let (mut pos, mut idx) = (Vec::new(), Vec::new());
    let n = 24;
    for i in 0..=n {
        for j in 0..=n {
            let (x, z) = (i as f32 / n as f32 - 0.5, j as f32 / n as f32 - 0.5);
            pos.push(Vec3::new(x, 0.0, z) * 20.0 * scale);
        }
    }
    for i in 0..n {
        for j in 0..n {
            let k = (i * (n + 1) + j) as u32;
            let w = n as u32 + 1;
            idx.push([k, k + 1, k + w]);
            idx.push([k + 1, k + w + 1, k + w]);
        }
    }
    let (lo, hi) = (
        Vec3::new(-8.0, 0.2, -8.0) * scale,
        Vec3::new(8.0, 6.0, 8.0) * scale,
    );
    let blob = soup(rng, 400, lo, hi, 0.8 * scale);
    let at = |c: Vec3, r: f32| {
        Affine3A::from_scale_rotation_translation(Vec3::splat(r * scale), Quat::IDENTITY, c * scale)
    };
    Scene {
        meshes: vec![(pos, idx), icosphere(3), blob],
        instances: vec![
            InstanceInput {
                mesh: 0,
                world_from_object: Affine3A::IDENTITY,
            },
            InstanceInput {
                mesh: 1,
                world_from_object: at(Vec3::new(1.0, 1.5, -2.0), 1.5),
            },
            InstanceInput {
                mesh: 1,
                world_from_object: at(Vec3::new(-3.0, 1.0, 3.0), 1.0),
            },
            InstanceInput {
                mesh: 2,
                world_from_object: Affine3A::IDENTITY,
            },
        ],
    }
}

/// Secondary rays as a path tracer spawns them: from hit points (moved off the surface by
/// `SpawnPoint::origin`), on the side they leave by (a quarter through the surface), some
/// grazing it, some towards a point light with a finite `tmax`. They start a few ulps from
/// their own leaf (flat on the floor), the rays whose walks the box test's slack decides: the
/// answers stay brute force's. (A slack too small for the triangle test shows first in
/// `accel_watertight` and in the accel crate's `slack_covers_what_the_triangle_test_accepts`.)
#[test]
fn rays_leaving_surfaces() {
    let mut rng = Rng(12);
    for scale in [1e-2, 1.0, 300.0] {
        let scene = floor_sphere_soup(&mut rng, scale);
        for accel in [
            scene.build(BvhQuality::default()),
            scene.build_flattened(BvhQuality::default()),
        ] {
            let (lo, hi) = (
                Vec3::new(-9.0, 0.5, -9.0) * scale,
                Vec3::new(9.0, 8.0, 9.0) * scale,
            );
            let light = Vec3::new(2.0, 7.0, 1.0) * scale;
            let mut rays = Vec::new();
            for _ in 0..3000 {
                let from = rng.vec_in(lo, hi) + Vec3::Y * 10.0 * scale;
                let ray = Ray::new(from, rng.vec_in(lo, hi) - Vec3::Y * 8.0 * scale - from);
                let Some(hit) = accel.intersect(&ray) else {
                    continue;
                };
                let [a, b, c] = scene.world_triangle(hit.instance, hit.triangle);
                let mut n = (b - a).cross(c - a).normalize_or_zero();
                if n.dot(ray.dir) > 0.0 {
                    n = -n;
                }
                let side = if rng.f32() < 0.25 { -n } else { n };
                let sp = accel.spawn_point(&ray, &hit);
                let o = sp.origin(side);
                let mut d = rng.unit_vector();
                if d.dot(side) < 0.0 {
                    d = -d;
                }
                if rng.f32() < 0.3 {
                    // Grazing: nearly in the surface's plane.
                    d = (d - side * d.dot(side) * (1.0 - 1e-3 * rng.f32())).normalize();
                }
                rays.push(Ray::new(o, d));
                let to = light - o;
                let mut shadow = Ray::new(o, to.normalize());
                shadow.tmax = to.length() * (1.0 - 1e-4);
                rays.push(shadow);
            }
            let hits = check(&scene, &accel, &rays);
            assert_mixed(hits, rays.len());
        }
    }
}

fn accel(scene: &Scene) -> Accel {
    scene.build(BvhQuality::default())
}
