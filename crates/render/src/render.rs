//! The render loop: fixed tiles rendered in parallel by rayon. Every sample value is a pure
//! function of (pixel, index, dimension, seed) and every pixel is owned by one tile, so the
//! image is bit-identical for any thread count and any run, whatever order the tiles finish in.
//!
//! Here: the entry points, band by band into a sink ([`render_bands`]) or a window at once,
//! and what every render shares (the Cryptomatte IDs, the Depth and Position passes' centre
//! rays). The pixels come from one of two tile loops, `tiles` (every pixel at `spp` samples)
//! or `rounds` (adaptive sampling), both tracing their samples through a `job::Job`.

mod job;
mod rounds;
#[cfg(test)]
mod tests;
mod tiles;

use crate::bands::progress_units;
use crate::camera::Camera;
use crate::cryptomatte;
use crate::film::{AovLayout, CryptoIds, Film, Window};
use crate::filter::Filter;
use crate::options::{check, RenderError, RenderOptions};
use crate::passes::{Pass, PassSet};
use crate::spares::Spares;
use aperture_accel::Accel;
use aperture_scene::Scene;
use glam::{Vec2, Vec3};
use job::{integrator, Job};
use rayon::prelude::*;
use rounds::render_adaptive;
use std::time::Instant;
use tiles::render_uniform;
pub(crate) use tiles::tiles_of;
pub use tiles::TILE;

