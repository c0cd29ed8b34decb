//! The thin lens's options (issue 61) from the command line: `--aperture-vignetting` and
//! `--distortion` render what the file's `aperture_vignetting` and `distortion_*` keys render,
//! bit for bit, and `info` shows the file's values.

mod common;

use aperture_imageio::read_exr;
use common::{aperture, quad_glb, quad_json, Scratch};
use serde_json::{json, Value};
use std::process::Command;

/// A lit quad seen slightly off axis by a camera with depth of field, whose `extras` add `lens`.
fn scene(lens: Value) -> Vec<u8> {
    let mut doc = quad_json();
    doc["materials"] = json!([{"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.5, 0.2, 1.0],
        "metallicFactor": 0.0}}]);
    doc["meshes"] = json!([{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
        "material": 0}]}]);
    let mut extras = json!({"use_dof": true, "aperture_radius": 0.2, "focus_distance": 2.5});
    for (k, v) in lens.as_object().unwrap() {
        extras[k] = v.clone();
    }
    doc["cameras"] = json!([{"type": "perspective", "extras": extras,
        "perspective": {"yfov": 0.9, "znear": 0.1}}]);
    doc["nodes"] = json!([{"mesh": 0, "scale": [2.0, 2.0, 1.0]},
        {"camera": 0, "translation": [0.3, 0.2, 3.0]}]);
    doc["scenes"] = json!([{"nodes": [0, 1]}]);
    quad_glb(&doc)
}

fn render(dir: &Scratch, name: &str, file: &[u8], args: &[&str]) -> Vec<u32> {
    let path = dir.path(&format!("{name}.glb"));
    std::fs::write(&path, file).unwrap();
    let out = dir.path(&format!("{name}.exr"));
    let status = Command::new(aperture())
        .arg("render")
        .arg(&path)
        .arg("-o")
        .arg(&out)
        .args(["--width", "32", "--height", "24", "--spp", "4", "--quiet"])
        .args(["--env", "0.3,0.3,0.3", "--passes", "none"])
        .args(args)
        .status()
        .unwrap();
    assert!(status.success(), "{name} {args:?}");
    let img = read_exr(&out).unwrap();
    img.rgba.iter().flatten().map(|v| v.to_bits()).collect()
}

#[test]
fn flags_render_what_the_files_keys_render() {
    let dir = Scratch::new("lens-cli");
    let keys = json!({"aperture_vignetting": 0.6, "distortion_k1": -0.3, "distortion_k2": 0.05,
        "distortion_p1": 0.01});
    let from_file = render(&dir, "file", &scene(keys), &[]);
    let plain = scene(json!({}));
    let from_flags = render(
        &dir,
        "flags",
        &plain,
        &[
            "--aperture-vignetting",
            "0.6",
            "--distortion",
            "-0.3,0.05,0,0.01",
        ],
    );
    let ideal = render(&dir, "ideal", &plain, &[]);
    assert_ne!(from_file, ideal, "the lens keys should change the image");
    assert_eq!(from_file, from_flags);
    // The flags win over the file: zero gives the ideal thin lens back.
    let keys = json!({"aperture_vignetting": 0.6, "distortion_k1": -0.3});
    let zeroed = render(
        &dir,
        "zeroed",
        &scene(keys),
        &["--aperture-vignetting", "0", "--distortion", "0"],
    );
    assert_eq!(zeroed, ideal);
}

#[test]
fn bad_flags_are_refused_and_info_shows_the_keys() {
    let dir = Scratch::new("lens-cli-info");
    let path = dir.path("lens.glb");
    std::fs::write(
        &path,
        scene(json!({"aperture_vignetting": 0.25, "distortion_k1": -0.125})),
    )
    .unwrap();
    for bad in [
        ["--aperture-vignetting", "1.5"],
        ["--distortion", "1,2,3,4,5,6"],
        ["--distortion", "0.1,inf"],
    ] {
        let out = Command::new(aperture())
            .arg("render")
            .arg(&path)
            .args(["-o", dir.path("bad.exr").to_str().unwrap()])
            .args(bad)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{bad:?} was accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(bad[0]), "{bad:?}: {err}");
    }
    let out = Command::new(aperture())
        .arg("info")
        .arg(&path)
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("lens: vignetting 0.25, distortion k1 -0.125 k2 0.0 k3 0.0"),
        "{text}"
    );
    let out = Command::new(aperture())
        .args(["info", "--json"])
        .arg(&path)
        .output()
        .unwrap();
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let d = &v["cameras"][0]["dof"];
    assert_eq!(d["vignetting"], 0.25, "{d}");
    assert_eq!(d["distortion"]["k1"], -0.125, "{d}");
}
