//! A real lens traced surface by surface (issue 61, `lens_prescription`), as pbrt-v4's
//! `RealisticCamera` (Kolb, Mitchell and Hanrahan 1995): a film point and a point of the exit
//! pupil's bounds make a ray that is traced from the rear element to the front one; it leaves
//! the lens, or is blocked (no light: weight 0). The weight is the film's irradiance estimate
//! `cos⁴θ · A_pupil / d²` (θ off the axis, `A_pupil` the area the point was drawn from, `d`
//! the film's distance to the rear element), divided by its value at the film's centre so that
//! a uniformly bright scene renders 1 there, as through the thin lens (`docs/lenses.md`).
//!
//! One job a file: `trace.rs` the surfaces, `pupil.rs` the exit pupil's bounds and samples,
//! `focus.rs` the thick-lens focusing and the f-number.

mod focus;
pub mod intern;
mod pupil;
mod trace;

pub use pupil::BINS as PUPIL_BINS;

use aperture_scene::{Dof, LensPrescription, SensorFit};
use glam::{DVec2, DVec3, Vec2, Vec3};
use pupil::Bounds;
use trace::Surface;

/// How a lens point is drawn (the second exists to measure the first against).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PupilSampling {
    /// In the bounds of the exit pupil of the film point's ring (the renderer's).
    ExitPupil,
    /// Uniformly over the rear element's disc on its vertex plane, grown to the reach the exit
    /// pupil's search covers ([`pupil::REAR_REACH`] rear radii: a ray aimed just outside the
    /// element's rim on that plane can still meet it where it curves); naive.
    RearElement,
}

/// What `aperture info` prints of a prescription camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensFigures {
    /// Effective focal length, mm.
    pub focal_length_mm: f64,
    /// Back focal distance (rear vertex to the image-side focal point, focus at infinity), mm.
    pub back_focal_mm: f64,
    /// The f-number (paraxial: focal length over the entrance pupil's diameter).
    pub fstop: f64,
    /// Radius of the on-axis exit pupil's bounds on the rear element's plane, mm.
    pub exit_pupil_radius_mm: f64,
    /// The film's distance behind the rear element after focusing, mm.
    pub film_distance_mm: f64,
    /// Radius of the entrance pupil, metres (the equivalent thin lens's aperture radius).
    pub entrance_pupil_radius: f64,
    /// Distance from the image-side principal plane to the film, metres (the equivalent thin
    /// lens's image distance, for the field of view).
    pub image_distance: f64,
}

/// A prescription ready to make rays for one image size.
#[derive(Debug, Clone, PartialEq)]
pub struct RealisticLens {
    surfaces: Vec<Surface>,
    /// Half the film's width and height, metres.
    film_half: DVec2,
    /// Half the film's diagonal, metres.
    film_radius: f64,
    /// The exit pupil's bounds by ring of film radius.
    pupil: Vec<Bounds>,
    /// `1 / E₀`, `E₀` the irradiance weight's mean at the film's centre.
    norm: f64,
    /// Image size in pixels.
    size: Vec2,
    /// The lens's figures.
    pub figures: LensFigures,
}

/// The film's size in metres for a `width × height` image: the sensor keys as Blender fits
/// them (`sensor_fit`; AUTO fits `sensor_width` to the larger side).
pub fn film_size(dof: &Dof, width: u32, height: u32) -> DVec2 {
    let aspect = f64::from(width) / f64::from(height.max(1));
    let (sw, sh) = (
        f64::from(dof.sensor_width) * 1e-3,
        f64::from(dof.sensor_height) * 1e-3,
    );
    match dof.sensor_fit {
        SensorFit::Auto if aspect >= 1.0 => DVec2::new(sw, sw / aspect),
        SensorFit::Auto => DVec2::new(sw * aspect, sw),
        SensorFit::Horizontal => DVec2::new(sw, sw / aspect),
        SensorFit::Vertical => DVec2::new(sh * aspect, sh),
    }
}

