//! The rays of a query as numpy gives them: (N, 3) float32 or float64 arrays in any memory
//! order (a list is turned into a float64 array), and `tmin`/`tmax` as one number or N. The
//! arrays are read in place, without the GIL, by the workers that trace them: each batch of
//! rays is read, checked and traced in one pass ([`each_batch`]), so nothing is copied or
//! checked on one thread before the traversal starts.
//!
//! Reading without the GIL: the arrays are kept alive (and unresizable: we hold references)
//! for the whole call, and rust-numpy's borrow flags keep Rust writers out; a Python thread
//! that writes into the arrays during the call races with the read as it would with any
//! extension that releases the GIL (embreex included): the answers are then those of whichever
//! values were read.

use crate::errors::value_error;
use aperture_accel::Ray;
use glam::Vec3;
use numpy::ndarray::ArrayView2;
use numpy::{
    PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// Rays per task handed to a worker (its outputs are one slice of each column).
pub(crate) const TASK: usize = 2048;
/// Rays read, checked and traced at once (bench-rays' chunk: what the packet queries are
/// timed with).
pub(crate) const BATCH: usize = 256;

/// An input array, borrowed read-only for the call.
enum Held<'py> {
    F32(PyReadonlyArray2<'py, f32>),
    F64(PyReadonlyArray2<'py, f64>),
}

/// An input array's elements, readable without the GIL.
#[derive(Clone, Copy)]
enum Columns<'a> {
    F32(ArrayView2<'a, f32>),
    F64(ArrayView2<'a, f64>),
}

/// A float the rays are read from.
trait Elem: Copy {
    fn f32(self) -> f32;
}

impl Elem for f32 {
    #[inline(always)]
    fn f32(self) -> f32 {
        self
    }
}

impl Elem for f64 {
    #[inline(always)]
    fn f32(self) -> f32 {
        self as f32
    }
}

/// Rows `start..start + out.len()` of `v` as vectors (a straight walk when C-contiguous).
#[inline(always)]
fn read_rows<T: Elem>(v: &ArrayView2<'_, T>, start: usize, out: &mut [Vec3]) {
    match v.as_slice() {
        Some(flat) => {
            let rows = flat[3 * start..3 * (start + out.len())].chunks_exact(3);
            for (o, c) in out.iter_mut().zip(rows) {
                *o = Vec3::new(c[0].f32(), c[1].f32(), c[2].f32());
            }
        }
        None => {
            for (k, o) in out.iter_mut().enumerate() {
                let i = start + k;
                *o = Vec3::new(v[[i, 0]].f32(), v[[i, 1]].f32(), v[[i, 2]].f32());
            }
        }
    }
}

impl Columns<'_> {
    fn read(&self, start: usize, out: &mut [Vec3]) {
        match self {
            Columns::F32(v) => read_rows(v, start, out),
            Columns::F64(v) => read_rows(v, start, out),
        }
    }

    fn at(&self, i: usize) -> Vec3 {
        let mut v = [Vec3::ZERO];
        self.read(i, &mut v);
        v[0]
    }
}

impl Held<'_> {
    fn columns(&self) -> Columns<'_> {
        match self {
            Held::F32(a) => Columns::F32(a.as_array()),
            Held::F64(a) => Columns::F64(a.as_array()),
        }
    }

    fn len(&self) -> usize {
        match self {
            Held::F32(a) => a.as_array().nrows(),
            Held::F64(a) => a.as_array().nrows(),
        }
    }
}

