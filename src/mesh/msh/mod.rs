//! Reader of gmsh MSH 4.1 files (ascii or binary) into a [`Mesh`].
//!
//! The heavy lifting (entities, node coordinates, element connectivity) is done by the `mshio`
//! crate; this module adds what mshio leaves out or gets wrong for our purpose:
//!
//! - **Header checks before mshio.** mshio panics (`unimplemented!`, `unwrap`, integer overflow
//!   in debug builds) on some malformed headers, and only says "unsupported version" for
//!   MSH 2.2. We read `$MeshFormat` and the `$Nodes`/`$Elements` section headers ourselves
//!   first, so that these cases give a clear error instead of a panic. The mshio call itself is
//!   still wrapped in `catch_unwind` as a last resort.
//! - **Node tags.** When the tags are globally dense (`max - min == count - 1`), mshio throws
//!   them away and keeps only the coordinates. Dense tags need not follow the file order (e.g.
//!   after `Plugin(Crack)` or a renumbering), so assuming "n-th node has tag min + n" would
//!   silently scramble the connectivity. We therefore re-read the tags from the `$Nodes`
//!   section and cross-check the block sizes against mshio's.
//! - **`$PhysicalNames`**, which mshio ignores; it is always ASCII text, even in binary files.
//! - **Element kinds and orientation**: only quadratic cells are accepted (the solver's
//!   elements are quad8/tri6), and every cell is made counter-clockwise, so that Jacobians are
//!   positive and outward normals point the right way without checks further down.
//!
//! Errors are [`Error::Mesh`] values naming the file, the problem and the node, element or
//! section concerned, and saying how to fix the input.

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use mshio::{ElementType, MshFile, MshParserError};

mod report;
mod scan;
mod structure;

pub use report::describe;

use super::topology::model_size;
use super::{Cell, CellKind, Line3, Mesh, PhysicalGroup, PointElement};
use crate::error::{MeshEntity, MeshProblem};
use crate::{Error, Result};
use scan::{
    Header, NodeTags, TagIndex, find_line, looks_truncated, read_header, read_physical_names,
};
use structure::check_structure;

/// Advice appended to every "wrong element order" error.
const SECOND_ORDER_HINT: &str = "mesh with `gmsh -2 -order 2` and `-setnumber Mesh.SecondOrderIncomplete 1`, \
     or put `Mesh.ElementOrder = 2; Mesh.SecondOrderIncomplete = 1;` in the .geo file";

/// Reads a gmsh MSH 4.1 file (ascii or binary) into a [`Mesh`].
///
/// Node tags are mapped to contiguous 0-based indices (the gmsh tags are kept in
/// [`Mesh::node_tags`]), z is dropped after checking that the mesh is planar, quadratic
/// surface cells go to [`Mesh::cells`] (reoriented counter-clockwise where needed), 3-node
/// lines to [`Mesh::lines`] and point elements to [`Mesh::points`]. Physical groups are
/// collected from `$Entities` and named from `$PhysicalNames`.
///
/// Every failure is an `Err` naming the file: missing file, empty file, not MSH / truncated,
/// other MSH versions, first-order or unsupported elements, unknown node references,
/// non-planar or degenerate geometry. The function does not panic on bad input.
pub fn read_msh(path: &Path) -> Result<Mesh> {
    let bytes = read_bounded(path, MAX_MESH_FILE_BYTES)?;
    parse_msh(path, &bytes)
}

/// Largest mesh file read (1 GiB): twice an ASCII MSH file of
/// [`MAX_MESH_ELEMENTS`](crate::mesh::gmsh::MAX_MESH_ELEMENTS) quad8 elements, which is about
/// 0.5 GB. The whole file is held in memory while it is parsed.
pub const MAX_MESH_FILE_BYTES: u64 = 1 << 30;

/// Bytes read first, to recognise a file that is not MSH at all (such as `/dev/zero`)
/// before reading more.
const HEADER_BYTES: u64 = 4096;

/// The content of the mesh file `path`, refused beyond `limit` bytes: a regular file by its
/// length before reading, anything else (a FIFO, a device) while reading, which never reads
/// more than the limit; a file that does not start like MSH is refused after its first
/// [`HEADER_BYTES`].
fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>> {
    use std::io::Read;
    let file = match std::fs::File::open(path) {
        Ok(file) => file,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(Error::mesh(
                path,
                MeshProblem::NotFound,
                None,
                "cannot read the mesh: file not found",
            ));
        }
        Err(e) => return Err(Error::io(path, e)),
    };
    let too_large = |lead: String| {
        Error::mesh(
            path,
            MeshProblem::TooLarge,
            None,
            format!(
                "{lead} the {limit} bytes asperity reads (a mesh that size is far beyond what \
                 the solver can hold in memory); coarsen the mesh"
            ),
        )
    };
    let metadata = file.metadata().map_err(|e| Error::io(path, e))?;
    if metadata.is_file() && metadata.len() > limit {
        return Err(too_large(format!(
            "the mesh file has {} bytes, more than",
            metadata.len()
        )));
    }
    let mut bytes = Vec::new();
    let mut reader = file.take(HEADER_BYTES.min(limit + 1));
    reader
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    let starts_with_text = bytes.iter().any(|b| !b.is_ascii_whitespace());
    if starts_with_text
        && let Err(fault) = read_header(&bytes)
        && fault.problem == MeshProblem::Header
    {
        return Err(fault.at(path));
    }
    let rest = limit + 1 - bytes.len() as u64;
    let mut reader = reader.into_inner().take(rest);
    reader
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(too_large(
            "the mesh file (not a regular file) goes on beyond".into(),
        ));
    }
    Ok(bytes)
}

