use super::*;
use crate::bench_results::{parse_series_csv, Series, CSV_HEADER};
use crate::plot::{load_font, tick_label};
use aperture_render::FilterKind;
use clap::Parser as _;
use std::path::Path;

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
        (3, FilterKind::Box, 3)
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
