//! Whole-or-nothing file writes: a temporary file in the target's folder, then a rename.
//!
//! The temporary file must be in the same folder because a rename is atomic only within one
//! file system; a reader of the target sees either the old file or the complete new one.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::Error;

/// Distinguishes temporary files of concurrent writes within one process; the process id
/// distinguishes processes.
static COUNTER: AtomicU64 = AtomicU64::new(0);

fn io_error(path: &Path, doing: &str, error: io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        message: format!("{doing}: {error}"),
    }
}

/// Writes `bytes` to `path` atomically. On any error the temporary file is removed and the
/// target is left as it was.
pub(crate) fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    write_atomically_with(path, |file| {
        file.write_all(bytes)
            .map_err(|e| io_error(path, "writing", e))
    })
}

/// Creates a temporary file beside `path`, lets `write` fill it, then syncs it and renames it
/// into place. On any error (from `write` or the file system) the temporary file is removed
/// and the target is left as it was.
pub(crate) fn write_atomically_with<E: From<Error>>(
    path: &Path,
    write: impl FnOnce(&mut File) -> Result<(), E>,
) -> Result<(), E> {
    let file_name = path
        .file_name()
        .ok_or_else(|| Error::Io {
            path: path.to_path_buf(),
            message: "not a file name".into(),
        })?
        .to_string_lossy()
        .into_owned();
    let dir = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
        _ => PathBuf::from("."),
    };

    let (temp_path, mut file) = create_temp(&dir, &file_name, path)?;
    let result = write(&mut file).and_then(|()| {
        // Without the sync a crash soon after the rename can leave an empty file under the
        // final name on some file systems; the cost is one flush per image.
        file.sync_all()
            .map_err(|e| io_error(path, &format!("writing {}", temp_path.display()), e))?;
        drop(file);
        fs::rename(&temp_path, path).map_err(|e| {
            E::from(io_error(
                path,
                &format!("renaming {} into place", temp_path.display()),
                e,
            ))
        })
    });
    if result.is_err() {
        // Best effort: the original error is the one worth reporting.
        let _ = fs::remove_file(&temp_path);
    }
    result
}

fn create_temp(dir: &Path, file_name: &str, target: &Path) -> Result<(PathBuf, File), Error> {
    let pid = std::process::id();
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        // Hidden and clearly temporary, so a crash leaves a recognisable leftover.
        let temp_path = dir.join(format!(".{file_name}.{pid}.{n}.tmp"));
        // create_new: never clobber a file we did not create (another writer's temp file).
        // Readable too: a streamed EXR's header is sorted in place after writing.
        match OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&temp_path)
        {
            Ok(file) => return Ok((temp_path, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => {
                return Err(io_error(
                    target,
                    &format!("creating temporary file in {}", dir.display()),
                    e,
                ))
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A fresh, empty folder for one test, removed again when dropped.
    pub(crate) struct Scratch(PathBuf);

    impl std::ops::Deref for Scratch {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }

    pub(crate) fn scratch_dir(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!(
            "aperture-imageio-test-{}-{name}",
            std::process::id()
        ));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    pub(crate) fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn writes_whole_file_and_leaves_no_temp() {
        let dir = scratch_dir("atomic-ok");
        let path = dir.join("a.bin");
        write_atomically(&path, b"first").unwrap();
        write_atomically(&path, b"second, longer").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"second, longer");
        assert_eq!(entries(&dir), vec!["a.bin".to_string()]);
    }

    #[test]
    fn missing_folder_errors_and_leaves_nothing() {
        let dir = scratch_dir("atomic-missing");
        let path = dir.join("no-such-folder").join("a.bin");
        let err = write_atomically(&path, b"x").unwrap_err();
        assert!(matches!(err, Error::Io { .. }), "{err}");
        assert!(entries(&dir).is_empty());
    }

    #[test]
    fn failed_rename_removes_temp_and_keeps_target() {
        // Renaming a file onto a non-empty folder fails, after the temp file was written.
        let dir = scratch_dir("atomic-rename");
        let target = dir.join("occupied");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("keep"), b"k").unwrap();
        let err = write_atomically(&target, b"x").unwrap_err();
        assert!(matches!(err, Error::Io { .. }), "{err}");
        assert_eq!(entries(&dir), vec!["occupied".to_string()]);
        assert_eq!(fs::read(target.join("keep")).unwrap(), b"k");
    }

    #[test]
    fn path_without_file_name_errors() {
        let err = write_atomically(Path::new("/"), b"x").unwrap_err();
        assert!(matches!(err, Error::Io { .. }), "{err}");
    }
}
