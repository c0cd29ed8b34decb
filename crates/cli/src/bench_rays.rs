//! `aperture bench-rays`: closest-hit and occlusion throughput of each BVH preset on ray sets
//! made from the scene's thin-lens camera (and on given ray files), one ray at a time and
//! batched, on one thread and on all. The sets and the timing are the library's
//! (`aperture_raybench`); this file maps the arguments, prints the table and writes
//! `bench-rays.csv` and `bench-rays.png`.

use crate::number_args::{non_negative_f32, positive_f32};
use crate::plot::{draw_legend, load_font, write_png, PALETTE};
use anyhow::{bail, Context as _};
use aperture_accel::BvhQuality;
use aperture_raybench::{
    estimated_bytes, generate_sets, load_set, save_sets, time_sets, Mode, QualityRun, RaySet,
    RaySetOptions, Timing, TimingOptions,
};
use aperture_render::Camera;
use aperture_render::{Frame, FrameSpec, Session};
use aperture_scene::{DofOverrides, LoadOptions};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `aperture bench-rays`.
#[derive(clap::Args, Debug)]
pub struct BenchRaysArgs {
    /// The .gltf or .glb file.
    pub scene: PathBuf,
    /// Lens samples per pixel of the primary sets (consecutive per pixel).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub lens_samples: u32,
    /// Image width in pixels.
    #[arg(long, default_value_t = 320, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub width: u32,
    /// Image height in pixels [default: from the width and the camera's aspect ratio].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub height: Option<u32>,
    /// The camera, by name or index [default: the first].
    #[arg(long)]
    pub camera: Option<String>,
    /// Lens radius in scene units, overriding the file's (and turning depth of field on): for
    /// scenes whose camera is a pinhole, whose lens samples would all start at one point.
    #[arg(long, value_parser = non_negative_f32)]
    pub aperture_radius: Option<f32>,
    /// Focus distance in scene units, overriding the file's.
    #[arg(long, value_parser = positive_f32)]
    pub focus_distance: Option<f32>,
    /// Seed of the sample values and of the random order.
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// BVH presets to build and time, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "fast,medium,high",
          value_parser = parse_quality)]
    pub bvh_quality: Vec<BvhQuality>,
    /// Threads of the "all threads" runs [default: all cores]; every query also runs on one.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
    /// Timed runs per measurement; the median is reported (with the least and most).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeats: u32,
    /// Write each generated set as DIR/<set>.rays (the Embree anchor's format; shadow rays'
    /// finite tmax goes to DIR/shadow.tmax, which only aperture reads).
    #[arg(long, value_name = "DIR")]
    pub save_rays: Option<PathBuf>,
    /// A ray file to time as well (repeatable); its set is named after the file's stem.
    #[arg(long, value_name = "FILE")]
    pub rays: Vec<PathBuf>,
    /// Time only the --rays files, not the generated sets.
    #[arg(long, requires = "rays")]
    pub no_generated: bool,
    /// Output folder for bench-rays.csv and bench-rays.png (created if missing).
    #[arg(short, long, value_name = "DIR")]
    pub output: Option<PathBuf>,
}

fn parse_quality(s: &str) -> Result<BvhQuality, String> {
    s.parse()
        .map_err(|e: aperture_accel::ParseBvhQualityError| e.to_string())
}

