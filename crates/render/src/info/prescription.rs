//! The `dof.prescription` object of `aperture info --json` (issue 61, `lens_prescription`):
//! the lens's first-order figures, traced as the camera traces them.

use aperture_scene::Dof;
use serde_json::{json, Value};

/// Image size the figures are worked out for: the sensor's aspect, 1,000 pixels across (only
/// the exit pupil's rings depend on it, by a ring's width).
const WIDTH: u32 = 1000;

/// `null` for a thin-lens camera; else the prescription's source and rows count, and its
/// effective focal length, back focal distance, f-number, exit pupil radius and film distance
/// (mm), or the reason it cannot image.
pub fn json(d: &Dof) -> Value {
    let Some(p) = &d.prescription else {
        return Value::Null;
    };
    let height = ((WIDTH as f32 * d.sensor_height / d.sensor_width).round() as u32).max(1);
    let round = |x: f64| (x * 1e4).round() / 1e4;
    let figures = match crate::realistic::intern::interned(p, d, WIDTH, height) {
        Ok(lens) => {
            let f = &lens.figures;
            json!({
                "focal_length_mm": round(f.focal_length_mm),
                "back_focal_distance_mm": round(f.back_focal_mm),
                "fstop": round(f.fstop),
                "exit_pupil_radius_mm": round(f.exit_pupil_radius_mm),
                "film_distance_mm": round(f.film_distance_mm),
            })
        }
        Err(reason) => json!({ "error": reason }),
    };
    json!({
        "source": p.source,
        "surfaces": p.surfaces.len(),
        "fstop_asked": p.fstop,
        "lens": figures,
    })
}
