//! What a live session saves (BENCHMARKS.md, "Render session"): for one scene, the cold start
//! (load → first pass) against a camera edit (edit → first pass) and a transform edit of a
//! drawn node (edit → first pass), the first pass being 1 sample a pixel at 1/8 of 960×540
//! (what a viewport shows first). Medians over `REPEATS` edits, alternating two values.
//!
//! ```text
//! cargo run --release -p aperture-render --example session_bench -- SCENE.glb [REPEATS]
//! ```

use aperture_render::{FrameSpec, RenderOptions, Session};
use aperture_scene::{Edit, LoadOptions};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: session_bench SCENE.glb [REPEATS]")?;
    let repeats: usize = args.next().map_or(Ok(9), |s| s.parse())?;
    let preview = RenderOptions {
        width: 120,
        height: 68,
        spp: 1,
        ..RenderOptions::default()
    };
    let spec = FrameSpec::default();
    let t0 = Instant::now();
    let mut session = Session::load(path.as_ref(), &LoadOptions::default())?;
    let load = t0.elapsed().as_secs_f64();
    let frame = session.frame(&spec)?;
    frame.render(&preview, &|_, _| {})?;
    let cold = t0.elapsed().as_secs_f64();
    let scene = frame.scene();
    let triangles: usize = (scene.instances.iter())
        .map(|i| scene.meshes[i.mesh as usize].indices.len())
        .sum();
    let camera = scene.cameras[0].index.map(|c| c as usize);
    let node = scene.instances.first().map(|i| i.node as usize);
    let place = scene
        .instances
        .first()
        .map(|i| i.world_from_object.translation);
    let time = |session: &mut Session, edit: Edit| -> Result<f64, Box<dyn std::error::Error>> {
        let t = Instant::now();
        session.edit(edit)?;
        session.frame(&spec)?.render(&preview, &|_, _| {})?;
        Ok(t.elapsed().as_secs_f64())
    };
    let mut camera_ms = Vec::new();
    let mut transform_ms = Vec::new();
    for k in 0..repeats {
        if let Some(camera) = camera {
            let fstop = if k % 2 == 0 { 2.8 } else { 5.6 };
            let key = "aperture_fstop".to_owned();
            let edit = Edit::CameraKey {
                camera,
                key,
                value: fstop.into(),
            };
            camera_ms.push(time(&mut session, edit)? * 1e3);
        }
        if let (Some(node), Some(t)) = (node, place) {
            // The node moved a little, back and forth (its stored transform replaced).
            let dx = if k % 2 == 0 { 0.01 } else { 0.0 };
            let mut matrix = glam::Mat4::IDENTITY.to_cols_array_2d();
            matrix[3] = [t.x + dx, t.y, t.z, 1.0];
            transform_ms.push(time(&mut session, Edit::NodeMatrix { node, matrix })? * 1e3);
        }
    }
    let m = |v: Vec<f64>| if v.is_empty() { f64::NAN } else { median(v) };
    println!(
        "{path}: {triangles} triangles drawn; load {:.1} ms, cold start (load → first pass) {:.1} ms; \
         camera edit → first pass {:.2} ms (median of {repeats}); transform edit → first pass {:.1} ms",
        load * 1e3,
        cold * 1e3,
        m(camera_ms),
        m(transform_ms)
    );
    Ok(())
}
