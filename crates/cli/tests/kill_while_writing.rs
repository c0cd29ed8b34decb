//! SIGKILL at random moments of `aperture render` (loading, rendering, writing): the output
//! path then holds the previous complete file, or a complete new one, never a partial file
//! (SPEC §6: written whole or not at all). Twenty kills per output kind.
//!
//! Kinds covered: EXR (streamed band by band), PNG, merged EXR (`aperture merge` of two tiles)
//! and frame sequences (`--frames`, where every frame file must be whole or absent, and
//! `--skip-existing` then renders exactly the missing ones).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const KILLS: usize = 20;

/// One output kind: the command that writes it and how a complete file is recognised.
struct Kind {
    name: &'static str,
    file: &'static str,
    /// The command writing `out` (the seed varies the content from run to run).
    command: fn(&Path, u32) -> Command,
    /// The file decodes completely, with the expected size.
    complete: fn(&Path) -> Result<(), String>,
}

fn exr_complete(path: &Path) -> Result<(), String> {
    let im = aperture_imageio::read_exr(path).map_err(|e| e.to_string())?;
    match (im.width, im.height) {
        (768, 512) => Ok(()),
        other => Err(format!("size {other:?}")),
    }
}

fn png_complete(path: &Path) -> Result<(), String> {
    let im = image::open(path).map_err(|e| e.to_string())?;
    match (im.width(), im.height()) {
        (1024, 768) => Ok(()),
        other => Err(format!("size {other:?}")),
    }
}

const EXR_ARGS: &[&str] = &[
    "--width",
    "768",
    "--height",
    "512",
    "--spp",
    "1",
    "--max-bounces",
    "0",
];

fn exr_render(out: &Path, seed: u32) -> Command {
    render(EXR_ARGS, out, seed)
}

fn png_render(out: &Path, seed: u32) -> Command {
    let args = [
        "--width",
        "1024",
        "--height",
        "768",
        "--spp",
        "1",
        "--max-bounces",
        "0",
    ];
    render(&args, out, seed)
}

/// `aperture merge` of the two tiles of a 768x512 render, rendered once beside `out` (the seed
/// picks which of two renders' tiles, so the merged file changes).
fn merge(out: &Path, seed: u32) -> Command {
    let dir = out.parent().unwrap();
    let parts: Vec<PathBuf> = (0..2)
        .map(|k| dir.join(format!("part-{}-{k}.exr", seed % 2)))
        .collect();
    for (k, p) in parts.iter().enumerate() {
        if !p.exists() {
            let tile = format!("{k}/2");
            let mut args = EXR_ARGS.to_vec();
            args.extend(["--tile", &tile]);
            let ok = render(&args, p, seed % 2).status().unwrap().success();
            assert!(ok, "rendering {}", p.display());
        }
    }
    let mut c = Command::new(env!("CARGO_BIN_EXE_aperture"));
    c.arg("merge")
        .args(&parts)
        .arg("-o")
        .arg(out)
        .arg("--quiet")
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    c
}

const KINDS: &[Kind] = &[
    Kind {
        name: "EXR",
        file: "out.exr",
        command: exr_render,
        complete: exr_complete,
    },
    Kind {
        name: "PNG",
        file: "out.png",
        command: png_render,
        complete: png_complete,
    },
    Kind {
        name: "merged EXR",
        file: "merged.exr",
        command: merge,
        complete: exr_complete,
    },
];

fn demo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.glb")
}

fn render(args: &[&str], out: &Path, seed: u32) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_aperture"));
    c.arg("render")
        .arg(demo())
        .arg("-o")
        .arg(out)
        .args(args)
        .args(["--seed", &seed.to_string(), "--quiet", "--threads", "2"])
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    c
}

/// xorshift64*: random kill moments without a dependency.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Temporary files the writer left beside `out` (a killed writer cannot remove its own).
fn leftovers(dir: &Path, out: &Path) -> Vec<PathBuf> {
    let prefix = format!(".{}.", out.file_name().unwrap().to_string_lossy());
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy();
            n.starts_with(&prefix) && n.ends_with(".tmp")
        })
        .collect()
}