/// Runs `aperture bench-rays`.
pub fn run(args: BenchRaysArgs) -> anyhow::Result<()> {
    let load = LoadOptions {
        dof_overrides: DofOverrides {
            aperture_radius: args.aperture_radius,
            focus_distance: args.focus_distance,
            ..DofOverrides::default()
        },
        ..LoadOptions::default()
    };
    let mut session = Session::load(&args.scene, &load)
        .with_context(|| format!("loading {}", args.scene.display()))?;
    let mut sets = Vec::new();
    if !args.no_generated {
        // One structure finds the first hits; every preset then times the same rays.
        let spec = FrameSpec {
            quality: BvhQuality::Medium,
            ..FrameSpec::default()
        };
        sets = generated_sets(&args, session.frame(&spec)?)?;
    }
    let scene = session.pose(None)?;
    for path in &args.rays {
        check_ray_file_fits(path)?;
        sets.push(load_set(path)?);
    }
    if sets.is_empty() {
        bail!("no rays to time");
    }
    let all = args.threads.map_or_else(
        || std::thread::available_parallelism().map_or(1, |n| n.get()),
        |t| t as usize,
    );
    let mut thread_counts = vec![1];
    if all > 1 {
        thread_counts.push(all);
    }
    let opts = TimingOptions {
        qualities: args.bvh_quality.clone(),
        thread_counts,
        repeats: args.repeats,
    };
    let runs = time_sets(scene, &sets, &opts, &mut |q, t| {
        eprintln!(
            "{q} {} {} {} {}t: {:.3} Mrays/s",
            t.set,
            t.query.name(),
            t.mode.name(),
            t.threads,
            t.mrays_median
        )
    })?;
    let scene_name = args
        .scene
        .file_name()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    print!("{}", table(&runs, args.repeats));
    if let Some(dir) = &args.output {
        write_outputs(dir, &scene_name, &runs)?;
    }
    Ok(())
}

/// Refuses a ray file whose rays (read, then timed with their answers) would not fit in memory.
fn check_ray_file_fits(path: &Path) -> anyhow::Result<()> {
    // Missing files are reported by the reader, naming the file.
    let Ok(meta) = std::fs::metadata(path) else {
        return Ok(());
    };
    let rays = meta.len() / aperture_accel::rayfile::RAY_RECORD_BYTES as u64;
    // The file's bytes, the rays, then one closest-hit answer and one occlusion answer each.
    let needed = meta.len().saturating_add(rays.saturating_mul(32 + 24 + 1));
    aperture_budget::MemoryBudget::from_system()
        .check(&format!("timing the rays of {}", path.display()), needed)?;
    Ok(())
}

/// The four generated sets for the arguments' camera and image, saved when asked.
fn generated_sets(args: &BenchRaysArgs, frame: &Frame) -> anyhow::Result<Vec<RaySet>> {
    let scene = frame.scene();
    let index = match &args.camera {
        Some(c) => crate::render_opts::find_camera(c, scene).map_err(anyhow::Error::msg)?,
        None => 0,
    };
    let Some(cam) = scene.cameras.get(index) else {
        bail!("{} has no camera", args.scene.display());
    };
    let height = args
        .height
        .unwrap_or_else(|| aperture_render::default_height(cam, args.width));
    let camera = Camera::new(cam, args.width, height);
    if camera.aperture.radius() == 0.0 {
        eprintln!(
            "warning: camera {:?} is a pinhole (depth of field off): its lens samples all start \
             at its centre; --aperture-radius R gives it a lens",
            cam.name
        );
    }
    let opts = RaySetOptions {
        lens_samples: args.lens_samples,
        seed: args.seed,
    };
    aperture_budget::MemoryBudget::from_system().check_with_hint(
        &format!(
            "the ray sets of a {}x{height} image with {} lens samples",
            args.width, args.lens_samples
        ),
        estimated_bytes(&camera, &opts),
        "; lower --width, --height or --lens-samples",
    )?;
    let sets = generate_sets(scene, frame.accel(), &camera, &opts);
    eprintln!(
        "{}x{height}, {} lens samples: {}",
        args.width,
        args.lens_samples,
        sets.iter()
            .map(|s| format!("{} {} rays", s.name, s.rays.len()))
            .collect::<Vec<_>>()
            .join(", ")
    );
    if let Some(dir) = &args.save_rays {
        let files = save_sets(dir, &sets)?;
        eprintln!("wrote {} ray files to {}", files.len(), dir.display());
    }
    Ok(sets)
}

