//! `aperture bench`: error against time for several sampler configurations.
//!
//! Renders a scene at each sample budget with each configuration, times the render (wall time of
//! the render alone: the scene is loaded and the BVH built once, before any timing), measures the
//! error against a reference (RMSE, relative MSE, mean absolute error, LDR FLIP) and writes
//! `DIR/results.csv`, a log-log plot of relative MSE against time (`DIR/error_vs_time.svg` and
//! `.png`) and a table on stdout. Without `--reference` it first renders one at high spp, with
//! another seed so its noise is independent of the runs', and saves it as `DIR/reference.exr`.
//!
//! `--series FILE.csv[:LABEL]` adds curves measured elsewhere (another renderer, an earlier run)
//! to the plot, the table and the time-to-error comparison. Their format is `results.csv`'s: a
//! header line, then one line per render; columns are found by name, `seconds` and `rel_mse`
//! are required, `config`, `spp`, `mean_spp`, `rmse`, `mae` and `flip` are read when present
//! (empty = unknown), any other column is ignored.

use crate::plot::{load_font, tick_label, write_png, PALETTE};
use crate::render_args::TracingArgs;
use anyhow::{bail, Context as _};
use aperture_imageio::{metrics, Image};
use aperture_render::{AdaptiveOptions, RenderOptions, SamplerKind};
use aperture_scene::LoadOptions;
use clap::ValueEnum;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One sampling configuration of `--configs`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Config {
    /// Owen-scrambled Sobol, every pixel at the budget.
    Sobol,
    /// Independent random numbers, every pixel at the budget.
    Random,
    /// Sobol with adaptive sampling: the budget is the most a pixel takes, the noise threshold
    /// follows it (`--adaptive-scale / √spp`).
    Adaptive,
}

impl Config {
    fn name(self) -> &'static str {
        match self {
            Self::Sobol => "sobol",
            Self::Random => "random",
            Self::Adaptive => "adaptive",
        }
    }
}

/// Arguments of `aperture bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// The .gltf or .glb file.
    pub scene: PathBuf,
    /// Reference image (EXR, same size as the renders) [default: render one at --reference-spp].
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Sample budgets, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16,32,64,128",
          value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub spp: Vec<u32>,
    /// Configurations, comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        value_enum,
        default_value = "sobol,random,adaptive"
    )]
    pub configs: Vec<Config>,
    /// Output folder (created if missing).
    #[arg(short, long, default_value = "bench-out")]
    pub output: PathBuf,
    /// Image width [default: the reference's, else 320].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub width: Option<u32>,
    /// Image height [default: the reference's, else from the width and the camera's aspect].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub height: Option<u32>,
    /// Samples per pixel of the reference rendered when --reference is not given.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub reference_spp: u32,
    /// Seed of the timed renders (the reference uses another).
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// The adaptive configuration's noise threshold at budget N is this / √N (on the demo
    /// scene 4 and 6 gave the lowest error-against-time curves, 2 a slower one).
    #[arg(long, default_value_t = 4.0)]
    pub adaptive_scale: f32,
    /// Relative MSEs at which to compare the series' times (interpolated in log-log), comma
    /// separated.
    #[arg(long, value_delimiter = ',', default_value = "1e-3", value_parser = positive_f64)]
    pub target_rel_mse: Vec<f64>,
    /// Worker threads [default: all cores].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
    /// Renders per configuration and budget; the time reported is their median.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100))]
    pub repeats: u32,
    /// Bounces, clamps and pixel filter, as `aperture render` takes them, for every render
    /// (the generated reference included: a given --reference must use the same clamps).
    #[command(flatten)]
    pub tracing: TracingArgs,
    /// An extra series to plot and compare, as FILE.csv or FILE.csv:LABEL (repeatable). The
    /// file has `results.csv`'s columns; without LABEL its `config` column names the curves.
    #[arg(long, value_parser = parse_series)]
    pub series: Vec<SeriesArg>,
}

/// One `--series` argument.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SeriesArg {
    /// The CSV file.
    pub path: PathBuf,
    /// The curve's name; `None`: the file's `config` column (else the file's stem).
    pub label: Option<String>,
}

