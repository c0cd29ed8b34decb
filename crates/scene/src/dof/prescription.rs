//! `lens_prescription` (issue 61): pbrt-v4's lens file (rows of radius, thickness, IOR and
//! aperture diameter in mm, front to back, the stop with radius 0, `#` comments), or the same
//! rows inline as an array of 4-number arrays, read and checked. A bad file or row is an error
//! naming the camera, the key and the value.

use std::io::Read;
use std::path::Path;

use serde_json::Value;

use crate::types::LensSurface;

/// The most surfaces a prescription may have (real lenses have fewer than 40).
const MAX_SURFACES: usize = 64;
/// The largest lens file read (a prescription is a few hundred bytes).
const MAX_FILE_BYTES: u64 = 1 << 20;

/// A prescription's rows and where they came from.
pub(crate) type Rows = (String, Vec<LensSurface>);

/// What is wrong with a value: the value as shown, and why.
pub(crate) type Bad = (String, String);

/// The value of a `lens_prescription` key: a path relative to `base_dir` (the glTF file's
/// folder) or inline rows.
pub(crate) fn from_value(key: &str, v: &Value, base_dir: &Path) -> Result<Rows, Bad> {
    match v {
        Value::String(s) => {
            let path = crate::uri::resolve_path(base_dir, s, key)
                .map_err(|e| (format!("{s:?}"), e.to_string()))?;
            from_file(&path, &format!("{s:?}"))
        }
        Value::Array(rows) => {
            let mut numbers = Vec::with_capacity(rows.len());
            for (i, row) in rows.iter().enumerate() {
                let bad = || (row.to_string(), format!("row {i}: {ROW_SHAPE}"));
                let r = row.as_array().filter(|r| r.len() == 4).ok_or_else(bad)?;
                let mut out = [0.0; 4];
                for (o, x) in out.iter_mut().zip(r) {
                    *o = x.as_f64().ok_or_else(bad)?;
                }
                numbers.push(out);
            }
            let surfaces = check(&numbers).map_err(|reason| ("[...]".to_owned(), reason))?;
            Ok(("inline".into(), surfaces))
        }
        _ => Err((
            v.to_string(),
            "expected a lens file's path or an array of [radius, thickness, IOR, aperture] rows"
                .to_owned(),
        )),
    }
}

const ROW_SHAPE: &str = "expected 4 numbers: radius, thickness, IOR, aperture diameter (mm)";

/// The lens file at `path` (`shown` as the user wrote it).
pub(crate) fn from_file(path: &Path, shown: &str) -> Result<Rows, Bad> {
    let bad = |reason: String| (shown.to_owned(), reason);
    let mut text = String::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_FILE_BYTES + 1).read_to_string(&mut text))
        .map_err(|e| bad(format!("cannot read the lens file: {e}")))?;
    if text.len() as u64 > MAX_FILE_BYTES {
        return Err(bad("the lens file is larger than 1 MiB".into()));
    }
    let rows = parse_text(&text).map_err(bad)?;
    let surfaces = check(&rows).map_err(bad)?;
    Ok((shown.trim_matches('"').to_owned(), surfaces))
}

/// The rows of a lens file: `#` starts a comment, blank lines are skipped, numbers are
/// separated by white space (or commas).
pub(crate) fn parse_text(text: &str) -> Result<Vec<[f64; 4]>, String> {
    let mut rows = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        let tokens: Vec<&str> = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|t| !t.is_empty())
            .collect();
        if tokens.is_empty() {
            continue;
        }
        if tokens.len() != 4 {
            return Err(format!(
                "line {}: {ROW_SHAPE}, found {}",
                n + 1,
                tokens.len()
            ));
        }
        let mut row = [0.0; 4];
        for (x, t) in row.iter_mut().zip(&tokens) {
            *x = t
                .parse::<f64>()
                .map_err(|_| format!("line {}: {t:?} is not a number", n + 1))?;
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The surfaces of `rows`, checked: finite numbers, thickness ≥ 0, IOR 0 (air) or ≥ 1,
/// aperture > 0, exactly one stop and at least one refracting surface.
pub(crate) fn check(rows: &[[f64; 4]]) -> Result<Vec<LensSurface>, String> {
    if rows.is_empty() {
        return Err("no rows".into());
    }
    if rows.len() > MAX_SURFACES {
        return Err(format!("{} rows: at most {MAX_SURFACES}", rows.len()));
    }
    let mut surfaces = Vec::with_capacity(rows.len());
    for (i, r) in rows.iter().enumerate() {
        let f = r.map(|x| x as f32);
        if f.iter().any(|x| !x.is_finite()) {
            return Err(format!("row {i}: {r:?} has a number that is not finite"));
        }
        let [radius, thickness, ior, aperture] = f;
        if thickness < 0.0 {
            return Err(format!("row {i}: thickness {thickness} must be >= 0"));
        }
        if ior != 0.0 && ior < 1.0 {
            return Err(format!("row {i}: IOR {ior} must be 0 (air) or >= 1"));
        }
        if aperture <= 0.0 {
            return Err(format!("row {i}: aperture diameter {aperture} must be > 0"));
        }
        surfaces.push(LensSurface {
            radius,
            thickness,
            ior,
            aperture,
        });
    }
    match surfaces.iter().filter(|s| s.is_stop()).count() {
        0 => return Err("no stop (a row with radius 0)".into()),
        1 => {}
        n => return Err(format!("{n} stops (rows with radius 0): a lens has one")),
    }
    if surfaces.len() < 2 {
        return Err("no refracting surface besides the stop".into());
    }
    Ok(surfaces)
}