/// The table on stdout: per preset its build, then one line per measurement.
fn table(runs: &[QualityRun], repeats: u32) -> String {
    let mut s = String::new();
    for run in runs {
        let _ = writeln!(
            s,
            "\n{}: build {:.3} s, {:.1} MB (Mrays/s: median [min max] of {repeats})",
            run.quality,
            run.build_seconds,
            run.memory_bytes as f64 / 1e6
        );
        let _ = writeln!(
            s,
            "{:<16} {:<9} {:<8} {:>3} {:>9} {:>9} {:>9} {:>19}",
            "set", "query", "mode", "thr", "rays", "hits", "median", "[min max]"
        );
        for t in &run.timings {
            let _ = writeln!(
                s,
                "{:<16} {:<9} {:<8} {:>3} {:>9} {:>9} {:>9.3} [{:>8.3} {:>8.3}]",
                t.set,
                t.query.name(),
                t.mode.name(),
                t.threads,
                t.rays,
                t.hits,
                t.mrays_median,
                t.mrays_min,
                t.mrays_max
            );
        }
    }
    s
}

const CSV_HEADER: &str = "scene,quality,set,query,mode,threads,rays,hits,mrays_median,mrays_min,mrays_max,build_seconds,memory_bytes";

/// `bench-rays.csv`: one line per (quality, set, query, mode, threads).
fn to_csv(scene: &str, runs: &[QualityRun]) -> String {
    let mut s = format!("{CSV_HEADER}\n");
    let scene = scene.replace([',', '\n'], "_");
    for run in runs {
        for t in &run.timings {
            let _ = writeln!(
                s,
                "{scene},{},{},{},{},{},{},{},{:.4},{:.4},{:.4},{:.6},{}",
                run.quality,
                t.set.replace([',', '\n'], "_"),
                t.query.name(),
                t.mode.name(),
                t.threads,
                t.rays,
                t.hits,
                t.mrays_median,
                t.mrays_min,
                t.mrays_max,
                run.build_seconds,
                run.memory_bytes
            );
        }
    }
    s
}

fn write_outputs(dir: &Path, scene: &str, runs: &[QualityRun]) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let csv = dir.join("bench-rays.csv");
    let tmp = dir.join("bench-rays.csv.tmp");
    std::fs::write(&tmp, to_csv(scene, runs))
        .with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, &csv).with_context(|| format!("writing {}", csv.display()))?;
    let png = dir.join("bench-rays.png");
    if !load_font() {
        bail!(
            "no TrueType font found for the plot's labels (set APERTURE_FONT to a .ttf file); \
             {} written, {} not",
            csv.display(),
            png.display()
        );
    }
    write_png(&png, (1500, 640), |root| plot(root, scene, runs))?;
    eprintln!("wrote {} and {}", csv.display(), png.display());
    Ok(())
}

