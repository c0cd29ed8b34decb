//! Tests of the render loop as a whole: options refused, the wavefront against samples traced
//! alone, one light per vertex against every light, thread-count independence, dropped
//! samples and progress.

use super::job::{integrator, Job, WAVEFRONT_SAMPLES};
use super::*;
use crate::aov::SampleAov;
use crate::background::backdrop;
use crate::frame_accel::build_accel;
use crate::integrator::Integrator;
use crate::options::RenderOptions;
use crate::sampler::MAX_SPP;
use crate::AdaptiveOptions;
use aperture_scene::Scene;
use aperture_shading::environment::Environment;
use aperture_shading::light_tree::LightTree;
use aperture_shading::test_scenes;
use glam::Affine3A;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A plane under a point light, an emissive ball, depth of field: every code path.
/// The lights of `scene` shaded as `opts` says, gathered for one test.
fn lights(scene: &Scene, opts: &RenderOptions) -> FrameLights {
    FrameLights::build(&geometry(scene, opts), None)
}

fn busy_scene() -> Scene {
    let mut s = test_scenes::lit_plane(3.0);
    s.cameras[0].dof.enabled = true;
    s.cameras[0].dof.aperture_radius = 0.2;
    s.cameras[0].dof.focus_distance = 5.0;
    s.materials
        .push(test_scenes::emitter(Vec3::new(4.0, 2.0, 1.0)));
    s.meshes.push(test_scenes::icosphere(1, 1).into());
    s.instances.push(aperture_scene::Instance {
        mesh: 1,
        world_from_object: Affine3A::from_translation(Vec3::new(1.0, 0.5, 1.0)),
        node: 1,
        materials: 0,
    });
    s
}

#[test]
fn bad_options_are_refused() {
    let scene = busy_scene();
    let accel = build_accel(&scene, Default::default());
    for opts in [
        RenderOptions {
            spp: 0,
            ..RenderOptions::default()
        },
        RenderOptions {
            width: 0,
            ..RenderOptions::default()
        },
        RenderOptions {
            camera: 3,
            ..RenderOptions::default()
        },
        RenderOptions {
            env: Environment::Constant(Vec3::new(-1.0, 0.0, 0.0)),
            ..RenderOptions::default()
        },
        // Past the end of the sampler's sequence.
        RenderOptions {
            spp: 64,
            sample_offset: MAX_SPP - 63,
            ..RenderOptions::default()
        },
        // A batch past the first sample with adaptive sampling.
        RenderOptions {
            sample_offset: 64,
            adaptive: Some(AdaptiveOptions {
                threshold: 0.01,
                min_spp: 4,
            }),
            ..RenderOptions::default()
        },
    ] {
        assert!(render(&scene, &accel, &opts, &|_, _| {}).is_err());
    }
}

#[test]
fn wavefront_gives_each_sample_as_alone() {
    // Lens, emitter, point light and a camera that sees both geometry and background;
    // every sample of a run is compared bit for bit with the same sample traced alone,
    // radiance and pass values, under a constant and an importance-sampled environment
    // (whose shadow rays leave the scene).
    let mut scene = busy_scene();
    // A plane of 3.2 × 3.2 instead of 40 × 40: the view holds background too.
    scene.instances[0].world_from_object = Affine3A::from_scale(Vec3::new(0.08, 1.0, 0.08));
    let accel = build_accel(&scene, Default::default());
    let sky = Environment::Image(std::sync::Arc::new(
        aperture_shading::environment::EnvImage {
            width: 4,
            height: 2,
            texels: (0..8)
                .map(|i| Vec3::new(0.1 * i as f32, 0.3, 0.05))
                .collect(),
            rotation: 0.3,
            strength: 1.0,
            sampling: Default::default(),
        },
    ));
    for env in [Environment::Constant(Vec3::splat(0.2)), sky] {
        let opts = RenderOptions {
            width: 23,
            height: 13,
            spp: 3,
            env,
            ..RenderOptions::default()
        };
        let lit = lights(&scene, &opts);
        let mut integrator = integrator(geometry(&scene, &opts), &accel, &lit, &opts);
        integrator.light_passes = true;
        check_wavefront::<false>(&scene, &integrator, &opts);
        check_wavefront::<true>(&scene, &integrator, &opts);
    }
}