/// `FILE.csv[:LABEL]`. A colon followed by a path separator is part of the path (`C:\x.csv`).
fn parse_series(s: &str) -> Result<SeriesArg, String> {
    let (path, label) = match s.rsplit_once(':') {
        Some((p, l)) if !l.contains(['/', '\\']) => (p, Some(l)),
        _ => (s, None),
    };
    if path.is_empty() {
        return Err("empty file name".into());
    }
    if label.is_some_and(|l| l.trim().is_empty() || l.contains(',')) {
        return Err(format!("bad label in {s:?}: empty or with a comma"));
    }
    Ok(SeriesArg {
        path: PathBuf::from(path),
        label: label.map(str::to_string),
    })
}

fn positive_f64(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("{s:?} is not a positive number")),
    }
}

/// One measured render (ours, or a line of a `--series` file, whose unknown values are NaN).
#[derive(Debug, Clone)]
struct Row {
    label: String,
    spp: u32,
    seconds: f64,
    samples: u64,
    mean_spp: f64,
    rmse: f64,
    rel_mse: f64,
    mae: f64,
    flip: f64,
}

/// Runs `aperture bench`.
pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    let scene = aperture_scene::load(&args.scene, &LoadOptions::default())
        .with_context(|| format!("loading {}", args.scene.display()))?;
    let Some(cam) = scene.cameras.first() else {
        bail!("{} has no camera", args.scene.display());
    };
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("creating {}", args.output.display()))?;
    let reference = match &args.reference {
        Some(p) => Some(
            aperture_imageio::read_exr(p)
                .with_context(|| format!("reading the reference {}", p.display()))?,
        ),
        None => None,
    };
    let width = args
        .width
        .or(reference.as_ref().map(|r| r.width))
        .unwrap_or(320);
    let height = args
        .height
        .or(reference.as_ref().map(|r| r.height))
        .unwrap_or_else(|| aperture_render::default_height(cam, width));
    if let Some(r) = &reference {
        if (r.width, r.height) != (width, height) {
            bail!(
                "the reference is {}x{} but the renders would be {width}x{height}",
                r.width,
                r.height
            );
        }
    }
    let pool = {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(t) = args.threads {
            b = b.num_threads(t as usize);
        }
        b.build().context("starting worker threads")?
    };
    let threads = pool.current_num_threads();
    let clamp = args.tracing.clamp();
    let clamped = clamp != aperture_render::Clamp::OFF;
    if clamped {
        println!(
            "Clamping samples (direct {}, indirect {}; 0 = off): errors are against the clamped \
             estimator, so a --reference must use the same clamps.",
            clamp.direct, clamp.indirect
        );
    }
    // Read before rendering, so a bad file fails at once.
    let mut extra = Vec::new();
    for s in &args.series {
        extra.extend(read_series(s)?);
    }
    let base = RenderOptions {
        width,
        height,
        seed: args.seed,
        max_bounces: args.tracing.max_bounces,
        filter: args.tracing.filter.into(),
        clamp,
        ..RenderOptions::default()
    };
    let rows = pool.install(|| -> anyhow::Result<Vec<Row>> {
        let accel = aperture_render::build_accel(&scene, aperture_accel::BvhQuality::default());
        let reference = match reference {
            Some(r) => r,
            None => {
                let opts = RenderOptions {
                    spp: args.reference_spp,
                    seed: args.seed.wrapping_add(0x5eed),
                    ..base.clone()
                };
                println!(
                    "No --reference given: rendering one at {} spp ({width}x{height}) first.",
                    opts.spp
                );
                let t0 = Instant::now();
                let film = aperture_render::render(&scene, &accel, &opts, &|_, _| {})?;
                let secs = t0.elapsed().as_secs_f64();
                let image = aperture_output::film_to_image(&film, &scene, &opts, false, secs)?;
                let path = args.output.join("reference.exr");
                aperture_imageio::write_image(&path, &image, &Default::default())
                    .with_context(|| format!("writing {}", path.display()))?;
                println!(
                    "Reference: {:.1} s, saved as {} (pass it with --reference next time).",
                    secs,
                    path.display()
                );
                image
            }
        };
        let mut rows = Vec::new();
        for &config in &args.configs {
            for &spp in &args.spp {
                let opts = RenderOptions {
                    spp,
                    sampler: match config {
                        Config::Random => SamplerKind::Random,
                        Config::Sobol | Config::Adaptive => SamplerKind::Sobol,
                    },
                    adaptive: (config == Config::Adaptive).then(|| AdaptiveOptions {
                        threshold: args.adaptive_scale / (spp as f32).sqrt(),
                        min_spp: AdaptiveOptions::auto_min_spp(spp),
                    }),
                    ..base.clone()
                };
                // Same seed each time, so the image (and its error) is the same: only the time,
                // disturbed by whatever else the machine runs, varies.
                let mut times = Vec::new();
                let mut film = None;
                for _ in 0..args.repeats {
                    let t0 = Instant::now();
                    film = Some(aperture_render::render(&scene, &accel, &opts, &|_, _| {})?);
                    times.push(t0.elapsed().as_secs_f64());
                }
                let film = film.context("no render (--repeats 0)")?;
                let seconds = median(&mut times);
                let mut image = Image::new(width, height);
                image.rgba = film.to_rgba();
                let samples = film.total_samples();
                let row = Row {
                    label: config.name().to_string(),
                    spp,
                    seconds,
                    samples,
                    mean_spp: samples as f64 / (width as f64 * height as f64),
                    rmse: metrics::rmse(&image, &reference)?,
                    rel_mse: metrics::relative_mse(&image, &reference)?,
                    mae: metrics::mae(&image, &reference)?,
                    flip: metrics::flip(&image, &reference)?,
                };
                eprintln!(
                    "{:>8} {:>6} spp: {:>8.3} s, relMSE {:.3e}",
                    config.name(),
                    spp,
                    seconds,
                    row.rel_mse
                );
                rows.push(row);
            }
        }
        Ok(rows)
    })?;

    let csv = args.output.join("results.csv");
    write_atomic(&csv, to_csv(&rows, width, height, threads).as_bytes())?;
    let mut title = format!(
        "{} at {width}x{height}, {threads} threads",
        args.scene
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    // A clamped run measures another (biased) estimator; the picture must say so.
    if clamped {
        title += &format!(", clamp {}/{}", clamp.direct, clamp.indirect);
    }
    let svg = args.output.join("error_vs_time.svg");
    let png = args.output.join("error_vs_time.png");
    let all: Vec<Row> = rows.iter().chain(&extra).cloned().collect();
    print!("{}", table(&all));
    let series = rows_to_series(&all);
    plot_error_vs_time(&series, &title, &svg, &png)?;
    println!();
    print!("{}", time_to_error_table(&series, &args.target_rel_mse));
    let target = args.target_rel_mse[0];
    let find = |name: &str| {
        series
            .iter()
            .find(|(n, _)| n == name)
            .and_then(|(_, p)| interpolate_time(p, target))
    };
    if let (Some(u), Some(a)) = (find("sobol"), find("adaptive")) {
        println!(
            "adaptive / uniform Sobol time to relative MSE {target:.0e}: {:.2}",
            a / u
        );
    }
    println!(
        "Wrote {}, {} and {}. Times are wall-clock on a machine that may be shared: compare \
         configurations within one run.",
        csv.display(),
        svg.display(),
        png.display()
    );
    Ok(())
}

