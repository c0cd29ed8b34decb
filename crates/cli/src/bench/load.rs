//! `aperture bench --configs load`: the time from the file to the first samples, by stage,
//! over `--repeats` fresh loads (issue 59), and the process's peak memory. Nothing is kept
//! from one load to the next; no error is measured.

use super::{image_size, median, BenchArgs};
use crate::bench_results::write_atomic;
use anyhow::Context as _;
use aperture_render::{FrameSpec, RenderOptions, Session};
use aperture_scene::LoadOptions;
use std::time::Instant;

/// One fresh load, in seconds from its start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct LoadTimes {
    /// The file read, decoded and posed (`Session::load` and `pose`).
    pub load: f64,
    /// Then the BVH built (`Session::frame`).
    pub bvh: f64,
    /// Then one sample a pixel rendered at the bench's size: the first samples.
    pub first_samples: f64,
}

/// Loads `args.scene` `--repeats` times (each load dropped before the next), rendering one
/// sample a pixel after each at the size the other configurations render.
pub(super) fn measure_loads(args: &BenchArgs) -> anyhow::Result<Vec<LoadTimes>> {
    let mut out = Vec::new();
    for _ in 0..args.repeats {
        let t0 = Instant::now();
        let mut session = Session::load(&args.scene, &LoadOptions::default())
            .with_context(|| format!("loading {}", args.scene.display()))?;
        let scene = session.pose(None)?;
        let cam = scene.cameras.first().context("the scene has no camera")?;
        let (width, height) = image_size(args, cam, None)?;
        let opts = RenderOptions {
            width,
            height,
            spp: 1,
            seed: args.seed,
            ..RenderOptions::default()
        };
        let load = t0.elapsed().as_secs_f64();
        let frame = session.frame(&FrameSpec::default())?;
        let bvh = t0.elapsed().as_secs_f64();
        frame.render(&opts, &|_, _| {})?;
        let first_samples = t0.elapsed().as_secs_f64();
        drop(session);
        out.push(LoadTimes {
            load,
            bvh: bvh - load,
            first_samples,
        });
    }
    Ok(out)
}

/// `load.csv`: a header, then one line per load.
pub(super) fn loads_csv(rows: &[LoadTimes]) -> String {
    let mut s = String::from("repeat,load_s,bvh_s,first_samples_s\n");
    for (i, r) in rows.iter().enumerate() {
        s += &format!("{i},{:.4},{:.4},{:.4}\n", r.load, r.bvh, r.first_samples);
    }
    s
}

/// The medians of `rows` as one line, with the process's peak memory when known.
pub(super) fn loads_line(rows: &[LoadTimes], peak: Option<u64>) -> String {
    let col = |f: fn(&LoadTimes) -> f64| median(&mut rows.iter().map(f).collect::<Vec<_>>());
    let mut line = format!(
        "load (median of {}): read, decode and pose {:.3} s, BVH {:.3} s, first samples at {:.3} s",
        rows.len(),
        col(|r| r.load),
        col(|r| r.bvh),
        col(|r| r.first_samples)
    );
    if let Some(b) = peak {
        line += &format!(", peak memory {}", aperture_budget::human_bytes(b));
    }
    line
}

/// Measures the loads, writes `DIR/load.csv` and prints the medians (the peak memory is the
/// process's so far: run before anything else is loaded, it is the loads').
pub(super) fn run_loads(args: &BenchArgs) -> anyhow::Result<()> {
    let rows = measure_loads(args)?;
    let csv = args.output.join("load.csv");
    write_atomic(&csv, loads_csv(&rows).as_bytes())?;
    println!(
        "{}",
        loads_line(&rows, aperture_budget::peak_resident_bytes())
    );
    println!("Wrote {}.", csv.display());
    Ok(())
}
