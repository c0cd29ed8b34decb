//! `aperture bench`: error against time for several sampler configurations.
//!
//! Renders a scene at each sample budget with each configuration, times the render (wall time of
//! the render alone: the scene is loaded and the BVH built once, before any timing), measures the
//! error against a reference (RMSE, relative MSE, mean absolute error) and writes
//! `DIR/results.csv`, a log-log plot of relative MSE against time (`DIR/error_vs_time.svg` and
//! `.png`) and a table on stdout. Without `--reference` it first renders one at high spp, with
//! another seed so its noise is independent of the runs', and saves it as `DIR/reference.exr`.

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
    /// The adaptive configuration's noise threshold at budget N is this / √N (2 measured best
    /// on the demo scene among 0.25, 0.5, 2 and 8).
    #[arg(long, default_value_t = 2.0)]
    pub adaptive_scale: f32,
    /// Relative MSE at which to compare the configurations' times (interpolated in log-log).
    #[arg(long, default_value_t = 1e-3)]
    pub target_rel_mse: f64,
    /// Worker threads [default: all cores].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
}

/// One measured render.
#[derive(Debug, Clone)]
struct Row {
    config: Config,
    spp: u32,
    seconds: f64,
    samples: u64,
    mean_spp: f64,
    rmse: f64,
    rel_mse: f64,
    mae: f64,
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
    let base = RenderOptions {
        width,
        height,
        seed: args.seed,
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
                let image = crate::progress::film_to_image(&film, cam, &opts, secs);
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
                let t0 = Instant::now();
                let film = aperture_render::render(&scene, &accel, &opts, &|_, _| {})?;
                let seconds = t0.elapsed().as_secs_f64();
                let mut image = Image::new(width, height);
                image.rgba = film.to_rgba();
                let samples = film.total_samples();
                let row = Row {
                    config,
                    spp,
                    seconds,
                    samples,
                    mean_spp: samples as f64 / (width as f64 * height as f64),
                    rmse: metrics::rmse(&image, &reference)?,
                    rel_mse: metrics::relative_mse(&image, &reference)?,
                    mae: metrics::mae(&image, &reference)?,
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
    let title = format!(
        "{} at {width}x{height}, {threads} threads",
        args.scene
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let svg = args.output.join("error_vs_time.svg");
    let png = args.output.join("error_vs_time.png");
    print!("{}", table(&rows));
    plot_error_vs_time(&rows_to_series(&rows, &args.configs), &title, &svg, &png)?;
    println!();
    let mut uniform = None;
    for &config in &args.configs {
        let t = time_to_reach(&rows, config, args.target_rel_mse);
        match t {
            Some(t) => println!(
                "{:>8}: relative MSE {:.0e} reached in {:.3} s",
                config.name(),
                args.target_rel_mse,
                t
            ),
            None => println!(
                "{:>8}: relative MSE {:.0e} not reached within the budgets",
                config.name(),
                args.target_rel_mse
            ),
        }
        if config == Config::Sobol {
            uniform = t;
        }
    }
    if let (Some(u), Some(a)) = (
        uniform,
        time_to_reach(&rows, Config::Adaptive, args.target_rel_mse),
    ) {
        println!("adaptive / uniform Sobol time to that error: {:.2}", a / u);
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

fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}

fn to_csv(rows: &[Row], width: u32, height: u32, threads: usize) -> String {
    let mut s =
        String::from("config,spp,width,height,threads,seconds,samples,mean_spp,rmse,rel_mse,mae\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{width},{height},{threads},{:.6},{},{:.3},{:.6e},{:.6e},{:.6e}",
            r.config.name(),
            r.spp,
            r.seconds,
            r.samples,
            r.mean_spp,
            r.rmse,
            r.rel_mse,
            r.mae
        );
    }
    s
}

fn table(rows: &[Row]) -> String {
    let mut s = format!(
        "{:<9} {:>6} {:>9} {:>9} {:>11} {:>11} {:>11}\n",
        "config", "spp", "mean spp", "time (s)", "RMSE", "rel. MSE", "MAE"
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{:<9} {:>6} {:>9.1} {:>9.3} {:>11.4e} {:>11.4e} {:>11.4e}",
            r.config.name(),
            r.spp,
            r.mean_spp,
            r.seconds,
            r.rmse,
            r.rel_mse,
            r.mae
        );
    }
    s
}

fn rows_to_series(rows: &[Row], configs: &[Config]) -> Vec<(String, Vec<(f64, f64)>)> {
    configs
        .iter()
        .map(|&c| {
            let pts = rows
                .iter()
                .filter(|r| r.config == c)
                .map(|r| (r.seconds, r.rel_mse))
                .collect();
            (c.name().to_string(), pts)
        })
        .collect()
}

/// The time at which `config`'s relative MSE first falls to `target`, interpolated linearly in
/// log(time)–log(error) between the two budgets around it.
fn time_to_reach(rows: &[Row], config: Config, target: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.config == config)
        .map(|r| (r.seconds, r.rel_mse))
        .collect();
    interpolate_time(&pts, target)
}

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
    let mut buf = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, SIZE).into_drawing_area();
        draw_plot(&root, series, title).map_err(|e| anyhow::anyhow!("plotting: {e}"))?;
        root.present()
            .map_err(|e| anyhow::anyhow!("plotting: {e}"))?;
    }
    let tmp = png.with_extension("png.tmp");
    image::save_buffer_with_format(
        &tmp,
        &buf,
        SIZE.0,
        SIZE.1,
        image::ColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, png).with_context(|| format!("writing {}", png.display()))
}

