//! Meshes deforming within the shutter (motion steps, SPEC §7): a stripe whose vertices move
//! leaves a streak as long as their screen motion, and keys that do not move change nothing.

use aperture_accel::VertexMotion;
use aperture_render::motion::{DeformedNeighbours, FrameMotion, FrameNeighbours, Shutter};
use aperture_render::{build_accel, build_motion_accel, render_window, SceneHints, Window};
use aperture_render::{Pass, RenderOptions};
use aperture_scene::Scene;
use glam::Vec3;
use std::sync::Arc;

mod motion_common;
use motion_common::*;

/// The stripe's mesh keyed at `steps` times: vertex `v` at key `k` moved along the stripe's
/// width (world x) by `offset(v, k / (steps − 1))` world units.
fn keyed(scene: &Scene, steps: usize, offset: impl Fn(Vec3, f32) -> f32) -> FrameMotion {
    let frame = &scene.meshes[0].positions;
    let keys: Vec<Vec<Vec3>> = (0..steps)
        .map(|k| {
            let tau = k as f32 / (steps - 1) as f32;
            // Object x is world x scaled by the stripe's width.
            let shift = |p: &Vec3| *p + Vec3::X * offset(*p, tau) / STRIPE;
            frame.iter().map(shift).collect()
        })
        .collect();
    let refs: Vec<&[Vec3]> = keys.iter().map(Vec::as_slice).collect();
    FrameMotion {
        shutter: Shutter::default(),
        interval: (0.0, 1.0),
        camera: None,
        instances: Vec::new(),
        meshes: vec![VertexMotion::new(&refs)],
    }
}

/// The stripe rendered still, and with `motion` (built into the accel as a render does).
fn still_and_blurred(motion: FrameMotion) -> (aperture_render::Film, aperture_render::Film) {
    let scene = stripe_scene();
    let camera = turned(&scene, 0.0);
    let whole = Window::whole(W, H);
    let accel = build_accel(&scene, Default::default());
    let still = render_window(&scene, &accel, &camera, &options(None), whole, &|_, _| {});
    let hints = SceneHints::still();
    let accel = build_motion_accel(&scene, Default::default(), &hints, None, Some(&motion));
    let opts = options(Some(motion));
    let film = render_window(&scene, &accel, &camera, &opts, whole, &|_, _| {});
    (still.unwrap(), film.unwrap())
}

#[test]
fn a_morphed_stripe_leaves_a_streak_as_long_as_its_screen_motion() {
    let f_px = 0.5 * H as f32 / (0.5 * YFOV).tan();
    for (shift, steps) in [(1.0f32, 3), (2.5, 3), (2.5, 6)] {
        // Every vertex moves from x = −shift/2 to +shift/2: the stripe translates.
        let motion = keyed(&stripe_scene(), steps, |_, tau| shift * (tau - 0.5));
        assert!(motion.meshes[0].is_some());
        let (still, film) = still_and_blurred(motion);
        // Centred, the row keeping the still stripe's energy (the stripe keeps its width).
        let want = f_px * shift / DIST;
        let what = format!("shift {shift}, {steps} steps");
        assert_centred_streak(&still, &film, want, &what);
    }
}

#[test]
fn a_stretching_stripe_streaks_on_its_moving_side_only() {
    // The right edge moves 1.2 units right over the shutter; the left edge stays: a
    // deformation no rigid motion gives.
    let f_px = 0.5 * H as f32 / (0.5 * YFOV).tan();
    let reach = 1.2;
    let motion = keyed(&stripe_scene(), 3, |p, tau| {
        if p.x > 0.0 {
            reach * tau
        } else {
            0.0
        }
    });
    let (still, film) = still_and_blurred(motion);
    let (s0, s1) = lit_extent(&still);
    let (b0, b1) = lit_extent(&film);
    assert!(b0.abs_diff(s0) <= 1, "left edge {b0}, still {s0}");
    let grown = (b1 - s1) as f32;
    let want = f_px * reach / DIST;
    assert!(
        (grown - want).abs() < 2.0,
        "right edge grew {grown} px, want {want}"
    );
}

#[test]
fn keys_that_do_not_move_render_the_still_image_bit_for_bit() {
    // The deforming path whole (swept tree, interpolated triangles and surfaces, a time per
    // sample) with keys equal to the frame's vertices: the still image, bit for bit.
    let motion = keyed(&stripe_scene(), 3, |_, _| 0.0);
    assert!(motion.meshes[0]
        .as_ref()
        .is_some_and(VertexMotion::is_still));
    let (still, film) = still_and_blurred(motion);
    assert_eq!(still.to_rgba(), film.to_rgba());
}

/// The `Vector` pass follows a deforming mesh's vertices: the stripe's vertices, a `step` to
/// the left at the previous frame and to the right at the next (its instance still), give
/// every pixel on it the screen motion of that step (Cycles' order and signs, as for a
/// moving instance in `motion_blur.rs`).
#[test]
fn the_vector_pass_of_a_morphed_stripe_is_its_vertices_screen_motion() {
    let f_px = 0.5 * H as f32 / (0.5 * YFOV).tan();
    let scene = stripe_scene();
    let camera = turned(&scene, 0.0);
    let step = 0.05;
    let mesh = &scene.meshes[0];
    // Object x is world x scaled by the stripe's width.
    let moved = |dx: f32| -> Vec<Vec3> {
        let shift = Vec3::X * dx / STRIPE;
        mesh.positions.iter().map(|p| *p + shift).collect()
    };
    let neighbours = FrameNeighbours {
        camera_prev: camera,
        camera_next: camera,
        instances: vec![None],
        meshes: vec![Some(Arc::new(DeformedNeighbours {
            indices: mesh.indices.clone(),
            prev: moved(-step),
            next: moved(step),
        }))],
    };
    let opts = RenderOptions {
        spp: 1,
        passes: [Pass::Vector, Pass::Depth].into_iter().collect(),
        vector: Some(Arc::new(neighbours)),
        ..options(None)
    };
    let accel = build_accel(&scene, Default::default());
    let film = render_window(
        &scene,
        &accel,
        &camera,
        &opts,
        Window::whole(W, H),
        &|_, _| {},
    );
    let film = film.unwrap();
    let motion = f_px * step / DIST;
    let mut checked = 0;
    for (v, depth) in film.vector.iter().zip(&film.depth) {
        if *depth >= aperture_render::DEPTH_BACKGROUND {
            continue;
        }
        for (got, want) in v.iter().zip([-motion, 0.0, -motion, 0.0]) {
            assert!((got - want).abs() < 0.05, "{v:?}, motion {motion} px");
        }
        checked += 1;
    }
    assert!(checked > 20, "the stripe covers {checked} pixels");
}