/// The surfaces of `p` in lens space (metres), the film `film_distance` behind the last one.
fn lens_space(p: &LensPrescription, film_distance: f64) -> Vec<Surface> {
    let mut z = -film_distance;
    let mut out: Vec<Surface> = Vec::with_capacity(p.surfaces.len());
    for (i, s) in p.surfaces.iter().enumerate().rev() {
        if i + 1 < p.surfaces.len() {
            z -= f64::from(s.thickness) * 1e-3;
        }
        out.push(Surface {
            radius: f64::from(s.radius) * 1e-3,
            z,
            eta: if s.ior == 0.0 { 1.0 } else { f64::from(s.ior) },
            half_aperture: 0.5e-3 * f64::from(s.aperture),
        });
    }
    out.reverse();
    out
}

/// `surfaces` moved `shift` metres away from the film.
fn shifted(surfaces: &[Surface], shift: f64) -> Vec<Surface> {
    surfaces
        .iter()
        .map(|s| Surface {
            z: s.z - shift,
            ..*s
        })
        .collect()
}

impl RealisticLens {
    /// The lens of prescription `p` focused at `dof.focus_distance` from the film, for a
    /// `width × height` image on the film the sensor keys give; an error says why a
    /// prescription cannot image (a paraxial ray blocked, an afocal system, no light at the
    /// film's centre).
    pub fn new(p: &LensPrescription, dof: &Dof, width: u32, height: u32) -> Result<Self, String> {
        let film = film_size(dof, width, height);
        let film_radius = 0.5 * film.length();
        let stop = p.stop().ok_or("no stop")?;
        let mut surfaces = lens_space(p, 0.0);
        let h = focus::paraxial_height(2.0 * film_radius);
        let thick = focus::thick_lens(&surfaces, h)
            .ok_or("a paraxial ray does not pass the lens (blocked, or totally reflected)")?;
        let focal = thick.focal_length();
        if !(focal > 0.0 && focal.is_finite()) {
            return Err(format!(
                "the effective focal length {:.3} mm is not positive",
                focal * 1e3
            ));
        }
        let fstop = p.fstop.map(f64::from);
        let (half, fnumber) = focus::stop_for_fstop(&surfaces, stop, focal, h, fstop)
            .ok_or("a paraxial ray does not reach the stop")?;
        surfaces[stop].half_aperture = half;
        let shift = focus::focus_shift(&thick, f64::from(dof.focus_distance)).max(1e-6);
        let surfaces = shifted(&surfaces, shift);
        let pupil = pupil::exit_pupil(&surfaces, film_radius);
        let figures = LensFigures {
            focal_length_mm: focal * 1e3,
            back_focal_mm: thick.image.focal * 1e3,
            fstop: fnumber,
            exit_pupil_radius_mm: 0.5e3 * (pupil[0].max - pupil[0].min).max_element(),
            film_distance_mm: shift * 1e3,
            entrance_pupil_radius: 0.5 * focal / fnumber,
            image_distance: shift - thick.image.principal,
        };
        let mut lens = Self {
            surfaces,
            film_half: 0.5 * film,
            film_radius,
            pupil,
            norm: 1.0,
            size: Vec2::new(width as f32, height as f32),
            figures,
        };
        let e0 = lens.centre_irradiance();
        if e0.is_nan() || e0 <= 0.0 {
            return Err("no light reaches the film's centre through the lens".into());
        }
        lens.norm = 1.0 / e0;
        Ok(lens)
    }

    /// The mean weight (before normalising) of the rays from the film's centre: 64 × 64
    /// stratified points of its exit pupil's bounds.
    fn centre_irradiance(&self) -> f64 {
        const N: u32 = 64;
        let mut sum = 0.0;
        for i in 0..N * N {
            let u = DVec2::new(
                (f64::from(i % N) + 0.5) / f64::from(N),
                (f64::from(i / N) + 0.5) / f64::from(N),
            );
            if let Some((_, w)) = self.trace(DVec2::ZERO, u, PupilSampling::ExitPupil) {
                sum += w;
            }
        }
        sum / f64::from(N * N)
    }

    /// The film point (metres, lens space) of raster position `p_film`: the image is
    /// upside down on the film, so the raster's top right is the film's bottom left.
    #[inline(always)]
    pub fn film_point(&self, p_film: Vec2) -> DVec2 {
        let ndc = DVec2::new(
            2.0 * f64::from(p_film.x / self.size.x) - 1.0,
            1.0 - 2.0 * f64::from(p_film.y / self.size.y),
        );
        -ndc * self.film_half
    }

    /// The film's distance to the rear element's vertex, metres.
    fn rear_distance(&self) -> f64 {
        self.surfaces.last().map_or(0.0, |s| -s.z)
    }

