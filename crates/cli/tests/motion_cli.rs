//! `aperture render --motion-blur` as a user runs it on an animated glTF sample: tiles of a
//! blurred frame merge into the whole frame bit for bit, the blur changes the image, and
//! `--no-motion-blur` leaves it the still frame.

mod common;

use common::{run_in as aperture, stderr, Scratch};

#[test]
fn tiles_of_a_blurred_frame_merge_into_the_whole_frame() {
    let Some(scene) = common::sample("animation/BoxAnimated/BoxAnimated.glb") else {
        return;
    };
    let scene = scene.to_str().unwrap();
    let dir = Scratch::new("cli-motion");
    let size = [
        "--width", "48", "--height", "36", "--spp", "8", "--quiet", "--frame", "20", "--env",
        "1,1,1", "--passes", "all",
    ];
    let render = |out: &str, extra: &[&str]| {
        let mut a = vec!["render", scene, "-o", out];
        a.extend_from_slice(&size);
        a.extend_from_slice(extra);
        let o = aperture(&a, &dir.0);
        assert!(o.status.success(), "{a:?}: {}", stderr(&o));
    };
    let blur = ["--motion-blur", "--shutter", "2"];
    render("whole.exr", &blur);
    render("t0.exr", &[&blur[..], &["--tile", "0/2"]].concat());
    render("t1.exr", &[&blur[..], &["--tile", "1/2"]].concat());
    let o = aperture(&["merge", "t1.exr", "t0.exr", "-o", "merged.exr"], &dir.0);
    assert!(o.status.success(), "{}", stderr(&o));
    let read = |n: &str| aperture_imageio::read_exr(&dir.path(n)).unwrap();
    common::assert_same_pixels(&read("merged.exr"), &read("whole.exr"));

    render("still.exr", &[]);
    render("off.exr", &["--no-motion-blur"]);
    common::assert_same_pixels(&read("off.exr"), &read("still.exr"));
    let (whole, still) = (read("whole.exr"), read("still.exr"));
    assert_ne!(whole.rgba, still.rgba, "motion blur changed nothing");
}
