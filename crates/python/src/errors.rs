//! The module's exceptions and how the library's errors become them: `aperture.LoadError` for
//! a file that cannot be loaded, `ValueError` for a value the library refuses (options, edits,
//! arrays), `aperture.RenderError` for a render that fails, `OSError` for a file that cannot be
//! written. Each carries the library's message.

use aperture_output::OutputError;
use aperture_render::{RenderError as LibRenderError, SessionError};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyOSError, PyValueError};
use pyo3::PyErr;

create_exception!(
    aperture,
    LoadError,
    PyException,
    "The file could not be loaded (or loaded again after an edit): the library's message."
);
create_exception!(
    aperture,
    RenderError,
    PyException,
    "A render, denoise or write failed: the library's message."
);

/// A `ValueError` with `msg`.
pub(crate) fn value_error(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// A load or pose failure.
pub(crate) fn load_error(e: SessionError) -> PyErr {
    LoadError::new_err(e.to_string())
}

/// An edit the session refused (a bad node, material or key), or a reload that failed.
pub(crate) fn edit_error(e: SessionError) -> PyErr {
    match e {
        SessionError::Scene(aperture_scene::Error::Io { .. }) => load_error(e),
        e => value_error(e.to_string()),
    }
}

/// A render that could not start: its options are out of range (`ValueError`), or it failed.
pub(crate) fn render_error(e: LibRenderError) -> PyErr {
    match e {
        LibRenderError::NoSuchCamera { .. } | LibRenderError::InvalidOption { .. } => {
            value_error(e.to_string())
        }
        e => RenderError::new_err(e.to_string()),
    }
}

/// A render that could not be turned into an image or written.
pub(crate) fn output_error(e: OutputError) -> PyErr {
    match e {
        OutputError::Render(e) => render_error(e),
        OutputError::Image(e) => PyOSError::new_err(e.to_string()),
        e => RenderError::new_err(e.to_string()),
    }
}
