//! The summary line of `aperture render` (issue 59): load, BVH and first-samples times, and
//! the process's peak memory on Linux.

mod common;

use common::{aperture, demo_scene, Scratch};
use std::process::Command;

/// The number after `key` in `line` (`"load 0.12 s"` → 0.12), up to the next space.
fn number_after(line: &str, key: &str) -> Option<f64> {
    let rest = &line[line.find(key)? + key.len()..];
    rest.split(' ').next()?.parse().ok()
}

#[test]
fn the_summary_has_load_bvh_first_samples_and_peak_memory() {
    let dir = Scratch::new("summary");
    let out = dir.path("demo.exr");
    let run = Command::new(aperture())
        .arg("render")
        .arg(demo_scene())
        .arg("-o")
        .arg(&out)
        .args([
            "--width",
            "64",
            "--height",
            "36",
            "--spp",
            "2",
            "--threads",
            "2",
        ])
        .args(["--bvh-quality", "medium"])
        .output()
        .expect("aperture runs");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let line = stderr
        .lines()
        .find(|l| l.contains("Msamples/s"))
        .unwrap_or_else(|| panic!("no summary line in {stderr:?}"));
    let total = number_after(line, "64x36, 2 spp, ").expect("the job's time");
    let load = number_after(line, "(load ").expect("the load time");
    let bvh = number_after(line, "BVH medium ").expect("the BVH time");
    let first = number_after(line, "first samples at ").expect("the first samples' time");
    // The first samples come after loading, and within the job.
    assert!(load >= 0.0 && bvh >= 0.0, "{line}");
    assert!(first >= load && first <= total + 0.01, "{line}");
    if cfg!(target_os = "linux") {
        let peak = line
            .split("peak memory ")
            .nth(1)
            .unwrap_or_else(|| panic!("no peak memory in {line:?}"));
        let (value, unit) = peak.split_once(' ').expect("a value and a unit");
        let mb = value.parse::<f64>().expect("a number")
            * match &unit[..2] {
                "MB" => 1.0,
                "GB" => 1000.0,
                other => panic!("unit {other:?} in {line:?}"),
            };
        // The demo's meshes, textures and a process: more than a few MB, less than a GB.
        assert!((5.0..1000.0).contains(&mb), "{line}");
    }
}
