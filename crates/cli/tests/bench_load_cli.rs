//! `aperture bench --configs load` (issue 59): fresh loads of the demo timed by stage, written
//! to `load.csv` and summarised with the peak memory, and no reference or sampler run.

mod common;

use common::{aperture, demo_scene, Scratch};
use std::process::Command;

#[test]
fn load_config_times_each_stage_of_fresh_loads() {
    let dir = Scratch::new("bench-load");
    let out = dir.path("bench");
    let run = Command::new(aperture())
        .arg("bench")
        .arg(demo_scene())
        .args(["--configs", "load", "--repeats", "3", "--width", "48"])
        .args(["--threads", "2", "-o"])
        .arg(&out)
        .output()
        .expect("aperture runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(
        stdout.contains("load (median of 3): read, decode and pose "),
        "{stdout}"
    );
    if cfg!(target_os = "linux") {
        assert!(stdout.contains(", peak memory "), "{stdout}");
    }
    let csv = std::fs::read_to_string(out.join("load.csv")).expect("load.csv");
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("repeat,load_s,bvh_s,first_samples_s"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().expect("a number")).collect())
        .collect();
    assert_eq!(rows.len(), 3, "{csv}");
    for (i, r) in rows.iter().enumerate() {
        let (load, bvh, first) = (r[1], r[2], r[3]);
        assert_eq!(r[0], i as f64);
        // The stages follow each other: the first samples come after the load and the BVH.
        assert!(load > 0.0 && bvh > 0.0 && first >= load + bvh, "{csv}");
    }
    // Only the load was asked for: no reference, no error-against-time results.
    assert!(!out.join("reference.exr").exists() && !out.join("results.csv").exists());
}
