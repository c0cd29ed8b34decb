//! `aperture info --frame N`'s motion blur as text (the report's `motion`, which
//! `aperture_render::info::motion` builds).

use serde_json::{json, Value};

/// Seconds to the microsecond.
fn secs(v: &Value) -> String {
    format!("{:.6}", v.as_f64().unwrap_or(f64::NAN))
}

/// The report's `motion` object as a line of text.
pub fn print_motion(r: &Value) {
    let m = &r["motion"];
    if m["motion_blur"] != json!(true) {
        println!("  motion blur: {}", m["why"].as_str().unwrap_or("off"));
        return;
    }
    let moving = m["moving_instances"].as_array().map_or(0, Vec::len);
    let deforming = m["deforming_instances"].as_array().map_or(0, Vec::len);
    println!(
        "  motion blur: shutter {} frame(s) {}, open {} s to {} s, {} steps; camera {}, {} \
         moving instance(s), {} deforming",
        m["shutter_frames"],
        m["position"].as_str().unwrap_or_default(),
        secs(&m["interval"][0]),
        secs(&m["interval"][1]),
        m["motion_steps"],
        if m["camera_moves"] == json!(true) {
            "moves"
        } else {
            "still"
        },
        moving,
        deforming
    );
}
