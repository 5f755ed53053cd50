//! `asperity init`: a commented template case and its gmsh script, ready to run: a block
//! pressed onto a foundation with a frictional interface (plane strain, half model). The
//! script shows both ways of defining a contact (two coincident curves, or one conforming
//! curve that asperity splits); the case uses the first and names the second in comments.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// The template files: (name, contents).
pub const TEMPLATES: [(&str, &str); 2] = [
    ("case.toml", include_str!("../../templates/case.toml")),
    (
        "block_on_foundation.geo",
        include_str!("../../templates/block_on_foundation.geo"),
    ),
];

/// Writes the template files into `dir` (created if missing) and returns their paths. Never
/// overwrites: if one of them exists already, nothing is written and the error names it.
pub fn write_templates(dir: &Path) -> Result<Vec<PathBuf>> {
    let paths: Vec<PathBuf> = TEMPLATES.iter().map(|(name, _)| dir.join(name)).collect();
    if dir.symlink_metadata().is_ok() && !dir.is_dir() {
        return Err(Error::io(
            dir,
            std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                "it is not a folder (a file, or a link to nothing)",
            ),
        ));
    }
    // A link to nothing counts as existing: create_new below would refuse it half-way.
    if let Some(existing) = paths.iter().find(|p| p.symlink_metadata().is_ok()) {
        return Err(Error::io(
            existing,
            std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                "the file exists already; `asperity init` does not overwrite files",
            ),
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    for (path, (_, text)) in paths.iter().zip(TEMPLATES) {
        // create_new: a file appearing between the check above and here is not overwritten.
        let mut file = std::fs::File::create_new(path).map_err(|e| Error::io(path, e))?;
        file.write_all(text.as_bytes())
            .map_err(|e| Error::io(path, e))?;
    }
    Ok(paths)
}
