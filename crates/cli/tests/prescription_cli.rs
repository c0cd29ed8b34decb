//! `--lens-prescription` (issue 61) renders what the file's `lens_prescription` key renders,
//! bit for bit; `info` prints the lens's figures; a bad file is refused with its path.

mod common;

use aperture_imageio::read_exr;
use common::{aperture, quad_glb, quad_json, Scratch};
use serde_json::{json, Value};
use std::process::Command;

/// A lit quad seen off axis by a camera focused at 2.5 m at f/4, whose `extras` add `lens`.
fn scene(lens: Value) -> Vec<u8> {
    let mut doc = quad_json();
    doc["materials"] = json!([{"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.5, 0.2, 1.0],
        "metallicFactor": 0.0}}]);
    doc["meshes"] = json!([{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
        "material": 0}]}]);
    let mut extras = json!({"aperture_fstop": 4.0, "focus_distance": 2.5});
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

fn run(args: &[&str], path: &std::path::Path, out: &std::path::Path) -> std::process::Output {
    Command::new(aperture())
        .arg("render")
        .arg(path)
        .arg("-o")
        .arg(out)
        .args(["--width", "32", "--height", "24", "--spp", "4", "--quiet"])
        .args(["--env", "0.3,0.3,0.3", "--passes", "none"])
        .args(args)
        .output()
        .unwrap()
}

fn render(dir: &Scratch, name: &str, file: &[u8], args: &[&str]) -> Vec<u32> {
    let path = dir.path(&format!("{name}.glb"));
    std::fs::write(&path, file).unwrap();
    let out = dir.path(&format!("{name}.exr"));
    let o = run(args, &path, &out);
    assert!(
        o.status.success(),
        "{name} {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let img = read_exr(&out).unwrap();
    img.rgba.iter().flatten().map(|v| v.to_bits()).collect()
}

fn lens_file(dir: &Scratch) -> std::path::PathBuf {
    let shipped = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../assets/lenses/dgauss-50mm.dat"
    );
    let path = dir.path("dgauss.dat");
    std::fs::copy(shipped, &path).unwrap();
    path
}

#[test]
fn the_flag_renders_what_the_files_key_renders() {
    let dir = Scratch::new("prescription-cli");
    let lens = lens_file(&dir);
    let from_key = render(
        &dir,
        "key",
        &scene(json!({"lens_prescription": "dgauss.dat"})),
        &[],
    );
    let plain = scene(json!({}));
    let flag = ["--lens-prescription", lens.to_str().unwrap()];
    let from_flag = render(&dir, "flag", &plain, &flag);
    let thin = render(&dir, "thin", &plain, &[]);
    assert_ne!(from_key, thin, "the prescription should change the image");
    assert_eq!(from_key, from_flag);
}

#[test]
fn info_prints_the_lens_and_a_bad_file_is_refused() {
    let dir = Scratch::new("prescription-cli-info");
    lens_file(&dir);
    let path = dir.path("lens.glb");
    std::fs::write(&path, scene(json!({"lens_prescription": "dgauss.dat"}))).unwrap();
    let out = Command::new(aperture())
        .arg("info")
        .arg(&path)
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("prescription \"dgauss.dat\" (11 surfaces): focal length 50.358")
            && text.contains("f/4.0"),
        "{text}"
    );
    let out = Command::new(aperture())
        .args(["info", "--json"])
        .arg(&path)
        .output()
        .unwrap();
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let l = &v["cameras"][0]["dof"]["prescription"]["lens"];
    assert!(
        (l["focal_length_mm"].as_f64().unwrap() - 50.358).abs() < 1e-3,
        "{l}"
    );
    assert!((l["fstop"].as_f64().unwrap() - 4.0).abs() < 1e-3, "{l}");
    assert!(l["exit_pupil_radius_mm"].as_f64().unwrap() > 0.0, "{l}");
    let missing = dir.path("missing.dat");
    let o = run(
        &["--lens-prescription", missing.to_str().unwrap()],
        &path,
        &dir.path("bad.exr"),
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("lens_prescription") && err.contains("missing.dat"),
        "{err}"
    );
}