#[test]
fn one_light_per_vertex_converges_to_every_light() {
    // Two point lights and an emissive ball: three candidates, the ball picked at some
    // vertices and not at others, so both its light samples and its MIS weights depend
    // on the pick. The image's mean radiance with one light picked per vertex equals
    // (within the spread of independently scrambled runs) the mean with every light
    // sampled at every vertex, as it must for an unbiased pick.
    let mut scene = busy_scene();
    scene.lights.push(aperture_scene::Light {
        name: None,
        kind: aperture_scene::LightKind::Point,
        position: Vec3::new(-0.5, 1.0, 2.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::new(4.0, 6.0, 8.0),
    });
    let accel = build_accel(&scene, Default::default());
    let opts = RenderOptions {
        width: 48,
        height: 32,
        spp: 64,
        ..RenderOptions::default()
    };
    let mean = |pick: bool, seed: u32| {
        let lit = lights(&scene, &opts);
        let mut integrator = integrator(geometry(&scene, &opts), &accel, &lit, &opts);
        assert!(integrator.pick_light);
        integrator.pick_light = pick;
        image_mean(
            &integrator,
            &RenderOptions {
                seed,
                ..opts.clone()
            },
        )
    };
    let (picked, e_picked) = over_seeds(|seed| mean(true, seed));
    let (every, e_every) = over_seeds(|seed| mean(false, seed));
    assert_within_noise((picked, e_picked), (every, e_every), 0.01);
}

#[test]
fn light_tree_converges_to_the_exhaustive_choice() {
    // Eighty coloured point lights around the emissive ball: the tree's picks, and its
    // probability of the ball's triangles in their MIS weights, give the image mean of the
    // exhaustive choice.
    let mut scene = busy_scene();
    let mut x = 0x9e37_79b9u32;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x as f32 / u32::MAX as f32
    };
    for _ in 0..80 {
        scene.lights.push(aperture_scene::Light {
            name: None,
            kind: aperture_scene::LightKind::Point,
            position: Vec3::new(4.0 * next() - 2.0, 0.2 + 2.0 * next(), 4.0 * next() - 2.0),
            direction: Vec3::NEG_Y,
            intensity: Vec3::new(next(), next(), next()) * 0.2,
        });
    }
    let accel = build_accel(&scene, Default::default());
    let opts = RenderOptions {
        width: 32,
        height: 24,
        spp: 128,
        ..RenderOptions::default()
    };
    let mean = |tree: bool, seed: u32| {
        let lit = lights(&scene, &opts);
        let mut integrator = integrator(geometry(&scene, &opts), &accel, &lit, &opts);
        // Fewer lights than the threshold: the tree is built here.
        assert!(integrator.light_tree.is_none() && integrator.pick_light);
        if tree {
            let em = integrator.emissive;
            integrator.light_tree = LightTree::build(&integrator.geom, em).map(Into::into);
        }
        image_mean(
            &integrator,
            &RenderOptions {
                seed,
                ..opts.clone()
            },
        )
    };
    let tree = over_seeds(|seed| mean(true, seed));
    let exhaustive = over_seeds(|seed| mean(false, seed));
    assert_within_noise(tree, exhaustive, 0.02);
}

#[test]
fn many_point_lights_and_emitters_share_the_tree() {
    // Past the threshold the tree serves the emitters too (their MIS weights then follow the
    // tree's probability, which `light_tree_converges_to_the_exhaustive_choice` checks).
    let mut scene = busy_scene();
    let n = aperture_shading::light_tree::PUNCTUAL_THRESHOLD;
    for k in 0..n {
        scene.lights.push(aperture_scene::Light {
            name: None,
            kind: aperture_scene::LightKind::Point,
            position: Vec3::new(k as f32 * 0.01 - 2.0, 1.5, -1.0),
            direction: Vec3::NEG_Y,
            intensity: Vec3::splat(0.01),
        });
    }
    let accel = build_accel(&scene, Default::default());
    let opts = RenderOptions::default();
    let lit = lights(&scene, &opts);
    let integrator = integrator(geometry(&scene, &opts), &accel, &lit, &opts);
    let tree = integrator
        .light_tree
        .as_ref()
        .expect("the tree past the threshold");
    let triangles = integrator
        .emissive
        .as_ref()
        .map_or(0, |e| e.triangles.len());
    let leaves = tree.leaves();
    let emitting = leaves
        .iter()
        .filter(|l| matches!(l, aperture_shading::light_tree::Leaf::Triangle(_)))
        .count();
    assert!(triangles > 0);
    assert_eq!(emitting, triangles, "every emissive triangle is a leaf");
    assert_eq!(leaves.len(), triangles + scene.lights.len());
}

