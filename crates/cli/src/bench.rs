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

use crate::bench_plot::plot_error_vs_time;
use crate::bench_results::{
    interpolate_time, read_series, rows_to_series, table, time_to_error_table, to_csv,
    write_atomic, Row,
};
use crate::render_args::TracingArgs;
use anyhow::{bail, Context as _};
use aperture_imageio::{metrics, Image};
use aperture_render::{AdaptiveOptions, RenderOptions, SamplerKind};
use aperture_render::{Frame, FrameSpec};
use aperture_scene::LoadOptions;
use clap::ValueEnum;
use std::path::PathBuf;
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
    /// Sobol, every pixel at the budget, then denoised (Open Image Denoise with the Denoising
    /// passes, as `render --denoise`); the time includes the denoising.
    Denoised,
    /// No sampler: `--repeats` fresh loads of the file, each timed to its BVH and its first
    /// samples (one a pixel), with the peak memory; measured first, written to `DIR/load.csv`.
    Load,
}

impl Config {
    fn name(self) -> &'static str {
        match self {
            Self::Sobol => "sobol",
            Self::Random => "random",
            Self::Adaptive => "adaptive",
            Self::Denoised => "denoised",
            Self::Load => "load",
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
    /// Configurations, comma separated (`denoised` needs Open Image Denoise: see `render
    /// --denoise`).
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
    /// The `denoised` configuration's library and settings (see `aperture render --denoise`).
    #[command(flatten)]
    pub denoise: crate::denoise_cmd::DenoiseOptions,
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

/// Runs `aperture bench`.
pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    if args.configs.contains(&Config::Load) {
        std::fs::create_dir_all(&args.output)
            .with_context(|| format!("creating {}", args.output.display()))?;
        let pool = crate::workers::worker_pool(args.threads)?;
        pool.install(|| load::run_loads(&args))?;
        if args.configs.iter().all(|&c| c == Config::Load) {
            return Ok(());
        }
    }
    let mut session = aperture_render::Session::load(&args.scene, &LoadOptions::default())
        .with_context(|| format!("loading {}", args.scene.display()))?;
    let scene = session.pose(None)?;
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
    let (width, height) = image_size(&args, cam, reference.as_ref())?;
    let denoiser = args
        .denoise
        .load_if(args.configs.contains(&Config::Denoised))?;
    let pool = crate::workers::worker_pool(args.threads)?;
    let threads = pool.current_num_threads();
    let clamp = args.tracing.clamp();
    if clamp != aperture_render::Clamp::OFF {
        println!(
            "Clamping samples (direct {}, indirect {}; 0 = off): errors are against the clamped \
             estimator, so a --reference must use the same clamps.",
            clamp.direct, clamp.indirect
        );
    }
    // Read before rendering, so a bad file fails at once.
    let mut extra = Vec::new();
    for s in &args.series {
        extra.extend(read_series(&s.path, s.label.as_deref())?);
    }
    let base = RenderOptions {
        width,
        height,
        seed: args.seed,
        max_bounces: args.tracing.max_bounces,
        filter: args.tracing.filter,
        clamp,
        ..RenderOptions::default()
    };
    let rows = pool.install(|| -> anyhow::Result<Vec<Row>> {
        let frame = session.frame(&FrameSpec::default())?;
        let reference = match reference {
            Some(r) => r,
            None => render_reference(&args, frame, &base)?,
        };
        let mut rows = Vec::new();
        for &config in args.configs.iter().filter(|&&c| c != Config::Load) {
            for &spp in &args.spp {
                let opts = config_options(&base, config, spp, args.adaptive_scale);
                let denoise = denoiser.as_ref().filter(|_| config == Config::Denoised);
                let job = Job {
                    frame,
                    opts: &opts,
                    config,
                    denoiser: denoise,
                };
                rows.push(measure(&args, &job, &reference)?);
            }
        }
        Ok(rows)
    })?;
    report(&args, &rows, &extra, (width, height), threads)
}

/// The renders' size: `--width`/`--height`, else the reference's, else 320 wide at the camera's
/// aspect; an error when a given reference has another size.
fn image_size(
    args: &BenchArgs,
    cam: &aperture_scene::Camera,
    reference: Option<&Image>,
) -> anyhow::Result<(u32, u32)> {
    let width = args.width.or(reference.map(|r| r.width)).unwrap_or(320);
    let height = args
        .height
        .or(reference.map(|r| r.height))
        .unwrap_or_else(|| aperture_render::default_height(cam, width));
    if let Some(r) = reference {
        if (r.width, r.height) != (width, height) {
            bail!(
                "the reference is {}x{} but the renders would be {width}x{height}",
                r.width,
                r.height
            );
        }
    }
    Ok((width, height))
}

/// Renders the reference at `--reference-spp` with another seed and saves it as
/// `DIR/reference.exr`.
fn render_reference(
    args: &BenchArgs,
    frame: &Frame,
    base: &RenderOptions,
) -> anyhow::Result<Image> {
    let opts = RenderOptions {
        spp: args.reference_spp,
        seed: args.seed.wrapping_add(0x5eed),
        ..base.clone()
    };
    println!(
        "No --reference given: rendering one at {} spp ({}x{}) first.",
        opts.spp, opts.width, opts.height
    );
    let t0 = Instant::now();
    let film = frame.render(&opts, &|_, _| {})?;
    let secs = t0.elapsed().as_secs_f64();
    let image = aperture_output::film_to_image(&film, frame.scene(), &opts, false, secs)?;
    let path = args.output.join("reference.exr");
    aperture_imageio::write_image(&path, &image, &Default::default())
        .with_context(|| format!("writing {}", path.display()))?;
    println!(
        "Reference: {:.1} s, saved as {} (pass it with --reference next time).",
        secs,
        path.display()
    );
    Ok(image)
}

/// The render options of one configuration at budget `spp`.
fn config_options(
    base: &RenderOptions,
    config: Config,
    spp: u32,
    adaptive_scale: f32,
) -> RenderOptions {
    RenderOptions {
        spp,
        sampler: match config {
            Config::Random => SamplerKind::Random,
            Config::Sobol | Config::Adaptive | Config::Denoised | Config::Load => {
                SamplerKind::Sobol
            }
        },
        passes: match config {
            Config::Denoised => aperture_render::PassSet::NONE
                .with(aperture_render::Pass::DenoisingAlbedo)
                .with(aperture_render::Pass::DenoisingNormal),
            _ => base.passes,
        },
        adaptive: (config == Config::Adaptive).then(|| AdaptiveOptions {
            threshold: adaptive_scale / (spp as f32).sqrt(),
            min_spp: AdaptiveOptions::auto_min_spp(spp),
        }),
        ..base.clone()
    }
}

/// Renders `--repeats` times with `opts`, and measures the median time and the error against
/// the reference.
/// One measured configuration at one budget.
struct Job<'a> {
    frame: &'a Frame,
    opts: &'a RenderOptions,
    config: Config,
    /// Denoise each render (its time included).
    denoiser: Option<&'a aperture_denoise::Denoiser>,
}

