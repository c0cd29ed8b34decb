//! Damaged inputs: a generator writes small broken glTF/GLB files (one folder per kind) into the
//! test's temporary directory; each must load to the right typed error, saying where, and none
//! may panic.

mod base;
mod cases;
mod compressed;
mod mutations;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use aperture_scene::{load, LoadOptions};
use aperture_tests::meshopt_writer::join_glb as glb;

use base::{folder, triangle_bin, triangle_json};
use cases::{cases, Case};

/// Writes a case's files into a folder of its own; the path of the one to load.
fn write(dir: &Path, case: &Case) -> PathBuf {
    let sub = dir.join(case.kind.replace(|c: char| !c.is_ascii_alphanumeric(), "_"));
    std::fs::create_dir_all(&sub).unwrap();
    for (name, bytes) in &case.files {
        std::fs::write(sub.join(name), bytes).unwrap();
    }
    sub.join(case.files[0].0)
}

#[test]
fn the_valid_base_files_load() {
    let dir = folder().join("valid");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tri.bin"), triangle_bin()).unwrap();
    std::fs::write(
        dir.join("scene.gltf"),
        serde_json::to_vec(&triangle_json(Some("tri.bin"))).unwrap(),
    )
    .unwrap();
    std::fs::write(
        dir.join("scene.glb"),
        glb(&triangle_json(None), &triangle_bin()),
    )
    .unwrap();
    for f in ["scene.gltf", "scene.glb"] {
        let s = load(&dir.join(f), &LoadOptions::default()).unwrap();
        assert_eq!(s.drawn_triangle_count(), 1, "{f}");
        assert_eq!(s.cameras.len(), 1, "{f}: automatic camera");
    }
}

#[test]
fn every_damaged_input_is_a_typed_error_and_none_panics() {
    let dir = folder();
    let cases = cases();
    assert!(cases.len() >= 15);
    let mut problems = Vec::new();
    for case in &cases {
        let path = write(&dir, case);
        let result = catch_unwind(AssertUnwindSafe(|| load(&path, &LoadOptions::default())));
        match result {
            Err(_) => problems.push(format!("{}: panicked", case.kind)),
            Ok(Ok(_)) => problems.push(format!("{}: loaded without error", case.kind)),
            Ok(Err(e)) => {
                let msg = e.to_string();
                eprintln!("{:<45} {msg}", case.kind);
                if !(case.check)(&e) || !msg.contains(case.says) {
                    problems.push(format!("{}: unexpected error {e:?} / {msg}", case.kind));
                }
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