/// The mean radiance of an image traced sample by sample.
fn image_mean(integrator: &Integrator<'_>, opts: &RenderOptions) -> Vec3 {
    let camera = Camera::new(&integrator.geom.scene.cameras[0], opts.width, opts.height);
    let filter = Filter::new(opts.filter);
    let job = lens_job(integrator, &camera, &filter, opts);
    let mut sum = Vec3::ZERO;
    for (x, y) in (0..opts.height).flat_map(|y| (0..opts.width).map(move |x| (x, y))) {
        for i in 0..opts.spp {
            let (stream, ray) = job.camera_ray(x, y, i);
            if let Some(r) = ray {
                sum += integrator.li_alone::<false>(r.origin, r.dir, &stream).0;
            }
        }
    }
    sum / (opts.width * opts.height * opts.spp) as f32
}

/// Mean and standard error of `mean` over six seeds (each an independent scramble).
fn over_seeds(mean: impl Fn(u32) -> Vec3) -> (Vec3, Vec3) {
    let m: Vec<Vec3> = (0..6).map(mean).collect();
    let avg = m.iter().sum::<Vec3>() / m.len() as f32;
    let var = m.iter().map(|x| (*x - avg) * (*x - avg)).sum::<Vec3>() / 5.0;
    (avg, (var / 6.0).powf(0.5))
}

/// `a` and `b` (means with their standard errors) agree within four standard errors, and
/// that spread is below `spread` of `b`, so the comparison means something.
fn assert_within_noise(a: (Vec3, Vec3), b: (Vec3, Vec3), spread: f32) {
    assert!(b.0.min_element() > 0.01, "{}", b.0);
    for c in 0..3 {
        let tolerance = 4.0 * (a.1[c].powi(2) + b.1[c].powi(2)).sqrt();
        assert!(
            (a.0[c] - b.0[c]).abs() <= tolerance,
            "channel {c}: {} against {} (tolerance {tolerance})",
            a.0,
            b.0
        );
        assert!(
            tolerance < spread * b.0[c],
            "channel {c}: tolerance {tolerance}"
        );
    }
}

/// A job of a thin-lens camera without passes, for tests that trace its samples (pixels
/// that see only a constant background are not traced, as in a render).
fn lens_job<'a>(
    integrator: &'a Integrator<'a>,
    camera: &'a Camera,
    filter: &'a Filter,
    opts: &'a RenderOptions,
) -> Job<'a> {
    let env = &opts.env;
    Job {
        integrator,
        camera,
        filter,
        opts,
        layout: AovLayout::default(),
        ids: CryptoIds::default(),
        wavefronts: Spares::default(),
        backdrop: backdrop(integrator, integrator.accel, camera, filter, env),
    }
}

