//! The render loop: fixed tiles rendered in parallel by rayon. Every sample value is a pure
//! function of (pixel, index, dimension, seed) and every pixel is owned by one tile, so the
//! image is bit-identical for any thread count and any run, whatever order the tiles finish in.
//!
//! Here: a window rendered from a posed scene, its BVH and its lights ([`render_in`], what a
//! [`crate::Frame`] renders with), the same for a scene built by hand ([`render`],
//! [`render_window`]), and what every render shares (the Cryptomatte IDs, the Depth and
//! Position passes' centre rays). The pixels come from one of two tile loops, `tiles` (every
//! pixel at `spp` samples, onto what a film holds) or `rounds` (adaptive sampling), both
//! tracing their samples through a `job::Job`.

#[cfg(test)]
mod centre_tests;
mod job;
mod rounds;
#[cfg(test)]
mod tests;
mod tiles;

use crate::camera::Camera;
use crate::cryptomatte;
use crate::film::{AovLayout, CryptoIds, Film, Window};
use crate::filter::Filter;
use crate::frame_lights::FrameLights;
use crate::options::{check, RenderError, RenderOptions};
use crate::passes::{Pass, PassSet};
use crate::spares::Spares;
use aperture_accel::{Accel, Hit, Ray};
use aperture_scene::Scene;
use glam::{Vec2, Vec3};
pub(crate) use job::geometry;
use job::{integrator, Job};
use rayon::prelude::*;
use rounds::render_adaptive;
pub(crate) use tiles::tiles_of;
pub use tiles::TILE;

/// Renders a scene built by hand with its camera `opts.camera` (its lights gathered for this
/// render alone; a [`crate::Frame`] keeps them). `progress(done, total)` is called after each
/// tile (from worker threads).
pub fn render(
    scene: &Scene,
    accel: &Accel,
    opts: &RenderOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Film, RenderError> {
    let camera = scene_camera(scene, opts)?;
    let whole = Window::whole(opts.width, opts.height);
    render_window(scene, accel, &camera, opts, whole, progress)
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
    let camera = Camera::new(cam, opts.width, opts.height);
    if let Some(reason) = camera.lens_error() {
        return Err(RenderError::Lens {
            camera: cam.name.clone(),
            source_name: cam
                .dof
                .prescription
                .as_ref()
                .map_or_else(String::new, |p| p.source.clone()),
            reason: reason.to_owned(),
        });
    }
    Ok(camera)
}

/// [`render`] of the pixels of `window` only, through `camera`.
pub fn render_window(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    opts: &RenderOptions,
    window: Window,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Film, RenderError> {
    let lights = FrameLights::build(&geometry(scene, opts), None);
    let mut film = Film::for_window(window, opts.width, opts.height, opts.passes);
    let posed = Posed {
        scene,
        accel,
        lights: &lights,
    };
    render_in(&posed, camera, opts, &mut film, progress)?;
    Ok(film)
}

/// What a render draws from: a posed scene, its BVH and its lights.
pub(crate) struct Posed<'a> {
    pub scene: &'a Scene,
    pub accel: &'a Accel,
    pub lights: &'a FrameLights,
}

/// Renders the job's samples of every pixel of `film`'s window onto what it holds. Each pixel
/// is bit-identical to the same pixel of a whole render: every sample is a pure function of
/// (pixel, index, dimension, seed), and adaptive sampling, whose stopping rule looks at
/// neighbours, renders the apron of pixels around the window that its decisions can reach and
/// then drops it. The Depth, Position and Vector passes are traced when the film has none yet.
pub(crate) fn render_in(
    posed: &Posed<'_>,
    camera: &Camera,
    opts: &RenderOptions,
    film: &mut Film,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(), RenderError> {
    check(opts)?;
    let window = film.window();
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
    let scene = posed.scene;
    let integrator = integrator(geometry(scene, opts), posed.accel, posed.lights, opts);
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
            None => {
                crate::background::backdrop(&integrator, posed.accel, camera, &filter, &opts.env)
            }
        },
    };
    let first = film.total_samples() == 0 && film.dropped_samples() == 0;
    match opts.adaptive {
        Some(a) => *film = render_adaptive(&job, &a, window, progress),
        None => tiles::accumulate(&job, film, !first, progress),
    }
    let wanted = [Pass::Depth, Pass::Position, Pass::Vector]
        .iter()
        .any(|&p| opts.passes.contains(p));
    if first && wanted && !opts.cancel.is_cancelled() {
        centre_rays(&job, film);
    }
    Ok(())
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
    let hits: Vec<Option<(Vec3, Hit)>> = (w.y0..w.y0 + w.height)
        .into_par_iter()
        .flat_map_iter(|y| centre_row(job, w, y, time))
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
        let on = |&(p, hit): &(Vec3, Hit)| {
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

/// The first surfaces row `y` of `w` sees through its pixels' centres at `time`, found
/// together: a row's centre rays are coherent, so they walk the BVH as packets (one at a
/// time, they took 7 % of a 1-spp 1080p EXR of 980 k triangles).
fn centre_row(job: &Job<'_>, w: Window, y: u32, time: f32) -> Vec<Option<(Vec3, Hit)>> {
    let mut rays = Vec::with_capacity(w.width as usize);
    let mut at = Vec::with_capacity(w.width as usize);
    for (k, x) in (w.x0..w.x0 + w.width).enumerate() {
        let p_film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        if let Some(r) = job.camera.centre_ray(p_film) {
            rays.push(Ray {
                time,
                ..Ray::new(r.origin, r.dir)
            });
            at.push(k);
        }
    }
    let (mut hits, mut seen) = (Vec::new(), Vec::new());
    job.integrator.first_surfaces(&rays, &mut hits, &mut seen);
    let mut row = vec![None; w.width as usize];
    for (k, s) in at.into_iter().zip(seen) {
        row[k] = s;
    }
    row
}

/// Depth where the centre ray meets nothing: Cycles' value.
pub const DEPTH_BACKGROUND: f32 = 1e10;