/// Parses the content of an MSH file; `path` is only used in error messages and stored in the
/// mesh. Split from [`read_msh`] so that tests and fuzz targets can feed byte strings.
pub fn parse_msh(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(file_error(
            path,
            MeshProblem::Empty,
            "the mesh file is empty".into(),
        ));
    }
    let at = |fault: Fault| fault.at(path);
    let header = read_header(bytes).map_err(at)?;
    let structure = check_structure(bytes, &header)
        .map_err(|fault| fault.truncated_if(looks_truncated(bytes)))
        .map_err(at)?;
    let msh = parse_with_mshio(path, bytes, &header)?;
    let (entities, nodes, elements) = sections(path, &msh)?;
    let mut mesh = read_nodes(path, nodes, &structure.node_tags)?;
    let size = model_size(&mesh.nodes);
    let index = TagIndex::new(&mesh.node_tags).map_err(at)?;
    read_elements(path, elements, &index, &mut mesh)?;
    orient_cells(&mut mesh, size)?;
    let names = read_physical_names(bytes, header.body_start).map_err(at)?;
    mesh.groups = physical_groups(entities, &names);
    let has_names = find_line(bytes, header.body_start, b"$PhysicalNames").is_some();
    warn_about_names(path, has_names, &mesh.groups);
    Ok(mesh)
}

/// An error about the file `path` as a whole.
fn file_error(path: &Path, problem: MeshProblem, message: String) -> Error {
    Error::mesh(path, problem, None, message)
}

/// An error about section `name` of the file `path`.
fn section_error(path: &Path, name: &'static str, problem: MeshProblem, message: &str) -> Error {
    Error::mesh(path, problem, Some(MeshEntity::Section(name)), message)
}

/// An error about element `tag` of the file `path`.
fn element_error(path: &Path, tag: u64, problem: MeshProblem, message: String) -> Error {
    Error::mesh(path, problem, Some(MeshEntity::Element(tag)), message)
}

/// The file parsed by mshio, once the checks of `header` passed; its errors (and, as a last
/// resort, its panics: the checks avoid those of mshio 0.4.2 that we know of) said as ours.
fn parse_with_mshio(path: &Path, bytes: &[u8], header: &Header) -> Result<MshFile<u64, i32, f64>> {
    let parsed = catch_unwind(AssertUnwindSafe(|| {
        mshio::parse_msh_bytes(bytes)
            .map_err(|e| parse_error_message(bytes, header.binary.is_some(), &e))
    }));
    let (problem, message) = match parsed {
        Ok(Ok(msh)) => return Ok(msh),
        Ok(Err(reason)) if looks_truncated(bytes) => (
            MeshProblem::Truncated,
            format!(
                "cannot parse the mesh: the file is truncated (it does not end with a $End... \
                 line); re-export it from gmsh. Parser error: {reason}"
            ),
        ),
        Ok(Err(reason)) if reason.contains("parametric") => (
            MeshProblem::Parametric,
            format!(
                "cannot parse the mesh: it contains parametric node coordinates, which are not \
                 supported; save it with `Mesh.SaveParametric = 0` (the default). Parser error: \
                 {reason}"
            ),
        ),
        Ok(Err(reason)) => (
            MeshProblem::Corrupt,
            format!("cannot parse the mesh (corrupt or unsupported MSH 4.1 content): {reason}"),
        ),
        Err(_) => (
            MeshProblem::ParserPanic,
            "cannot parse the mesh: the MSH parser (mshio) crashed on this file, which is \
             probably truncated or corrupt; re-export it from gmsh"
                .into(),
        ),
    };
    Err(file_error(path, problem, message))
}

type Sections<'a> = (
    &'a mshio::Entities<i32, f64>,
    &'a mshio::Nodes<u64, i32, f64>,
    &'a mshio::Elements<u64, i32>,
);

/// The `$Entities`, `$Nodes` and `$Elements` sections, which every mesh needs.
fn sections<'a>(path: &Path, msh: &'a MshFile<u64, i32, f64>) -> Result<Sections<'a>> {
    let missing = |name, message| section_error(path, name, MeshProblem::MissingSection, message);
    let data = &msh.data;
    Ok((
        data.entities.as_ref().ok_or_else(|| {
            missing(
                "$Entities",
                "the file has no $Entities section (physical groups cannot be read)",
            )
        })?,
        (data.nodes.as_ref()).ok_or_else(|| missing("$Nodes", "the file has no $Nodes section"))?,
        (data.elements.as_ref())
            .ok_or_else(|| missing("$Elements", "the file has no $Elements section"))?,
    ))
}

