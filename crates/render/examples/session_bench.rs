//! What a live session saves (BENCHMARKS.md, "Render session"): for one scene, the cold start
//! (load → first pass) against each kind of edit (edit → first pass), the first pass being 1
//! sample a pixel at 1/8 of 960×540 (what a viewport shows first). Medians over `REPEATS`
//! edits, alternating two values.
//!
//! ```text
//! cargo run --release -p aperture-render --example session_bench -- SCENE.glb [REPEATS]
//! ```

use aperture_render::{FrameSpec, RenderOptions, Session};
use aperture_scene::{Edit, LoadOptions};
use glam::Vec3A;
use std::time::Instant;

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

/// 1 sample a pixel at 1/8 of 960×540.
fn preview() -> RenderOptions {
    RenderOptions {
        width: 120,
        height: 68,
        spp: 1,
        ..RenderOptions::default()
    }
}

/// The median (NaN for none).
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Milliseconds from `edit` to the end of the frame's first pass.
fn edit_to_pass(session: &mut Session, edit: Edit) -> Result<f64> {
    let t = Instant::now();
    session.edit(edit)?;
    let frame = session.frame(&FrameSpec::default())?;
    frame.render(&preview(), &|_, _| {})?;
    Ok(t.elapsed().as_secs_f64() * 1e3)
}

/// What the scene offers to edit: its camera, its first drawn node and that node's place, and
/// whether it has a punctual light.
struct Targets {
    camera: Option<usize>,
    node: Option<(usize, Vec3A)>,
    light: bool,
}

/// The edits of round `k` (two values alternating), by kind.
fn edits(t: &Targets, k: usize) -> Vec<(&'static str, Edit)> {
    let pointer = |path: &str, value: Vec<f64>| Edit::Pointer {
        path: path.to_owned(),
        value,
    };
    let g = if k % 2 == 0 { 0.5 } else { 0.8 };
    let mut out = vec![(
        "material",
        pointer(
            "/materials/0/pbrMetallicRoughness/baseColorFactor",
            vec![g, g, g, 1.0],
        ),
    )];
    if let Some(camera) = t.camera {
        let key = "aperture_fstop".to_owned();
        let value = (2.8 + 2.8 * g).into();
        out.push(("camera", Edit::CameraKey { camera, key, value }));
    }
    if t.light {
        let path = "/extensions/KHR_lights_punctual/lights/0/intensity";
        out.push(("light", pointer(path, vec![1000.0 + 500.0 * g])));
    }
    if let Some((node, p)) = t.node {
        // The node moved a little, back and forth (its stored transform replaced).
        let mut matrix = glam::Mat4::IDENTITY.to_cols_array_2d();
        matrix[3] = [p.x + g as f32 * 0.01, p.y, p.z, 1.0];
        out.push(("transform", Edit::NodeMatrix { node, matrix }));
    }
    out
}

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: session_bench SCENE.glb [REPEATS]")?;
    let repeats: usize = args.next().map_or(Ok(9), |s| s.parse())?;
    let t0 = Instant::now();
    let mut session = Session::load(path.as_ref(), &LoadOptions::default())?;
    let load = t0.elapsed().as_secs_f64() * 1e3;
    let frame = session.frame(&FrameSpec::default())?;
    frame.render(&preview(), &|_, _| {})?;
    let cold = t0.elapsed().as_secs_f64() * 1e3;
    let scene = frame.scene();
    let triangles: usize = (scene.instances.iter())
        .map(|i| scene.meshes[i.mesh as usize].indices.len())
        .sum();
    let first = scene.instances.first();
    let targets = Targets {
        camera: scene.cameras[0].index.map(|c| c as usize),
        node: first.map(|i| (i.node as usize, i.world_from_object.translation)),
        light: !scene.lights.is_empty(),
    };
    let mut times: Vec<(&str, Vec<f64>)> = Vec::new();
    for k in 0..repeats {
        for (kind, edit) in edits(&targets, k) {
            let ms = edit_to_pass(&mut session, edit)?;
            match times.iter_mut().find(|(k, _)| *k == kind) {
                Some((_, v)) => v.push(ms),
                None => times.push((kind, vec![ms])),
            }
        }
    }
    // Visibility last: a hidden node would change what the other edits cost.
    let mut hidden = Vec::new();
    for k in 0..repeats {
        if let Some((node, _)) = targets.node {
            let edit = Edit::NodeVisible {
                node,
                visible: k % 2 == 1,
            };
            hidden.push(edit_to_pass(&mut session, edit)?);
        }
    }
    times.push(("visibility", hidden));
    let each: Vec<String> = (times.into_iter())
        .map(|(kind, v)| format!("{kind} {:.2} ms", median(v)))
        .collect();
    println!(
        "{path}: {triangles} triangles drawn; load {load:.1} ms, cold start (load → first pass) \
         {cold:.1} ms; edit → first pass (median of {repeats}): {}",
        each.join(", ")
    );
    Ok(())
}