fn kill_while_writing(kind: &Kind) {
    let dir = std::env::temp_dir().join(format!(
        "aperture-kill-{}-{}",
        kind.name.replace(' ', "-"),
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join(kind.file);
    // A complete file first, and how long a whole run takes.
    // Building a command does its set-up (a merge renders its parts once): both seeds' first,
    // so the timing below is the command's own.
    drop((kind.command)(&out, 0));
    drop((kind.command)(&out, 1));
    let t0 = Instant::now();
    let status = (kind.command)(&out, 0).status().unwrap();
    let whole = t0.elapsed();
    assert!(status.success(), "{}: the first render failed", kind.name);
    (kind.complete)(&out).unwrap_or_else(|e| panic!("{}: first file: {e}", kind.name));
    let mut old = std::fs::read(&out).unwrap();

    let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ u64::from(std::process::id()));
    let (mut kept_old, mut replaced, mut mid_write) = (0, 0, 0);
    for k in 0..KILLS {
        // Every other kill anywhere from the start to a little past the usual end, the others
        // near the end, where a PNG (written only once rendered) is being written.
        let at = whole.mul_f64(if k % 2 == 0 {
            1.1 * rng.unit()
        } else {
            0.8 + 0.25 * rng.unit()
        });
        let mut child = (kind.command)(&out, k as u32 + 1).spawn().unwrap();
        std::thread::sleep(at);
        let _ = child.kill(); // SIGKILL; an error means it had already exited.
        child.wait().unwrap();
        let temps = leftovers(&dir, &out);
        if temps
            .iter()
            .any(|t| std::fs::metadata(t).is_ok_and(|m| m.len() > 0))
        {
            mid_write += 1;
        }
        for t in temps {
            std::fs::remove_file(t).unwrap();
        }
        let now = std::fs::read(&out)
            .unwrap_or_else(|e| panic!("{}: kill {k} at {at:?}: the file is gone: {e}", kind.name));
        if now == old {
            kept_old += 1;
        } else {
            (kind.complete)(&out).unwrap_or_else(|e| {
                panic!(
                    "{}: kill {k} at {at:?} left a partial file ({} bytes): {e}",
                    kind.name,
                    now.len()
                )
            });
            replaced += 1;
            old = now;
        }
    }
    eprintln!(
        "{}: {KILLS} kills over {whole:?} runs: {kept_old} kept the old file, {replaced} found \
         a complete new one, {mid_write} killed a writer mid-file",
        kind.name
    );
    std::fs::remove_dir_all(&dir).unwrap();
    // The kills must have landed before the end (else nothing was tested).
    assert!(
        kept_old > 0,
        "{}: every render finished before its kill",
        kind.name
    );
}

#[test]
fn a_killed_exr_render_leaves_the_old_file_or_a_whole_new_one() {
    kill_while_writing(&KINDS[0]);
}

#[test]
fn a_killed_png_render_leaves_the_old_file_or_a_whole_new_one() {
    kill_while_writing(&KINDS[1]);
}

#[test]
fn a_killed_merge_leaves_the_old_file_or_a_whole_new_one() {
    kill_while_writing(&KINDS[2]);
}

/// `--frames 1..6` killed at random moments twenty times, each time resumed with
/// `--skip-existing`: every frame file is whole or absent after each kill, and the last run
/// renders exactly the frames still missing.
#[test]
fn a_killed_frame_sequence_leaves_whole_frames_and_resumes_where_it_stopped() {
    let dir = std::env::temp_dir().join(format!("aperture-kill-frames-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let pattern = dir.join("shot_##.exr");
    let frame = |f: u32| dir.join(format!("shot_{f:02}.exr"));
    // Not --quiet: the resumed run says which frames it skipped.
    let sequence = || {
        let mut c = Command::new(env!("CARGO_BIN_EXE_aperture"));
        c.arg("render")
            .arg(demo())
            .arg("-o")
            .arg(&pattern)
            .args(EXR_ARGS)
            .args(["--frames", "1..6", "--skip-existing", "--threads", "2"])
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        c
    };
    // One frame's time, to spread the kills over a sequence.
    let t0 = Instant::now();
    let ok = render(EXR_ARGS, &dir.join("probe.exr"), 0)
        .status()
        .unwrap()
        .success();
    assert!(ok);
    let one = t0.elapsed();
    std::fs::remove_file(dir.join("probe.exr")).unwrap();
    let mut rng = Rng(0xD1B5_4A32_D192_ED03 ^ u64::from(std::process::id()));
    let mut seen_partial_sequence = false;
    for k in 0..KILLS {
        let mut child = sequence().spawn().unwrap();
        std::thread::sleep(one.mul_f64(2.5 * rng.unit()));
        let _ = child.kill();
        child.wait().unwrap();
        let mut present = 0;
        for f in 1..=6 {
            if frame(f).exists() {
                present += 1;
                exr_complete(&frame(f))
                    .unwrap_or_else(|e| panic!("kill {k}: frame {f} is partial: {e}"));
            }
        }
        seen_partial_sequence |= present < 6;
        for t in leftovers_matching(&dir, ".shot_") {
            std::fs::remove_file(t).unwrap();
        }
    }
    assert!(
        seen_partial_sequence,
        "every sequence finished before its kill"
    );
    // The resumes above may have finished the sequence: one more from scratch, killed as soon
    // as its first frame is whole (a sleep of two frames' time let a quick sequence finish on
    // a loaded machine), then resumed to the end.
    for f in 1..=6 {
        let _ = std::fs::remove_file(frame(f));
    }
    kill_once_written(sequence().spawn().unwrap(), &frame(1), one.mul_f64(50.0));
    let missing: Vec<u32> = (1..=6).filter(|&f| !frame(f).exists()).collect();
    assert!(
        !missing.is_empty(),
        "the sequence finished past its first frame"
    );
    let out = sequence().output().unwrap();
    assert!(out.status.success());
    let log = String::from_utf8_lossy(&out.stderr);
    let skipped = log.matches("exists, skipped").count();
    eprintln!(
        "frames: after {KILLS} kills, {} missing, {skipped} skipped on resume",
        missing.len()
    );
    assert_eq!(skipped, 6 - missing.len(), "{log}");
    for f in 1..=6 {
        exr_complete(&frame(f)).unwrap();
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Kills `child` as soon as `file` exists (or after `limit`), and waits for it.
fn kill_once_written(mut child: std::process::Child, file: &Path, limit: Duration) {
    let started = Instant::now();
    while !file.exists() && started.elapsed() < limit {
        std::thread::sleep(Duration::from_millis(1));
    }
    let _ = child.kill();
    child.wait().unwrap();
}

/// Temporary files in `dir` whose names start with `prefix`.
fn leftovers_matching(dir: &Path, prefix: &str) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy();
            n.starts_with(prefix) && n.ends_with(".tmp")
        })
        .collect()
}

/// A kill can also land before the first file exists: then there is none, never a partial one.
#[test]
fn a_render_killed_before_its_first_file_leaves_none() {
    let dir = std::env::temp_dir().join(format!("aperture-kill-first-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("first.exr");
    let mut child = exr_render(&out, 0).spawn().unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let _ = child.kill();
    child.wait().unwrap();
    if out.exists() {
        exr_complete(&out).expect("a whole file");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
