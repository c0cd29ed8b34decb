//! Motion blur (SPEC §7): the time dimension's stratification and independence, a camera
//! rotation's blur of the background, and tiles of a blurred frame equal to the whole frame.

use aperture_accel::MotionTransform;
use aperture_render::motion::{
    raster_of, CameraPath, FrameMotion, FrameNeighbours, MovingInstance, Shutter,
};
use aperture_render::{build_accel, build_motion_accel, render_window, SceneHints};
use aperture_render::{Pass, RenderOptions, Window};
use aperture_render::{SampleStream, SamplerKind};
use aperture_scene::{Dof, Scene};
use aperture_shading::test_scenes::{emitter, look_at_camera, scene};
use glam::{Affine3A, Quat, Vec3};
use std::sync::Arc;

mod motion_common;
use motion_common::*;

#[test]
fn time_samples_are_stratified() {
    // The first 2^m times of a pixel fall one in each interval of length 2^-m.
    for (x, y, seed) in [(0, 0, 0), (17, 3, 9), (640, 480, 12345)] {
        for n in [4u32, 16, 64, 256] {
            let mut seen = vec![false; n as usize];
            for i in 0..n {
                let t = SampleStream::new(SamplerKind::Sobol, x, y, i, seed).time();
                assert!((0.0..1.0).contains(&t), "time {t}");
                let cell = (t * n as f32) as usize;
                assert!(
                    !seen[cell],
                    "pixel ({x},{y}) n={n}: two times in cell {cell}"
                );
                seen[cell] = true;
            }
        }
    }
}

/// Pearson correlation of two equally long lists.
fn correlation(a: &[f32], b: &[f32]) -> f32 {
    let n = a.len() as f32;
    let (ma, mb) = (a.iter().sum::<f32>() / n, b.iter().sum::<f32>() / n);
    let cov: f32 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f32 = a.iter().map(|x| (x - ma) * (x - ma)).sum();
    let vb: f32 = b.iter().map(|y| (y - mb) * (y - mb)).sum();
    cov / (va * vb).sqrt()
}

#[test]
fn time_is_independent_of_the_pixel_and_lens_dimensions() {
    // Over the samples of many pixels, time is uncorrelated with each camera dimension, and
    // the joint (time, dimension) points fill the four quadrants evenly.
    let mut time = Vec::new();
    let mut dims: [Vec<f32>; 4] = Default::default();
    for p in 0..64u32 {
        for i in 0..64u32 {
            let s = SampleStream::new(SamplerKind::Sobol, p % 8, p / 8, i, 7);
            time.push(s.time());
            for (d, v) in dims.iter_mut().zip(s.camera()) {
                d.push(v);
            }
        }
    }
    for (k, d) in dims.iter().enumerate() {
        let r = correlation(&time, d);
        assert!(r.abs() < 0.05, "dimension {k}: correlation {r}");
        let mut quad_counts = [0u32; 4];
        for (t, v) in time.iter().zip(d) {
            quad_counts[usize::from(*t >= 0.5) * 2 + usize::from(*v >= 0.5)] += 1;
        }
        let expected = time.len() as f32 / 4.0;
        for c in quad_counts {
            assert!(
                (c as f32 - expected).abs() < 0.05 * expected,
                "dimension {k}: {quad_counts:?}"
            );
        }
    }
}

/// The camera turning from `-angle/2` to `angle/2` over the shutter.
fn turning(scene: &Scene, angle: f32) -> FrameMotion {
    let keys = (0..9)
        .map(|k| turned(scene, angle * (k as f32 / 8.0 - 0.5)))
        .collect();
    FrameMotion {
        shutter: Shutter::default(),
        interval: (0.0, 1.0),
        camera: CameraPath::new(keys),
        instances: Vec::new(),
        meshes: Vec::new(),
    }
}

#[test]
fn a_camera_rotation_blurs_the_background_by_its_angle() {
    let scene = stripe_scene();
    let accel = build_accel(&scene, Default::default());
    let camera = turned(&scene, 0.0);
    let whole = Window::whole(W, H);
    let still = render_window(&scene, &accel, &camera, &options(None), whole, &|_, _| {}).unwrap();
    let (s0, s1) = lit_extent(&still);
    let stripe_px = (s1 - s0 + 1) as f32;
    let f_px = 0.5 * H as f32 / (0.5 * YFOV).tan();
    assert!(
        (stripe_px - f_px * STRIPE / DIST).abs() < 2.0,
        "still stripe {stripe_px} px"
    );
    for angle in [0.2f32, 0.5] {
        let opts = options(Some(turning(&scene, angle)));
        let film = render_window(&scene, &accel, &camera, &opts, whole, &|_, _| {}).unwrap();
        let (b0, b1) = lit_extent(&film);
        let streak = (b1 - b0 + 1) as f32 - stripe_px;
        // The stripe's centre sweeps f·tan(±angle/2) on the image plane.
        let want = 2.0 * f_px * (0.5 * angle).tan();
        assert!(
            (streak - want).abs() < 2.0,
            "angle {angle}: streak {streak} px, want {want}"
        );
        let measured = 2.0 * (streak / (2.0 * f_px)).atan();
        assert!(
            (measured - angle).abs() < 2.0 / f_px,
            "angle {angle}: measured {measured}"
        );
        // Energy is kept: the row's sum is the still stripe's (within the noise).
        let sum = |f: &aperture_render::Film| (0..W).map(|x| f.pixel(x, H / 2)[0]).sum::<f32>();
        assert!(
            (sum(&film) / sum(&still) - 1.0).abs() < 0.05,
            "angle {angle}"
        );
    }
}