/// [`Job::samples`] against each sample traced alone ([`Integrator::li_alone`]).
fn check_wavefront<const AOV: bool>(scene: &Scene, integrator: &Integrator, opts: &RenderOptions) {
    let camera = Camera::new(&scene.cameras[0], opts.width, opts.height);
    let filter = Filter::new(opts.filter);
    let job = lens_job(integrator, &camera, &filter, opts);
    // Under the constant environment, part of the view is background only, untraced.
    let untraced = job.backdrop.as_ref().map(|b| &b.scene);
    let constant = matches!(opts.env, Environment::Constant(_));
    assert_eq!(untraced.is_some(), constant);
    let mut background = 0;
    // More items than two runs, in an order that jumps between pixels and samples.
    let items: Vec<(usize, u32, u32, u32)> = (0..opts.height)
        .flat_map(|y| (0..opts.width).map(move |x| (x, y)))
        .flat_map(|(x, y)| (0..opts.spp).map(move |i| (x, y, i)))
        .rev()
        .enumerate()
        .map(|(k, (x, y, i))| (k, x, y, i))
        .collect();
    assert!(items.len() > 2 * WAVEFRONT_SAMPLES);
    let mut seen = 0;
    let (mut hits, mut misses, mut lit_passes) = (0, 0, 0);
    job.samples::<_, AOV>(items.iter().copied(), |k, result, record| {
        assert_eq!(k, seen, "results arrive in order");
        seen += 1;
        let (_, x, y, i) = items[k];
        background += untraced.is_some_and(|r| !r.contains(x, y)) as u32;
        let (stream, ray) = job.camera_ray(x, y, i);
        let alone = ray.map(|r| integrator.li_alone::<AOV>(r.origin, r.dir, &stream));
        let bits = |r: Option<(Vec3, bool)>| r.map(|(l, c)| (l.to_array().map(f32::to_bits), c));
        let want = alone.map(|(l, c, _)| (l, c));
        assert_eq!(bits(result), bits(want), "pixel ({x}, {y}) sample {i}");
        let want_record = alone.map_or(SampleAov::default(), |(_, _, a)| a);
        assert_eq!(*record, want_record, "pixel ({x}, {y}) sample {i}");
        lit_passes += record.light.iter().any(|c| *c != Vec3::ZERO) as u32;
        match result {
            Some((_, true)) => hits += 1,
            _ => misses += 1,
        }
    });
    assert_eq!(seen, items.len());
    assert!(
        hits > 0 && misses > background,
        "{hits} hits, {misses} misses"
    );
    assert_eq!(background > 0, constant, "{background} background samples");
    assert_eq!(lit_passes > 0, AOV, "light passes recorded only with AOV");
}

fn render_in_pool(threads: usize, scene: &Scene, opts: &RenderOptions) -> Film {
    let accel = build_accel(scene, Default::default());
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| render(scene, &accel, opts, &|_, _| {}).unwrap())
}

#[test]
fn identical_for_any_thread_count_and_run() {
    let scene = busy_scene();
    // Not a multiple of the tile size, so edge tiles are partial.
    let opts = RenderOptions {
        width: 45,
        height: 37,
        spp: 4,
        ..RenderOptions::default()
    };
    let one = render_in_pool(1, &scene, &opts);
    let two = render_in_pool(2, &scene, &opts);
    let again = render_in_pool(2, &scene, &opts);
    assert_eq!(one, two);
    assert_eq!(two, again);
    let px = one.to_rgba();
    assert!(px.iter().all(|p| p.iter().all(|c| c.is_finite())));
    assert!(px.iter().any(|p| p[0] != px[0][0]));
    // Another seed changes the image (the comparison above is not vacuous).
    let other = render_in_pool(2, &scene, &RenderOptions { seed: 1, ..opts });
    assert_ne!(one, other);
}

#[test]
fn non_finite_samples_are_dropped_and_counted() {
    let mut scene = busy_scene();
    // An emitter of infinite strength: every sample that sees it is infinite.
    scene.materials[1].emissive_strength = f32::INFINITY;
    let accel = build_accel(&scene, Default::default());
    let opts = RenderOptions {
        width: 24,
        height: 24,
        spp: 2,
        ..RenderOptions::default()
    };
    let film = render(&scene, &accel, &opts, &|_, _| {}).unwrap();
    assert!(film.dropped_samples() > 0);
    assert!(film.to_rgba().iter().flatten().all(|c| c.is_finite()));
    let sum: u64 = (0..24)
        .flat_map(|y| (0..24).map(move |x| (x, y)))
        .map(|(x, y)| film.pixel_sum(x, y).count as u64)
        .sum();
    assert_eq!(sum + film.dropped_samples(), 24 * 24 * 2);
}

#[test]
fn progress_reports_every_tile() {
    let scene = busy_scene();
    let accel = build_accel(&scene, Default::default());
    let opts = RenderOptions {
        width: 40,
        height: 40,
        spp: 1,
        ..RenderOptions::default()
    };
    let calls = AtomicUsize::new(0);
    let last = AtomicUsize::new(0);
    render(&scene, &accel, &opts, &|done, total| {
        calls.fetch_add(1, Ordering::Relaxed);
        assert!(done <= total);
        last.fetch_max(done, Ordering::Relaxed);
        assert_eq!(total, 4);
    })
    .unwrap();
    assert_eq!(calls.into_inner(), 4);
    assert_eq!(last.into_inner(), 4);
}
