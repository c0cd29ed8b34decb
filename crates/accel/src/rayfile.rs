//! Ray files in the raw format of the Embree anchor (`../shared/tools/embree-anchor`), so the
//! identical rays can be timed by Embree and by us.
//!
//! A `.rays` file is little-endian `f32`, six per ray (origin x y z, direction x y z, the
//! direction normalised), no header: 24 bytes a ray. The format has no `tmin` or `tmax`: rays read
//! from it are `[0, ∞)`. Where our rays end short of infinity (shadow rays towards a light), a
//! sidecar `.tmax` file beside the `.rays` one holds one little-endian `f32` `tmax` per ray; it is
//! ours alone (Embree's script neither writes nor reads it), and [`read_rays`] applies it when it
//! is there.

use crate::types::Ray;
use glam::Vec3;
use std::path::{Path, PathBuf};

/// Bytes one ray takes in a `.rays` file.
pub const RAY_RECORD_BYTES: usize = 24;

/// Why a ray file could not be read or written. Every variant names the file.
#[derive(Debug)]
pub enum RayFileError {
    /// The file could not be opened, read or written.
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file's length is not a whole number of records (a truncated or foreign file).
    Length {
        /// The file.
        path: PathBuf,
        /// Its length in bytes.
        len: usize,
        /// The record size it must be a multiple of (24 for `.rays`, 4 for `.tmax`).
        record: usize,
    },
    /// A value is NaN or infinite (an origin or direction component, or a `tmax` that is NaN).
    NotFinite {
        /// The file.
        path: PathBuf,
        /// The ray (0-based).
        ray: usize,
    },
    /// A `.tmax` sidecar holds another number of rays than its `.rays` file.
    TmaxCount {
        /// The sidecar.
        path: PathBuf,
        /// Values it holds.
        found: usize,
        /// Rays of the `.rays` file.
        expected: usize,
    },
}

impl std::fmt::Display for RayFileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Io { path, source } => write!(f, "{}: {source}", path.display()),
            Self::Length { path, len, record } => write!(
                f,
                "{}: {len} bytes is not a whole number of {record}-byte records (truncated?)",
                path.display()
            ),
            Self::NotFinite { path, ray } => {
                write!(
                    f,
                    "{}: ray {ray} has a NaN or infinite value",
                    path.display()
                )
            }
            Self::TmaxCount {
                path,
                found,
                expected,
            } => write!(
                f,
                "{}: {found} tmax values for {expected} rays",
                path.display()
            ),
        }
    }
}

impl std::error::Error for RayFileError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// The sidecar holding the `tmax` of the rays of `rays_path` (`x.rays` → `x.tmax`).
pub fn tmax_path(rays_path: &Path) -> PathBuf {
    rays_path.with_extension("tmax")
}

/// The bytes of a `.rays` file holding `rays` (origins and directions as given; `tmin` and
/// `tmax` are not stored).
pub fn encode_rays(rays: &[Ray]) -> Vec<u8> {
    let mut out = Vec::with_capacity(rays.len() * RAY_RECORD_BYTES);
    for r in rays {
        for v in r.origin.to_array().into_iter().chain(r.dir.to_array()) {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// The rays of a `.rays` file's bytes, each over `[0, ∞)`; `path` names the file in errors.
pub fn decode_rays(bytes: &[u8], path: &Path) -> Result<Vec<Ray>, RayFileError> {
    if bytes.len() % RAY_RECORD_BYTES != 0 {
        return Err(RayFileError::Length {
            path: path.to_owned(),
            len: bytes.len(),
            record: RAY_RECORD_BYTES,
        });
    }
    bytes
        .chunks_exact(RAY_RECORD_BYTES)
        .enumerate()
        .map(|(i, rec)| {
            let f: Vec<f32> = rec
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            let ray = Ray::new(Vec3::from_slice(&f[0..3]), Vec3::from_slice(&f[3..6]));
            if ray.origin.is_finite() && ray.dir.is_finite() {
                Ok(ray)
            } else {
                Err(RayFileError::NotFinite {
                    path: path.to_owned(),
                    ray: i,
                })
            }
        })
        .collect()
}

fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> RayFileError + '_ {
    move |source| RayFileError::Io {
        path: path.to_owned(),
        source,
    }
}

/// Reads a `.rays` file, then applies its `.tmax` sidecar if there is one.
pub fn read_rays(path: &Path) -> Result<Vec<Ray>, RayFileError> {
    let bytes = std::fs::read(path).map_err(io_error(path))?;
    let mut rays = decode_rays(&bytes, path)?;
    let sidecar = tmax_path(path);
    if sidecar != path && sidecar.is_file() {
        let bytes = std::fs::read(&sidecar).map_err(io_error(&sidecar))?;
        if bytes.len() % 4 != 0 {
            return Err(RayFileError::Length {
                path: sidecar,
                len: bytes.len(),
                record: 4,
            });
        }
        if bytes.len() / 4 != rays.len() {
            return Err(RayFileError::TmaxCount {
                path: sidecar,
                found: bytes.len() / 4,
                expected: rays.len(),
            });
        }
        for (i, (ray, c)) in rays.iter_mut().zip(bytes.chunks_exact(4)).enumerate() {
            let tmax = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            if tmax.is_nan() {
                return Err(RayFileError::NotFinite {
                    path: sidecar,
                    ray: i,
                });
            }
            ray.tmax = tmax;
        }
    }
    Ok(rays)
}

/// Writes `rays` as a `.rays` file at `path` and, when any ray ends short of infinity, their
/// `tmax` to the sidecar ([`tmax_path`]); otherwise removes a stale sidecar. Each file is written
/// to a temporary name and renamed, so a reader never sees half a file.
pub fn write_rays(path: &Path, rays: &[Ray]) -> Result<(), RayFileError> {
    write_atomic(path, &encode_rays(rays))?;
    let sidecar = tmax_path(path);
    if sidecar == path {
        return Ok(());
    }
    if rays.iter().any(|r| r.tmax != f32::INFINITY) {
        let bytes: Vec<u8> = rays.iter().flat_map(|r| r.tmax.to_le_bytes()).collect();
        write_atomic(&sidecar, &bytes)
    } else {
        match std::fs::remove_file(&sidecar) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(io_error(&sidecar)(e)),
            _ => Ok(()),
        }
    }
}

fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), RayFileError> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(".{}.tmp", std::process::id()));
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, bytes).map_err(io_error(&tmp))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io_error(path)(e)
    })
}
