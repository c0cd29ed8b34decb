//! `aperture info --frame N`: the shutter interval of the frame and what moves within it
//! (SPEC §7), as the render would pose it.

use crate::motion_args::MotionArgs;
use aperture_render::motion::{pose_frame_motion, MotionSettings};
use aperture_scene::{Animated, Scene};
use serde_json::{json, Value};

/// The `motion` object of the report: off, or the interval, the settings and what moves.
pub fn motion_json(
    args: &MotionArgs,
    animated: &Animated,
    scene: &Scene,
    (time, fps): (Option<f32>, f32),
) -> anyhow::Result<Value> {
    let settings = MotionSettings::resolve(&scene.stats.motion, &args.overrides());
    let (Some(shutter), Some(time)) = (settings.shutter, time) else {
        let why = match settings.shutter {
            None => "off",
            Some(_) => "on, but no time given (--frame or --time)",
        };
        return Ok(json!({"motion_blur": false, "why": why}));
    };
    // The size only scales the camera's image plane: whether it moves does not depend on it.
    let camera = (0, 1920, 1080);
    let frame = (f64::from(time), f64::from(fps));
    let Some(m) = pose_frame_motion(animated, &settings, frame, scene, camera)? else {
        return Ok(json!({"motion_blur": false, "why": "off"}));
    };
    let moving: Vec<Value> = (m.instances.iter().enumerate())
        .filter(|(_, i)| i.is_some())
        .filter_map(|(k, _)| scene.instances.get(k))
        .map(|i| json!(scene.node_name(i.node)))
        .collect();
    let deforms =
        |i: &&aperture_scene::Instance| matches!(m.meshes.get(i.mesh as usize), Some(Some(_)));
    let deforming: Vec<Value> = (scene.instances.iter().filter(deforms))
        .map(|i| json!(scene.node_name(i.node)))
        .collect();
    Ok(json!({
        "motion_blur": true,
        "shutter_frames": shutter.frames,
        "position": format!("{:?}", shutter.position).to_uppercase(),
        "rolling_shutter_duration": shutter.rolling,
        "interval": [m.interval.0, m.interval.1],
        "motion_steps": settings.steps,
        "camera_moves": m.camera.is_some(),
        "moving_instances": moving,
        "deforming_instances": deforming,
    }))
}

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
