//! The report's `motion` (`aperture info --frame N`): the shutter interval of the frame and what moves within it
//! (SPEC §7), as the render would pose it.

use crate::motion::{pose_frame_motion, MotionOverrides, MotionSettings};
use aperture_scene::{Animated, Scene};
use serde_json::{json, Value};

/// The `motion` object of the report: off, or the interval, the settings and what moves.
pub fn motion_json(
    overrides: &MotionOverrides,
    animated: &Animated,
    scene: &Scene,
    (time, fps): (Option<f32>, f32),
) -> Result<Value, aperture_scene::Error> {
    let settings = MotionSettings::resolve(&scene.stats.motion, overrides);
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
