//! A render session on the demo scene: loaded once, then 8 camera positions × 4 f-stops, each
//! refined progressively. Per image it prints the time from the edit to a 1-sample preview at
//! 1/8 resolution (what a viewport shows first), and to the first and last full passes.
//!
//! ```text
//! cargo run --release -p aperture-render --example session [-- SCENE.glb [SPP]]
//! ```

use aperture_render::{Frame, FrameSpec, Progressive, RenderOptions, Session, Window};
use aperture_scene::{Edit, LoadOptions};
use glam::{Affine3A, Mat4, Vec3};
use std::time::Instant;

/// A camera's world transform at `eye` looking at `target` (+Y up; the camera looks down −Z).
fn looking_at(eye: Vec3, target: Vec3) -> Mat4 {
    let forward = (target - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    Mat4::from_cols(
        right.extend(0.0),
        up.extend(0.0),
        (-forward).extend(0.0),
        eye.extend(1.0),
    )
}

/// Seconds since `t` to a 1-sample preview of `frame` at 1/8 size, then to the first and the
/// last pass of a progressive render of `opts`.
fn refine(
    frame: &Frame,
    opts: &RenderOptions,
    t: Instant,
) -> Result<(f64, f64, f64), Box<dyn std::error::Error>> {
    let preview = RenderOptions {
        width: opts.width / 8,
        height: opts.height / 8,
        spp: 1,
        ..opts.clone()
    };
    frame.render(&preview, &|_, _| {})?;
    let to_preview = t.elapsed().as_secs_f64();
    let whole = Window::whole(opts.width, opts.height);
    let mut render = Progressive::new(frame, opts, whole)?;
    render.next_pass(frame, &|_, _| {})?;
    let to_first = t.elapsed().as_secs_f64();
    while render.next_pass(frame, &|_, _| {})?.is_some() {}
    Ok((to_preview, to_first, t.elapsed().as_secs_f64()))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let demo = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/demo.glb");
    let path = args.next().unwrap_or_else(|| demo.to_owned());
    let spp: u32 = args.next().map_or(Ok(16), |s| s.parse())?;
    let t0 = Instant::now();
    let mut session = Session::load(path.as_ref(), &LoadOptions::default())?;
    let spec = FrameSpec::default();
    let (node, index, world_from_camera) = {
        let cam = &session.frame(&spec)?.scene().cameras[0];
        (cam.node, cam.index, cam.world_from_camera)
    };
    let cold = t0.elapsed().as_secs_f64();
    let (Some(node), Some(camera)) = (node, index) else {
        return Err("the scene's first camera has no node to move".into());
    };
    let opts = RenderOptions {
        width: 480,
        height: 270,
        spp,
        ..RenderOptions::default()
    };
    let name = std::path::Path::new(&path)
        .file_name()
        .map(|n| n.to_string_lossy());
    println!(
        "{}: loaded, posed and built once in {:.1} ms; {}x{} to {spp} spp in passes 1, 2, 4, …",
        name.unwrap_or_default(),
        cold * 1e3,
        opts.width,
        opts.height
    );
    println!("position  f-stop  edit→preview (1 spp, 1/8 size)  edit→first pass  edit→last pass");
    let eye = Vec3::from(world_from_camera.translation);
    let forward = world_from_camera.transform_vector3(Vec3::NEG_Z);
    // The point the camera looks at, 6 units ahead; the positions orbit it.
    let target = eye + forward * 6.0;
    for position in 0..8 {
        let angle = (position as f32 - 3.5) * 0.06;
        let offset = eye - target;
        let orbit = Affine3A::from_rotation_y(angle).transform_vector3(offset);
        let matrix = looking_at(target + orbit, target).to_cols_array_2d();
        for fstop in [1.4f64, 2.8, 5.6, 11.0] {
            let t = Instant::now();
            if fstop == 1.4 {
                session.edit(Edit::NodeMatrix {
                    node: node as usize,
                    matrix,
                })?;
            }
            let key = "aperture_fstop".to_owned();
            session.edit(Edit::CameraKey {
                camera: camera as usize,
                key,
                value: fstop.into(),
            })?;
            let (to_preview, to_first, to_last) = refine(session.frame(&spec)?, &opts, t)?;
            println!(
                "{position:>8}  f/{fstop:<4}  {:>28.1} ms  {:>12.1} ms  {:>13.1} ms",
                to_preview * 1e3,
                to_first * 1e3,
                to_last * 1e3
            );
        }
    }
    Ok(())
}
