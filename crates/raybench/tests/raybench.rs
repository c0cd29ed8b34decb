//! The ray sets of `aperture bench-rays`: deterministic, the two primary orders permutations of
//! each other, primary rays through their focal-plane points, shadow rays ending short of the
//! light, and the queries' answers consistent across queries, modes and pool sizes. Nothing here
//! times anything.

use aperture_accel::{BvhQuality, Ray};
use aperture_raybench::{
    closest_hits, generate_sets, occlusions, primary_ray, primary_samples, shadow_target,
    time_sets, Mode, Query, RaySet, RaySetOptions, TimingOptions, BENCH_TILE, SET_NAMES,
};
use aperture_render::{build_accel, Camera};
use aperture_shading::test_scenes;
use glam::Vec3;

const W: u32 = 24;
const H: u32 = 18;
const LENS: u32 = 4;

fn setup() -> (aperture_scene::Scene, aperture_accel::Accel, Camera) {
    let scene = test_scenes::balls();
    let accel = build_accel(&scene, BvhQuality::Medium);
    let camera = Camera::new(&scene.cameras[0], W, H);
    (scene, accel, camera)
}

fn sets(seed: u32) -> Vec<RaySet> {
    let (scene, accel, camera) = setup();
    let opts = RaySetOptions {
        lens_samples: LENS,
        seed,
    };
    generate_sets(&scene, &accel, &camera, &opts)
}

fn bits(r: &Ray) -> [u32; 8] {
    [
        r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.tmin, r.tmax,
    ]
    .map(f32::to_bits)
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

#[test]
fn sets_are_named_and_sized() {
    let s = sets(1);
    let names: Vec<&str> = s.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, SET_NAMES);
    let primary = (W * H * LENS) as usize;
    assert_eq!(s[0].rays.len(), primary);
    assert_eq!(s[1].rays.len(), primary);
    // The balls scene's ground fills most of the view: most primary rays hit, and every hit
    // gets one bounce and one shadow ray.
    assert!(s[2].rays.len() > primary / 2, "{}", s[2].rays.len());
    assert_eq!(s[2].rays.len(), s[3].rays.len());
}

#[test]
fn same_seed_gives_identical_rays_and_another_seed_other_rays() {
    let a = sets(7);
    let b = sets(7);
    let c = sets(8);
    for ((a, b), c) in a.iter().zip(&b).zip(&c) {
        let ab: Vec<_> = a.rays.iter().map(bits).collect();
        assert_eq!(
            ab,
            b.rays.iter().map(bits).collect::<Vec<_>>(),
            "{}",
            a.name
        );
        assert_ne!(
            ab,
            c.rays.iter().map(bits).collect::<Vec<_>>(),
            "{}",
            a.name
        );
    }
}

#[test]
fn tile_and_random_orders_are_permutations_of_each_other() {
    let s = sets(3);
    let mut tile: Vec<_> = s[0].rays.iter().map(bits).collect();
    let mut random: Vec<_> = s[1].rays.iter().map(bits).collect();
    assert_ne!(tile, random, "the random order is shuffled");
    tile.sort_unstable();
    random.sort_unstable();
    assert_eq!(tile, random);
    // No ray twice (so the permutation check is not fooled by repeats).
    tile.dedup();
    assert_eq!(tile.len(), s[0].rays.len());
}

#[test]
fn tile_order_keeps_a_pixels_lens_samples_together_and_tiles_whole() {
    let (_, _, camera) = setup();
    let opts = RaySetOptions {
        lens_samples: LENS,
        seed: 0,
    };
    let samples = primary_samples(&camera, &opts);
    for chunk in samples.chunks(LENS as usize) {
        assert!(chunk.iter().all(|s| (s.x, s.y) == (chunk[0].x, chunk[0].y)));
        let idx: Vec<u32> = chunk.iter().map(|s| s.index).collect();
        assert_eq!(idx, (0..LENS).collect::<Vec<_>>());
    }
    // The first tile's pixels come first, all of them.
    let first = (BENCH_TILE * BENCH_TILE.min(H) * LENS) as usize;
    assert!(samples[..first]
        .iter()
        .all(|s| s.x < BENCH_TILE && s.y < BENCH_TILE));
    assert!(samples[first].x >= BENCH_TILE);
    // The film position lies in its pixel.
    assert!(samples.iter().all(|s| {
        let p = s.sample.p_film;
        p.x >= s.x as f32 && p.x <= s.x as f32 + 1.0 && p.y >= s.y as f32 && p.y <= s.y as f32 + 1.0
    }));
}

