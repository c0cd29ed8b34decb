//! What the motion-blur tests share: a thin emissive stripe in front of a pinhole camera, the
//! render options of its images and where a row of them is lit.
// Each test binary uses its own part of these.
#![allow(dead_code)]

use aperture_render::motion::FrameMotion;
use aperture_render::test_scenes::{emitter, look_at_camera, quad, scene};
use aperture_render::{Camera, FilterKind, RenderOptions};
use aperture_scene::{Dof, Scene};
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
