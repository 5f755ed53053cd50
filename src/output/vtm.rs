//! VTK multiblock files (`.vtm`): one per output frame, naming the parts of the model so that
//! ParaView's pipeline browser and `pyvista.read` show them by name. The file holds no data,
//! only the tree of blocks and the VTU file of each leaf:
//!
//! ```text
//! frame_0001.vtm
//! ├── bodies     ── one dataset per body, by the body's name
//! └── contacts   ── one dataset per contact pair, by the pair's name
//! ```
//!
//! Written by hand (a few lines of XML, as the `.pvd`), read by VTK's
//! `vtkXMLMultiBlockDataReader`, which keeps the names as the blocks' `NAME` metadata.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::atomic::write_text;
use super::pvd::escape_attr;
use crate::Result;

/// A block of a `.vtm` file: a name and its datasets (name, VTU file relative to the `.vtm`).
#[derive(Clone, Debug, PartialEq)]
pub struct VtmBlock {
    pub name: String,
    pub datasets: Vec<(String, PathBuf)>,
}

/// Writes the multiblock file `path` with `blocks` in order (atomically). File names are
/// written with `/` separators, as ParaView reads them on every platform.
pub fn write_vtm(path: &Path, blocks: &[VtmBlock]) -> Result<()> {
    let mut xml = String::from(
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"vtkMultiBlockDataSet\" version=\"1.0\" byte_order=\"LittleEndian\">\n  \
         <vtkMultiBlockDataSet>\n",
    );
    for (i, block) in blocks.iter().enumerate() {
        let _ = writeln!(
            xml,
            "    <Block index=\"{i}\" name=\"{}\">",
            escape_attr(&block.name)
        );
        for (j, (name, file)) in block.datasets.iter().enumerate() {
            let file: Vec<String> = file
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            let _ = writeln!(
                xml,
                "      <DataSet index=\"{j}\" name=\"{}\" file=\"{}\"/>",
                escape_attr(name),
                escape_attr(&file.join("/"))
            );
        }
        xml.push_str("    </Block>\n");
    }
    xml.push_str("  </vtkMultiBlockDataSet>\n</VTKFile>\n");
    write_text(path, &xml)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_and_datasets_are_named_and_escaped() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.vtm");
        let blocks = [VtmBlock {
            name: "bodies".into(),
            datasets: vec![("hub & shaft".into(), PathBuf::from("bodies_0001.vtu"))],
        }];
        write_vtm(&path, &blocks).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.contains("<Block index=\"0\" name=\"bodies\">"),
            "{text}"
        );
        assert!(
            text.contains(
                "<DataSet index=\"0\" name=\"hub &amp; shaft\" file=\"bodies_0001.vtu\"/>"
            ),
            "{text}"
        );
    }
}