    /// The ray (origin on the front element, unit direction; lens space = camera space) and
    /// its weight (before normalising) of film point `film` and lens numbers `u`.
    #[inline]
    fn trace(&self, film: DVec2, u: DVec2, how: PupilSampling) -> Option<((DVec3, DVec3), f64)> {
        let rear = self.surfaces.last()?;
        let (p, area) = match how {
            PupilSampling::ExitPupil => {
                let bounds = &self.pupil[pupil::bin(film, self.film_radius)];
                if bounds.is_empty() {
                    return None;
                }
                pupil::sample(bounds, film, u)
            }
            PupilSampling::RearElement => {
                let d = aperture_shading::warp::concentric_disc(u.as_vec2()).as_dvec2();
                let r = pupil::REAR_REACH * rear.half_aperture;
                (d * r, std::f64::consts::PI * r * r)
            }
        };
        let o = film.extend(0.0);
        let d = p.extend(rear.z) - o;
        let (origin, dir) = trace::from_film(&self.surfaces, (o, d))?;
        let cos = d.normalize().z;
        let dist = self.rear_distance();
        let w = cos * cos * cos * cos * area / (dist * dist);
        Some(((origin, dir.normalize()), w))
    }

    /// The ray (camera space) and weight of raster position `p_film` and lens numbers
    /// `p_lens`; `None` when the lens blocks it (the sample is black).
    #[inline]
    pub fn ray(&self, p_film: Vec2, p_lens: Vec2, how: PupilSampling) -> Option<(Vec3, Vec3, f32)> {
        let ((o, d), w) = self.trace(self.film_point(p_film), p_lens.as_dvec2(), how)?;
        let (o, d, w) = (o.as_vec3(), d.as_vec3(), (w * self.norm) as f32);
        (o.is_finite() && d.is_finite() && w > 0.0 && w.is_finite()).then_some((o, d, w))
    }

    /// The ray of raster position `p_film` through its exit pupil's centre (camera space):
    /// the Depth and Position passes' ray. When the centre is blocked, the passing point of a
    /// 5 × 5 grid of the bounds nearest it.
    pub fn centre_ray(&self, p_film: Vec2) -> Option<(Vec3, Vec3)> {
        let film = self.film_point(p_film);
        let mut best: Option<(f64, (DVec3, DVec3))> = None;
        for (i, j) in std::iter::once((2, 2)).chain((0..25).map(|k| (k % 5, k / 5))) {
            let u = DVec2::new(0.1 + 0.2 * f64::from(i), 0.1 + 0.2 * f64::from(j));
            let off = (u - 0.5).length_squared();
            if best.is_some_and(|b| b.0 <= off) {
                continue;
            }
            if let Some((ray, _)) = self.trace(film, u, PupilSampling::ExitPupil) {
                best = Some((off, ray));
            }
        }
        let (o, d) = best?.1;
        Some((o.as_vec3(), d.as_vec3()))
    }

    /// The surfaces' vertices `z`, front to back, metres (lens space).
    pub fn vertices(&self) -> Vec<f64> {
        self.surfaces.iter().map(|s| s.z).collect()
    }

    /// The exit pupil's bounds of ring `i` (`< PUPIL_BINS`) as `[min x, min y, max x, max y]`,
    /// metres on the rear element's plane; `None` when empty.
    pub fn pupil_bounds(&self, i: usize) -> Option<[f64; 4]> {
        let b = self.pupil.get(i).filter(|b| !b.is_empty())?;
        Some([b.min.x, b.min.y, b.max.x, b.max.y])
    }

    /// A ray from film point `film` (metres, lens space) towards rear-plane point `rear`
    /// traced through the lens: where it leaves the front element and its direction.
    pub fn trace_from_film(&self, film: DVec2, rear: DVec2) -> Option<(DVec3, DVec3)> {
        let z = self.surfaces.last()?.z;
        let o = film.extend(0.0);
        trace::from_film(&self.surfaces, (o, rear.extend(z) - o))
    }

    /// A ray from the scene traced through the lens to the film side: where it leaves the
    /// rear element and its direction.
    pub fn trace_from_scene(&self, origin: DVec3, dir: DVec3) -> Option<(DVec3, DVec3)> {
        trace::from_scene(&self.surfaces, (origin, dir), None)
    }
}
