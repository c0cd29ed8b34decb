//! Keyword options under the command line's names (`--spp` is `spp=`, `--no-dof` is
//! `no_dof=True`), each checked as the command line checks it: a value out of range is a
//! `ValueError` saying which and why, an unknown name a `TypeError` (as Python's own).

use crate::errors::value_error;
use aperture_shading::Convention;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

/// The keyword arguments of one call, taken one by one; what is left is an error.
pub(crate) struct Kwargs<'py> {
    dict: Option<Bound<'py, PyDict>>,
    what: &'static str,
}

impl<'py> Kwargs<'py> {
    /// The options of `what` (`load`, `render`, …), a copy of the caller's dict.
    pub fn new(dict: Option<&Bound<'py, PyDict>>, what: &'static str) -> PyResult<Self> {
        let dict = dict.map(|d| d.copy()).transpose()?;
        Ok(Self { dict, what })
    }

    /// The value of `name` (`None` when missing or `None`), removed from the dict.
    pub fn take(&mut self, name: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(d) = &self.dict else {
            return Ok(None);
        };
        let v = d.get_item(name)?;
        if v.is_some() {
            d.del_item(name)?;
        }
        Ok(v.filter(|v| !v.is_none()))
    }

    /// Fails on any option not taken.
    pub fn finish(self) -> PyResult<()> {
        let Some(d) = self.dict else {
            return Ok(());
        };
        match d.keys().iter().next() {
            None => Ok(()),
            Some(k) => Err(PyTypeError::new_err(format!(
                "{}() got an unexpected option {k}",
                self.what
            ))),
        }
    }

    /// An integer option within `lo..=hi`.
    pub fn int(&mut self, name: &str, lo: i64, hi: i64) -> PyResult<Option<i64>> {
        let Some(v) = self.take(name)? else {
            return Ok(None);
        };
        if v.is_instance_of::<pyo3::types::PyBool>() {
            return Err(PyTypeError::new_err(format!(
                "{name} must be an integer, not a bool"
            )));
        }
        let n: i64 = v
            .extract()
            .map_err(|_| PyTypeError::new_err(format!("{name} must be an integer, got {v}")))?;
        if !(lo..=hi).contains(&n) {
            return Err(value_error(format!(
                "invalid {name} = {n}: must be in {lo}..={hi}"
            )));
        }
        Ok(Some(n))
    }

    /// A `u32` option within `lo..=hi`.
    pub fn uint(&mut self, name: &str, lo: u32, hi: u32) -> PyResult<Option<u32>> {
        Ok(self
            .int(name, i64::from(lo), i64::from(hi))?
            .map(|n| n as u32))
    }

    /// A number for which `ok` holds (`why` says what is allowed).
    pub fn float(&mut self, name: &str, ok: fn(f64) -> bool, why: &str) -> PyResult<Option<f64>> {
        let Some(v) = self.take(name)? else {
            return Ok(None);
        };
        let x: f64 = v
            .extract()
            .map_err(|_| PyTypeError::new_err(format!("{name} must be a number, got {v}")))?;
        if !ok(x) {
            return Err(value_error(format!("invalid {name} = {x}: {why}")));
        }
        Ok(Some(x))
    }

    /// A boolean option.
    pub fn flag(&mut self, name: &str) -> PyResult<Option<bool>> {
        let Some(v) = self.take(name)? else {
            return Ok(None);
        };
        v.extract::<bool>()
            .map(Some)
            .map_err(|_| PyTypeError::new_err(format!("{name} must be True or False, got {v}")))
    }

    /// A string option.
    pub fn string(&mut self, name: &str) -> PyResult<Option<String>> {
        let Some(v) = self.take(name)? else {
            return Ok(None);
        };
        v.extract::<String>()
            .map(Some)
            .map_err(|_| PyTypeError::new_err(format!("{name} must be a string, got {v}")))
    }

    /// A name or an index (an `int` or a `str`), as the command line's `NAME|INDEX` values.
    pub fn name_or_index(&mut self, name: &str) -> PyResult<Option<String>> {
        let Some(v) = self.take(name)? else {
            return Ok(None);
        };
        if v.is_instance_of::<PyString>() {
            return Ok(Some(v.extract()?));
        }
        match v.extract::<i64>() {
            Ok(n) if n >= 0 && !v.is_instance_of::<pyo3::types::PyBool>() => {
                Ok(Some(n.to_string()))
            }
            Ok(n) => Err(value_error(format!(
                "invalid {name} = {n}: an index is ≥ 0"
            ))),
            Err(_) => Err(PyTypeError::new_err(format!(
                "{name} must be a name (str) or an index (int), got {v}"
            ))),
        }
    }

    /// One of `choices` (by name), `None` when missing.
    pub fn choice<T: Copy>(&mut self, name: &str, choices: &[(&str, T)]) -> PyResult<Option<T>> {
        let Some(s) = self.string(name)? else {
            return Ok(None);
        };
        let key = s.to_ascii_lowercase().replace('_', "-");
        match choices.iter().find(|(n, _)| *n == key) {
            Some((_, v)) => Ok(Some(*v)),
            None => {
                let names: Vec<&str> = choices.iter().map(|(n, _)| *n).collect();
                Err(value_error(format!(
                    "invalid {name} = {s:?}: expected one of {}",
                    names.join(", ")
                )))
            }
        }
    }

    /// `transmission=` or `single_sided=`: `auto`, `gltf` or `blender`.
    pub fn convention(&mut self, name: &str) -> PyResult<Option<Convention>> {
        self.choice(
            name,
            &[
                ("auto", Convention::Auto),
                ("gltf", Convention::Gltf),
                ("blender", Convention::Blender),
            ],
        )
    }
}

/// Finite numbers.
pub(crate) fn finite(x: f64) -> bool {
    x.is_finite()
}

/// Finite numbers ≥ 0.
pub(crate) fn non_negative(x: f64) -> bool {
    x.is_finite() && x >= 0.0
}

/// Finite numbers > 0.
pub(crate) fn positive(x: f64) -> bool {
    x.is_finite() && x > 0.0
}
