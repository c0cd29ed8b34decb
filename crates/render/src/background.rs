//! Pixels that can only see the background. A thin-lens camera's rays through a pixel fill a
//! known pencil (lens points to the pixel's footprint on the focal plane), so the pixels whose
//! rays may meet a box form a rectangle of the image that its corners, and its crossings of
//! the lens plane, give ([`window`]). The scene's geometry is held by a few boxes, the top of
//! its BVH ([`aperture_accel::Accel::cover`]); outside the union of their rectangles every
//! sample's ray leaves the scene at once. Under a constant environment all such samples are
//! the same sample, which the render adds without tracing them: a product shot's background,
//! and the sky above an outdoor scene's horizon, are much of their images.

use crate::aov::SampleAov;
use crate::camera::Camera;
use crate::filter::Filter;
use crate::integrator::Integrator;
use crate::sampler::{SampleStream, SamplerKind};
use aperture_accel::Accel;
use aperture_shading::environment::Environment;
use glam::Vec3;

mod mask;
mod window;

pub(crate) use mask::PixelMask;
#[cfg(test)]
use window::box_pixels;
use window::LensView;
pub(crate) use window::PixelRect;

/// The most boxes the scene's geometry is cut into ([`aperture_accel::Accel::cover`]): enough
/// to separate a ground from the objects on it and the objects from each other; projecting
/// them costs microseconds.
const COVER_BUDGET: usize = 64;

/// Under a constant environment, the pixels whose rays may meet the scene and the one sample
/// every other pixel's samples are (a camera ray that meets nothing sees the same radiance in
/// every direction).
pub(crate) struct Backdrop {
    /// The pixels traced.
    pub scene: PixelMask,
    /// The sample of the others: radiance, coverage (false), pass values.
    pub l: Vec3,
    pub covered: bool,
    pub record: SampleAov,
}

/// The [`Backdrop`] of a render, when the environment is constant and some pixel of the image
/// can only see it.
pub(crate) fn backdrop(
    integrator: &Integrator<'_>,
    accel: &Accel,
    camera: &Camera,
    filter: &Filter,
    env: &Environment,
) -> Option<Backdrop> {
    if !matches!(env, Environment::Constant(_)) {
        return None;
    }
    let boxes = accel.cover(COVER_BUDGET);
    let scene = scene_pixels(camera, &boxes, filter.half_width());
    if scene.is_all() {
        return None;
    }
    // Any direction and stream: the path ends at its camera ray, before any sample value
    // could matter.
    let stream = SampleStream::new(SamplerKind::Sobol, 0, 0, 0, 0);
    let (l, covered, record) = integrator.missed_sample(Vec3::NEG_Z, &stream);
    Some(Backdrop {
        scene,
        l,
        covered,
        record,
    })
}

/// The pixels of `camera`'s image whose rays (any lens point, any film point within
/// `filter_half` pixels of the pixel's centre) may meet any of `boxes` (world space): the union
/// of each box's rectangle ([`LensView::rect`]). No pixel when there is no box; every pixel at
/// once when one box's rectangle is the image (a camera inside a room) or the camera has no
/// bound.
pub(crate) fn scene_pixels(camera: &Camera, boxes: &[(Vec3, Vec3)], filter_half: f32) -> PixelMask {
    let (w, h) = (camera.width, camera.height);
    let all = PixelRect::all(w, h);
    let whole = || PixelMask::from_rects(w, h, &[all]);
    let Some(view) = LensView::new(camera, filter_half) else {
        return whole();
    };
    let mut rects = Vec::with_capacity(boxes.len());
    for &(lo, hi) in boxes {
        let rect = view.rect(lo, hi);
        if rect == all {
            return whole();
        }
        rects.push(rect);
    }
    PixelMask::from_rects(w, h, &rects)
}

#[cfg(test)]
mod tests;
