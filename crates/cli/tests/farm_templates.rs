//! The farm templates users copy are valid and do what they say: the Open Job Description
//! template passes `openjd check` and, run by `openjd run`, merges into the one-machine
//! render; the Kubernetes manifests pass the API's schemas (`kubernetes-validate --strict`),
//! agree with each other on what the render and merge commands need, and their container
//! commands, run here with `/data` pointed at a folder, merge into the one-machine render.
//!
//! Needs the checkers: `tools/farm/setup-tools.sh` installs them (`.ci/run` does). Without
//! them the tests skip with a message, and fail under `CI=true`.

mod common;

use common::{Scratch, SMALL};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The folder holding `openjd`, `kubernetes-validate` and a Python with PyYAML, if any.
fn tools() -> Option<PathBuf> {
    let venv = std::env::var_os("APERTURE_FARM_VENV")
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache/aperture/farm-venv"))
        });
    let bin = venv.map(|v| v.join("bin"));
    match bin {
        Some(b) if b.join("openjd").is_file() && b.join("kubernetes-validate").is_file() => Some(b),
        _ => {
            common::missing(
                "openjd and kubernetes-validate are not installed: run tools/farm/setup-tools.sh",
            );
            None
        }
    }
}

fn farm(path: &str) -> PathBuf {
    common::repo().join("tools/farm").join(path)
}

fn run(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{cmd:?} failed:\n{text}");
    text
}

/// `openjd run` of the template's Merge step and its dependencies, then the merged file.
fn openjd_run(
    bin: &Path,
    dir: &Scratch,
    split: &str,
    parts: u32,
    spp: u32,
) -> aperture_imageio::Image {
    let out = dir.path(&format!("{split}.exr"));
    let param = |k: &str, v: String| ["-p".to_string(), format!("{k}={v}")];
    let mut cmd = Command::new(bin.join("openjd"));
    cmd.arg("run")
        .arg(farm("openjd/aperture-split.yaml"))
        .args(["--step", "Merge", "--run-dependencies"]);
    for (k, v) in [
        ("SceneFile", common::demo_scene().display().to_string()),
        ("OutputFile", out.display().to_string()),
        (
            "PartsDir",
            dir.path(&format!("{split}.parts")).display().to_string(),
        ),
        ("Split", split.to_string()),
        ("Parts", parts.to_string()),
        ("LastPart", (parts - 1).to_string()),
        ("Spp", spp.to_string()),
        ("RenderArgs", SMALL.join(" ")),
        ("Aperture", common::aperture().display().to_string()),
    ] {
        cmd.args(param(k, v));
    }
    let log = run(&mut cmd);
    assert!(log.contains("Session ended successfully"), "{log}");
    aperture_imageio::read_exr(&out).unwrap()
}

#[test]
fn openjd_template_checks_and_runs_tiles_and_batches() {
    let Some(bin) = tools() else { return };
    let template = farm("openjd/aperture-split.yaml");
    let said = run(Command::new(bin.join("openjd")).arg("check").arg(&template));
    assert!(said.contains("passes validation"), "{said}");
    let dir = Scratch::new("openjd");
    let mut whole_args: Vec<&str> = SMALL.to_vec();
    whole_args.extend(["--spp", "16"]);
    let whole = common::local_render(&dir.path("whole.exr"), &whole_args);
    let tiles = openjd_run(&bin, &dir, "tiles", 4, 16);
    common::assert_same_pixels(&tiles, &whole);
    let batches = openjd_run(&bin, &dir, "batches", 2, 8);
    let (worst, layer) = common::largest_relative_difference(&batches, &whole);
    eprintln!("openjd batches: largest relative difference {worst:.3e} ({layer})");
    assert!(worst < 1e-6);
}

fn manifests() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(farm("kubernetes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .collect();
    files.sort();
    files
}

#[test]
fn kubernetes_manifests_pass_the_api_schema() {
    let Some(bin) = tools() else { return };
    let files = manifests();
    assert!(files.len() >= 4, "{files:?}");
    let said = run(Command::new(bin.join("kubernetes-validate"))
        .arg("--strict")
        .args(&files));
    for f in &files {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            said.lines()
                .any(|l| l.contains(&name) && l.contains("passed")),
            "{name}: {said}"
        );
    }
}

