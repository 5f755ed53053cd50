//! ParaView collection files (`.pvd`): the list of VTU files of a run, one or more per time
//! (load step), which ParaView and `pyvista.get_reader` open as one time series.
//!
//! vtkio has no support for this format and it is a few lines of XML, so it is written by
//! hand here. Each listed file carries a `part` number and a `name`: with several parts per
//! time (e.g. `bodies` and `interface`) ParaView shows a multiblock dataset whose blocks
//! carry those names.

use std::fmt::Write as _;
use std::path::{Component, Path, PathBuf};

use super::atomic::{invalid_data, write_text};
use super::csv::format_f64;
use crate::Result;

/// One file of a `.pvd` collection.
#[derive(Clone, Debug, PartialEq)]
pub struct PvdEntry {
    /// Time (or load factor) of this file; ParaView's time slider shows it.
    pub time: f64,
    /// Part number: files with the same `time` and different `part`s are shown together.
    pub part: u32,
    /// Block name of this part (e.g. `bodies`, `interface`).
    pub name: String,
    /// The file, relative to the `.pvd`'s directory or absolute. Absolute paths inside that
    /// directory are written relative to it, so the output folder can be moved as a whole.
    pub file: PathBuf,
}

impl PvdEntry {
    /// A single-part entry (part 0, no name): the common case of one VTU per step.
    pub fn new(time: f64, file: impl Into<PathBuf>) -> Self {
        PvdEntry {
            time,
            part: 0,
            name: String::new(),
            file: file.into(),
        }
    }
}

/// Writes the collection `path` listing `entries` in the given order (atomically, creating
/// the parent directory). Rewriting the whole file after every step keeps it valid XML at all
/// times, so a run can be watched in ParaView while it computes.
///
/// Fails if a time is not finite.
pub fn write_pvd(path: &Path, entries: &[PvdEntry]) -> Result<()> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut xml = String::from(
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (i, entry) in entries.iter().enumerate() {
        if !entry.time.is_finite() {
            return Err(invalid_data(
                path,
                format!(
                    "entry {i} ({}): time {} is not finite",
                    entry.file.display(),
                    entry.time
                ),
            ));
        }
        let file = relative_file(dir, &entry.file);
        let _ = writeln!(
            xml,
            "    <DataSet timestep=\"{}\" group=\"\" part=\"{}\" name=\"{}\" file=\"{}\"/>",
            format_f64(entry.time),
            entry.part,
            escape_attr(&entry.name),
            escape_attr(&file),
        );
    }
    xml.push_str("  </Collection>\n</VTKFile>\n");
    write_text(path, &xml)
}

/// The path to write for `file`: relative paths are kept (they are relative to the pvd
/// already), absolute ones under `dir` lose that prefix. Separators are `/`, which ParaView
/// accepts on every platform.
fn relative_file(dir: &Path, file: &Path) -> String {
    let rel = if file.is_absolute() {
        let abs_dir = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
        file.strip_prefix(&abs_dir).unwrap_or(file)
    } else {
        file
    };
    let mut out = String::new();
    for c in rel.components() {
        match c {
            Component::RootDir => out.push('/'),
            Component::CurDir => {}
            c => {
                if !out.is_empty() && !out.ends_with('/') {
                    out.push('/');
                }
                out.push_str(&c.as_os_str().to_string_lossy());
            }
        }
    }
    out
}

/// Escapes the characters that would end or break an XML attribute value.
pub(crate) fn escape_attr(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absolute_paths_inside_the_pvd_directory_become_relative() {
        assert_eq!(
            relative_file(Path::new("/out"), Path::new("/out/vtu/s1.vtu")),
            "vtu/s1.vtu"
        );
        assert_eq!(
            relative_file(Path::new("/out"), Path::new("./vtu/s1.vtu")),
            "vtu/s1.vtu"
        );
        assert_eq!(
            relative_file(Path::new("/out"), Path::new("/elsewhere/a.vtu")),
            "/elsewhere/a.vtu"
        );
    }

    #[test]
    fn attribute_values_are_escaped() {
        assert_eq!(escape_attr("a&b\"<c>"), "a&amp;b&quot;&lt;c&gt;");
    }
}
