//! `aperture render --region/--tile/--sample-offset` and `aperture merge` as a user runs
//! them: parts that merge into the whole render, usage errors with exit code 2, refusals
//! with exit code 1 that name the part and leave no output.

mod common;

use common::{run_in as aperture, stderr, Scratch};

#[test]
fn parts_rendered_and_merged_by_the_cli_equal_the_whole_render() {
    let dir = Scratch::new("cli-parts");
    let scene = common::demo_scene();
    let scene = scene.to_str().unwrap();
    let size = ["--width", "48", "--height", "27", "--spp", "4", "--quiet"];
    let render = |out: &str, extra: &[&str]| {
        let mut a = vec!["render", scene, "-o", out];
        a.extend_from_slice(&size);
        a.extend_from_slice(extra);
        let o = aperture(&a, &dir.0);
        assert!(o.status.success(), "{a:?}: {}", stderr(&o));
    };
    render("whole.exr", &[]);
    // Two bands, the second split in two regions; named so that text order is not tile order.
    render("tile-10.exr", &["--tile", "0/2"]);
    render("tile-2a.exr", &["--region", "0,13,20,27"]);
    render("tile-2b.exr", &["--region", "20,13,48,27"]);
    let o = aperture(
        &[
            "merge",
            "tile-2b.exr",
            "tile-10.exr",
            "tile-2a.exr",
            "-o",
            "out.exr",
        ],
        &dir.0,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("3 parts"), "{}", stderr(&o));
    let merged = aperture_imageio::read_exr(&dir.path("out.exr")).unwrap();
    let whole = aperture_imageio::read_exr(&dir.path("whole.exr")).unwrap();
    common::assert_same_pixels(&merged, &whole);
    let tile = aperture_imageio::read_exr(&dir.path("tile-10.exr")).unwrap();
    assert_eq!(
        tile.placement,
        Some(aperture_imageio::Placement {
            x: 0,
            y: 0,
            full_width: 48,
            full_height: 27
        })
    );
    assert_eq!(
        tile.meta("aperture:tile"),
        Some(&aperture_imageio::MetaValue::Text("0/2".into()))
    );

    // A missing tile: exit 1, the region and the tile named, no output.
    let o = aperture(
        &["merge", "tile-10.exr", "tile-2a.exr", "-o", "gap.exr"],
        &dir.0,
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("20,13,48,27"), "{}", stderr(&o));
    assert!(!dir.path("gap.exr").exists());
    // A damaged part: named.
    let bytes = std::fs::read(dir.path("tile-2a.exr")).unwrap();
    std::fs::write(dir.path("cut.exr"), &bytes[..bytes.len() / 2]).unwrap();
    let o = aperture(
        &[
            "merge",
            "tile-10.exr",
            "cut.exr",
            "tile-2b.exr",
            "-o",
            "cut-out.exr",
        ],
        &dir.0,
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("cut.exr"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"));
    assert!(!dir.path("cut-out.exr").exists());
}

#[test]
fn bad_split_options_are_usage_errors() {
    let dir = Scratch::new("cli-usage");
    let scene = common::demo_scene();
    let scene = scene.to_str().unwrap();
    for (args, says) in [
        (&["--region", "0,0,49,10"][..], "48x27"),
        (&["--tile", "0/28"], "27 rows"),
        (
            &["--sample-offset", "8", "--noise-threshold", "0.1"],
            "--noise-threshold",
        ),
        (&["--sample-offset", "65535", "--spp", "2"], "65536"),
    ] {
        let mut a = vec![
            "render", scene, "-o", "x.exr", "--width", "48", "--height", "27",
        ];
        a.extend_from_slice(args);
        let o = aperture(&a, &dir.0);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
    }
    let o = aperture(
        &[
            "render", scene, "-o", "x.png", "--width", "48", "--tile", "0/2",
        ],
        &dir.0,
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains(".exr"));
    assert!(!dir.path("x.exr").exists() && !dir.path("x.png").exists());
}