#[test]
fn every_primary_ray_passes_through_its_focal_plane_point() {
    let (_, _, camera) = setup();
    let opts = RaySetOptions {
        lens_samples: LENS,
        seed: 5,
    };
    let forward = camera
        .world_from_camera
        .transform_vector3(Vec3::NEG_Z)
        .normalize();
    let centre = camera.world_from_camera.transform_point3(Vec3::ZERO);
    let radius = camera.aperture.radius();
    assert!(radius > 0.0, "the test camera has a lens");
    let mut max_offset: f32 = 0.0;
    for s in primary_samples(&camera, &opts) {
        let ray = primary_ray(&camera, &s).expect("a perspective camera makes every ray");
        let c = camera.centre_ray(s.sample.p_film).unwrap();
        let focus = c.origin + c.dir * (camera.focus_distance / c.dir.dot(forward));
        // Distance from the focus point to the ray's line.
        let miss = (focus - ray.origin).cross(ray.dir).length();
        assert!(miss < 1e-5 * camera.focus_distance, "{s:?}: {miss}");
        let off = (ray.origin - centre).length();
        assert!(
            off <= radius * (1.0 + 1e-5),
            "{s:?}: lens point {off} > {radius}"
        );
        max_offset = max_offset.max(off);
    }
    assert!(
        max_offset > 0.5 * radius,
        "lens points spread over the aperture"
    );
}

#[test]
fn shadow_rays_end_just_short_of_the_point_light() {
    let (scene, _, _) = setup();
    let light = shadow_target(&scene).unwrap();
    assert_eq!(light, scene.lights[0].position);
    let s = sets(2);
    let shadow = &s[3].rays;
    assert!(!shadow.is_empty());
    for r in shadow {
        assert!(r.tmax.is_finite());
        let dist = (light - r.origin).length();
        assert!(r.tmax < dist && r.tmax > 0.999 * dist, "{r:?}");
        assert!((r.origin + r.dir * dist - light).length() < 1e-4 * dist);
    }
    // Without a point light the target is above the scene's bounds.
    let mut dark = scene.clone();
    dark.lights.clear();
    let above = shadow_target(&dark).unwrap();
    assert!(above.y > scene.bounds().max.y);
}

#[test]
fn occlusion_equals_a_closest_hit_in_every_set_mode_and_pool() {
    let (_, accel, _) = setup();
    for set in sets(4) {
        let n = set.rays.len();
        let reference: Vec<_> = set.rays.iter().map(|r| accel.intersect(r)).collect();
        for threads in [1, 2] {
            let pool = pool(threads);
            for mode in Mode::ALL {
                let mut hits = vec![None; n];
                let mut occ = vec![false; n];
                pool.install(|| {
                    closest_hits(&accel, &set.rays, mode, &mut hits);
                    occlusions(&accel, &set.rays, mode, &mut occ);
                });
                assert_eq!(hits, reference, "{} {mode:?} {threads}", set.name);
                let expected: Vec<bool> = reference.iter().map(Option::is_some).collect();
                assert_eq!(occ, expected, "{} {mode:?} {threads}", set.name);
            }
        }
        // Each set has rays that hit something (so the comparisons above are not all misses).
        assert!(reference.iter().any(Option::is_some), "{}", set.name);
    }
}

#[test]
fn timing_reports_every_quality_set_query_mode_and_pool() {
    let (scene, _, _) = setup();
    let s = sets(0);
    let opts = TimingOptions {
        qualities: BvhQuality::ALL.to_vec(),
        thread_counts: vec![1, 2],
        repeats: 1,
    };
    let mut seen = 0;
    let runs = time_sets(&scene, &s, &opts, &mut |_, _| seen += 1).unwrap();
    assert_eq!(runs.len(), 3);
    // quality × set × query × mode × pool
    assert_eq!(seen, 3 * 4 * 2 * Mode::ALL.len() * 2);
    for run in &runs {
        assert!(run.memory_bytes > 0);
        assert_eq!(run.timings.len(), 4 * 2 * Mode::ALL.len() * 2);
        for t in &run.timings {
            let set = s.iter().find(|x| x.name == t.set).unwrap();
            assert_eq!(t.rays, set.rays.len());
            let hits = set
                .rays
                .iter()
                .filter(|r| run_query(&scene, run.quality, t.query, r))
                .count();
            assert_eq!(t.hits, hits, "{t:?}");
            assert!(t.mrays_min <= t.mrays_median && t.mrays_median <= t.mrays_max);
        }
    }
}

fn run_query(scene: &aperture_scene::Scene, q: BvhQuality, query: Query, r: &Ray) -> bool {
    thread_local! {
        static ACCELS: std::cell::RefCell<Vec<(BvhQuality, aperture_accel::Accel)>> =
            const { std::cell::RefCell::new(Vec::new()) };
    }
    ACCELS.with(|a| {
        let mut a = a.borrow_mut();
        if !a.iter().any(|(k, _)| *k == q) {
            a.push((q, build_accel(scene, q)));
        }
        let accel = &a.iter().find(|(k, _)| *k == q).unwrap().1;
        match query {
            Query::Closest => accel.intersect(r).is_some(),
            Query::Occluded => accel.occluded(r),
        }
    })
}