/// An (N, 3) float32 or float64 array (a list is turned into a float64 one), borrowed.
fn held<'py>(v: &Bound<'py, PyAny>, name: &str) -> PyResult<Held<'py>> {
    let array = match v.cast::<PyUntypedArray>() {
        Ok(a) => a.clone(),
        Err(_) => {
            let np = v.py().import("numpy")?;
            let a = np.call_method1("asarray", (v, "float64")).map_err(|e| {
                value_error(format!("{name} must be an (N, 3) array of numbers: {e}"))
            })?;
            a.cast_into::<PyUntypedArray>()?
        }
    };
    if array.ndim() != 2 || array.shape()[1] != 3 {
        return Err(value_error(format!(
            "{name} must have shape (N, 3), got {:?}",
            array.shape()
        )));
    }
    let busy = |e: numpy::BorrowError| value_error(format!("{name} cannot be read: {e}"));
    if let Ok(a) = array.cast::<PyArray2<f32>>() {
        return Ok(Held::F32(a.try_readonly().map_err(busy)?));
    }
    if let Ok(a) = array.cast::<PyArray2<f64>>() {
        return Ok(Held::F64(a.try_readonly().map_err(busy)?));
    }
    Err(value_error(format!(
        "{name} must be float32 or float64, got {}",
        array.dtype()
    )))
}

/// A ray bound: one for every ray, or one each.
pub(crate) enum Limit {
    All(f32),
    Each(Vec<f32>),
}

impl Limit {
    #[inline(always)]
    fn at(&self, i: usize) -> f32 {
        match self {
            Limit::All(x) => *x,
            Limit::Each(v) => v[i],
        }
    }
}

/// A ray bound's values: one number, or an (N,) array (or sequence) of them.
fn bound_values(v: &Bound<'_, PyAny>, name: &str) -> PyResult<Result<f64, Vec<f64>>> {
    if let Ok(x) = v.extract::<f64>() {
        return Ok(Ok(x));
    }
    if let Ok(a) = v.cast::<PyArray1<f32>>() {
        if let Ok(r) = a.try_readonly() {
            return Ok(Err(r.as_array().iter().map(|&x| f64::from(x)).collect()));
        }
    }
    if let Ok(a) = v.cast::<PyArray1<f64>>() {
        if let Ok(r) = a.try_readonly() {
            return Ok(Err(r.as_array().to_vec()));
        }
    }
    v.extract().map(Err).map_err(|_| {
        value_error(format!(
            "{name} must be a number or an (N,) array of numbers"
        ))
    })
}

/// A ray bound for `n` rays, checked: ≥ 0 (infinity allowed), not NaN.
fn bounds(v: &Bound<'_, PyAny>, name: &str, n: usize) -> PyResult<Limit> {
    let bad = |i: usize, x: f64| {
        value_error(format!(
            "{name}[{i}] = {x} is not allowed: must be ≥ 0 (inf allowed)"
        ))
    };
    match bound_values(v, name)? {
        Ok(x) if n > 0 && (x.is_nan() || x < 0.0) => Err(bad(0, x)),
        Ok(x) => Ok(Limit::All(x as f32)),
        Err(all) if all.len() != n => Err(value_error(format!(
            "{name} has {} values for {n} rays",
            all.len()
        ))),
        Err(all) => match all.iter().position(|x| x.is_nan() || *x < 0.0) {
            None => Ok(Limit::Each(all.into_iter().map(|x| x as f32).collect())),
            Some(i) => Err(bad(i, all[i])),
        },
    }
}

/// The query's arrays, held with the GIL for the call.
pub(crate) struct RayArrays<'py> {
    origins: Held<'py>,
    directions: Held<'py>,
    tmin: Limit,
    tmax: Limit,
}

/// What [`each_batch`] reads: the rays, without the GIL.
pub(crate) struct RaySource<'a> {
    origins: Columns<'a>,
    directions: Columns<'a>,
    tmin: &'a Limit,
    tmax: &'a Limit,
    /// How many rays.
    pub n: usize,
}