/// A mesh of the nodes of `nodes`, tagged by `tags` (our own reading of the `$Nodes`
/// section, which must describe the same blocks as mshio's): finite and in the x-y plane.
fn read_nodes(path: &Path, nodes: &mshio::Nodes<u64, i32, f64>, tags: &[NodeTags]) -> Result<Mesh> {
    if tags.len() != nodes.node_blocks.len()
        || tags.iter().zip(&nodes.node_blocks).any(|(t, b)| {
            t.len() != b.nodes.len() || (t.dim, t.entity) != (b.entity_dim, b.entity_tag)
        })
    {
        return Err(section_error(
            path,
            "$Nodes",
            MeshProblem::Corrupt,
            "the $Nodes section is inconsistent (node tag lists do not match the node blocks)",
        ));
    }
    let node_count: usize = tags.iter().map(NodeTags::len).sum();
    if node_count >= u32::MAX as usize {
        return Err(file_error(
            path,
            MeshProblem::TooManyNodes,
            format!("too many nodes ({node_count})"),
        ));
    }
    let mut mesh = Mesh {
        path: path.to_path_buf(),
        nodes: Vec::with_capacity(node_count),
        node_tags: Vec::with_capacity(node_count),
        ..Mesh::default()
    };
    let mut zs = Vec::with_capacity(node_count);
    for (block, block_tags) in nodes.node_blocks.iter().zip(tags) {
        for (node, &tag) in block.nodes.iter().zip(&block_tags.tags) {
            mesh.nodes.push([node.x, node.y]);
            mesh.node_tags.push(tag);
            zs.push(node.z);
        }
    }
    let finite = |i: usize| {
        mesh.nodes[i]
            .iter()
            .chain(&zs[i..=i])
            .all(|v| v.is_finite())
    };
    let node_fault = |i: usize, problem: MeshProblem, message: String| {
        Error::mesh(
            path,
            problem,
            Some(MeshEntity::Node(mesh.node_tags[i])),
            message,
        )
    };
    if let Some(i) = (0..node_count).find(|&i| !finite(i)) {
        return Err(node_fault(
            i,
            MeshProblem::NonFinite,
            format!("node {} has a non-finite coordinate", mesh.node_tags[i]),
        ));
    }
    let size = model_size(&mesh.nodes);
    if let Some(i) = zs.iter().position(|z| z.abs() > 1e-9 * size) {
        return Err(node_fault(
            i,
            MeshProblem::NotPlanar,
            format!(
                "node {} has z = {:e}: the mesh must lie in the x-y plane (z = 0)",
                mesh.node_tags[i], zs[i]
            ),
        ));
    }
    Ok(mesh)
}

/// Adds the elements of `elements` to `mesh`: quadratic cells, 3-node lines and points, their
/// nodes found by tag in `index`. Any other element type is refused, as is a mesh without
/// cells.
fn read_elements(
    path: &Path,
    elements: &mshio::Elements<u64, i32>,
    index: &TagIndex,
    mesh: &mut Mesh,
) -> Result<()> {
    for block in &elements.element_blocks {
        let kind = match block.element_type {
            ElementType::Qua8 => Some(CellKind::Quad8),
            ElementType::Tri6 => Some(CellKind::Tri6),
            ElementType::Lin3 | ElementType::Pnt => None,
            other => {
                let tag = block.elements.first().map_or(0, |e| e.element_tag);
                let (problem, message) = unsupported_element(other, tag);
                return Err(element_error(path, tag, problem, message));
            }
        };
        let entity = block.entity_tag;
        let lookup = |element_tag: u64, node_tag: u64| {
            index.get(node_tag).ok_or_else(|| {
                element_error(
                    path,
                    element_tag,
                    MeshProblem::UnknownNode,
                    format!(
                        "element {element_tag} references node {node_tag}, which is not in the \
                         $Nodes section"
                    ),
                )
            })
        };
        match kind {
            Some(kind) => {
                mesh.cells.reserve(block.elements.len());
                for e in &block.elements {
                    let mut cell_nodes = [0u32; 8];
                    for (slot, &t) in cell_nodes.iter_mut().zip(&e.nodes) {
                        *slot = lookup(e.element_tag, t)?;
                    }
                    mesh.cells.push(Cell {
                        kind,
                        nodes: cell_nodes,
                        entity,
                        tag: e.element_tag,
                    });
                }
            }
            None if block.element_type == ElementType::Lin3 => {
                mesh.lines.reserve(block.elements.len());
                for e in &block.elements {
                    let mut line_nodes = [0u32; 3];
                    for (slot, &t) in line_nodes.iter_mut().zip(&e.nodes) {
                        *slot = lookup(e.element_tag, t)?;
                    }
                    mesh.lines.push(Line3 {
                        nodes: line_nodes,
                        entity,
                        tag: e.element_tag,
                    });
                }
            }
            None => {
                for e in &block.elements {
                    let node = lookup(e.element_tag, e.nodes.first().copied().unwrap_or(0))?;
                    mesh.points.push(PointElement {
                        node,
                        entity,
                        tag: e.element_tag,
                    });
                }
            }
        }
    }
    if mesh.cells.is_empty() {
        return Err(file_error(
            path,
            MeshProblem::NoCells,
            "the mesh has no surface cells (8-node quads or 6-node triangles): mesh in 2D \
             (`gmsh -2`) and, if the .geo defines physical groups, put the surfaces in a \
             `Physical Surface` (gmsh then saves only grouped elements)"
                .into(),
        ));
    }
    Ok(())
}

/// Makes every cell of `mesh` (whose bounding-box diagonal is `size`) counter-clockwise;
/// refuses a cell whose corners enclose no area.
fn orient_cells(mesh: &mut Mesh, size: f64) -> Result<()> {
    let tolerance = 1e-12 * size * size;
    for i in 0..mesh.cells.len() {
        let area = mesh.corner_area(&mesh.cells[i]);
        if area.abs() < tolerance || !area.is_finite() {
            let cell = &mesh.cells[i];
            let corners: Vec<String> = cell.nodes[..cell.kind.corner_count()]
                .iter()
                .map(|&n| {
                    let p = mesh.nodes[n as usize];
                    format!("({}, {})", p[0], p[1])
                })
                .collect();
            return Err(element_error(
                &mesh.path,
                cell.tag,
                MeshProblem::Degenerate,
                format!(
                    "element {} is degenerate: its corners {} enclose no area",
                    cell.tag,
                    corners.join(", ")
                ),
            ));
        }
        if area < 0.0 {
            reverse(&mut mesh.cells[i]);
            mesh.reoriented_cells += 1;
        }
    }
    if mesh.reoriented_cells > 0 {
        tracing::warn!(
            "{}: {} of {} cells were clockwise and have been reoriented counter-clockwise",
            mesh.path.display(),
            mesh.reoriented_cells,
            mesh.cells.len()
        );
    }
    Ok(())
}

