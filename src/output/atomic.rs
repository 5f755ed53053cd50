//! Writing a file so that it is either complete or absent.
//!
//! A run can stop at any moment (an error in a later step, Ctrl-C, a killed job), and
//! ParaView or a post-processing script may read the output folder while the run is still
//! going. Writing straight into `step_0007.vtu` would expose a truncated file in both
//! cases; instead every writer of this module tree goes through [`write_atomically`], which
//! writes a hidden temporary file next to the target and renames it into place. A rename
//! within one directory (one filesystem) replaces the target in a single step on POSIX
//! systems, so readers see either the old file or the new one, never a mixture.

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// Writes `path` by calling `write` on a buffered temporary file in the same directory and
/// renaming that file onto `path` once `write` has succeeded and the data is flushed.
///
/// Creates the parent directory if it is missing. On any failure the temporary file is
/// removed and the error names `path`; an existing file at `path` is left untouched.
///
/// Validation of the data should happen *before* calling this, so that a bad value does not
/// even create the temporary file; `write` may still fail (disk full, ...), in which case
/// the cleanup here applies.
pub(crate) fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<()> {
    let file_name = path.file_name().ok_or_else(|| {
        Error::io(
            path,
            io::Error::new(io::ErrorKind::InvalidInput, "the path has no file name"),
        )
    })?;
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.to_path_buf(),
        _ => PathBuf::from("."),
    };
    fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;

    // Hidden (leading dot) so that file browsers and `*.vtu` globs skip it, and in the same
    // directory so that the final rename cannot cross filesystems.
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(file_name);
    tmp_name.push(".tmp");
    let tmp = dir.join(tmp_name);

    let result = (|| -> io::Result<()> {
        let mut writer = BufWriter::with_capacity(1 << 20, File::create(&tmp)?);
        write(&mut writer)?;
        // `into_inner` flushes and reports flush errors, which dropping a `BufWriter` would
        // silently swallow (a full disk would then yield a truncated file and `Ok`).
        let file = writer
            .into_inner()
            .map_err(io::IntoInnerError::into_error)?;
        // Make the data durable before the rename makes it visible, so that a crash of
        // the machine cannot leave a renamed but empty file.
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp, path)
    })();

    result.map_err(|e| {
        // Best effort: the original error matters more than a failed cleanup.
        let _ = fs::remove_file(&tmp);
        Error::io(path, e)
    })
}

/// Builds the [`Error::Io`] used for data that cannot be written (wrong lengths, NaN, ...):
/// the file is what the user sees, so the error names it, and the message names the
/// offending array and index.
pub(crate) fn invalid_data(path: &Path, message: impl Into<String>) -> Error {
    Error::io(
        path,
        io::Error::new(io::ErrorKind::InvalidData, message.into()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_nothing_behind_and_keeps_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        fs::write(&path, "old").unwrap();
        let err = write_atomically(&path, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("boom"))
        })
        .unwrap_err();
        assert!(err.to_string().contains("boom"), "{err}");
        assert_eq!(fs::read_to_string(&path).unwrap(), "old");
        let names: Vec<_> = fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a.txt")]);
    }

    #[test]
    fn creates_missing_parent_directories() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x/y/b.txt");
        write_atomically(&path, |w| w.write_all(b"new")).unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "new");
        assert!(!dir.path().join("x/y/.b.txt.tmp").exists());
    }
}
