//! Where the OIDN library is looked for, in order (README "Denoising"):
//!
//! 1. an explicit path: `--oidn PATH`, else the `APERTURE_OIDN` environment variable (a file,
//!    or a folder holding the library: `libOpenImageDenoise.so.2` on Linux,
//!    `OpenImageDenoise.dll` on Windows, `libOpenImageDenoise.2.dylib` on macOS, [`LIBRARY`]);
//!    when given, nothing else is tried;
//! 2. the system's library search path (as `dlopen`, or `LoadLibraryExW` on Windows, finds it);
//! 3. the copy `tools/oidn/install.sh` installs: `${XDG_CACHE_HOME:-~/.cache}/aperture/oidn/lib/`;
//! 4. the `pyoidn` wheel in a Python site-packages folder (`pyoidn/oidn/lib/`, also `bin/` on
//!    Windows);
//! 5. a Blender installation's `lib/`: the `bpy` module's `bpy/lib/` in a site-packages folder
//!    (the project's own under `~/.cache/aperture/bpy-*/` too), or beside a `blender` on `PATH`
//!    (`blender.exe`, and its `blender.shared/` too, on Windows).

use crate::platform::{self, subdirs, BLENDER, BLENDER_LIB_DIRS, PACKAGE_LIB_DIRS};
use std::path::{Path, PathBuf};

pub use crate::platform::LIBRARY;

/// The environment variable naming the library (or its folder) when no path is given.
pub const ENV: &str = "APERTURE_OIDN";

/// Where a candidate library comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Origin {
    /// `--oidn PATH` (or a path given through the library's API).
    Explicit,
    /// The `APERTURE_OIDN` environment variable.
    Env,
    /// The system's library search path.
    System,
    /// `tools/oidn/install.sh`'s copy in the user's cache.
    Cache,
    /// A `pyoidn` wheel in a Python site-packages.
    Pyoidn,
    /// A Blender installation (or its `bpy` module).
    Blender,
}

impl std::fmt::Display for Origin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Origin::Explicit => "--oidn",
            Origin::Env => ENV,
            Origin::System => "system library path",
            Origin::Cache => "tools/oidn/install.sh's cache",
            Origin::Pyoidn => "pyoidn wheel",
            Origin::Blender => "Blender",
        })
    }
}

/// One place to try: a path to `dlopen` (a bare name for the system search).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Candidate {
    /// What to open.
    pub path: PathBuf,
    /// Where it comes from.
    pub origin: Origin,
}

/// The path a user gave: the library itself, or a folder holding [`LIBRARY`].
pub fn given(path: &Path) -> PathBuf {
    if path.is_dir() {
        path.join(LIBRARY)
    } else {
        path.to_path_buf()
    }
}

/// The explicit choice, if any: `explicit`, else a non-empty `env` (the value of [`ENV`]).
pub fn explicit_choice(explicit: Option<&Path>, env: Option<&str>) -> Option<Candidate> {
    if let Some(p) = explicit {
        return Some(Candidate {
            path: given(p),
            origin: Origin::Explicit,
        });
    }
    env.filter(|v| !v.is_empty()).map(|v| Candidate {
        path: given(Path::new(v)),
        origin: Origin::Env,
    })
}

/// The folder `tools/oidn/install.sh` installs into: `${XDG_CACHE_HOME:-$HOME/.cache}/aperture/oidn/lib`.
pub fn cache_dir() -> Option<PathBuf> {
    let cache = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| home().map(|h| h.join(".cache")))?;
    Some(cache.join("aperture").join("oidn").join("lib"))
}

fn home() -> Option<PathBuf> {
    platform::home()
}

/// The implicit places of steps 2–5, in order; only existing files past step 2.
pub fn implicit_candidates() -> Vec<Candidate> {
    let mut out = vec![Candidate {
        path: PathBuf::from(LIBRARY),
        origin: Origin::System,
    }];
    let mut push = |dir: PathBuf, origin| {
        let path = dir.join(LIBRARY);
        if path.is_file() && !out.iter().any(|c| c.path == path) {
            out.push(Candidate { path, origin });
        }
    };
    if let Some(dir) = cache_dir() {
        push(dir, Origin::Cache);
    }
    let sites = site_packages();
    for site in &sites {
        for lib in PACKAGE_LIB_DIRS {
            push(site.join("pyoidn").join("oidn").join(lib), Origin::Pyoidn);
        }
    }
    for site in &sites {
        for lib in BLENDER_LIB_DIRS {
            push(site.join("bpy").join(lib), Origin::Blender);
        }
    }
    for dir in blender_dirs() {
        push(dir, Origin::Blender);
    }
    out
}

/// Python site-packages folders worth a look, without running Python: the active virtual
/// environment or conda prefix, the user's, pyenv's, the system's, and the project's `bpy`
/// environments under `~/.cache/aperture/`.
fn site_packages() -> Vec<PathBuf> {
    let mut prefixes: Vec<PathBuf> = ["VIRTUAL_ENV", "CONDA_PREFIX"]
        .iter()
        .filter_map(|v| {
            std::env::var_os(v)
                .filter(|p| !p.is_empty())
                .map(PathBuf::from)
        })
        .collect();
    if let Some(h) = home() {
        prefixes.push(h.join(".local"));
        prefixes.extend(subdirs(&h.join(".pyenv").join("versions")));
        prefixes.extend(
            subdirs(&h.join(".cache").join("aperture"))
                .into_iter()
                .filter(|d| {
                    d.file_name()
                        .is_some_and(|n| n.to_string_lossy().starts_with("bpy"))
                }),
        );
    }
    prefixes.extend(["/usr/local", "/usr"].map(PathBuf::from));
    let mut out = Vec::new();
    for prefix in prefixes {
        platform::site_packages_of(&prefix, &mut out);
    }
    out
}

/// Blender's own `lib/` folders: beside each `blender` executable on `PATH`, and under
/// `/opt/blender*`.
fn blender_dirs() -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Some(path) = std::env::var_os("PATH") {
        for dir in std::env::split_paths(&path) {
            let exe = dir.join(BLENDER);
            if exe.is_file() {
                let real = std::fs::canonicalize(&exe).unwrap_or(exe);
                if let Some(parent) = real.parent() {
                    out.extend(BLENDER_LIB_DIRS.iter().map(|d| parent.join(d)));
                }
            }
        }
    }
    out.extend(
        subdirs(Path::new("/opt"))
            .into_iter()
            .filter(|d| {
                d.file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with("blender"))
            })
            .map(|d| d.join("lib")),
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_option_wins_over_the_environment() {
        let c = explicit_choice(Some(Path::new("/x/lib.so")), Some("/y")).unwrap();
        assert_eq!(
            (c.path, c.origin),
            (PathBuf::from("/x/lib.so"), Origin::Explicit)
        );
        let c = explicit_choice(None, Some("/y/lib.so")).unwrap();
        assert_eq!(c.origin, Origin::Env);
        assert_eq!(explicit_choice(None, Some("")), None);
        assert_eq!(explicit_choice(None, None), None);
    }

    #[test]
    fn a_folder_means_the_library_inside_it() {
        let dir = std::env::temp_dir();
        assert_eq!(given(&dir), dir.join(LIBRARY));
    }

    #[test]
    fn the_system_search_comes_first() {
        let c = implicit_candidates();
        assert_eq!(c[0].origin, Origin::System);
        assert_eq!(c[0].path, PathBuf::from(LIBRARY));
    }
}