/// Registers a sans-serif TrueType font for bitmap text: `APERTURE_FONT`, else the first of a
/// few common system fonts. False when none can be read.
fn load_font() -> bool {
    static LOADED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *LOADED.get_or_init(|| {
        let candidates = std::env::var_os("APERTURE_FONT")
            .map(PathBuf::from)
            .into_iter()
            .chain(
                [
                    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
                    "/usr/share/fonts/TTF/DejaVuSans.ttf",
                    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
                    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
                    "/System/Library/Fonts/Supplemental/Arial.ttf",
                    "C:\\Windows\\Fonts\\arial.ttf",
                ]
                .map(PathBuf::from),
            );
        for path in candidates {
            if let Ok(bytes) = std::fs::read(&path) {
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                if plotters::style::register_font(
                    "sans-serif",
                    plotters::style::FontStyle::Normal,
                    bytes,
                )
                .is_ok()
                {
                    return true;
                }
            }
        }
        false
    })
}

/// Log-axis tick text: only 1, 2 and 5 times a power of ten, so labels never overlap.
fn tick_label(v: f64) -> String {
    let lead = v / 10f64.powf(v.log10().floor());
    if [1.0, 2.0, 5.0].iter().any(|d| (lead - d).abs() < 1e-6) {
        format!("{}", (v * 1e6).round() / 1e6)
    } else {
        String::new()
    }
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
    let palette = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
    ];
    for (i, (name, p)) in series.iter().enumerate() {
        // A configuration keeps its colour whichever others are plotted.
        let slot = match name.as_str() {
            "sobol" => 0,
            "random" => 1,
            "adaptive" => 2,
            _ => i,
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
        for bad in [&["--spp", "1,0"][..], &["--configs", "halton"]] {
            assert_eq!(parse(bad).unwrap_err().exit_code(), 2, "{bad:?}");
        }
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
        let mut args = parse(&[
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
        assert!(lines[0].starts_with("config,spp,"));
        assert!(lines[1].starts_with("sobol,1,16,12,"));
        assert!(lines[6].starts_with("adaptive,4,"));
        let reference = aperture_imageio::read_exr(&dir.join("reference.exr")).unwrap();
        assert_eq!((reference.width, reference.height), (16, 12));
        if load_font() {
            let svg = std::fs::read_to_string(dir.join("error_vs_time.svg")).unwrap();
            assert!(svg.contains("relative MSE") && svg.contains("adaptive"));
            assert!(dir.join("error_vs_time.png").is_file());
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