/// Renders with the scene camera `opts.camera`. `progress(done, total)` is called after each
/// tile (from worker threads).
pub fn render(
    scene: &Scene,
    accel: &Accel,
    opts: &RenderOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Film, RenderError> {
    let camera = scene_camera(scene, opts)?;
    render_with_camera(scene, accel, &camera, opts, progress)
}

/// The camera `opts.camera` of the scene, for the options' image size.
pub fn scene_camera(scene: &Scene, opts: &RenderOptions) -> Result<Camera, RenderError> {
    let cam = scene
        .cameras
        .get(opts.camera)
        .ok_or(RenderError::NoSuchCamera {
            index: opts.camera,
            count: scene.cameras.len(),
        })?;
    Ok(Camera::new(cam, opts.width, opts.height))
}

/// Renders through an explicit camera (its width and height must match the options').
pub fn render_with_camera(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    opts: &RenderOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Film, RenderError> {
    let whole = Window::whole(opts.width, opts.height);
    render_window(scene, accel, camera, opts, whole, progress)
}

/// Renders the pixels of `window` only. Each is bit-identical to the same pixel of a whole
/// render: every sample is a pure function of (pixel, index, dimension, seed), and adaptive
/// sampling, whose stopping rule looks at neighbours, renders the apron of pixels around the
/// window that its decisions can reach and then drops it.
pub fn render_window(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    opts: &RenderOptions,
    window: Window,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Film, RenderError> {
    check(opts)?;
    if !window.fits(opts.width, opts.height) {
        return Err(RenderError::InvalidOption {
            name: "region",
            value: format!(
                "{}x{} at ({}, {})",
                window.width, window.height, window.x0, window.y0
            ),
            why: "must hold a pixel and lie inside the image",
        });
    }
    let integrator = integrator(scene, accel, opts);
    let filter = Filter::new(opts.filter);
    let job = Job {
        integrator: &integrator,
        camera,
        filter: &filter,
        opts,
        layout: AovLayout::new(opts.passes),
        ids: crypto_ids(scene, opts.passes),
        wavefronts: Spares::default(),
        // A moving camera sees other pixels' background at other times: no backdrop then.
        backdrop: match opts.motion.as_deref().and_then(|m| m.camera.as_ref()) {
            Some(_) => None,
            None => crate::background::backdrop(&integrator, accel, camera, &filter, &opts.env),
        },
    };
    let mut film = match opts.adaptive {
        Some(a) => render_adaptive(&job, &a, window, progress),
        None => render_uniform(&job, window, progress),
    };
    let wanted = [Pass::Depth, Pass::Position, Pass::Vector]
        .iter()
        .any(|&p| opts.passes.contains(p));
    if wanted && !opts.cancel.is_cancelled() {
        centre_rays(&job, &mut film);
    }
    Ok(film)
}

/// Cryptomatte IDs of every instance's node and every material, when the passes need them.
fn crypto_ids(scene: &Scene, passes: PassSet) -> CryptoIds {
    let id = |name: &str| cryptomatte::id_bits(cryptomatte::murmur3_32(name.as_bytes()));
    CryptoIds {
        object: if passes.contains(Pass::CryptoObject) {
            scene
                .instances
                .iter()
                .map(|i| id(&scene.node_name(i.node)))
                .collect()
        } else {
            Vec::new()
        },
        material: if passes.contains(Pass::CryptoMaterial) {
            (0..scene.materials.len())
                .map(|m| id(&material_name(scene, m)))
                .collect()
        } else {
            Vec::new()
        },
    }
}

/// A material's name for compositors: its glTF name, else `materials[N]`.
pub fn material_name(scene: &Scene, index: usize) -> String {
    match scene.materials.get(index).and_then(|m| m.name.as_deref()) {
        Some(name) => name.to_owned(),
        None => format!("materials[{index}]"),
    }
}

/// The Depth, Position and Vector passes: the surface seen through each pixel's centre and the
/// lens centre, one ray per pixel, traced once (sharp and deterministic, not a sample).
fn centre_rays(job: &Job<'_>, film: &mut Film) {
    let w = film.window();
    let cam = job.camera;
    let forward = cam.world_from_camera.transform_vector3(Vec3::NEG_Z);
    // The frame's instant: where moving instances are at the frame itself.
    let time = job.opts.motion.as_deref().map_or(0.0, |m| m.frame_time());
    let hits: Vec<Option<(Vec3, aperture_accel::Hit)>> = (0..w.pixels())
        .into_par_iter()
        .map(|i| {
            let (x, y) = (w.x0 + (i as u32 % w.width), w.y0 + (i as u32 / w.width));
            let p_film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let ray = cam.centre_ray(p_film)?;
            job.integrator.first_surface(ray.origin, ray.dir, time)
        })
        .collect();
    let origin = Vec3::from(cam.world_from_camera.translation);
    let ortho = matches!(cam.model, crate::camera::CameraModel::Orthographic { .. });
    if job.opts.passes.contains(Pass::Depth) {
        film.depth = hits
            .iter()
            .map(|h| match h {
                // Distance along the view axis (from the camera's plane for orthographic).
                Some((p, _)) if ortho || (*p - origin).dot(forward) > 0.0 => {
                    (*p - origin).dot(forward)
                }
                _ => DEPTH_BACKGROUND,
            })
            .collect();
    }
    if job.opts.passes.contains(Pass::Position) {
        film.position = hits.iter().map(|h| h.map_or(Vec3::ZERO, |h| h.0)).collect();
    }
    if job.opts.passes.contains(Pass::Vector) {
        let instances = &job.integrator.geom.scene.instances;
        let on = |&(p, hit): &(Vec3, aperture_accel::Hit)| {
            let inst = instances.get(hit.instance as usize)?;
            Some((p, hit, inst.mesh, inst.world_from_object))
        };
        film.vector = match job.opts.vector.as_deref() {
            None => vec![[0.0; 4]; hits.len()],
            Some(n) => hits
                .iter()
                .map(|h| n.vector(cam, h.as_ref().and_then(on)))
                .collect(),
        };
    }
}

/// Depth where the centre ray meets nothing: Cycles' value.
pub const DEPTH_BACKGROUND: f32 = 1e10;

/// What [`render_bands`] took, over all its bands.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BandTotals {
    /// Samples taken, dropped ones included.
    pub samples: u64,
    /// Samples dropped as NaN or infinite.
    pub dropped: u64,
    /// Seconds spent rendering (not in the sink).
    pub render_secs: f64,
}

/// Renders `bands` (windows of whole rows, top to bottom; see [`crate::bands::bands`]) one
/// after the other through `camera`, handing each finished film to `sink` before the next is
/// rendered, so memory holds one band's sums: how a large image is streamed to a file. A band's
/// pixels are those of a whole render (see [`render_window`]). `progress(done, total)` counts
/// over all bands.
pub fn render_bands<E: From<RenderError>>(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    opts: &RenderOptions,
    bands: &[Window],
    progress: &(dyn Fn(usize, usize) + Sync),
    sink: &mut dyn FnMut(Film) -> Result<(), E>,
) -> Result<BandTotals, E> {
    let units: Vec<usize> = bands.iter().map(|b| progress_units(opts, *b)).collect();
    let total_units: usize = units.iter().sum();
    let mut totals = BandTotals::default();
    let mut offset = 0;
    for (band, n) in bands.iter().zip(&units) {
        let t0 = Instant::now();
        let report = |done: usize, _: usize| progress(offset + done, total_units);
        let film = render_window(scene, accel, camera, opts, *band, &report)?;
        totals.render_secs += t0.elapsed().as_secs_f64();
        offset += n;
        totals.samples += film.total_samples();
        totals.dropped += film.dropped_samples();
        sink(film)?;
    }
    Ok(totals)
}