/// The job's image: rendered, and denoised when the job says so.
fn job_image(job: &Job<'_>) -> anyhow::Result<(Image, u64)> {
    let film = job.frame.render(job.opts, &|_, _| {})?;
    let mut image = Image::new(job.opts.width, job.opts.height);
    if let Some(d) = job.denoiser {
        let scene = job.frame.scene();
        let mut full = aperture_output::film_to_image(&film, scene, job.opts, false, 0.0)?;
        aperture_output::denoised::denoise_image(&mut full, d)?;
        image.rgba = full.rgba;
    } else {
        image.rgba = film.to_rgba();
    }
    Ok((image, film.total_samples()))
}

fn measure(args: &BenchArgs, job: &Job<'_>, reference: &Image) -> anyhow::Result<Row> {
    let (opts, config) = (job.opts, job.config);
    // Same seed each time, so the image (and its error) is the same: only the time,
    // disturbed by whatever else the machine runs, varies.
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..args.repeats {
        let t0 = Instant::now();
        last = Some(job_image(job)?);
        times.push(t0.elapsed().as_secs_f64());
    }
    let (image, samples) = last.context("no render (--repeats 0)")?;
    let seconds = median(&mut times);
    let (width, height) = (opts.width, opts.height);
    let row = Row {
        label: config.name().to_string(),
        spp: opts.spp,
        seconds,
        samples,
        mean_spp: samples as f64 / (width as f64 * height as f64),
        rmse: metrics::rmse(&image, reference)?,
        rel_mse: metrics::relative_mse(&image, reference)?,
        mae: metrics::mae(&image, reference)?,
        flip: metrics::flip(&image, reference)?,
    };
    eprintln!(
        "{:>8} {:>6} spp: {:>8.3} s, relMSE {:.3e}",
        config.name(),
        opts.spp,
        seconds,
        row.rel_mse
    );
    Ok(row)
}

/// Writes `results.csv` and the plot, and prints the tables: our `rows` and the `--series`
/// ones (`extra`).
fn report(
    args: &BenchArgs,
    rows: &[Row],
    extra: &[Row],
    (width, height): (u32, u32),
    threads: usize,
) -> anyhow::Result<()> {
    let csv = args.output.join("results.csv");
    write_atomic(&csv, to_csv(rows, width, height, threads).as_bytes())?;
    let mut title = format!(
        "{} at {width}x{height}, {threads} threads",
        args.scene
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    // A clamped run measures another (biased) estimator; the picture must say so.
    let clamp = args.tracing.clamp();
    if clamp != aperture_render::Clamp::OFF {
        title += &format!(", clamp {}/{}", clamp.direct, clamp.indirect);
    }
    let svg = args.output.join("error_vs_time.svg");
    let png = args.output.join("error_vs_time.png");
    let all: Vec<Row> = rows.iter().chain(extra).cloned().collect();
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

mod load;
#[cfg(test)]
mod tests;
