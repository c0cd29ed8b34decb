//! Every committed corpus file (`fuzz/corpus/<target>/`) through its target's entry point, on
//! stable, in `cargo test`: what the fuzzer once reached stays reachable without a panic (CI
//! runs no fuzzer). Crashes the fuzzer found are regression tests in the crates' own tests.

use std::path::Path;

use aperture_fuzz_harness::Target;

#[test]
fn every_corpus_file_runs_through_its_target() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../corpus");
    for target in Target::ALL {
        let dir = root.join(target.name());
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e} (the corpus is committed)", dir.display()))
            .map(|e| e.expect("entry").path())
            .collect();
        files.sort();
        assert!(!files.is_empty(), "{} is empty", dir.display());
        for f in &files {
            let bytes = std::fs::read(f).expect("corpus file");
            // A panic here names the file through the test's output.
            eprintln!("{}", f.display());
            target.run(&bytes);
        }
        println!("{}: {} files", target.name(), files.len());
    }
}

/// The corpora stay small: libFuzzer's merge keeps what adds coverage, and nothing over
/// 16 KiB is committed.
#[test]
fn corpus_files_are_small() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../corpus");
    for target in Target::ALL {
        for e in std::fs::read_dir(root.join(target.name())).expect("corpus") {
            let p = e.expect("entry").path();
            let len = std::fs::metadata(&p).expect("metadata").len();
            assert!(len <= 16 << 10, "{}: {len} bytes", p.display());
        }
    }
}

/// The seeds of the wrapped targets decode: the wrappers build files the loader accepts, so the
/// fuzzer starts from the decoders' success paths, not from an error in the wrapping.
#[test]
fn wrapped_seeds_decode() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../corpus");
    let options = aperture_scene::LoadOptions::default();
    let here = Path::new(".");
    for (dir, wrap) in [
        (
            "draco",
            aperture_fuzz_harness::wrap_draco as fn(&[u8]) -> Option<Vec<u8>>,
        ),
        ("meshopt", aperture_fuzz_harness::wrap_meshopt),
    ] {
        for e in std::fs::read_dir(root.join(dir)).expect("corpus") {
            let p = e.expect("entry").path();
            if !p
                .file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("seed-")
            {
                continue;
            }
            let glb = wrap(&std::fs::read(&p).unwrap()).expect("wraps");
            if let Err(e) = aperture_scene::load_bytes(&glb, here, &options) {
                panic!("{}: {e}", p.display());
            }
        }
    }
}
