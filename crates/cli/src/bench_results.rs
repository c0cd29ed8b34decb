//! `aperture bench`'s results: the measured rows, `results.csv` written and `--series` files
//! read back, the printed tables and the time each curve takes to reach an error.

use anyhow::{bail, Context as _};
use std::fmt::Write as _;
use std::path::Path;

/// One measured render (ours, or a line of a `--series` file, whose unknown values are NaN).
#[derive(Debug, Clone)]
pub(crate) struct Row {
    pub(crate) label: String,
    pub(crate) spp: u32,
    pub(crate) seconds: f64,
    pub(crate) samples: u64,
    pub(crate) mean_spp: f64,
    pub(crate) rmse: f64,
    pub(crate) rel_mse: f64,
    pub(crate) mae: f64,
    pub(crate) flip: f64,
}

/// Writes `bytes` to `path` through a temporary file renamed into place.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}

/// The header line of `results.csv`.
pub(crate) const CSV_HEADER: &str =
    "config,spp,width,height,threads,seconds,samples,mean_spp,rmse,rel_mse,mae,flip";

/// `results.csv`'s text: the header, then one line per row.
pub(crate) fn to_csv(rows: &[Row], width: u32, height: u32, threads: usize) -> String {
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
pub(crate) fn read_series(path: &Path, label: Option<&str>) -> anyhow::Result<Vec<Row>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading the series {}", path.display()))?;
    parse_series_csv(&text, label, path)
        .with_context(|| format!("in the series {}", path.display()))
}

/// The rows of a `--series` file's text; `label` names them all, else the `config` column, else
/// `path`'s stem.
pub(crate) fn parse_series_csv(
    text: &str,
    label: Option<&str>,
    path: &Path,
) -> anyhow::Result<Vec<Row>> {
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

/// The table printed on stdout: one line per row.
pub(crate) fn table(rows: &[Row]) -> String {
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
pub(crate) fn rows_to_series(rows: &[Row]) -> Series {
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
pub(crate) fn time_to_error_table(series: &Series, targets: &[f64]) -> String {
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
pub(crate) fn interpolate_time(pts: &[(f64, f64)], target: f64) -> Option<f64> {
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

/// Named curves of (seconds, relative MSE) points.
pub(crate) type Series = Vec<(String, Vec<(f64, f64)>)>;
