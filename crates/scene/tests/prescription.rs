//! `lens_prescription` (issue 61) read from a lens file beside the glTF, inline, or the command
//! line; every bad input is an error naming the camera, the key and the value, never a panic.

use aperture_scene::{load_bytes, DofOverrides, LoadOptions};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

mod common;

fn glb(extras: Value) -> Vec<u8> {
    let doc = json!({
        "asset": {"version": "2.0"},
        "cameras": [{
            "name": "Lens",
            "type": "perspective",
            "perspective": {"yfov": 0.5, "znear": 0.1},
            "extras": extras
        }],
        "nodes": [{"camera": 0}],
        "scenes": [{"nodes": [0]}]
    });
    common::glb::glb(&doc, &[])
}

/// A fresh folder for lens files.
fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "aperture-prescription-{name}-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const GOOD: &str = "# a test lens\n 30 4 1.6 20\n -60 2 1 20 # back of the glass\n0 10 0 12\n\n";

fn load(extras: Value, dir: &Path) -> Result<aperture_scene::Scene, String> {
    load_bytes(&glb(extras), dir, &LoadOptions::default()).map_err(|e| e.to_string())
}

#[test]
fn a_lens_file_beside_the_gltf_and_inline_rows_read_alike() {
    let dir = folder("good");
    std::fs::write(dir.join("test.dat"), GOOD).unwrap();
    let s = load(
        json!({"lens_prescription": "test.dat", "aperture_fstop": 4}),
        &dir,
    )
    .unwrap();
    let p = s.cameras[0]
        .dof
        .prescription
        .clone()
        .expect("a prescription");
    assert_eq!(p.surfaces.len(), 3);
    assert_eq!(p.stop(), Some(2));
    assert_eq!(p.fstop, Some(4.0));
    assert_eq!(p.surfaces[1].radius, -60.0);
    assert_eq!(p.source, "test.dat");
    let inline = json!([[30, 4, 1.6, 20], [-60, 2, 1, 20], [0, 10, 0, 12]]);
    let s = load(json!({ "lens_prescription": inline }), &dir).unwrap();
    let q = s.cameras[0].dof.prescription.clone().unwrap();
    assert_eq!(q.surfaces, p.surfaces);
    // An aperture radius leaves the stop as written.
    assert_eq!(q.fstop, None);
    // The command line's file (relative to the working directory) wins over the file's key.
    let opts = LoadOptions {
        dof_overrides: DofOverrides {
            lens_prescription: Some(dir.join("test.dat")),
            ..DofOverrides::default()
        },
        ..LoadOptions::default()
    };
    let s = load_bytes(
        &glb(json!({ "lens_prescription": [[50, 1, 1.5, 9], [0, 5, 0, 5]] })),
        &dir,
        &opts,
    );
    let cli = s.unwrap().cameras[0].dof.prescription.clone().unwrap();
    assert_eq!(cli.surfaces, p.surfaces);
    // No key: the thin lens.
    assert!(load(json!({}), &dir).unwrap().cameras[0]
        .dof
        .prescription
        .is_none());
}

#[test]
fn bad_files_and_rows_are_errors_naming_camera_key_and_value() {
    let dir = folder("bad");
    let cases: Vec<(Value, &str)> = vec![
        (json!("missing.dat"), "cannot read the lens file"),
        (json!("../outside.dat"), "'..' would leave"),
        (json!(12), "expected a lens file's path or an array"),
        (json!([[30, 4, 1.6]]), "row 0: expected 4 numbers"),
        (json!([[30, 4, 1.6, "x"]]), "row 0: expected 4 numbers"),
        (json!([[30, 4, 1.6, 20], [-60, 2, 1, 20]]), "no stop"),
        (json!([[0, 4, 0, 20], [0, 2, 0, 20]]), "2 stops"),
        (json!([[0, 4, 0, 20]]), "no refracting surface"),
        (
            json!([[30, -4, 1.6, 20], [0, 1, 0, 5]]),
            "thickness -4 must be >= 0",
        ),
        (
            json!([[30, 4, 0.5, 20], [0, 1, 0, 5]]),
            "IOR 0.5 must be 0 (air) or >= 1",
        ),
        (
            json!([[30, 4, 1.6, 0], [0, 1, 0, 5]]),
            "aperture diameter 0 must be > 0",
        ),
        (json!([[1e39, 4, 1.6, 20], [0, 1, 0, 5]]), "not finite"),
        (json!([]), "no rows"),
    ];
    for (value, reason) in cases {
        let e = load(json!({ "lens_prescription": value }), &dir).unwrap_err();
        assert!(
            e.contains("camera \"Lens\"")
                && e.contains("cameras.extras.lens_prescription")
                && e.contains(reason),
            "{value}: {e}"
        );
    }
    // A file with a malformed row names the file and the line.
    std::fs::write(dir.join("bad.dat"), "# ok\n30 4 1.6 20\n30 4 nan-ish 20\n").unwrap();
    let e = load(json!({"lens_prescription": "bad.dat"}), &dir).unwrap_err();
    assert!(
        e.contains("\"bad.dat\"")
            && e.contains("line 3")
            && e.contains("\"nan-ish\" is not a number"),
        "{e}"
    );
    std::fs::write(dir.join("nan.dat"), "30 4 1.6 NaN\n0 1 0 5\n").unwrap();
    let e = load(json!({"lens_prescription": "nan.dat"}), &dir).unwrap_err();
    assert!(e.contains("not finite"), "{e}");
    // On the command line: its key and the path.
    let opts = LoadOptions {
        dof_overrides: DofOverrides {
            lens_prescription: Some(dir.join("none.dat")),
            ..DofOverrides::default()
        },
        ..LoadOptions::default()
    };
    let e = load_bytes(&glb(json!({})), &dir, &opts)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("command line lens_prescription") && e.contains("none.dat"),
        "{e}"
    );
}