/// The manifest `name` as JSON (PyYAML beside the checkers reads it).
fn manifest(bin: &Path, name: &str) -> Value {
    let json = run(Command::new(bin.join("python"))
        .args([
            "-c",
            "import json, sys, yaml; print(json.dumps(yaml.safe_load(open(sys.argv[1]))))",
        ])
        .arg(farm(&format!("kubernetes/{name}"))));
    serde_json::from_str(&json).unwrap()
}

/// The first container of a Job: its `sh -c` script and its environment.
fn container(job: &Value) -> (String, Vec<(String, String)>) {
    let c = &job["spec"]["template"]["spec"]["containers"][0];
    assert_eq!(c["command"], serde_json::json!(["/bin/sh", "-c"]));
    let script = c["args"][0].as_str().expect("a script").to_string();
    let env = c["env"]
        .as_array()
        .map(|vars| {
            vars.iter()
                .map(|v| {
                    (
                        v["name"].as_str().unwrap().to_string(),
                        v["value"].as_str().unwrap().to_string(),
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    // The volume the script's /data is.
    assert_eq!(c["volumeMounts"][0]["mountPath"], "/data");
    assert_eq!(
        job["spec"]["template"]["spec"]["volumes"][0]["persistentVolumeClaim"]["claimName"],
        "aperture-data"
    );
    (script, env)
}

/// Runs a container's script on this machine: `/data` is `data`, `aperture` the test
/// binary, the manifest's environment with `overrides` on top.
fn run_script(script: &str, env: &[(String, String)], overrides: &[(&str, String)], data: &Path) {
    let bin_dir = common::aperture().parent().unwrap().to_path_buf();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut cmd = Command::new("/bin/sh");
    cmd.arg("-c")
        .arg(script.replace("/data", &data.display().to_string()))
        .env("PATH", path);
    for (k, v) in env {
        cmd.env(k, v);
    }
    for (k, v) in overrides {
        cmd.env(k, v);
    }
    run(&mut cmd);
}

#[test]
fn kubernetes_jobs_render_and_merge_what_they_say() {
    let Some(bin) = tools() else { return };
    let merge = manifest(&bin, "merge.yaml");
    let claim = manifest(&bin, "volume.yaml");
    assert_eq!(claim["metadata"]["name"], "aperture-data");
    assert_eq!(claim["spec"]["accessModes"][0], "ReadWriteMany");
    let (merge_script, merge_env) = container(&merge);
    let dir = Scratch::new("kubernetes");
    let small = SMALL.join(" ");
    let mut whole_args: Vec<&str> = SMALL.to_vec();
    whole_args.extend(["--spp", "16"]);
    let whole = common::local_render(&dir.path("whole.exr"), &whole_args);
    for (name, overrides) in [
        (
            "render-tiles.yaml",
            vec![("RENDER_ARGS", format!("{small} --spp 16"))],
        ),
        (
            "render-batches.yaml",
            vec![("RENDER_ARGS", small.clone()), ("SPP", "4".to_string())],
        ),
    ] {
        let job = manifest(&bin, name);
        let spec = &job["spec"];
        assert_eq!(spec["completionMode"], "Indexed", "{name}");
        let completions = spec["completions"].as_u64().unwrap();
        let (script, env) = container(&job);
        let var = |k: &str| env.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
        if let Some(tiles) = var("TILES") {
            assert_eq!(
                tiles,
                completions.to_string(),
                "{name}: TILES = completions"
            );
        }
        assert_eq!(
            merge_env.iter().find(|(n, _)| n == "PARTS").unwrap().1,
            completions.to_string(),
            "merge.yaml's PARTS = {name}'s completions"
        );
        let data = dir.path(name);
        std::fs::create_dir_all(&data).unwrap();
        std::fs::copy(common::demo_scene(), data.join("scene.glb")).unwrap();
        for k in 0..completions {
            let mut o: Vec<(&str, String)> = overrides.clone();
            o.push(("JOB_COMPLETION_INDEX", k.to_string()));
            run_script(&script, &env, &o, &data);
        }
        run_script(&merge_script, &merge_env, &[], &data);
        let merged = aperture_imageio::read_exr(&data.join("frame.exr")).unwrap();
        let (worst, layer) = common::largest_relative_difference(&merged, &whole);
        eprintln!("{name}: largest relative difference {worst:.3e} ({layer})");
        if name.contains("tiles") {
            common::assert_same_pixels(&merged, &whole);
        } else {
            assert!(worst < 1e-6, "{name}: {worst} in {layer}");
        }
    }
}

/// Every frame `1, 3, 5, 7` under `dir/PREFIX_####.exr` equals this machine's sequence.
fn assert_frames_equal_local(scene: &Path, dir: &Path, prefix: &str, args: &[&str]) {
    let local = dir.join("local");
    std::fs::create_dir_all(&local).unwrap();
    let mut a = args.to_vec();
    a.extend(["--frames", "1..7:2"]);
    common::local_render_of(scene, &local.join("f_####.exr"), &a);
    let names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(prefix))
        .collect();
    assert_eq!(names.len(), 4, "{names:?}");
    for f in [1, 3, 5, 7] {
        let farm = aperture_imageio::read_exr(&dir.join(format!("{prefix}{f:04}.exr"))).unwrap();
        let here = aperture_imageio::read_exr(&local.join(format!("f_{f:04}.exr"))).unwrap();
        common::assert_same_pixels(&farm, &here);
    }
}

const FRAME_SIZE: [&str; 6] = ["--width", "48", "--height", "36", "--spp", "4"];

#[test]
fn openjd_frames_template_renders_every_frame() {
    let Some(bin) = tools() else { return };
    let Some(scene) = common::sample("animation/BoxAnimated/BoxAnimated.glb") else {
        return;
    };
    let template = farm("openjd/aperture-frames.yaml");
    let said = run(Command::new(bin.join("openjd")).arg("check").arg(&template));
    assert!(said.contains("passes validation"), "{said}");
    let dir = Scratch::new("openjd-frames");
    let shots = dir.path("shots");
    let log = run(Command::new(bin.join("openjd"))
        .arg("run")
        .arg(&template)
        .args(["--step", "Render"])
        .args(["-p", &format!("SceneFile={}", scene.display())])
        .args([
            "-p",
            &format!("OutputPattern={}/shot_####.exr", shots.display()),
        ])
        .args(["-p", "Frames=1-7:2"])
        .args([
            "-p",
            &format!("RenderArgs={} --quiet", FRAME_SIZE.join(" ")),
        ])
        .args(["-p", &format!("Aperture={}", common::aperture().display())]));
    assert!(log.contains("Session ended successfully"), "{log}");
    assert_frames_equal_local(&scene, &shots, "shot_", &FRAME_SIZE);
}

#[test]
fn kubernetes_frames_job_renders_every_frame_once() {
    let Some(bin) = tools() else { return };
    let Some(scene) = common::sample("animation/BoxAnimated/BoxAnimated.glb") else {
        return;
    };
    let job = manifest(&bin, "render-frames.yaml");
    assert_eq!(job["spec"]["completionMode"], "Indexed");
    let completions = job["spec"]["completions"].as_u64().unwrap();
    let (script, env) = container(&job);
    let chunks = env.iter().find(|(n, _)| n == "CHUNKS").unwrap().1.clone();
    assert_eq!(chunks, completions.to_string(), "CHUNKS = completions");
    let dir = Scratch::new("kubernetes-frames");
    let data = dir.path("data");
    std::fs::create_dir_all(&data).unwrap();
    std::fs::copy(&scene, data.join("scene.glb")).unwrap();
    // More pods than frames: most chunks are empty and must say so and succeed.
    for k in 0..completions {
        run_script(
            &script,
            &env,
            &[
                ("FRAMES", "1..7:2".to_string()),
                ("RENDER_ARGS", format!("{} --quiet", FRAME_SIZE.join(" "))),
                ("JOB_COMPLETION_INDEX", k.to_string()),
            ],
            &data,
        );
    }
    assert_frames_equal_local(&scene, &data.join("frames"), "shot_", &FRAME_SIZE);
}
