//! `--threads 1` is one worker thread for the whole process (issue 50): loading, BVH building
//! and rendering included. The test counts the threads of a render of a file large enough to
//! take a while to load (`Threads:` of /proc/<pid>/status, sampled until it exits): the main
//! thread, which waits, and one worker.
#![cfg(target_os = "linux")]

mod common;

use common::{aperture, Scratch};
use serde_json::json;
use std::process::{Command, Stdio};

/// Grids of `side`² quads, `meshes` of them, each on its own accessors (so each is its own
/// mesh and BVH, built in parallel when more threads are allowed).
fn grids(meshes: usize, side: u32) -> Vec<u8> {
    let mut bin = Vec::new();
    let verts = (side + 1) * (side + 1);
    for y in 0..=side {
        for x in 0..=side {
            for v in [x as f32 / side as f32, y as f32 / side as f32, 0.0] {
                bin.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    let pos_bytes = bin.len();
    for y in 0..side {
        for x in 0..side {
            let i = y * (side + 1) + x;
            for k in [i, i + 1, i + side + 2, i, i + side + 2, i + side + 1] {
                bin.extend_from_slice(&k.to_le_bytes());
            }
        }
    }
    let idx_bytes = bin.len() - pos_bytes;
    let mut accessors = Vec::new();
    let mut mesh_list = Vec::new();
    for m in 0..meshes {
        // Each mesh its own accessor pair over the same bytes: distinct meshes to the loader.
        accessors.push(
            json!({"bufferView": 0, "componentType": 5126, "count": verts,
            "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}),
        );
        accessors.push(json!({"bufferView": 1, "componentType": 5125,
            "count": 6 * side * side, "type": "SCALAR"}));
        mesh_list.push(json!({"primitives": [{"attributes": {"POSITION": 2 * m},
            "indices": 2 * m + 1}]}));
    }
    let nodes: Vec<_> = (0..meshes)
        .map(|m| json!({"mesh": m, "translation": [0.0, 0.0, -(m as f32)]}))
        .collect();
    let doc = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteLength": pos_bytes},
            {"buffer": 0, "byteOffset": pos_bytes, "byteLength": idx_bytes}
        ],
        "accessors": accessors,
        "meshes": mesh_list,
        "nodes": nodes,
        "scenes": [{"nodes": (0..meshes).collect::<Vec<_>>()}]
    });
    common::glb::glb(&doc, &bin)
}

/// `Threads:` of process `pid`, if it still runs.
fn threads_of(pid: u32) -> Option<usize> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("Threads:"))
        .and_then(|v| v.trim().parse().ok())
}

#[test]
fn threads_1_is_one_worker_while_loading_and_rendering() {
    let dir = Scratch::new("threads");
    let scene = dir.path("grids.glb");
    std::fs::write(&scene, grids(24, 160)).unwrap();
    let mut child = Command::new(aperture())
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(dir.path("grids.png"))
        .args([
            "--threads",
            "1",
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "1",
        ])
        .args(["--env", "1,1,1", "--quiet"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut samples = Vec::new();
    while child.try_wait().unwrap().is_none() {
        if let Some(t) = threads_of(child.id()) {
            samples.push(t);
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    assert!(child.wait().unwrap().success());
    // Enough samples that the load was seen (it takes far longer than a few samples).
    assert!(
        samples.len() >= 5,
        "the render ended before it was sampled: {samples:?}"
    );
    let most = samples.iter().copied().max().unwrap_or(0);
    let over = samples.iter().filter(|&&t| t > 2).count();
    assert!(
        most <= 2,
        "--threads 1 ran {most} threads at once ({over} of {} samples above 2)",
        samples.len()
    );
}
