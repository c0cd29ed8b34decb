//! Frame sequences (SPEC §7): loaded once, each frame rebuilds only the BVHs of what changed,
//! and `--skip-existing` leaves finished frames alone.

use aperture_output::sequence::{self, FrameReport, Frames, Sequence};
use aperture_output::write::ImageFormat;
use aperture_output::ExrOptions;
use aperture_render::sequence::FrameRange;
use aperture_render::{RenderOptions, Session};
use aperture_scene::{Animated, LoadOptions};

fn render(
    animated: &Animated,
    pattern: &std::path::Path,
    frames: &str,
    skip: bool,
) -> Vec<FrameReport> {
    let opts = RenderOptions {
        width: 48,
        height: 36,
        spp: 2,
        ..RenderOptions::default()
    };
    let seq = Sequence {
        motion: None,
        frames: Frames::Range(FrameRange::parse(frames).unwrap()),
        fps: 24.0,
        opts: &opts,
        quality: Default::default(),
        pattern,
        format: ImageFormat::Exr(ExrOptions::default()),
        skip_existing: skip,
        denoiser: None,
    };
    let mut reports = Vec::new();
    let mut session = Session::new(animated.clone());
    let mut keep = |r: &FrameReport| reports.push(r.clone());
    sequence::render_sequence(&mut session, &seq, &|_, _| {}, &mut keep).unwrap();
    reports
}

/// BoxAnimated: a still box and an animated one. After the first frame, only the top level
/// is rebuilt: the still box's world-space BVH and the moving box's own BVH are reused.
#[test]
fn frames_after_the_first_reuse_the_bvhs_of_what_did_not_change() {
    let Some(samples) = aperture_tests::samples_dir() else {
        return;
    };
    let file = samples.join("animation/BoxAnimated/BoxAnimated.glb");
    let animated = Animated::load(&file, &LoadOptions::default()).unwrap();
    assert!(animated.is_animated() && !animated.moving_nodes().is_empty());
    let dir = std::env::temp_dir().join(format!("aperture-sequence-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let pattern = dir.join("box_###.exr");
    let reports = render(&animated, &pattern, "1..5", false);
    assert_eq!(reports.len(), 5);
    for (k, r) in reports.iter().enumerate() {
        let w = r.rendered.as_ref().expect("rendered");
        assert_eq!(w.summary.dropped, 0);
        assert!(
            r.path.ends_with(format!("box_{:03}.exr", k + 1)),
            "{}",
            r.path.display()
        );
        assert!(r.path.is_file());
        if k == 0 {
            assert_eq!(w.accel.reused_blases, 0);
        } else {
            assert_eq!(
                w.accel.reused_blases, w.accel.blas_count,
                "frame {:?}",
                r.frame
            );
            assert!(w.accel.blas_count >= 2);
        }
    }
    // The box moves: its frames differ.
    let first = aperture_imageio::read_exr(&reports[0].path).unwrap();
    let last = aperture_imageio::read_exr(&reports[4].path).unwrap();
    assert_ne!(first.rgba, last.rgba);
    // A restarted job leaves the finished frames and renders the missing one.
    std::fs::remove_file(&reports[2].path).unwrap();
    let again = render(&animated, &pattern, "1..5", true);
    let rendered: Vec<Option<i64>> = again
        .iter()
        .filter(|r| r.rendered.is_some())
        .map(|r| r.frame)
        .collect();
    assert_eq!(rendered, [Some(3)]);
    assert!(reports[2].path.is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}
