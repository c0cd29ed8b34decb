//! Adaptive sampling (issue 7): in-focus flat regions stop early, bokeh keeps sampling; every
//! pixel holds a prefix of its own sample sequence; the image does not depend on threads.

use aperture_render::{build_accel, render, AdaptiveOptions, Film, RenderOptions, SamplerKind};
use aperture_scene::Scene;
use aperture_shading::test_scenes;
use glam::{Affine3A, Vec3};

/// A lit plane in focus and a small emitter out of focus near the camera, on the optical axis:
/// its bokeh fills the image centre.
fn scene() -> Scene {
    let mut s = test_scenes::lit_plane(3.0);
    s.cameras[0].dof.enabled = true;
    s.cameras[0].dof.aperture_radius = 0.2;
    // The camera at (0, 6, 6) looks at (0, 0, 1): the plane is ~7.8 away along the axis.
    s.cameras[0].dof.focus_distance = 61f32.sqrt();
    s.materials
        .push(test_scenes::emitter(Vec3::new(4.0, 3.0, 2.0)));
    s.meshes.push(test_scenes::icosphere(1, 1).into());
    let axis = Vec3::new(0.0, -6.0, -5.0).normalize();
    s.instances.push(aperture_scene::Instance {
        mesh: 1,
        world_from_object: Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.1),
            Default::default(),
            Vec3::new(0.0, 6.0, 6.0) + 2.0 * axis,
        ),
        node: 1,
        materials: 0,
    });
    s
}

const W: u32 = 32;
const H: u32 = 32;

fn opts(adaptive: Option<AdaptiveOptions>, spp: u32) -> RenderOptions {
    RenderOptions {
        width: W,
        height: H,
        spp,
        adaptive,
        ..RenderOptions::default()
    }
}

fn adaptive(threshold: f32) -> Option<AdaptiveOptions> {
    Some(AdaptiveOptions {
        threshold,
        min_spp: 4,
    })
}

fn render_in_pool(threads: usize, scene: &Scene, opts: &RenderOptions) -> Film {
    let accel = build_accel(scene, Default::default());
    let film = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| render(scene, &accel, opts, &|_, _| {}).unwrap());
    assert_eq!(film.dropped_samples(), 0);
    film
}

fn mean_taken(film: &Film, xs: std::ops::Range<u32>, ys: std::ops::Range<u32>) -> f64 {
    let n = (xs.len() * ys.len()) as f64;
    let sum: u64 = ys
        .flat_map(|y| xs.clone().map(move |x| (x, y)))
        .map(|(x, y)| u64::from(film.samples_taken(x, y)))
        .sum();
    sum as f64 / n
}

#[test]
fn in_focus_flat_regions_stop_early_and_bokeh_keeps_sampling() {
    let scene = scene();
    let film = render_in_pool(2, &scene, &opts(adaptive(0.02), 64));
    let centre = mean_taken(&film, 13..19, 13..19);
    let corners = [
        (0..6, 0..6),
        (26..32, 0..6),
        (0..6, 26..32),
        (26..32, 26..32),
    ]
    .into_iter()
    .map(|(xs, ys)| mean_taken(&film, xs, ys))
    .fold(0.0, f64::max);
    eprintln!("mean samples: bokeh centre {centre}, flat corners (worst) {corners}");
    assert!(centre >= 32.0, "bokeh centre took {centre}");
    assert!(
        corners * 2.0 <= centre,
        "corners {corners}, centre {centre}"
    );
    // The bokeh is really there (the comparison above is about the right pixels).
    assert!(film.pixel(16, 16)[0] > 2.0 * film.pixel(2, 2)[0]);
    // Fewer samples than the uniform budget, never fewer than the minimum.
    assert!(film.total_samples() < u64::from(W * H * 64));
    for y in 0..H {
        for x in 0..W {
            assert!((4..=64).contains(&film.samples_taken(x, y)));
        }
    }
}

#[test]
fn every_pixel_holds_a_prefix_of_its_sequence() {
    // A pixel that stopped at n samples equals the uniform render at n samples, bit for bit.
    let scene = scene();
    for sampler in [SamplerKind::Sobol, SamplerKind::Random] {
        let ad = RenderOptions {
            sampler,
            ..opts(adaptive(0.05), 32)
        };
        let film = render_in_pool(2, &scene, &ad);
        let mut seen = Vec::new();
        for n in [4, 8, 16, 32] {
            let uniform = render_in_pool(
                2,
                &scene,
                &RenderOptions {
                    sampler,
                    ..opts(None, n)
                },
            );
            assert_eq!(uniform.samples_taken(0, 0), n);
            for y in 0..H {
                for x in 0..W {
                    if film.samples_taken(x, y) == n {
                        assert_eq!(film.pixel_sum(x, y), uniform.pixel_sum(x, y), "({x},{y})");
                        seen.push(n);
                    }
                }
            }
        }
        seen.dedup();
        assert!(seen.len() >= 2, "{sampler:?}: counts {seen:?}");
    }
}

#[test]
fn identical_for_any_thread_count() {
    let scene = scene();
    let o = opts(adaptive(0.03), 16);
    let one = render_in_pool(1, &scene, &o);
    let two = render_in_pool(2, &scene, &o);
    assert_eq!(one, two);
    assert_eq!(one.samples_per_pixel(), two.samples_per_pixel());
    // A looser threshold takes fewer samples: the threshold is used.
    let loose = render_in_pool(2, &scene, &opts(adaptive(0.5), 16));
    assert!(loose.total_samples() < one.total_samples());
}

#[test]
fn bad_adaptive_options_are_refused() {
    let scene = scene();
    let accel = build_accel(&scene, Default::default());
    for a in [
        AdaptiveOptions {
            threshold: 0.0,
            min_spp: 4,
        },
        AdaptiveOptions {
            threshold: f32::NAN,
            min_spp: 4,
        },
        AdaptiveOptions {
            threshold: 0.01,
            min_spp: 0,
        },
        AdaptiveOptions {
            threshold: 0.01,
            min_spp: 17,
        },
    ] {
        assert!(render(&scene, &accel, &opts(Some(a), 16), &|_, _| {}).is_err());
    }
}