/// Median of a non-empty list (the mean of the middle two for an even length).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}

const CSV_HEADER: &str =
    "config,spp,width,height,threads,seconds,samples,mean_spp,rmse,rel_mse,mae,flip";

fn to_csv(rows: &[Row], width: u32, height: u32, threads: usize) -> String {
    let mut s = format!("{CSV_HEADER}\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{width},{height},{threads},{:.6},{},{:.3},{:.6e},{:.6e},{:.6e},{:.6e}",
            r.label, r.spp, r.seconds, r.samples, r.mean_spp, r.rmse, r.rel_mse, r.mae, r.flip
        );
    }
    s
}

/// Reads a `--series` file (see the module documentation for the format).
fn read_series(arg: &SeriesArg) -> anyhow::Result<Vec<Row>> {
    let text = std::fs::read_to_string(&arg.path)
        .with_context(|| format!("reading the series {}", arg.path.display()))?;
    parse_series_csv(&text, arg.label.as_deref(), &arg.path)
        .with_context(|| format!("in the series {}", arg.path.display()))
}

fn parse_series_csv(text: &str, label: Option<&str>, path: &Path) -> anyhow::Result<Vec<Row>> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        bail!("empty file");
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let col = |name: &str| names.iter().position(|&n| n == name);
    let (Some(seconds_col), Some(rel_mse_col)) = (col("seconds"), col("rel_mse")) else {
        bail!("the header has no `seconds` or no `rel_mse` column: {header:?}");
    };
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "series".into());
    let mut rows = Vec::new();
    for (i, line) in lines {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != names.len() {
            bail!(
                "line {}: {} fields, the header has {}",
                i + 1,
                fields.len(),
                names.len()
            );
        }
        let number = |c: Option<usize>| -> anyhow::Result<f64> {
            match c.map(|c| fields[c]) {
                None | Some("") => Ok(f64::NAN),
                Some(f) => f
                    .parse::<f64>()
                    .with_context(|| format!("line {}: {f:?} is not a number", i + 1)),
            }
        };
        let seconds = number(Some(seconds_col))?;
        let rel_mse = number(Some(rel_mse_col))?;
        if !(seconds.is_finite() && seconds > 0.0 && rel_mse.is_finite() && rel_mse >= 0.0) {
            bail!(
                "line {}: seconds must be positive and rel_mse a number ≥ 0",
                i + 1
            );
        }
        let spp = number(col("spp"))?;
        let samples = number(col("samples"))?;
        rows.push(Row {
            label: match (label, col("config")) {
                (Some(l), _) => l.to_string(),
                (None, Some(c)) if !fields[c].is_empty() => fields[c].to_string(),
                _ => stem.clone(),
            },
            spp: if spp.is_finite() { spp as u32 } else { 0 },
            seconds,
            samples: if samples.is_finite() {
                samples as u64
            } else {
                0
            },
            mean_spp: number(col("mean_spp"))?,
            rmse: number(col("rmse"))?,
            rel_mse,
            mae: number(col("mae"))?,
            flip: number(col("flip"))?,
        });
    }
    if rows.is_empty() {
        bail!("no data lines");
    }
    Ok(rows)
}