#[test]
fn tiles_of_a_blurred_frame_equal_the_whole_frame() {
    let scene = stripe_scene();
    let accel = build_accel(&scene, Default::default());
    let camera = turned(&scene, 0.0);
    let opts = RenderOptions {
        spp: 8,
        ..options(Some(turning(&scene, 0.3)))
    };
    let whole = render_window(
        &scene,
        &accel,
        &camera,
        &opts,
        Window::whole(W, H),
        &|_, _| {},
    )
    .unwrap();
    for (x0, y0, w, h) in [(0, 0, 70, 40), (70, 0, 130, 17), (70, 17, 130, 23)] {
        let tile = Window {
            x0,
            y0,
            width: w,
            height: h,
        };
        let part = render_window(&scene, &accel, &camera, &opts, tile, &|_, _| {}).unwrap();
        for y in 0..h {
            for x in 0..w {
                let (a, b) = (part.pixel(x, y), whole.pixel(x0 + x, y0 + y));
                assert_eq!(
                    a.map(f32::to_bits),
                    b.map(f32::to_bits),
                    "pixel ({}, {})",
                    x0 + x,
                    y0 + y
                );
            }
        }
    }
}

#[test]
fn a_still_frame_motion_changes_nothing() {
    // Motion blur on, nothing moving: the image is the one without motion blur, bit for bit.
    let scene = stripe_scene();
    let accel = build_accel(&scene, Default::default());
    let camera = turned(&scene, 0.0);
    let whole = Window::whole(W, H);
    let still_motion = FrameMotion {
        shutter: Shutter::default(),
        interval: (0.0, 1.0),
        camera: CameraPath::new(vec![camera; 3]),
        instances: Vec::new(),
        meshes: Vec::new(),
    };
    assert!(still_motion.camera.is_none());
    let a = render_window(&scene, &accel, &camera, &options(None), whole, &|_, _| {}).unwrap();
    let b = render_window(
        &scene,
        &accel,
        &camera,
        &options(Some(still_motion)),
        whole,
        &|_, _| {},
    )
    .unwrap();
    assert_eq!(a.to_rgba(), b.to_rgba());
}

/// An emissive sphere of radius `R` at depth `DIST`, centred in front of the camera.
const R: f32 = 0.5;

/// The sphere scene, and the sphere's motion over the shutter: from `x = −shift/2` to
/// `+shift/2`, the frame's placement at the centre.
fn moving_sphere(shift: f32) -> (Scene, FrameMotion) {
    let cam = look_at_camera(Vec3::ZERO, Vec3::NEG_Z, YFOV, Dof::default());
    let at = |x: f32| {
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(R),
            Quat::IDENTITY,
            Vec3::new(x, 0.0, -DIST),
        )
    };
    let sphere = aperture_shading::test_scenes::icosphere(4, 0);
    let scene = scene(vec![(sphere, at(0.0))], vec![emitter(Vec3::ONE)], cam);
    let keys = MotionTransform::new(&[at(-0.5 * shift), at(0.5 * shift)]).unwrap();
    let moving = MovingInstance {
        keys,
        object_from_frame: at(0.0).inverse(),
    };
    let motion = FrameMotion {
        shutter: Shutter::default(),
        interval: (0.0, 1.0),
        camera: None,
        instances: vec![Some(moving)],
        meshes: Vec::new(),
    };
    (scene, motion)
}

#[test]
fn a_moving_sphere_leaves_a_streak_as_long_as_its_screen_motion() {
    let f_px = 0.5 * H as f32 / (0.5 * YFOV).tan();
    let whole = Window::whole(W, H);
    let (scene, _) = moving_sphere(0.0);
    let hints = SceneHints::still();
    let still_accel = build_accel(&scene, Default::default());
    let camera = turned(&scene, 0.0);
    let still = render_window(
        &scene,
        &still_accel,
        &camera,
        &options(None),
        whole,
        &|_, _| {},
    )
    .unwrap();
    for shift in [1.0f32, 2.5] {
        let (scene, motion) = moving_sphere(shift);
        let accel = build_motion_accel(&scene, Default::default(), &hints, None, Some(&motion));
        let opts = RenderOptions {
            passes: [Pass::Depth].into_iter().collect(),
            ..options(Some(motion))
        };
        let film = render_window(&scene, &accel, &camera, &opts, whole, &|_, _| {}).unwrap();
        // The Depth pass is sharp: the sphere where it is at the frame's instant.
        let centre = film.depth[(H / 2 * W + W / 2) as usize];
        assert!(
            (centre - (DIST - R)).abs() < 0.01,
            "shift {shift}: depth {centre}"
        );
        // Symmetric about the frame's placement, the still disc's energy kept.
        let want = f_px * shift / DIST;
        assert_centred_streak(&still, &film, want, &format!("shift {shift}"));
    }
}