/// The physical groups of `entities`, named from `$PhysicalNames` (`names`; `dim:tag` where
/// a group has no name). Named groups whose entities were not saved still exist (with no
/// entities), so that a missing group is reported by `describe` rather than looking like a
/// typo in the case file.
fn physical_groups(
    entities: &mshio::Entities<i32, f64>,
    names: &HashMap<(u8, i32), String>,
) -> Vec<PhysicalGroup> {
    let mut groups: BTreeMap<(u8, i32), Vec<i32>> = BTreeMap::new();
    let mut add = |dim: u8, entity: i32, physical_tags: &[i32]| {
        for &p in physical_tags {
            groups.entry((dim, p)).or_default().push(entity);
        }
    };
    for p in &entities.points {
        add(0, p.tag, &p.physical_tags);
    }
    for c in &entities.curves {
        add(1, c.tag, &c.physical_tags);
    }
    for s in &entities.surfaces {
        add(2, s.tag, &s.physical_tags);
    }
    for v in &entities.volumes {
        add(3, v.tag, &v.physical_tags);
    }
    for &key in names.keys() {
        groups.entry(key).or_default();
    }
    groups
        .into_iter()
        .map(|((dim, tag), mut entities)| {
            entities.sort_unstable();
            entities.dedup();
            let name = names
                .get(&(dim, tag))
                .cloned()
                .unwrap_or_else(|| format!("{dim}:{tag}"));
            PhysicalGroup {
                dim,
                tag,
                name,
                entities,
            }
        })
        .collect()
}

/// Physical-name problems that need not stop a run but may surprise, one warning each with a
/// count: no `$PhysicalNames` section (the groups are then called `dim:tag` and a case must
/// use those), and one name given to several groups of one dimension (a case naming it gets
/// only the first of them).
fn warn_about_names(path: &Path, has_names: bool, groups: &[PhysicalGroup]) {
    if !has_names && !groups.is_empty() {
        tracing::warn!(
            "{}: no $PhysicalNames section: the {} physical groups are called `dim:tag` (e.g. \
             \"{}\")",
            path.display(),
            groups.len(),
            groups[0].name
        );
    }
    let mut seen = std::collections::HashSet::new();
    let repeated: Vec<&str> = groups
        .iter()
        .filter(|g| !seen.insert((g.dim, g.name.as_str())))
        .map(|g| g.name.as_str())
        .collect();
    if let Some(first) = repeated.first() {
        tracing::warn!(
            "{}: {} physical groups repeat the name of another group of the same dimension \
             (e.g. \"{first}\"); a case naming it gets only the first group",
            path.display(),
            repeated.len()
        );
    }
}

/// Extra geometric helpers of [`Mesh`] used by the reader and by [`describe`].
impl Mesh {
    /// Signed area of the corner polygon of `cell` (shoelace formula): positive when the
    /// corners run counter-clockwise. After [`read_msh`] it is positive for every cell.
    pub fn corner_area(&self, cell: &Cell) -> f64 {
        let n = cell.kind.corner_count();
        // Coordinates relative to the first corner: no cancellation for small cells far from
        // the origin.
        let o = self.nodes[cell.nodes[0] as usize];
        let rel = |k: usize| {
            let p = self.nodes[cell.nodes[k] as usize];
            [p[0] - o[0], p[1] - o[1]]
        };
        let mut twice = 0.0;
        for i in 1..n - 1 {
            let (a, b) = (rel(i), rel(i + 1));
            twice += a[0] * b[1] - b[0] * a[1];
        }
        0.5 * twice
    }
}

/// Reverses the orientation of a cell in place, keeping node 0 and each mid-side node on its
/// edge: the corners are traversed backwards, so edge k of the new cell is edge (n-1-k) of
/// the old one, reversed.
fn reverse(cell: &mut Cell) {
    let old = cell.nodes;
    let order: &[usize] = match cell.kind {
        CellKind::Quad8 => &[0, 3, 2, 1, 7, 6, 5, 4],
        CellKind::Tri6 => &[0, 2, 1, 5, 4, 3],
    };
    for (new, &o) in order.iter().enumerate() {
        cell.nodes[new] = old[o];
    }
}

/// A reading failure before the file name is known: what is wrong, where, and the message.
pub(super) struct Fault {
    problem: MeshProblem,
    entity: Option<MeshEntity>,
    message: String,
}

impl Fault {
    pub(super) fn new(
        problem: MeshProblem,
        entity: Option<MeshEntity>,
        message: impl Into<String>,
    ) -> Self {
        Self {
            problem,
            entity,
            message: message.into(),
        }
    }

