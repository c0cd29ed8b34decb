//! A prescription's first-order optics from two paraxial rays (pbrt-v4's
//! `ComputeThickLensApproximation` and `FocusThickLens`): the focal and principal planes on
//! each side, the focus found by moving the lens away from the film, and the f-number set by
//! closing the stop.

use super::trace::{from_film, from_scene, Surface};
use glam::DVec3;

/// Where the focal point and the principal plane of one side lie (`z` in lens space).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Cardinal {
    /// Focal point.
    pub focal: f64,
    /// Principal plane.
    pub principal: f64,
}

/// The cardinal points of both sides: image (film) side and object (scene) side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ThickLens {
    /// Film side: where rays parallel to the axis from the scene converge.
    pub image: Cardinal,
    /// Scene side: where rays parallel to the axis from the film converge.
    pub object: Cardinal,
}

impl ThickLens {
    /// The effective focal length (image side), metres.
    pub fn focal_length(&self) -> f64 {
        self.image.focal - self.image.principal
    }
}

/// The height of the paraxial rays: small against any lens (a thousandth of the film's
/// diagonal, as pbrt).
pub(crate) fn paraxial_height(film_diagonal: f64) -> f64 {
    1e-3 * film_diagonal
}

/// The cardinal points of the ray `(o_in, d_in)` parallel to the axis at height `h` as it
/// leaves the lens `(o, d)`: where it crosses the axis, and where it is back at height `h`.
fn cardinal(h: f64, (o, d): (DVec3, DVec3)) -> Option<Cardinal> {
    if d.x == 0.0 {
        return None;
    }
    let at = |t: f64| o.z + t * d.z;
    let c = Cardinal {
        focal: at(-o.x / d.x),
        principal: at((h - o.x) / d.x),
    };
    (c.focal.is_finite() && c.principal.is_finite()).then_some(c)
}

/// The thick-lens approximation of `surfaces` from rays at height `h`; `None` when a
/// paraxial ray is blocked or leaves parallel (an afocal system).
pub(crate) fn thick_lens(surfaces: &[Surface], h: f64) -> Option<ThickLens> {
    let front = surfaces.first()?.z;
    let scene = (DVec3::new(h, 0.0, front - 1.0), DVec3::Z);
    let image = cardinal(h, from_scene(surfaces, scene, None)?)?;
    let film = (DVec3::new(h, 0.0, 1.0), DVec3::NEG_Z);
    let object = cardinal(h, from_film(surfaces, film)?)?;
    Some(ThickLens { image, object })
}

/// How far to move the lens away from the film (metres; the lens's `z` decrease by it) so
/// that the plane `focus_distance` in front of the film is in focus: the thick-lens equation
/// solved for the film's position. A distance closer than the lens can focus (the object
/// and its image nearer than four focal lengths) gives the closest focus.
pub(crate) fn focus_shift(lens: &ThickLens, focus_distance: f64) -> f64 {
    let f = lens.focal_length();
    // Image distance u from the image-side principal plane, object distance from the
    // object-side one; u + object = l, and 1/u + 1/object = 1/f.
    let a = -lens.image.principal;
    let l = a + lens.object.principal + focus_distance;
    let c = l * (l - 4.0 * f);
    let u = if c > 0.0 && l > 0.0 {
        0.5 * (l - c.sqrt())
    } else {
        0.5 * l.max(4.0 * f)
    };
    u - a
}

/// The stop's half-aperture giving f-number `fstop` (at most the prescription's own), and
/// the f-number it gives: `focal / (2 · entrance pupil radius)`, the entrance pupil found
/// from the height at the stop of a paraxial ray parallel to the axis.
pub(crate) fn stop_for_fstop(
    surfaces: &[Surface],
    stop: usize,
    focal: f64,
    h: f64,
    fstop: Option<f64>,
) -> Option<(f64, f64)> {
    let front = surfaces.first()?.z;
    let mut at_stop = 0.0;
    from_scene(
        surfaces,
        (DVec3::new(h, 0.0, front - 1.0), DVec3::Z),
        Some(&mut at_stop),
    )?;
    if at_stop.is_nan() || at_stop <= 0.0 {
        return None;
    }
    let full = surfaces[stop].half_aperture;
    // Entrance pupil radius per unit of stop radius.
    let pupil_per_stop = h / at_stop;
    let native = focal / (2.0 * full * pupil_per_stop);
    match fstop {
        Some(n) if n > native => {
            let half = full * native / n;
            Some((half, focal / (2.0 * half * pupil_per_stop)))
        }
        _ => Some((full, native)),
    }
}
