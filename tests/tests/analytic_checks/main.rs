//! Analytic accuracy checks (issue 6): renders and camera geometry against closed forms and an
//! independent numerical quadrature, each written here from the textbook formulas rather than
//! taken from the renderer.
//!
//! - GGX white furnace: a sphere in a uniform environment, binned by view cosine, against the
//!   directional albedo E(μo) integrated numerically.
//! - An emissive rectangle over a diffuse plane against the closed-form form factor.
//! - A spot light's cone falloff (KHR_lights_punctual) over the whole cone, and a directional
//!   light at oblique incidence.
//! - The circle of confusion over a grid of focus, depth, radius, blades and squeeze, solved
//!   exactly through the `Camera` API (no rendering).

use aperture_render::{Camera, CameraSample, FilterKind, RenderOptions};
use glam::{DVec3, Vec2};

mod coc;
mod form_factor;
mod furnace;
mod lights;

fn opts(size: u32, spp: u32, max_bounces: u32) -> RenderOptions {
    RenderOptions {
        width: size,
        height: size,
        spp,
        seed: 11,
        max_bounces,
        filter: FilterKind::Box,
        ..RenderOptions::default()
    }
}

/// Pinhole rays through a `k × k` grid of positions inside pixel `(x, y)`: with the box filter
/// a pixel is the mean over its area, so predictions are averaged over the same area.
fn subpixel_rays(cam: &Camera, x: u32, y: u32, k: u32) -> Vec<(DVec3, DVec3)> {
    (0..k * k)
        .map(|i| {
            let p_film = Vec2::new(
                x as f32 + ((i % k) as f32 + 0.5) / k as f32,
                y as f32 + ((i / k) as f32 + 0.5) / k as f32,
            );
            let r = cam
                .generate_ray(&CameraSample {
                    p_film,
                    p_lens: Vec2::ZERO,
                    time: 0.0,
                })
                .expect("pinhole ray");
            (r.origin.as_dvec3(), r.dir.as_dvec3())
        })
        .collect()
}

/// Where a ray meets the plane y = 0, if in front of it.
fn hit_ground(o: DVec3, d: DVec3) -> Option<DVec3> {
    let t = -o.y / d.y;
    (t > 0.0).then(|| o + t * d)
}
