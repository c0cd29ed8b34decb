//! What the motion-blur tests share: a thin emissive stripe in front of a pinhole camera, the
//! render options of its images and where a row of them is lit.
// Each test binary uses its own part of these.
#![allow(dead_code)]

use aperture_render::motion::FrameMotion;
use aperture_render::{Camera, FilterKind, RenderOptions};
use aperture_scene::{Dof, Scene};
use aperture_shading::test_scenes::{emitter, look_at_camera, quad, scene};
use glam::{Affine3A, Quat, Vec3};
use std::sync::Arc;

pub const W: u32 = 200;
pub const H: u32 = 40;
pub const YFOV: f32 = 0.5;
/// Stripe width in world units at distance [`DIST`].
pub const STRIPE: f32 = 0.4;
pub const DIST: f32 = 10.0;

/// A thin vertical emissive stripe `DIST` in front of a pinhole camera at the origin.
pub fn stripe_scene() -> Scene {
    let cam = look_at_camera(Vec3::ZERO, Vec3::NEG_Z, YFOV, Dof::default());
    // The quad faces +Y; turned to face the camera (+Z), STRIPE wide and tall enough.
    let xf = Affine3A::from_scale_rotation_translation(
        Vec3::new(STRIPE, 1.0, 20.0),
        Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
        Vec3::new(0.0, 0.0, -DIST),
    );
    scene(vec![(quad(1.0, 0), xf)], vec![emitter(Vec3::ONE)], cam)
}

/// The scene's camera turned by `angle` radians about +Y.
pub fn turned(scene: &Scene, angle: f32) -> Camera {
    let mut c = Camera::new(&scene.cameras[0], W, H);
    c.world_from_camera = Affine3A::from_rotation_y(angle) * c.world_from_camera;
    c
}

/// Options of the stripe renders, with `motion`.
pub fn options(motion: Option<FrameMotion>) -> RenderOptions {
    RenderOptions {
        width: W,
        height: H,
        spp: 64,
        filter: FilterKind::Box,
        motion: motion.map(Arc::new),
        ..RenderOptions::default()
    }
}

/// Columns of the middle row that received any light: (first, last).
pub fn lit_extent(film: &aperture_render::Film) -> (u32, u32) {
    let lit: Vec<u32> = (0..W).filter(|&x| film.pixel(x, H / 2)[0] > 1e-4).collect();
    (
        *lit.first().expect("the stripe is seen"),
        *lit.last().unwrap(),
    )
}

/// Asserts that `film`'s middle row is `still`'s blurred into a streak `want` pixels longer
/// (within 2), centred on it (within 1 px, a centred shutter) and with the same energy (within
/// 5 %); `what` names the case.
pub fn assert_centred_streak(
    still: &aperture_render::Film,
    film: &aperture_render::Film,
    want: f32,
    what: &str,
) {
    let (s0, s1) = lit_extent(still);
    let (b0, b1) = lit_extent(film);
    let streak = (b1 - b0) as f32 - (s1 - s0) as f32;
    assert!(
        (streak - want).abs() < 2.0,
        "{what}: streak {streak} px, want {want}"
    );
    let centre = 0.5 * (b0 + b1) as f32 - 0.5 * (s0 + s1) as f32;
    assert!(
        centre.abs() <= 1.0,
        "{what}: streak centred {centre} px off"
    );
    let sum = |f: &aperture_render::Film| (0..W).map(|x| f.pixel(x, H / 2)[0]).sum::<f32>();
    let ratio = sum(film) / sum(still);
    assert!((ratio - 1.0).abs() < 0.05, "{what}: energy {ratio}");
}
