//! `aperture info`'s line for a camera with a `lens_prescription` (issue 61).

use serde_json::Value;

/// Prints the `prescription:` line of `dof.prescription` (nothing for a thin lens).
pub(crate) fn print(p: &Value) {
    if p.is_null() {
        return;
    }
    let l = &p["lens"];
    match l["error"].as_str() {
        Some(e) => println!(
            "      prescription {} ({} surfaces): cannot image: {e}",
            p["source"], p["surfaces"]
        ),
        None => println!(
            "      prescription {} ({} surfaces): focal length {} mm, f/{}, exit pupil radius {} mm, film {} mm behind the rear element",
            p["source"],
            p["surfaces"],
            l["focal_length_mm"],
            l["fstop"],
            l["exit_pupil_radius_mm"],
            l["film_distance_mm"]
        ),
    }
}