#[test]
fn the_vector_pass_of_a_translating_sphere_is_its_screen_motion() {
    // The sphere moves +x by `step` per frame; the camera stays. Cycles' Vector is
    // (pre − center, center − post) with y up: both pairs are minus the motion per frame.
    let f_px = 0.5 * H as f32 / (0.5 * YFOV).tan();
    let (scene, _) = moving_sphere(0.0);
    let accel = build_accel(&scene, Default::default());
    let camera = turned(&scene, 0.0);
    let step = 0.3;
    let placed = scene.instances[0].world_from_object;
    let shifted = |dx: f32| Affine3A::from_translation(Vec3::new(dx, 0.0, 0.0)) * placed;
    let neighbours = FrameNeighbours {
        camera_prev: camera,
        camera_next: camera,
        instances: vec![Some((shifted(-step), shifted(step)))],
        meshes: Vec::new(),
    };
    let opts = RenderOptions {
        spp: 1,
        passes: [Pass::Vector, Pass::Depth].into_iter().collect(),
        vector: Some(Arc::new(neighbours)),
        ..options(None)
    };
    let film = render_window(
        &scene,
        &accel,
        &camera,
        &opts,
        Window::whole(W, H),
        &|_, _| {},
    )
    .unwrap();
    let mut checked = 0;
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let v = film.vector[i];
            let depth = film.depth[i];
            if depth >= aperture_render::DEPTH_BACKGROUND {
                assert_eq!(v, [0.0; 4], "background ({x}, {y})");
                continue;
            }
            // A point at depth z moving by `step` sideways moves f·step/z pixels.
            let motion = f_px * step / depth;
            for (got, want) in v.iter().zip([-motion, 0.0, -motion, 0.0]) {
                assert!(
                    (got - want).abs() < 0.5,
                    "({x}, {y}): {v:?}, motion {motion}"
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 50, "the sphere covers {checked} pixels");
}

#[test]
fn raster_of_inverts_the_centre_ray() {
    let scene = stripe_scene();
    let camera = turned(&scene, 0.3);
    for (x, y) in [
        (0.5f32, 0.5f32),
        (100.0, 20.0),
        (199.5, 39.5),
        (37.25, 3.75),
    ] {
        let p_film = glam::Vec2::new(x, y);
        let r = camera.centre_ray(p_film).unwrap();
        let back = raster_of(&camera, r.origin + 7.0 * r.dir).unwrap();
        assert!((back - p_film).length() < 1e-3, "{p_film} → {back}");
    }
}

#[test]
fn a_rolling_shutter_shows_each_row_at_its_own_time() {
    // A pure rolling shutter (duration 0): row y sees the instant y / H of the interval, so
    // the stripe is sharp in every row and leans with the camera's turn.
    let scene = stripe_scene();
    let accel = build_accel(&scene, Default::default());
    let camera = turned(&scene, 0.0);
    let angle = 0.4f32;
    let mut motion = turning(&scene, angle);
    motion.shutter.rolling = Some(0.0);
    let film = render_window(
        &scene,
        &accel,
        &camera,
        &options(Some(motion)),
        Window::whole(W, H),
        &|_, _| {},
    )
    .unwrap();
    let f_px = 0.5 * H as f32 / (0.5 * YFOV).tan();
    let centre_of = |y: u32| {
        let lit: Vec<u32> = (0..W).filter(|&x| film.pixel(x, y)[0] > 1e-4).collect();
        let width = lit.last().unwrap() - lit.first().unwrap() + 1;
        let stripe = f_px * STRIPE / DIST;
        assert!(
            (width as f32) < stripe + 3.0,
            "row {y}: {width} px wide, sharp expected"
        );
        0.5 * (lit.first().unwrap() + lit.last().unwrap()) as f32
    };
    let (top, bottom) = (centre_of(2), centre_of(H - 3));
    // The camera turns by `angle · Δrow / H` between the rows; the stripe moves right.
    let turn = |y: u32| angle * ((y as f32 + 0.5) / H as f32 - 0.5);
    let want = f_px * ((turn(H - 3)).tan() - (turn(2)).tan());
    assert!(
        (bottom - top - want).abs() < 2.0,
        "lean {} px, want {want}",
        bottom - top
    );
}