/// `v` in the table's format, "-" when unknown (NaN: a value a series file did not give).
fn cell(v: f64, fmt: impl Fn(f64) -> String) -> String {
    if v.is_nan() {
        "-".to_string()
    } else {
        fmt(v)
    }
}

fn table(rows: &[Row]) -> String {
    let mut s = format!(
        "{:<12} {:>6} {:>9} {:>9} {:>11} {:>11} {:>11} {:>8}\n",
        "config", "spp", "mean spp", "time (s)", "RMSE", "rel. MSE", "MAE", "FLIP"
    );
    let e = |v: f64| cell(v, |v| format!("{v:.4e}"));
    for r in rows {
        let _ = writeln!(
            s,
            "{:<12} {:>6} {:>9} {:>9.3} {:>11} {:>11} {:>11} {:>8}",
            r.label,
            r.spp,
            cell(r.mean_spp, |v| format!("{v:.1}")),
            r.seconds,
            e(r.rmse),
            e(r.rel_mse),
            e(r.mae),
            cell(r.flip, |v| format!("{v:.4}"))
        );
    }
    s
}

/// One curve per label, in order of first appearance, points in row order.
fn rows_to_series(rows: &[Row]) -> Series {
    let mut series: Series = Vec::new();
    for r in rows {
        let point = (r.seconds, r.rel_mse);
        match series.iter_mut().find(|(n, _)| *n == r.label) {
            Some((_, p)) => p.push(point),
            None => series.push((r.label.clone(), vec![point])),
        }
    }
    series
}

