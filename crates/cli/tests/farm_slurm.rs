//! SPEC §8 on a real Slurm cluster: the user's template (`tools/farm/slurm/submit.sh`)
//! submits a job array and a dependent merge with `sbatch`, and the merged file equals the
//! render of one machine.
//!
//! Needs a cluster: `tools/farm/local-slurm.sh start` runs one on this machine and prints the
//! `SLURM_CONF` to export (`.ci/run` does both). Without `SLURM_CONF` the tests skip with a
//! message, and fail under `CI=true`.
// Slurm and its shell wrappers: Unix only (farms are Linux).
#![cfg(unix)]

mod common;

use common::{Scratch, SMALL};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// The longest a job may take before the test gives up (a hang guard, not a measurement).
const JOB_DEADLINE: Duration = Duration::from_secs(180);

/// True when a Slurm cluster answers; otherwise [`common::missing`].
fn cluster() -> bool {
    if std::env::var_os("SLURM_CONF").is_none() {
        common::missing(
            "SLURM_CONF is not set: start a cluster with tools/farm/local-slurm.sh start",
        );
        return false;
    }
    match Command::new("sinfo").args(["-h", "-o", "%a"]).output() {
        Ok(out) if out.status.success() => true,
        Ok(out) => {
            common::missing(&format!(
                "sinfo failed: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            ));
            false
        }
        Err(e) => {
            common::missing(&format!("sinfo cannot run: {e}"));
            false
        }
    }
}

/// The two jobs `submit.sh` made.
struct Submitted {
    array: String,
    merge: String,
}

/// Runs `tools/farm/slurm/submit.sh MODE N demo.glb OUTPUT ARGS` in `dir` with `aperture` as
/// the binary the jobs run.
fn submit(
    dir: &Scratch,
    aperture: &Path,
    mode: &str,
    n: u32,
    output: &Path,
    args: &[&str],
) -> Submitted {
    submit_scene(dir, aperture, mode, n, &common::demo_scene(), output, args)
}

/// [`submit`] of another scene.
fn submit_scene(
    dir: &Scratch,
    aperture: &Path,
    mode: &str,
    n: u32,
    scene: &Path,
    output: &Path,
    args: &[&str],
) -> Submitted {
    let out = Command::new(common::repo().join("tools/farm/slurm/submit.sh"))
        .current_dir(&dir.0)
        .env("APERTURE", aperture)
        .arg(mode)
        .arg(n.to_string())
        .arg(scene)
        .arg(output)
        .args(args)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "submit.sh: {text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let id = |what: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(what))
            .unwrap_or_else(|| panic!("no {what}job id in {text:?}"))
            .trim()
            .to_string()
    };
    Submitted {
        array: id("array "),
        merge: if mode == "frames" {
            String::new()
        } else {
            id("merge ")
        },
    }
}

/// The state of every job of `id` (the tasks of an array), as `scontrol` says.
fn states(id: &str) -> Vec<(String, String)> {
    let out = Command::new("scontrol")
        .args(["show", "job", "-o", id])
        .output()
        .unwrap();
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|line| {
            let field = |key: &str| {
                line.split_whitespace()
                    .find_map(|f| f.strip_prefix(key))
                    .unwrap_or("")
                    .to_string()
            };
            (field("ArrayTaskId="), field("JobState="))
        })
        .collect()
}

fn finished(state: &str) -> bool {
    !matches!(
        state,
        "PENDING" | "RUNNING" | "CONFIGURING" | "COMPLETING" | "SUSPENDED" | ""
    )
}

