//! `aperture render --progress json`, as a program reading the binary's stdout sees it.

mod common;

use common::sample;

/// One parseable JSON object per line on stdout, progress growing to the total, and a last
/// line naming the file written.
#[test]
fn json_progress_lines_parse() {
    let Some(box_glb) = sample("correctness/BoxTextured/BoxTextured.glb") else {
        return;
    };
    let out = std::env::temp_dir().join(format!("aperture-json-{}.exr", std::process::id()));
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_aperture"))
        .args([
            "render",
            box_glb.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .args([
            "--width",
            "64",
            "--height",
            "48",
            "--spp",
            "2",
            "--progress",
            "json",
        ])
        .output()
        .unwrap();
    assert!(run.status.success());
    let text = String::from_utf8(run.stdout).unwrap();
    let lines: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect();
    assert!(lines.len() >= 3, "{text}");
    let progress: Vec<&serde_json::Value> =
        lines.iter().filter(|l| l["event"] == "progress").collect();
    let last = progress.last().unwrap();
    assert_eq!(last["done"], last["total"]);
    assert_eq!(last["samples_done"], 64 * 48 * 2);
    assert!(progress
        .windows(2)
        .all(|w| w[0]["done"].as_u64() < w[1]["done"].as_u64()));
    let written = lines.last().unwrap();
    assert_eq!(written["event"], "frame");
    assert_eq!(written["path"], out.to_str().unwrap());
    std::fs::remove_file(&out).unwrap();
}
