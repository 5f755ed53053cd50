//! The last line of defence against writing outside the output folder.
//!
//! Output file names are made of a fixed prefix, a name from the case file (a contact pair)
//! and a step number, joined onto the output folder. The names are checked when the case is
//! read ([`crate::config::check_name`]); every writer checks the final path once more here,
//! so that a name that slipped through (a new writer, a name from another source) cannot
//! climb out of the folder: a `..` after a folder name, a file name with control
//! characters, an over-long or reserved file name are errors naming the path.

use std::io;
use std::path::{Component, Path};

use crate::{Error, Result};

/// Longest file name (in bytes) of common file systems (ext4, NTFS, APFS).
const MAX_FILE_NAME: usize = 255;

/// Checks an output file path before anything is written to it.
///
/// The output folder given by the user may start with `..` (`--out ../results`); a `..`
/// *after* a folder name can only come from a name spliced into the path
/// (`out/contact_x/../../ESCAPED_0001.csv`) and would leave the output folder, so it is
/// rejected. The file name itself must be a plain name without control characters, not
/// `.`/`..`, and at most 255 bytes.
pub fn check_output_path(path: &Path) -> Result<()> {
    let refuse = |why: String| {
        Error::io(
            path,
            io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("refusing to write this output file: {why}"),
            ),
        )
    };
    let mut below_a_folder = false;
    for component in path.components() {
        match component {
            Component::Normal(_) => below_a_folder = true,
            Component::ParentDir if below_a_folder => {
                return Err(refuse(
                    "it contains `..` after a folder name and would leave the output folder".into(),
                ));
            }
            _ => {}
        }
    }
    let name = match path.components().next_back() {
        Some(Component::Normal(name)) => name.to_string_lossy(),
        _ => return Err(refuse("it does not end in a file name".into())),
    };
    if name.len() > MAX_FILE_NAME {
        return Err(refuse(format!(
            "its file name has {} bytes (at most {MAX_FILE_NAME})",
            name.len()
        )));
    }
    if name.chars().any(char::is_control) {
        return Err(refuse("its file name contains a control character".into()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(path: &str) -> bool {
        matches!(check_output_path(Path::new(path)), Err(Error::Io { .. }))
    }

    #[test]
    fn output_paths_inside_the_folder_pass() {
        for path in [
            "out/contact_fit_0001.csv",
            "../results/history.csv",
            "/tmp/run/bodies_0001.vtu",
            "./out/level_2/summary.json",
            "../../a/b.csv",
        ] {
            assert!(check_output_path(Path::new(path)).is_ok(), "{path}");
        }
    }

    #[test]
    fn escaping_or_malformed_paths_are_refused() {
        let long = format!("out/{}.csv", "a".repeat(MAX_FILE_NAME));
        for path in [
            "out/contact_x/../../../../ESCAPED_0001.csv",
            "out/..",
            "out/a/..",
            "/",
            "out/line\nbreak.csv",
            "out/bell\u{7}.csv",
            long.as_str(),
        ] {
            assert!(refused(path), "{path:?} accepted");
        }
    }
}
