//! `aperture info SCENE | head -1`: when the reader closes the pipe, info ends quietly as Unix
//! tools do (status 141, 128 + SIGPIPE), never with Rust's "failed printing to stdout" panic.
//! Unix only: Windows has no SIGPIPE.
#![cfg(unix)]

mod common;

use common::{aperture, quad_glb, quad_json, Scratch};
use serde_json::json;
use std::io::Read;
use std::process::{Command, Stdio};

/// A quad seen by 2000 cameras: `info` prints two lines a camera, far more than a pipe holds
/// (64 KiB), so it is still printing when the reader goes away.
fn many_cameras() -> Vec<u8> {
    let mut doc = quad_json();
    doc["meshes"] = json!([{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}]);
    let n = 2000;
    doc["cameras"] = json!((0..n)
        .map(|_| json!({"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}))
        .collect::<Vec<_>>());
    let mut nodes = vec![json!({"mesh": 0})];
    nodes.extend((0..n).map(|i| json!({"camera": i, "translation": [0.0, 0.0, 3.0 + i as f64]})));
    doc["nodes"] = json!(nodes);
    doc["scenes"] = json!([{"nodes": (0..=n).collect::<Vec<_>>()}]);
    quad_glb(&doc)
}

#[test]
fn info_into_a_closed_pipe_ends_without_a_panic() {
    let dir = Scratch::new("broken-pipe");
    let scene = dir.path("cameras.glb");
    std::fs::write(&scene, many_cameras()).unwrap();
    let mut child = Command::new(aperture())
        .arg("info")
        .arg(&scene)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Read one byte, then close the pipe, as `head -c 1` does; info has more to print.
    let mut stdout = child.stdout.take().unwrap();
    let mut first = [0u8; 1];
    stdout.read_exact(&mut first).unwrap();
    drop(stdout);
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    let status = child.wait().unwrap();
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(status.code(), Some(141), "{stderr}");
}
