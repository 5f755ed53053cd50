//! Generated files written into a folder the user names (`asperity man --out DIR`): only
//! names that are free or hold an earlier version of the same generated file are written,
//! each atomically (a symbolic link is never written through); the others are refused
//! before anything is written.

use std::io::Read;
use std::path::Path;

use crate::{Error, Result};

/// Bytes of an existing file read to tell whether it is one of ours.
const HEAD_BYTES: u64 = 4096;

/// Writes `files` (name, content) into `dir`, created if missing. Every name is checked
/// first: a symbolic link, something other than a regular file, or a file whose first
/// bytes `ours` does not recognise (a file of the user's) is an error
/// ([`Error::OutputForeign`]) before any file is written; then each file is written
/// atomically, replacing the earlier version.
pub fn write_generated(
    dir: &Path,
    files: &[(String, Vec<u8>)],
    ours: impl Fn(&[u8]) -> bool,
) -> Result<()> {
    if dir.symlink_metadata().is_ok() && !dir.is_dir() {
        return Err(Error::OutputForeign {
            dir: dir.to_path_buf(),
            file: dir.to_path_buf(),
            reason: "it is not a folder (a file, or a link to nothing)".into(),
        });
    }
    for (name, _) in files {
        let path = dir.join(name);
        let Ok(meta) = path.symlink_metadata() else {
            continue;
        };
        let reason = if meta.file_type().is_symlink() {
            Some("it is a symbolic link, which is never written through")
        } else if !meta.is_file() {
            Some("it is not a regular file")
        } else if !ours(&head(&path)?) {
            Some("it is a file of another origin, which would be overwritten")
        } else {
            None
        };
        if let Some(reason) = reason {
            return Err(Error::OutputForeign {
                dir: dir.to_path_buf(),
                file: path,
                reason: format!("{reason}: move it away or choose another folder"),
            });
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    for (name, bytes) in files {
        super::atomic::write_bytes(&dir.join(name), bytes)?;
    }
    Ok(())
}

/// The first [`HEAD_BYTES`] bytes of the file `path`.
fn head(path: &Path) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(HEAD_BYTES).read_to_end(&mut bytes))
        .map_err(|e| Error::io(path, e))?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_free_names_and_earlier_versions_are_written() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path().join("pages");
        let ours = |b: &[u8]| b.starts_with(b"ours");
        let files = vec![("a.1".to_string(), b"ours a".to_vec())];
        write_generated(&d, &files, ours).unwrap();
        let files = vec![
            ("a.1".to_string(), b"ours a, again".to_vec()),
            ("b.1".to_string(), b"ours b".to_vec()),
        ];
        write_generated(&d, &files, ours).unwrap();
        assert_eq!(std::fs::read(d.join("a.1")).unwrap(), b"ours a, again");
        // A file of the user's and a link are refused, and nothing is written.
        std::fs::write(d.join("b.1"), "mine").unwrap();
        let outside = dir.path().join("outside");
        std::fs::write(&outside, "keep").unwrap();
        std::fs::remove_file(d.join("a.1")).unwrap();
        #[cfg(unix)]
        std::os::unix::fs::symlink(&outside, d.join("a.1")).unwrap();
        let error = write_generated(&d, &files, ours).unwrap_err();
        assert!(matches!(&error, Error::OutputForeign { .. }), "{error}");
        assert_eq!(std::fs::read_to_string(d.join("b.1")).unwrap(), "mine");
        assert_eq!(std::fs::read_to_string(&outside).unwrap(), "keep");
        std::fs::remove_file(d.join("b.1")).unwrap();
        let error = write_generated(&d, &files, ours).unwrap_err();
        assert!(error.to_string().contains("symbolic link"), "{error}");
        assert_eq!(std::fs::read_to_string(&outside).unwrap(), "keep");
        assert!(
            !d.join("b.1").exists(),
            "written before every name was checked"
        );
        // A file where the folder should be.
        let error = write_generated(&outside, &files, ours).unwrap_err();
        assert!(error.to_string().contains("not a folder"), "{error}");
    }
}