/// Time of each series to each target error, and its ratio to the first series' time.
fn time_to_error_table(series: &Series, targets: &[f64]) -> String {
    let mut s = format!("{:<12}", "time to");
    for t in targets {
        let _ = write!(s, " {:>20}", format!("rel. MSE {t:.0e}"));
    }
    s.push('\n');
    let first: Vec<Option<f64>> = targets
        .iter()
        .map(|&t| series.first().and_then(|(_, p)| interpolate_time(p, t)))
        .collect();
    for (name, p) in series {
        let _ = write!(s, "{name:<12}");
        for (&t, f) in targets.iter().zip(&first) {
            let text = match (interpolate_time(p, t), f) {
                (Some(x), Some(f)) => format!("{x:.3} s ({:.2}x)", x / f),
                (Some(x), None) => format!("{x:.3} s"),
                (None, _) => "not reached".to_string(),
            };
            let _ = write!(s, " {text:>20}");
        }
        s.push('\n');
    }
    let _ = writeln!(
        s,
        "(interpolated in log-log between budgets; (Nx): time / {}'s time)",
        series.first().map_or("-", |(n, _)| n.as_str())
    );
    s
}

/// The time at which a curve's relative MSE first falls to `target`, interpolated linearly in
/// log(time)–log(error) between the two budgets around it.
fn interpolate_time(pts: &[(f64, f64)], target: f64) -> Option<f64> {
    let first = pts.first()?;
    if first.1 <= target {
        return Some(first.0);
    }
    pts.windows(2).find_map(|w| {
        let ((t0, e0), (t1, e1)) = (w[0], w[1]);
        (e0 > target && e1 <= target).then(|| {
            let f = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
            (t0.ln() + f * (t1.ln() - t0.ln())).exp()
        })
    })
}

type Series = Vec<(String, Vec<(f64, f64)>)>;

/// Writes the log-log plot of relative MSE against render time, one curve per configuration,
/// as SVG and PNG (text laid out with a system font; see [`load_font`]).
fn plot_error_vs_time(series: &Series, title: &str, svg: &Path, png: &Path) -> anyhow::Result<()> {
    use plotters::prelude::*;
    const SIZE: (u32, u32) = (960, 640);
    // Both backends measure text with the registered font.
    if !load_font() {
        bail!(
            "no TrueType font found for the plot's labels (set APERTURE_FONT to a .ttf file); \
             {} and {} not written",
            svg.display(),
            png.display()
        );
    }
    {
        let root = SVGBackend::new(svg, SIZE).into_drawing_area();
        draw_plot(&root, series, title).map_err(|e| anyhow::anyhow!("plotting: {e}"))?;
        root.present()
            .map_err(|e| anyhow::anyhow!("writing {}: {e}", svg.display()))?;
    }
    write_png(png, SIZE, |root| {
        draw_plot(root, series, title).map_err(|e| anyhow::anyhow!("plotting: {e}"))
    })
}

