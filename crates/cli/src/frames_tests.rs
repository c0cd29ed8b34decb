//! `--frames` end to end through `render_cmd::run`: each frame of a sequence equals the single
//! `--frame` render, and malformed ranges are refused.

use crate::render_args::RenderArgs;
use clap::Parser as _;

fn args(scene: &std::path::Path, out: &std::path::Path, extra: &[&str]) -> RenderArgs {
    let mut argv = vec!["aperture", "render", "-o"];
    let out = out.to_str().unwrap().to_owned();
    let scene = scene.to_str().unwrap().to_owned();
    argv.push(&out);
    argv.push(&scene);
    argv.extend_from_slice(&["--width", "40", "--height", "30", "--spp", "2", "--quiet"]);
    argv.extend_from_slice(extra);
    match crate::Cli::try_parse_from(argv).unwrap().command {
        crate::Command::Render(r) => *r,
        _ => unreachable!("render subcommand"),
    }
}

/// Every frame of `--frames` is the `--frame N` render of that frame, bit for bit (pixels
/// and passes; the header holds times), for moving nodes (BoxAnimated) and a skinned,
/// deforming character (CesiumMan).
#[test]
fn sequence_frames_equal_single_frame_renders() {
    for file in [
        "animation/BoxAnimated/BoxAnimated.glb",
        "animation/CesiumMan/CesiumMan.glb",
    ] {
        let Some(scene) = crate::sample(file) else {
            return;
        };
        let dir = std::env::temp_dir().join(format!(
            "aperture-frames-{}-{}",
            std::process::id(),
            file.len()
        ));
        std::fs::create_dir_all(&dir).unwrap();
        let pattern = dir.join("f_####.exr");
        crate::render_cmd::run(args(&scene, &pattern, &["--frames", "3..11:4"])).unwrap();
        let mut frames = Vec::new();
        for n in [3, 7, 11] {
            let single = dir.join(format!("single_{n}.exr"));
            crate::render_cmd::run(args(&scene, &single, &["--frame", &n.to_string()])).unwrap();
            let a = aperture_imageio::read_exr(&dir.join(format!("f_{n:04}.exr"))).unwrap();
            let b = aperture_imageio::read_exr(&single).unwrap();
            let bits = |im: &aperture_imageio::Image| -> Vec<u32> {
                let mut v: Vec<u32> = im.rgba.iter().flatten().map(|f| f.to_bits()).collect();
                for l in &im.layers {
                    v.extend(l.data.iter().map(|f| f.to_bits()));
                }
                v
            };
            assert!(bits(&a) == bits(&b), "{file} frame {n}");
            frames.push(a.rgba);
        }
        assert_ne!(frames[0], frames[2], "{file}: the frames move");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn frames_and_a_single_time_exclude_each_other() {
    let p = std::path::Path::new("s.glb");
    for bad in [
        &["--frames", "1..3", "--frame", "2"][..],
        &["--frames", "1..3", "--time", "0.5"],
        &["--skip-existing"],
        &["--frames", "3..1"],
    ] {
        let mut argv = vec!["aperture", "render", "s.glb", "-o", "o.exr"];
        argv.extend_from_slice(bad);
        let e = crate::Cli::try_parse_from(argv).err().expect("refused");
        assert_eq!(e.exit_code(), 2, "{bad:?}");
    }
    let a = args(
        p,
        p,
        &["--frames", "1..3", "--fps", "25", "--skip-existing"],
    );
    assert_eq!(a.frames.map(|f| f.frames().count()), Some(3));
    assert!(a.skip_existing && a.when.fps == 25.0);
}
