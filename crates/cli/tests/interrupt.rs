//! Ctrl-C (SIGINT) during a long render: the process stops promptly with exit code 130; with
//! `--save-partial` the EXR holds the samples taken so far, `Debug Sample Count` saying how
//! many each pixel got and `aperture:interrupted` = 1 in the header; without it, no file.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use aperture_imageio::MetaValue;

fn demo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.glb")
}

/// A render that would take hours: 65536 samples per pixel.
fn long_render(out: &Path, extra: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_aperture"))
        .arg("render")
        .arg(demo())
        .arg("-o")
        .arg(out)
        .args([
            "--width", "96", "--height", "64", "--spp", "65536", "--quiet",
        ])
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("aperture")
}

/// Sends SIGINT once the render has been running a while; returns the exit code, stderr and
/// the seconds from the signal to the exit.
fn interrupt(mut child: Child) -> (Option<i32>, String, f64) {
    std::thread::sleep(Duration::from_millis(2500));
    let sent = Instant::now();
    let ok = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill")
        .success();
    assert!(ok, "the render ended before it was interrupted");
    // Not a timing assertion: a render that ignores the signal would hang the test, so it is
    // killed after a minute and reported.
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if sent.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            panic!("the render did not stop within a minute of SIGINT");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let secs = sent.elapsed().as_secs_f64();
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    eprintln!("stopped {secs:.3} s after SIGINT: {}", err.trim());
    (status.code(), err, secs)
}

fn check_partial(out: &Path) {
    let im = aperture_imageio::read_exr(out).expect("a valid EXR");
    assert_eq!(im.meta("aperture:interrupted"), Some(&MetaValue::Int(1)));
    let counts = &im.layer("Debug Sample Count").expect("sample counts").data;
    assert_eq!(counts.len(), 96 * 64);
    let taken: f64 = counts.iter().map(|&c| f64::from(c)).sum();
    assert!(taken > 0.0, "no sample taken");
    assert!(counts.iter().all(|&c| (0.0..=65536.0).contains(&c)));
    // Interrupted: some pixels did not get all their samples.
    assert!(counts.iter().any(|&c| c < 65536.0));
    // A pixel with samples has a finite, non-negative beauty; one without is black.
    for (p, &c) in im.rgba.iter().zip(counts) {
        assert!(p.iter().all(|v| v.is_finite() && *v >= 0.0), "{p:?}");
        if c == 0.0 {
            assert_eq!(*p, [0.0; 4]);
        }
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("aperture-int-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn sigint_with_save_partial_writes_the_samples_so_far() {
    let dir = temp_dir("partial");
    let out = dir.join("partial.exr");
    let (code, err, _) = interrupt(long_render(&out, &["--save-partial"]));
    assert_eq!(code, Some(130), "{err}");
    assert!(err.contains("--save-partial"), "{err}");
    check_partial(&out);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sigint_during_an_adaptive_render_saves_its_partial_rounds() {
    let dir = temp_dir("adaptive");
    let out = dir.join("adaptive.exr");
    let child = long_render(&out, &["--save-partial", "--noise-threshold", "1e-9"]);
    let (code, err, _) = interrupt(child);
    assert_eq!(code, Some(130), "{err}");
    check_partial(&out);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sigint_without_save_partial_writes_nothing() {
    let dir = temp_dir("nothing");
    let out = dir.join("nothing.exr");
    let (code, err, _) = interrupt(long_render(&out, &[]));
    assert_eq!(code, Some(130), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert!(left.is_empty(), "{left:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