    /// A missing section or unreadable numbers in a file that does not end with a `$End...`
    /// line are most likely due to a cut-short file: say so.
    fn truncated_if(self, truncated: bool) -> Self {
        let cut_short = matches!(
            self.problem,
            MeshProblem::MissingSection | MeshProblem::Corrupt | MeshProblem::CountMismatch
        );
        if !(truncated && cut_short) {
            return self;
        }
        Self {
            problem: MeshProblem::Truncated,
            message: format!(
                "the file is truncated (it does not end with a $End... line); re-export it from \
                 gmsh ({})",
                self.message
            ),
            ..self
        }
    }

    /// The [`Error::Mesh`] of this fault in the file `path`.
    fn at(self, path: &Path) -> Error {
        Error::mesh(path, self.problem, self.entity, self.message)
    }
}

/// Problem and message for an element type the solver cannot use.
fn unsupported_element(element_type: ElementType, tag: u64) -> (MeshProblem, String) {
    let code = element_type as i32;
    let unsupported = MeshProblem::UnsupportedElement;
    match element_type {
        ElementType::Lin2 | ElementType::Tri3 | ElementType::Qua4 => {
            let name = match element_type {
                ElementType::Lin2 => "2-node line",
                ElementType::Tri3 => "3-node triangle",
                _ => "4-node quadrangle",
            };
            (
                MeshProblem::FirstOrder,
                format!(
                    "the mesh is first order (element {tag} is a {name}, gmsh type {code}), but \
                     asperity needs quadratic elements: {SECOND_ORDER_HINT}"
                ),
            )
        }
        ElementType::Qua9 => (
            unsupported,
            format!(
                "element {tag} is a 9-node quadrangle (gmsh type 10), which is not supported: \
                 asperity uses 8-node quads (type 16); set `Mesh.SecondOrderIncomplete = 1` \
                 (or pass `-setnumber Mesh.SecondOrderIncomplete 1` to gmsh)"
            ),
        ),
        other => (
            unsupported,
            format!(
                "element {tag} has gmsh type {code} ({other:?}), which is not supported: asperity \
                 reads 8-node quads (type 16), 6-node triangles (9), 3-node lines (8) and points \
                 (15) of a 2D mesh; 8-node quads need `Mesh.ElementOrder = 2` and \
                 `Mesh.SecondOrderIncomplete = 1`"
            ),
        ),
    }
}