impl<'py> RayArrays<'py> {
    /// The arrays of a query, their shapes, dtypes and bounds checked (the rays themselves are
    /// checked as they are read).
    pub fn new(
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        tmin: Option<&Bound<'py, PyAny>>,
        tmax: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Self> {
        let o = held(origins, "origins")?;
        let d = held(directions, "directions")?;
        let n = o.len();
        if n != d.len() {
            return Err(value_error(format!(
                "{n} origins for {} directions",
                d.len()
            )));
        }
        let tmin = match tmin {
            None => Limit::All(0.0),
            Some(v) => bounds(v, "tmin", n)?,
        };
        let tmax = match tmax {
            None => Limit::All(f32::INFINITY),
            Some(v) => bounds(v, "tmax", n)?,
        };
        let all = matches!((&tmin, &tmax), (Limit::All(_), Limit::All(_)));
        let upto = if all { n.min(1) } else { n };
        if let Some(i) = (0..upto).find(|&i| {
            let (lo, hi) = (tmin.at(i), tmax.at(i));
            lo > hi || lo.is_infinite()
        }) {
            return Err(value_error(format!(
                "ray {i}: tmin {} must be finite and at most tmax {}",
                tmin.at(i),
                tmax.at(i)
            )));
        }
        Ok(Self {
            origins: o,
            directions: d,
            tmin,
            tmax,
        })
    }

    /// The rays, readable without the GIL.
    pub fn source(&self) -> RaySource<'_> {
        RaySource {
            origins: self.origins.columns(),
            directions: self.directions.columns(),
            tmin: &self.tmin,
            tmax: &self.tmax,
            n: self.origins.len(),
        }
    }

    /// The `ValueError` of the first ray not allowed (when [`each_batch`] saw one): the first
    /// non-finite origin, else the first non-finite or zero direction (found again here, on
    /// one thread: the workers stop at any one).
    pub fn error(&self) -> PyErr {
        let src = self.source();
        let first = |c: &Columns<'_>, ok: fn(Vec3) -> bool| (0..src.n).find(|&i| !ok(c.at(i)));
        let dir_ok = |d: Vec3| d.is_finite() && d != Vec3::ZERO;
        let (name, i, rule, c) = match first(&src.origins, |o| o.is_finite()) {
            Some(i) => ("origins", i, "", &src.origins),
            None => match first(&src.directions, dir_ok) {
                Some(i) => ("directions", i, " and not zero", &src.directions),
                None => return value_error("the rays were changed during the call"),
            },
        };
        value_error(format!(
            "{name}[{i}] = {} is not allowed: {name} must be finite{rule}",
            c.at(i)
        ))
    }
}

/// Reads, checks and answers every ray of `src`: `tasks` are the outputs of consecutive runs
/// of [`TASK`] rays, and `answer(rays, offset, task)` answers `rays` into `task` from
/// `offset` on. On the caller's thread when `serial`, else on the current rayon pool. Rays not
/// allowed (non-finite origins, non-finite or zero directions) make the answer `false` (the
/// remaining batches are skipped then; [`RayArrays::error`] names the ray).
pub(crate) fn each_batch<O: Send>(
    src: &RaySource<'_>,
    tasks: Vec<O>,
    serial: bool,
    answer: impl Fn(&[Ray], usize, &mut O) + Sync,
) -> bool {
    let bad = AtomicBool::new(false);
    let work = |(k, out): (usize, O)| {
        let mut out = out;
        let start = k * TASK;
        let end = src.n.min(start + TASK);
        let blank = Ray {
            origin: Vec3::ZERO,
            dir: Vec3::Z,
            tmin: 0.0,
            tmax: 0.0,
            time: 0.0,
        };
        let mut rays = [blank; BATCH];
        let (mut o, mut d) = ([Vec3::ZERO; BATCH], [Vec3::ZERO; BATCH]);
        let mut first = start;
        while first < end && !bad.load(Ordering::Relaxed) {
            let m = BATCH.min(end - first);
            src.origins.read(first, &mut o[..m]);
            src.directions.read(first, &mut d[..m]);
            let mut ok = true;
            for k in 0..m {
                let (o, d) = (o[k], d[k]);
                ok &= o.is_finite() & d.is_finite() & (d != Vec3::ZERO);
                rays[k] = Ray {
                    origin: o,
                    dir: d,
                    tmin: src.tmin.at(first + k),
                    tmax: src.tmax.at(first + k),
                    time: 0.0,
                };
            }
            if !ok {
                bad.store(true, Ordering::Relaxed);
                return;
            }
            answer(&rays[..m], first - start, &mut out);
            first += m;
        }
    };
    match serial {
        true => tasks.into_iter().enumerate().for_each(work),
        false => tasks
            .into_par_iter()
            .enumerate()
            .with_max_len(1)
            .for_each(work),
    }
    !bad.load(Ordering::Relaxed)
}