fn draw_plot<DB: plotters::prelude::DrawingBackend>(
    root: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    series: &Series,
    title: &str,
) -> Result<(), plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>> {
    use plotters::prelude::*;
    let pts = series.iter().flat_map(|(_, p)| p.iter()).copied();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in pts.filter(|&(x, y)| x > 0.0 && y > 0.0) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (1e-3, 1.0, 1e-4, 1.0);
    }
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("Error against render time: {title}"),
            ("sans-serif", 24),
        )
        .margin(20)
        .x_label_area_size(55)
        .y_label_area_size(85)
        .build_cartesian_2d(
            (x0 / 1.3..x1 * 1.3).log_scale(),
            (y0 / 1.5..y1 * 1.5).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("render time (s, wall clock, log scale)")
        .y_desc("relative MSE vs reference (log scale)")
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 15))
        .x_label_formatter(&|v| tick_label(*v))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    let palette = PALETTE;
    let mut extras = 0;
    for (name, p) in series.iter() {
        // A configuration keeps its colour whichever others are plotted; extra series take
        // the others in turn.
        let slot = match name.as_str() {
            "sobol" => 0,
            "random" => 1,
            "adaptive" => 2,
            _ => {
                extras += 1;
                2 + extras
            }
        };
        let color = palette[slot % palette.len()];
        let p: Vec<(f64, f64)> = p
            .iter()
            .copied()
            .filter(|&(x, y)| x > 0.0 && y > 0.0)
            .collect();
        chart
            .draw_series(LineSeries::new(p.clone(), color.stroke_width(3)))?
            .label(name.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(3))
            });
        chart.draw_series(p.iter().map(|&q| Circle::new(q, 5, color.filled())))?;
    }
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 18))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render_args::FilterArg;
    use clap::Parser as _;

    fn parse(args: &[&str]) -> Result<BenchArgs, clap::Error> {
        let mut argv = vec!["aperture", "bench", "s.glb"];
        argv.extend_from_slice(args);
        match crate::Cli::try_parse_from(argv)?.command {
            crate::Command::Bench(b) => Ok(b),
            _ => unreachable!("bench subcommand"),
        }
    }

    #[test]
    fn lists_parse() {
        let a = parse(&["--spp", "1,4,16", "--configs", "adaptive,sobol", "-o", "x"]).unwrap();
        assert_eq!(a.spp, vec![1, 4, 16]);
        assert_eq!(a.configs, vec![Config::Adaptive, Config::Sobol]);
        let d = parse(&[]).unwrap();
        assert_eq!(d.configs.len(), 3);
        assert_eq!(d.spp.len(), 8);
        assert_eq!(d.series, vec![]);
        assert_eq!(d.target_rel_mse, vec![1e-3]);
        assert_eq!(d.tracing.max_bounces, aperture_render::DEFAULT_MAX_BOUNCES);
        assert_eq!(d.tracing.clamp(), aperture_render::Clamp::OFF);
        let c = parse(&["--clamp-direct", "100", "--clamp-indirect", "10"]).unwrap();
        assert_eq!(
            (c.tracing.clamp_direct, c.tracing.clamp_indirect),
            (100.0, 10.0)
        );
        for bad in [
            &["--spp", "1,0"][..],
            &["--clamp-direct", "-1"],
            &["--clamp-indirect", "nan"],
            &["--configs", "halton"],
            &["--target-rel-mse", "1e-3,0"],
            &["--series", ":label"],
            &["--series", "m.csv: "],
            &["--filter", "mitchell"],
        ] {
            assert_eq!(parse(bad).unwrap_err().exit_code(), 2, "{bad:?}");
        }
    }

    #[test]
    fn series_arguments_parse() {
        let a = parse(&[
            "--series",
            "out/mitsuba.csv:Mitsuba 3",
            "--series",
            "old/results.csv",
            "--series",
            "C:\\bench\\m.csv",
            "--target-rel-mse",
            "1e-2,3e-3",
            "--max-bounces",
            "3",
            "--filter",
            "box",
            "--repeats",
            "3",
        ])
        .unwrap();
        let paths: Vec<_> = a.series.iter().map(|s| s.path.clone()).collect();
        assert_eq!(
            paths,
            ["out/mitsuba.csv", "old/results.csv", "C:\\bench\\m.csv"].map(PathBuf::from)
        );
        let labels: Vec<_> = a.series.iter().map(|s| s.label.as_deref()).collect();
        assert_eq!(labels, [Some("Mitsuba 3"), None, None]);
        assert_eq!(a.target_rel_mse, vec![1e-2, 3e-3]);
        assert_eq!(
            (a.tracing.max_bounces, a.tracing.filter, a.repeats),
            (3, FilterArg::Box, 3)
        );
        assert_eq!(parse(&["--repeats", "0"]).unwrap_err().exit_code(), 2);
    }

    #[test]
    fn median_of_odd_and_even_lists() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&mut [7.0]), 7.0);
    }

    #[test]
    fn series_files_read_by_column_name() {
        // Columns in another order, an extra column, an unknown (empty) MAE.
        let text = "spp,rel_mse,seconds,config,first_call_seconds,mae\n\
                    1,0.5,0.1,mitsuba,0.9,\n\
                    4,0.125,0.4,mitsuba,1.2,0.01\n";
        let rows = parse_series_csv(text, None, Path::new("m.csv")).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(
            (
                rows[1].label.as_str(),
                rows[1].spp,
                rows[1].seconds,
                rows[1].rel_mse
            ),
            ("mitsuba", 4, 0.4, 0.125)
        );
        assert!(rows[0].mae.is_nan() && rows[1].mae == 0.01 && rows[0].flip.is_nan());
        // A label overrides the config column; without either, the file's stem names it.
        let labelled = parse_series_csv(text, Some("M3"), Path::new("m.csv")).unwrap();
        assert!(labelled.iter().all(|r| r.label == "M3"));
        let bare = parse_series_csv("seconds,rel_mse\n1,0.1\n", None, Path::new("d/x.csv"));
        assert_eq!(bare.unwrap()[0].label, "x");
        // Our own output reads back as a series.
        let ours = to_csv(&labelled, 16, 12, 2);
        let back = parse_series_csv(&ours, None, Path::new("r.csv")).unwrap();
        assert_eq!(back.len(), 2);
        assert_eq!((back[0].label.as_str(), back[0].spp), ("M3", 1));
        assert!((back[1].rel_mse - 0.125).abs() < 1e-12);
        for bad in [
            "",
            "config,spp\nx,1\n",
            "seconds,rel_mse\n",
            "seconds,rel_mse\n1\n",
            "seconds,rel_mse\nfast,0.1\n",
            "seconds,rel_mse\n0,0.1\n",
            "seconds,rel_mse\n1,-0.1\n",
            "seconds,rel_mse\n1,\n",
        ] {
            assert!(
                parse_series_csv(bad, None, Path::new("b.csv")).is_err(),
                "{bad:?}"
            );
        }
    }

    #[test]
    fn time_to_error_table_gives_ratios_to_the_first_series() {
        let series: Series = vec![
            ("sobol".into(), vec![(1.0, 1e-2), (100.0, 1e-4)]),
            ("mitsuba".into(), vec![(2.0, 1e-2), (200.0, 1e-4)]),
            ("slow".into(), vec![(1.0, 1.0), (2.0, 0.5)]),
        ];
        let t = time_to_error_table(&series, &[1e-3]);
        let lines: Vec<&str> = t.lines().collect();
        assert!(
            lines[1].starts_with("sobol") && lines[1].contains("10.000 s (1.00x)"),
            "{t}"
        );
        assert!(lines[2].contains("20.000 s (2.00x)"), "{t}");
        assert!(lines[3].contains("not reached"), "{t}");
    }

    #[test]
    fn ticks_label_one_two_five() {
        assert_eq!(tick_label(0.5), "0.5");
        assert_eq!(tick_label(20.0), "20");
        assert_eq!(tick_label(3.0), "");
    }

    #[test]
    fn time_to_reach_interpolates_in_log_log() {
        // Error 1e-2 at 1 s, 1e-4 at 100 s: 1e-3 at 10 s.
        let t = interpolate_time(&[(1.0, 1e-2), (100.0, 1e-4)], 1e-3).unwrap();
        assert!((t - 10.0).abs() < 1e-9, "{t}");
        assert_eq!(interpolate_time(&[(1.0, 1e-2), (2.0, 5e-3)], 1e-3), None);
        assert_eq!(interpolate_time(&[(1.0, 1e-4)], 1e-3), Some(1.0));
    }

    /// The whole command on a real sample, without a reference: it renders one, then writes
    /// the CSV (one row per configuration and budget) and the plot.
    #[test]
    fn writes_reference_csv_and_plot() {
        let Some(box_glb) = crate::box_textured_sample() else {
            return;
        };
        let dir = std::env::temp_dir().join(format!("aperture-bench-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let extra = dir.join("other.csv");
        std::fs::write(&extra, "seconds,rel_mse\n0.001,0.5\n0.01,0.05\n").unwrap();
        let series_arg = format!("{}:other renderer", extra.display());
        let mut args = parse(&[
            "--series",
            &series_arg,
            "--spp",
            "1,4",
            "--width",
            "16",
            "--height",
            "12",
            "--reference-spp",
            "16",
        ])
        .unwrap();
        args.scene = box_glb;
        args.output = dir.clone();
        run(args).unwrap();
        let csv = std::fs::read_to_string(dir.join("results.csv")).unwrap();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 1 + 3 * 2, "{csv}");
        assert_eq!(lines[0], CSV_HEADER);
        assert!(lines[1].starts_with("sobol,1,16,12,"));
        assert!(lines[6].starts_with("adaptive,4,"));
        let reference = aperture_imageio::read_exr(&dir.join("reference.exr")).unwrap();
        assert_eq!((reference.width, reference.height), (16, 12));
        if load_font() {
            let svg = std::fs::read_to_string(dir.join("error_vs_time.svg")).unwrap();
            assert!(svg.contains("relative MSE") && svg.contains("adaptive"));
            assert!(svg.contains("other renderer"));
            assert!(dir.join("error_vs_time.png").is_file());
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