/// Turns an mshio error into a one-line reason: the chain of sections the error occurred in,
/// from the outside in, and where. mshio's own `Display` appends a hex dump of the whole rest
/// of the file, which is useless in a message.
fn parse_error_message(bytes: &[u8], binary: bool, error: &MshParserError<&[u8]>) -> String {
    let trace = error.filtered_backtrace();
    let Some((rest, _)) = trace.first() else {
        return "unknown parse error".into();
    };
    let chain: Vec<String> = trace
        .iter()
        .rev()
        .map(|(_, k)| k.context().map_or_else(|| k.to_string(), str::to_string))
        .map(|s| s.trim_end_matches('.').to_string())
        .collect();
    let mut message = chain.join(" > ");
    // The error location is a sub-slice of `bytes`: recover its offset from the addresses.
    let offset = (rest.as_ptr() as usize).wrapping_sub(bytes.as_ptr() as usize);
    if offset <= bytes.len() {
        if binary {
            let _ = write!(message, " (at byte {offset})");
        } else {
            let line = bytes[..offset].iter().filter(|&&b| b == b'\n').count() + 1;
            let _ = write!(message, " (at line {line})");
        }
    }
    message
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An element block: (dim, gmsh type, [(element tag, node tags)]).
    type Block = (i32, i32, Vec<(u64, Vec<u64>)>);

    /// Builds a small ascii MSH 4.1 file: one curve entity (tag 1, physical 2 "edge") and one
    /// surface entity (tag 1, physical 1 "my body"), all nodes in one block, and the given
    /// element blocks `(dim, gmsh type, [(element tag, node tags)])`.
    fn msh(nodes: &[(u64, [f64; 3])], blocks: &[Block]) -> String {
        let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
        s += "$PhysicalNames\n2\n1 2 \"edge\"\n2 1 \"my body\"\n$EndPhysicalNames\n";
        s += "$Entities\n1 1 1 0\n1 0 0 0 0\n1 0 0 0 1 1 0 1 2 0\n1 0 0 0 1 1 0 1 1 0\n$EndEntities\n";
        let (min, max) = (
            nodes.iter().map(|n| n.0).min().unwrap_or(0),
            nodes.iter().map(|n| n.0).max().unwrap_or(0),
        );
        s += &format!(
            "$Nodes\n1 {} {min} {max}\n2 1 0 {}\n",
            nodes.len(),
            nodes.len()
        );
        for (t, _) in nodes {
            s += &format!("{t}\n");
        }
        for (_, p) in nodes {
            s += &format!("{} {} {}\n", p[0], p[1], p[2]);
        }
        s += "$EndNodes\n";
        let count: usize = blocks.iter().map(|b| b.2.len()).sum();
        let tags = blocks.iter().flat_map(|b| b.2.iter().map(|e| e.0));
        let (min, max) = (tags.clone().min().unwrap_or(0), tags.max().unwrap_or(0));
        s += &format!("$Elements\n{} {count} {min} {max}\n", blocks.len());
        for (dim, kind, elements) in blocks {
            s += &format!("{dim} 1 {kind} {}\n", elements.len());
            for (tag, ns) in elements {
                let ns: Vec<String> = ns.iter().map(u64::to_string).collect();
                s += &format!("{tag} {}\n", ns.join(" "));
            }
        }
        s + "$EndElements\n"
    }

    /// The 8 nodes of the quad8 [0,2]x[0,1] with tags 101..=108, in gmsh counter-clockwise
    /// order (corners then mid-sides).
    fn quad_nodes() -> Vec<(u64, [f64; 3])> {
        let p = [
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [0.0, 1.0],
            [1.0, 0.0],
            [2.0, 0.5],
            [1.0, 1.0],
            [0.0, 0.5],
        ];
        p.iter()
            .enumerate()
            .map(|(i, q)| (101 + i as u64, [q[0], q[1], 0.0]))
            .collect()
    }

    fn parse_str(text: &str) -> Result<Mesh> {
        parse_msh(Path::new("test.msh"), text.as_bytes())
    }

    /// The problem and entity of a mesh error in "test.msh".
    fn error_of(text: &str) -> (MeshProblem, Option<MeshEntity>) {
        match parse_str(text) {
            Ok(_) => panic!("parsed without error"),
            Err(e) => problem(e, "test.msh"),
        }
    }

    fn problem(e: Error, file: &str) -> (MeshProblem, Option<MeshEntity>) {
        match e {
            Error::Mesh {
                path,
                problem,
                entity,
                ..
            } if path == Path::new(file) => (problem, entity),
            other => panic!("expected a mesh error of {file}, got {other}"),
        }
    }

    #[test]
    fn counter_clockwise_quad_is_kept() {
        let text = msh(&quad_nodes(), &[(2, 16, vec![(7, (101..=108).collect())])]);
        let mesh = parse_str(&text).unwrap();
        assert_eq!(mesh.cells.len(), 1);
        assert_eq!(mesh.cells[0].nodes(), &[0, 1, 2, 3, 4, 5, 6, 7]);
        assert_eq!(mesh.cells[0].tag, 7);
        assert_eq!(mesh.cells[0].entity, 1);
        assert_eq!(mesh.reoriented_cells, 0);
        assert!((mesh.corner_area(&mesh.cells[0]) - 2.0).abs() < 1e-15);
        assert_eq!(mesh.node_tags, (101..=108).collect::<Vec<_>>());
    }

    #[test]
    fn corner_area_is_accurate_far_from_the_origin() {
        let nodes: Vec<_> = quad_nodes()
            .into_iter()
            .map(|(t, p)| (t, [1e6 + 1e-3 * p[0], -1e6 + 1e-3 * p[1], 0.0]))
            .collect();
        let mesh = parse_str(&msh(&nodes, &[(2, 16, vec![(1, (101..=108).collect())])])).unwrap();
        let area = mesh.corner_area(&mesh.cells[0]);
        // Coordinates near 1e6 carry ~1e-10 absolute error; the plain shoelace formula would
        // be off by ~1e-4 here.
        assert!((area - 2e-6).abs() < 1e-12, "{area}");
    }

    #[test]
    fn clockwise_quad_is_reversed_with_its_mid_nodes() {
        // Same quad listed clockwise: corners 0,3,2,1 and mid-sides (0-3),(3-2),(2-1),(1-0).
        let cw = vec![101, 104, 103, 102, 108, 107, 106, 105];
        let mesh = parse_str(&msh(&quad_nodes(), &[(2, 16, vec![(1, cw)])])).unwrap();
        assert_eq!(mesh.reoriented_cells, 1);
        assert_eq!(mesh.cells[0].nodes(), &[0, 1, 2, 3, 4, 5, 6, 7]);
    }

    #[test]
    fn clockwise_tri6_is_reversed_with_its_mid_nodes() {
        let nodes = vec![
            (1, [0.0, 0.0, 0.0]),
            (2, [1.0, 0.0, 0.0]),
            (3, [0.0, 1.0, 0.0]),
            (4, [0.5, 0.0, 0.0]),
            (5, [0.5, 0.5, 0.0]),
            (6, [0.0, 0.5, 0.0]),
        ];
        let cw = vec![1, 3, 2, 6, 5, 4];
        let mesh = parse_str(&msh(&nodes, &[(2, 9, vec![(1, cw)])])).unwrap();
        assert_eq!(mesh.reoriented_cells, 1);
        assert_eq!(mesh.cells[0].kind, CellKind::Tri6);
        assert_eq!(mesh.cells[0].nodes(), &[0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn names_lines_points_and_groups() {
        let blocks = [
            (2, 16, vec![(1, (101..=108).collect())]),
            (1, 8, vec![(2, vec![101, 102, 105])]),
            (0, 15, vec![(3, vec![103])]),
        ];
        let mesh = parse_str(&msh(&quad_nodes(), &blocks)).unwrap();
        assert_eq!(mesh.lines.len(), 1);
        assert_eq!(mesh.lines[0].nodes, [0, 1, 4]);
        assert_eq!(mesh.points.len(), 1);
        assert_eq!(mesh.points[0].node, 2);
        let names: Vec<_> = mesh
            .groups
            .iter()
            .map(|g| (g.dim, g.tag, g.name.as_str()))
            .collect();
        assert_eq!(names, vec![(1, 2, "edge"), (2, 1, "my body")]);
        assert_eq!(mesh.group(2, "my body").unwrap().entities, vec![1]);
    }

    #[test]
    fn unnamed_groups_are_called_dim_colon_tag() {
        let text = msh(&quad_nodes(), &[(2, 16, vec![(1, (101..=108).collect())])]);
        let text = text.replace("2\n1 2 \"edge\"\n2 1 \"my body\"\n", "1\n1 2 \"edge\"\n");
        let mesh = parse_str(&text).unwrap();
        assert_eq!(mesh.groups[1].name, "2:1");
    }

    #[test]
    fn sparse_huge_tags_use_the_hash_map() {
        let mut nodes = quad_nodes();
        nodes[3].0 = 1 << 40;
        let ns = vec![101, 102, 103, 1 << 40, 105, 106, 107, 108];
        let mesh = parse_str(&msh(&nodes, &[(2, 16, vec![(1, ns)])])).unwrap();
        assert_eq!(mesh.cells[0].nodes(), &[0, 1, 2, 3, 4, 5, 6, 7]);
        assert_eq!(mesh.node_tags[3], 1 << 40);
    }

    #[test]
    fn bad_content_errors() {
        let quad = |ns: Vec<u64>| vec![(2, 16, vec![(9, ns)])];
        let mut nodes = quad_nodes();
        nodes[2].1[2] = 1e-3;
        let e = error_of(&msh(&nodes, &quad((101..=108).collect())));
        assert_eq!(e, (MeshProblem::NotPlanar, Some(MeshEntity::Node(103))));

        let e = error_of(&msh(
            &quad_nodes(),
            &quad(vec![101, 102, 103, 77, 105, 106, 107, 108]),
        ));
        assert_eq!(e, (MeshProblem::UnknownNode, Some(MeshEntity::Element(9))));

        let mut nodes = quad_nodes();
        nodes[1].0 = 101;
        let e = error_of(&msh(&nodes, &quad((101..=108).collect())));
        assert_eq!(e, (MeshProblem::DuplicateNode, Some(MeshEntity::Node(101))));

        // All corners on one line: zero area.
        let mut nodes = quad_nodes();
        nodes[2].1 = [3.0, 0.0, 0.0];
        nodes[3].1 = [1.5, 0.0, 0.0];
        let e = error_of(&msh(&nodes, &quad((101..=108).collect())));
        assert_eq!(e, (MeshProblem::Degenerate, Some(MeshEntity::Element(9))));

        let e = error_of(&msh(
            &quad_nodes(),
            &[(1, 8, vec![(1, vec![101, 102, 105])])],
        ));
        assert_eq!(e, (MeshProblem::NoCells, None));

        let e = error_of(&msh(
            &quad_nodes(),
            &[(2, 3, vec![(1, vec![101, 102, 103, 104])])],
        ));
        assert_eq!(e, (MeshProblem::FirstOrder, Some(MeshEntity::Element(1))));

        let e = error_of(&msh(
            &quad_nodes(),
            &[(2, 16, vec![]), (2, 10, vec![(1, vec![101; 9])])],
        ));
        assert_eq!(
            e,
            (
                MeshProblem::UnsupportedElement,
                Some(MeshEntity::Element(1))
            )
        );
    }

    #[test]
    fn missing_sections_and_bad_headers() {
        let full = msh(&quad_nodes(), &[(2, 16, vec![(1, (101..=108).collect())])]);
        let cut = |from: &str, to: &str| {
            let (a, b) = (
                full.find(from).unwrap(),
                full.find(to).unwrap() + to.len() + 1,
            );
            format!("{}{}", &full[..a], &full[b..])
        };
        for (section, end) in [
            ("$Entities", "$EndEntities"),
            ("$Nodes", "$EndNodes"),
            ("$Elements", "$EndElements"),
        ] {
            let e = error_of(&cut(section, end));
            let entity = Some(MeshEntity::Section(section));
            assert_eq!(e, (MeshProblem::MissingSection, entity));
        }
        let header = Some(MeshEntity::Section("$MeshFormat"));
        let e = error_of(&full.replace("4.1 0 8", "4.0 0 8"));
        assert_eq!(e, (MeshProblem::Version, header));
        let e = error_of(&full.replace("4.1 0 8", "4.1 7 8"));
        assert_eq!(e, (MeshProblem::Header, header));
        let e = error_of(&full.replace("4.1 0 8", "4.1 0 99999999999999999999999"));
        assert_eq!(e, (MeshProblem::Header, header));
        let e = error_of(&full.replace("\"edge\"", "edge"));
        let names = Some(MeshEntity::Section("$PhysicalNames"));
        assert_eq!(e, (MeshProblem::PhysicalNames, names));
        let e = error_of("  \n\t\n");
        assert_eq!(e, (MeshProblem::Empty, None));
    }

    /// Inputs on which mshio 0.4.2 itself panics: the pre-checks must turn them into errors.
    #[test]
    fn mshio_panic_inputs_are_errors() {
        // Binary file with 3-byte size_t: mshio hits `unimplemented!`.
        let mut binary = b"$MeshFormat\n4.1 1 3\n".to_vec();
        binary.extend_from_slice(&1i32.to_le_bytes());
        binary.extend_from_slice(b"\n$EndMeshFormat\n");
        let e = problem(parse_msh(Path::new("b.msh"), &binary).unwrap_err(), "b.msh");
        let header = Some(MeshEntity::Section("$MeshFormat"));
        assert_eq!(e, (MeshProblem::Header, header));

        // Sections declaring zero entries: mshio computes `count - 1` (overflow panic in debug).
        let full = msh(&quad_nodes(), &[(2, 16, vec![(1, (101..=108).collect())])]);
        let start = full.find("$Nodes").unwrap();
        let end = full.find("$Elements").unwrap();
        let empty_nodes = format!(
            "{}$Nodes\n0 0 1 1\n$EndNodes\n{}",
            &full[..start],
            &full[end..]
        );
        let e = error_of(&empty_nodes);
        let nodes = Some(MeshEntity::Section("$Nodes"));
        assert_eq!(e, (MeshProblem::EmptySection, nodes));
        let start = full.find("$Elements").unwrap();
        let empty_elements = format!("{}$Elements\n0 0 1 1\n$EndElements\n", &full[..start]);
        let e = error_of(&empty_elements);
        let elements = Some(MeshEntity::Section("$Elements"));
        assert_eq!(e, (MeshProblem::EmptySection, elements));
    }

    /// Cuts and corrupts the fixture `name` at every `stride`-th byte and checks that parsing
    /// gives an error (or, for harmless edits, a mesh), never a panic — neither ours nor
    /// mshio's (which `catch_unwind` would report as a crash).
    fn never_panics(name: &str, stride: usize) {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
        let bytes = std::fs::read(dir.join(name)).unwrap();
        let check = |data: &[u8]| {
            if let Err(e) = parse_msh(Path::new(name), data) {
                let (problem, _) = problem(e, name);
                assert_ne!(problem, MeshProblem::ParserPanic, "mshio panicked");
            }
        };
        for len in (0..bytes.len()).step_by(stride) {
            check(&bytes[..len]);
        }
        let mut data = bytes.clone();
        for i in (0..bytes.len()).step_by(stride) {
            for b in [b'0', b'9', b' ', b'\n', b'-', 0xff, 0] {
                data[i] = b;
                check(&data);
            }
            data[i] = bytes[i];
        }
    }

    #[test]
    fn truncated_or_corrupted_files_never_panic() {
        never_panics("clockwise.msh", 7);
        never_panics("two_bodies_bin.msh", 13);
    }

    /// Exhaustive version of the test above (over a minute in debug builds, a few seconds with
    /// `--release`).
    #[test]
    #[ignore = "slow: run with --ignored"]
    fn truncated_or_corrupted_files_never_panic_exhaustive() {
        for name in [
            "two_bodies_ascii.msh",
            "two_bodies_bin.msh",
            "tri6.msh",
            "sparse.msh",
        ] {
            never_panics(name, 1);
        }
    }

    #[test]
    fn describe_a_small_mesh() {
        let mut nodes = quad_nodes();
        nodes.push((200, [5.0, 5.0, 0.0]));
        let mesh = parse_str(&msh(&nodes, &[(2, 16, vec![(1, (101..=108).collect())])])).unwrap();
        let report = describe(&mesh, &[]);
        assert!(report.contains("nodes: 9"), "{report}");
        assert!(report.contains("cells: 1 (quad8: 1, tri6: 0)"), "{report}");
        assert!(report.contains("my body"), "{report}");
        assert!(
            report.contains("1 nodes are used by no element (tags 200)"),
            "{report}"
        );
        assert!(
            report.contains("physical group \"edge\" (dim 1, tag 2) has no lines"),
            "{report}"
        );
    }

    /// A cell whose corners are in order but whose mid-side node lies far from its edge's
    /// middle (the bottom one at 0.15 of the edge, nearer the corner than the quarter point)
    /// folds its map: a run refuses it, and `mesh-info` says so instead of "problems: none".
    #[test]
    fn describe_names_a_distorted_cell() {
        let mut nodes = quad_nodes();
        nodes[4].1 = [0.3, 0.0, 0.0];
        let mesh = parse_str(&msh(&nodes, &[(2, 16, vec![(1, (101..=108).collect())])])).unwrap();
        let distorted = crate::element::kinematics::distorted_cells(&mesh);
        assert_eq!(distorted, [1]);
        let report = describe(&mesh, &distorted);
        assert!(report.contains("1 distorted cells"), "{report}");
        assert!(report.contains("elements 1"), "{report}");
        let plain = parse_str(&msh(
            &quad_nodes(),
            &[(2, 16, vec![(1, (101..=108).collect())])],
        ));
        assert!(crate::element::kinematics::distorted_cells(&plain.unwrap()).is_empty());
    }

    /// A stream (here a FIFO fed without end) is read no further than the limit, then
    /// refused; within the limit it is read like a file.
    #[test]
    fn streams_are_read_up_to_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("mesh.msh");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(made.unwrap().success(), "mkfifo");
        let feed = |fifo: std::path::PathBuf, text: Vec<u8>, repeat: usize| {
            std::thread::spawn(move || {
                use std::io::Write;
                let mut pipe = std::fs::OpenOptions::new().write(true).open(fifo).unwrap();
                // The reader stops at its limit and closes the pipe: a broken pipe ends the
                // feed.
                for _ in 0..repeat {
                    if pipe.write_all(&text).is_err() {
                        break;
                    }
                }
            })
        };
        let limit = 10_000;
        let mesh = msh(&quad_nodes(), &[(2, 16, vec![(1, (101..=108).collect())])]);
        let mut endless = mesh.clone().into_bytes();
        endless.extend(b"$Comments\n");
        let writer = feed(fifo.clone(), endless, usize::MAX);
        let error = read_bounded(&fifo, limit).unwrap_err();
        writer.join().unwrap();
        let Error::Mesh {
            problem, message, ..
        } = &error
        else {
            panic!("{error}")
        };
        assert_eq!(*problem, MeshProblem::TooLarge, "{error}");
        assert!(message.contains("10000 bytes"), "{error}");

        let writer = feed(fifo.clone(), mesh.clone().into_bytes(), 1);
        let bytes = read_bounded(&fifo, limit).unwrap();
        writer.join().unwrap();
        assert_eq!(bytes, mesh.into_bytes());
    }
}
