//! Every input in the shared findings folder (`APERTURE_FUZZ_FINDINGS`, else
//! `../shared/fuzz-findings` beside the repository) through the entry point it was found on:
//! each must be a clean error (an `Err` that is no caught panic), in every build profile.
//!
//! The folder's README.md names each file's target in a table (`| `file` | `target` (...) |`);
//! a file it does not list is matched by its name's prefix (`texture-...`). Missing folder: a
//! skip with a message, but a failure under `CI=true`, where a silent skip would hide that the
//! test never ran.

use std::path::{Path, PathBuf};

use aperture_fuzz_harness::{Target, MEMORY_BUDGET};

fn findings_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("APERTURE_FUZZ_FINDINGS")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/fuzz-findings")
        });
    if dir.is_dir() {
        return Some(dir);
    }
    assert!(
        !std::env::var("CI").is_ok_and(|v| v == "true"),
        "CI=true but the fuzz findings folder is missing at {}",
        dir.display()
    );
    eprintln!("skipping: no fuzz findings folder at {}", dir.display());
    None
}

fn target_named(name: &str) -> Option<Target> {
    Target::ALL.into_iter().find(|t| t.name() == name)
}

/// The target README.md's table names for `file`, else the one its name starts with.
fn target_of(file: &str, readme: &str) -> Option<Target> {
    let listed = readme.lines().find_map(|line| {
        let mut cells = line.split('|').map(str::trim).skip(1);
        let first = cells.next()?;
        if first.trim_matches('`') != file {
            return None;
        }
        let target = cells.next()?.trim_start_matches('`');
        target_named(&target[..target.find('`')?])
    });
    listed.or_else(|| target_named(file.split(['-', '.']).next()?))
}

/// What the target's reader says of `data`, as [`Target::run`] reads it, with the result kept.
fn outcome(target: Target, data: &[u8]) -> Result<(), String> {
    let options = aperture_scene::LoadOptions {
        memory: aperture_budget::MemoryBudget::fixed(MEMORY_BUDGET),
        ..aperture_scene::LoadOptions::default()
    };
    let load = |glb: &[u8]| {
        aperture_scene::Animated::load_bytes(glb, Path::new("/nonexistent/findings"), &options)
            .map(drop)
            .map_err(|e| e.to_string())
    };
    let path = Path::new("finding");
    match target {
        Target::Texture => aperture_scene::decode_texture(data, 0, MEMORY_BUDGET)
            .map(drop)
            .map_err(|e| e.to_string()),
        Target::Exr => aperture_imageio::decode_exr_within(data, path, MEMORY_BUDGET)
            .map(drop)
            .map_err(|e| e.to_string()),
        Target::Env => aperture_imageio::decode_env_image(data, path, MEMORY_BUDGET)
            .map(drop)
            .map_err(|e| e.to_string()),
        Target::Load => load(data),
        Target::Draco => load(&aperture_fuzz_harness::wrap_draco(data).ok_or("not wrappable")?),
        Target::Meshopt => load(&aperture_fuzz_harness::wrap_meshopt(data).ok_or("not wrappable")?),
    }
}

#[test]
fn every_shared_finding_is_a_clean_error_from_its_target() {
    let Some(dir) = findings_dir() else { return };
    let readme = std::fs::read_to_string(dir.join("README.md")).unwrap_or_default();
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("entry").path())
        .filter(|p| p.is_file() && p.extension().is_none_or(|x| x != "md"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "{} holds no findings", dir.display());
    for file in &files {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let target = target_of(&name, &readme)
            .unwrap_or_else(|| panic!("{name}: no target in README.md nor in its name"));
        let bytes = std::fs::read(file).expect("finding");
        // The fuzz entry point itself (a panic fails the test, naming the file below).
        eprintln!("{name}: target {}", target.name());
        target.run(&bytes);
        match outcome(target, &bytes) {
            Ok(()) => panic!("{name}: loads through `{}`", target.name()),
            Err(e) => {
                eprintln!("{name}: {e}");
                assert!(!e.contains("panicked"), "{name}: a caught panic: {e}");
            }
        }
    }
    println!("{} findings, each a clean error", files.len());
}

#[test]
fn findings_are_matched_to_targets_by_the_readme_then_by_name() {
    let readme = "| file | target | what |\n|---|---|---|\n\
                  | `a.bin` | `exr` (`decode_exr`), found ... | ... |\n";
    assert_eq!(target_of("a.bin", readme), Some(Target::Exr));
    assert_eq!(target_of("texture-x.bin", readme), Some(Target::Texture));
    assert_eq!(target_of("meshopt.bin", ""), Some(Target::Meshopt));
    assert_eq!(target_of("other.bin", readme), None);
}