/// Waits until job `id` has finished and returns its state; the logs of `dir` on a hang.
fn wait_for(id: &str, dir: &Scratch) -> String {
    let t0 = Instant::now();
    loop {
        if let Some((_, state)) = states(id).first() {
            if finished(state) {
                return state.clone();
            }
        }
        assert!(
            t0.elapsed() < JOB_DEADLINE,
            "job {id} still unfinished after {JOB_DEADLINE:?}: {:?}\n{}",
            states(id),
            logs(dir)
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// The Slurm logs the jobs left in `dir`.
fn logs(dir: &Scratch) -> String {
    let mut text = String::new();
    for e in std::fs::read_dir(&dir.0).unwrap().flatten() {
        if e.path().extension().is_some_and(|x| x == "log") {
            text += &format!(
                "--- {}\n{}",
                e.path().display(),
                std::fs::read_to_string(e.path()).unwrap_or_default()
            );
        }
    }
    text
}

/// Submits, waits for the merge and reads the merged file.
fn farm_render(dir: &Scratch, mode: &str, n: u32, args: &[&str]) -> aperture_imageio::Image {
    let output = dir.path(&format!("{mode}.exr"));
    let t0 = Instant::now();
    let jobs = submit(dir, &common::aperture(), mode, n, &output, args);
    let state = wait_for(&jobs.merge, dir);
    assert_eq!(state, "COMPLETED", "merge job\n{}", logs(dir));
    eprintln!(
        "{mode}: {n} array tasks + merge through sbatch in {:.1} s",
        t0.elapsed().as_secs_f64()
    );
    for (task, state) in states(&jobs.array) {
        assert_eq!(state, "COMPLETED", "task {task}");
    }
    aperture_imageio::read_exr(&output).unwrap()
}

fn args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    SMALL.iter().copied().chain(extra.iter().copied()).collect()
}

#[test]
fn four_tiles_through_sbatch_equal_the_whole_render() {
    if !cluster() {
        return;
    }
    let dir = Scratch::new("slurm-tiles");
    let a = args(&["--spp", "16"]);
    let merged = farm_render(&dir, "tiles", 4, &a);
    let whole = common::local_render(&dir.path("whole.exr"), &a);
    let n = common::assert_same_pixels(&merged, &whole);
    eprintln!("tiles: {n} values bit-identical to the local render");
}

#[test]
fn two_sample_batches_through_sbatch_equal_the_longer_render() {
    if !cluster() {
        return;
    }
    let dir = Scratch::new("slurm-batches");
    let merged = farm_render(&dir, "batches", 2, &args(&["--spp", "8"]));
    let whole = common::local_render(&dir.path("whole.exr"), &args(&["--spp", "16"]));
    let (worst, layer) = common::largest_relative_difference(&merged, &whole);
    eprintln!("batches: largest relative difference {worst:.3e} ({layer})");
    assert!(worst < 1e-6, "{worst} in {layer}");
}

#[test]
fn adaptive_tiles_through_sbatch_equal_the_whole_adaptive_render() {
    if !cluster() {
        return;
    }
    let dir = Scratch::new("slurm-adaptive");
    let a = args(&["--spp", "32", "--noise-threshold", "0.05", "--min-spp", "4"]);
    let merged = farm_render(&dir, "tiles", 4, &a);
    let whole = common::local_render(&dir.path("whole.exr"), &a);
    common::assert_same_pixels(&merged, &whole);
    let counts = &whole.layer("Debug Sample Count").unwrap().data;
    assert!(
        counts.contains(&4.0) && counts.contains(&32.0),
        "adaptive sampling stopped some pixels early and not others"
    );
}

/// A tile that fails cancels the merge (`--kill-on-invalid-dep`, `kill_invalid_depend`)
/// instead of leaving it pending forever, and no merged file appears.
#[test]
fn a_failed_tile_cancels_the_merge() {
    if !cluster() {
        return;
    }
    let dir = Scratch::new("slurm-failure");
    // The binary, except for array task 2.
    let wrapper: PathBuf = dir.path("failing-aperture.sh");
    std::fs::write(
        &wrapper,
        format!(
            "#!/bin/sh\nif [ \"$SLURM_ARRAY_TASK_ID\" = 2 ]; then echo 'tile 2 made to fail' >&2; exit 3; fi\nexec '{}' \"$@\"\n",
            common::aperture().display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(
        &wrapper,
        std::os::unix::fs::PermissionsExt::from_mode(0o755),
    )
    .unwrap();
    let output = dir.path("never.exr");
    let jobs = submit(&dir, &wrapper, "tiles", 4, &output, &args(&["--spp", "4"]));
    // When task 2 has failed, the merge must go within seconds.
    let t0 = Instant::now();
    let failed_at = loop {
        let tasks = states(&jobs.array);
        if tasks.iter().any(|(k, s)| k == "2" && s == "FAILED") {
            break Instant::now();
        }
        assert!(
            t0.elapsed() < JOB_DEADLINE,
            "task 2 never failed: {tasks:?}"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    let state = wait_for(&jobs.merge, &dir);
    let latency = failed_at.elapsed();
    eprintln!(
        "failed tile: merge {state} {:.1} s after the tile failed",
        latency.as_secs_f64()
    );
    assert_eq!(state, "CANCELLED");
    assert!(
        latency < Duration::from_secs(10),
        "the merge was cancelled only after {latency:?}"
    );
    assert!(!output.exists());
}

/// A shot split by frames: 4 frames of an animated sample in 3 chunks (one of two frames),
/// each chunk one `--frames` sequence; every frame equals this machine's sequence render.
#[test]
fn frame_chunks_through_sbatch_equal_the_local_sequence() {
    if !cluster() {
        return;
    }
    let Some(scene) = common::sample("animation/BoxAnimated/BoxAnimated.glb") else {
        return;
    };
    let dir = Scratch::new("slurm-frames");
    let size = ["--width", "48", "--height", "36", "--spp", "4"];
    let mut a: Vec<&str> = size.to_vec();
    a.extend(["--frames", "1..7:2"]);
    let jobs = submit_scene(
        &dir,
        &common::aperture(),
        "frames",
        3,
        &scene,
        &dir.path("shot_####.exr"),
        &a,
    );
    let t0 = Instant::now();
    loop {
        let tasks = states(&jobs.array);
        if tasks.len() == 3 && tasks.iter().all(|(_, s)| finished(s)) {
            for (task, state) in &tasks {
                assert_eq!(state, "COMPLETED", "task {task}\n{}", logs(&dir));
            }
            break;
        }
        assert!(t0.elapsed() < JOB_DEADLINE, "frames unfinished: {tasks:?}");
        std::thread::sleep(Duration::from_millis(100));
    }
    common::local_render_of(&scene, &dir.path("local_####.exr"), &a);
    for frame in [1, 3, 5, 7] {
        let farm = aperture_imageio::read_exr(&dir.path(&format!("shot_{frame:04}.exr"))).unwrap();
        let local =
            aperture_imageio::read_exr(&dir.path(&format!("local_{frame:04}.exr"))).unwrap();
        common::assert_same_pixels(&farm, &local);
    }
    let shots = std::fs::read_dir(&dir.0)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .starts_with("shot_")
        })
        .count();
    assert_eq!(shots, 4, "exactly the range's frames");
}
