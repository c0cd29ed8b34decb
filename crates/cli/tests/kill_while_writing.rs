//! SIGKILL at random moments of `aperture render` (loading, rendering, writing): the output
//! path then holds the previous complete file, or a complete new one, never a partial file
//! (SPEC §6: written whole or not at all). Twenty kills per output kind.
//!
//! Kinds covered: EXR (streamed band by band) and PNG. Merged EXRs (`aperture merge`) and
//! frame sequences (`--frames`) are written by the same atomic writer; add a [`Kind`] for each
//! when they land.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const KILLS: usize = 20;

/// One output kind: the arguments that render it and how a complete file is recognised.
struct Kind {
    name: &'static str,
    file: &'static str,
    args: &'static [&'static str],
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

const KINDS: &[Kind] = &[
    Kind {
        name: "EXR",
        file: "out.exr",
        args: &[
            "--width",
            "768",
            "--height",
            "512",
            "--spp",
            "1",
            "--max-bounces",
            "0",
        ],
        complete: exr_complete,
    },
    Kind {
        name: "PNG",
        file: "out.png",
        args: &[
            "--width",
            "1024",
            "--height",
            "768",
            "--spp",
            "1",
            "--max-bounces",
            "0",
        ],
        complete: png_complete,
    },
];

fn demo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.glb")
}

fn render(kind: &Kind, out: &Path, seed: u32) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_aperture"));
    c.arg("render")
        .arg(demo())
        .arg("-o")
        .arg(out)
        .args(kind.args)
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
        kind.name,
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join(kind.file);
    // A complete file first, and how long a whole run takes.
    let t0 = Instant::now();
    let status = render(kind, &out, 0).status().unwrap();
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
        let mut child = render(kind, &out, k as u32 + 1).spawn().unwrap();
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

/// A kill can also land before the first file exists: then there is none, never a partial one.
#[test]
fn a_render_killed_before_its_first_file_leaves_none() {
    let dir = std::env::temp_dir().join(format!("aperture-kill-first-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("first.exr");
    let mut child = render(&KINDS[0], &out, 0).spawn().unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let _ = child.kill();
    child.wait().unwrap();
    if out.exists() {
        exr_complete(&out).expect("a whole file");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