/// Two panels (one ray at a time, batched): Mrays/s per (set, query), one line per (preset,
/// threads).
fn plot<DB: plotters::prelude::DrawingBackend>(
    root: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    scene: &str,
    runs: &[QualityRun],
) -> anyhow::Result<()> {
    use plotters::prelude::*;
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow::anyhow!("plotting: {e}");
    root.fill(&WHITE).map_err(err)?;
    let root = root
        .titled(&format!("Ray queries: {scene}"), ("sans-serif", 24))
        .map_err(err)?;
    let categories = categories(runs);
    let top = runs
        .iter()
        .flat_map(|r| &r.timings)
        .map(|t| t.mrays_median)
        .fold(0.0, f64::max)
        .max(1e-3)
        * 1.1;
    for (panel, mode) in root
        .split_evenly((1, Mode::ALL.len()))
        .iter()
        .zip(Mode::ALL)
    {
        let mut chart = ChartBuilder::on(panel)
            .caption(mode.name(), ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(50)
            .y_label_area_size(60)
            .build_cartesian_2d(-0.5..categories.len() as f64 - 0.5, 0.0..top)
            .map_err(err)?;
        let label = |v: &f64| {
            let i = v.round();
            if (v - i).abs() < 1e-6 && i >= 0.0 {
                categories.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        };
        chart
            .configure_mesh()
            .x_labels(categories.len().max(1))
            .x_label_formatter(&label)
            .x_label_style(("sans-serif", 12))
            .x_desc("set / query")
            .y_max_light_lines(1)
            .y_desc("Mrays/s (median)")
            .axis_desc_style(("sans-serif", 16))
            .disable_x_mesh()
            .draw()
            .map_err(err)?;
        for (k, (name, pts)) in series(runs, mode, &categories).into_iter().enumerate() {
            let color = PALETTE[k % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                .map_err(err)?
                .label(name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
                .map_err(err)?;
        }
        draw_legend(&mut chart, 13).map_err(err)?;
    }
    Ok(())
}

/// The x axis: `set/query` in the order first measured.
fn categories(runs: &[QualityRun]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for t in runs.iter().flat_map(|r| &r.timings) {
        let c = category(t);
        if !out.contains(&c) {
            out.push(c);
        }
    }
    out
}

/// `set/query`, short enough to sit under its tick: the generated sets lose `primary_`,
/// queries are `cl` and `occ`.
fn category(t: &Timing) -> String {
    let set = t.set.strip_prefix("primary_").unwrap_or(&t.set);
    let query = match t.query {
        aperture_raybench::Query::Closest => "cl",
        aperture_raybench::Query::Occluded => "occ",
    };
    format!("{set}/{query}")
}

/// One line per (preset, threads) of `mode`: (category index, median Mrays/s).
fn series(
    runs: &[QualityRun],
    mode: Mode,
    categories: &[String],
) -> Vec<(String, Vec<(f64, f64)>)> {
    let mut out: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for run in runs {
        for t in run.timings.iter().filter(|t| t.mode == mode) {
            let name = format!("{} {}t", run.quality, t.threads);
            let x = categories
                .iter()
                .position(|c| *c == category(t))
                .unwrap_or(0) as f64;
            match out.iter_mut().find(|(n, _)| *n == name) {
                Some((_, pts)) => pts.push((x, t.mrays_median)),
                None => out.push((name, vec![(x, t.mrays_median)])),
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use aperture_raybench::Query;

    fn timing(set: &str, query: Query, mode: Mode, threads: usize, m: f64) -> Timing {
        Timing {
            set: set.into(),
            query,
            mode,
            threads,
            rays: 10,
            hits: 4,
            mrays_median: m,
            mrays_min: m - 1.0,
            mrays_max: m + 1.0,
        }
    }

    fn runs() -> Vec<QualityRun> {
        let timings = vec![
            timing("primary_tile", Query::Closest, Mode::OneRay, 1, 3.0),
            timing("primary_tile", Query::Closest, Mode::Batch, 1, 4.0),
            timing("shadow", Query::Occluded, Mode::Batch, 2, 9.0),
        ];
        vec![QualityRun {
            quality: BvhQuality::Fast,
            build_seconds: 0.25,
            memory_bytes: 1000,
            timings,
        }]
    }

    #[test]
    fn csv_has_a_line_per_measurement() {
        let csv = to_csv("a,b.glb", &runs());
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], CSV_HEADER);
        assert_eq!(
            lines[1],
            "a_b.glb,fast,primary_tile,closest,one-ray,1,10,4,3.0000,2.0000,4.0000,0.250000,1000"
        );
        assert_eq!(lines.len(), 4);
        assert!(lines[3].starts_with("a_b.glb,fast,shadow,occluded,batch,2,"));
    }

    #[test]
    fn plot_series_are_per_quality_and_threads() {
        let r = runs();
        let cats = categories(&r);
        assert_eq!(cats, ["tile/cl", "shadow/occ"]);
        let batch = series(&r, Mode::Batch, &cats);
        assert_eq!(
            batch,
            vec![
                ("fast 1t".to_string(), vec![(0.0, 4.0)]),
                ("fast 2t".to_string(), vec![(1.0, 9.0)])
            ]
        );
    }

    #[test]
    fn qualities_parse() {
        assert_eq!(parse_quality("HIGH"), Ok(BvhQuality::High));
        assert!(parse_quality("best").unwrap_err().contains("best"));
    }
}
