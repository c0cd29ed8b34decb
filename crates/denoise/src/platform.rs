//! What the OIDN library and Blender are called on each platform, and where Python keeps its
//! packages there: the only platform-specific part of the search ([`crate::locate`]).

/// The library's file name on this platform, as a literal (for `concat!`).
#[cfg(windows)]
macro_rules! library_name {
    () => {
        "OpenImageDenoise.dll"
    };
}
#[cfg(target_os = "macos")]
macro_rules! library_name {
    () => {
        "libOpenImageDenoise.2.dylib"
    };
}
#[cfg(not(any(windows, target_os = "macos")))]
macro_rules! library_name {
    () => {
        "libOpenImageDenoise.so.2"
    };
}
pub(crate) use library_name;

/// The library's file name (its soname on Linux, its install name on macOS: any OIDN 2.x).
pub const LIBRARY: &str = library_name!();

/// Blender's executable.
pub(crate) const BLENDER: &str = if cfg!(windows) {
    "blender.exe"
} else {
    "blender"
};

/// Folders beside Blender's executable that hold its shared libraries: `lib/` on Linux (and
/// in the `bpy` module), also `blender.shared/` on Windows.
pub(crate) const BLENDER_LIB_DIRS: &[&str] = if cfg!(windows) {
    &["blender.shared", "lib"]
} else {
    &["lib"]
};

/// Folders inside a package (the `pyoidn` wheel's `oidn/`) that hold its libraries: Windows
/// builds of OIDN put the DLLs in `bin/`.
pub(crate) const PACKAGE_LIB_DIRS: &[&str] = if cfg!(windows) {
    &["lib", "bin"]
} else {
    &["lib"]
};

/// The user's home folder: `HOME`, else (Windows) `USERPROFILE`.
pub(crate) fn home() -> Option<std::path::PathBuf> {
    ["HOME", "USERPROFILE"]
        .iter()
        .filter_map(std::env::var_os)
        .find(|v| !v.is_empty())
        .map(std::path::PathBuf::from)
}

/// The site-packages folders of a Python installation or environment at `prefix`:
/// `lib/python3.*/{site,dist}-packages` on Unix, `Lib/site-packages` on Windows.
pub(crate) fn site_packages_of(prefix: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
    if cfg!(windows) {
        out.push(prefix.join("Lib").join("site-packages"));
        return;
    }
    for python in subdirs(&prefix.join("lib")) {
        let name = python.file_name().map(|n| n.to_string_lossy().into_owned());
        if name.is_some_and(|n| n.starts_with("python3")) {
            out.push(python.join("site-packages"));
            out.push(python.join("dist-packages"));
        }
    }
}

/// The folders inside `dir`, sorted (newest versions last is not assumed); none if unreadable.
pub(crate) fn subdirs(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out: Vec<std::path::PathBuf> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(Result::ok)
                .map(|e| e.path())
                .filter(|p| p.is_dir())
                .collect()
        })
        .unwrap_or_default();
    out.sort();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_library_has_this_platforms_name() {
        let want = if cfg!(windows) {
            "OpenImageDenoise.dll"
        } else if cfg!(target_os = "macos") {
            "libOpenImageDenoise.2.dylib"
        } else {
            "libOpenImageDenoise.so.2"
        };
        assert_eq!(LIBRARY, want);
    }
}
