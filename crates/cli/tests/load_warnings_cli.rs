//! `render` says what the load skipped or ignored, as `info` does (issue 50): a file with a
//! points primitive and an optional extension aperture lacks, rendered with and without
//! `--quiet`.

mod common;

use common::{aperture, quad_glb, quad_json, Scratch};
use serde_json::json;
use std::process::Command;

/// The quad, plus a mesh of points and an optional unknown extension.
fn file() -> Vec<u8> {
    let mut doc = quad_json();
    doc["extensionsUsed"] = json!(["ACME_sparkles"]);
    doc["meshes"] = json!([
        {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]},
        {"primitives": [{"attributes": {"POSITION": 0}, "mode": 0}]}
    ]);
    doc["nodes"] = json!([{"mesh": 0}, {"mesh": 1}]);
    doc["scenes"] = json!([{"nodes": [0, 1]}]);
    quad_glb(&doc)
}

/// The render's stderr with `extra` arguments.
fn render_stderr(dir: &Scratch, extra: &[&str]) -> String {
    let scene = dir.path("warned.glb");
    std::fs::write(&scene, file()).unwrap();
    let out = Command::new(aperture())
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(dir.path("warned.png"))
        .args([
            "--width", "8", "--height", "8", "--spp", "1", "--env", "1,1,1",
        ])
        .args(extra)
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    String::from_utf8(out.stderr).unwrap()
}

#[test]
fn render_prints_the_load_warnings_unless_quiet() {
    let dir = Scratch::new("load-warnings");
    let err = render_stderr(&dir, &[]);
    let points = "meshes[1].primitives[0]: Points primitive skipped (not triangles)";
    let ignored = "extension ACME_sparkles is used but not implemented: ignored";
    for w in [points, ignored] {
        assert_eq!(err.matches(w).count(), 1, "once each: {w}\n{err}");
    }
    assert!(err
        .lines()
        .all(|l| !l.contains(points) || l.starts_with("warning: ")));
    let quiet = render_stderr(&dir, &["--quiet"]);
    assert!(
        !quiet.contains(points) && !quiet.contains(ignored),
        "{quiet}"
    );
    // `info` lists the same two.
    let info = Command::new(aperture())
        .arg("info")
        .arg(dir.path("warned.glb"))
        .output()
        .unwrap();
    let info = String::from_utf8(info.stdout).unwrap();
    assert!(info.contains(points) && info.contains(ignored), "{info}");
}
