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
//! Errors are [`Error::Mesh`] values naming the file and saying how to fix the input.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::fmt::Write as _;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use mshio::{ElementType, MshFile, MshParserError};

use super::{Cell, CellKind, Line3, Mesh, PhysicalGroup, PointElement};
use crate::{Error, Result};

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
    let bytes = match std::fs::read(path) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(Error::mesh(path, "cannot read the mesh: file not found"));
        }
        Err(e) => return Err(Error::io(path, e)),
    };
    parse(path, &bytes)
}

/// Parses the content of an MSH file; `path` is only used in error messages and stored in the
/// mesh. Split from [`read_msh`] so that unit tests can feed byte strings.
fn parse(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let fail = |message: String| Error::mesh(path, message);

    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(fail("the mesh file is empty".into()));
    }
    let header = read_header(bytes).map_err(&fail)?;
    check_section_counts(bytes, &header).map_err(&fail)?;

    // Last resort only: the checks above avoid the panics of mshio 0.4.2 that we know of.
    let parsed = catch_unwind(AssertUnwindSafe(|| {
        mshio::parse_msh_bytes(bytes)
            .map_err(|e| parse_error_message(bytes, header.binary.is_some(), &e))
    }));
    let msh: MshFile<u64, i32, f64> = match parsed {
        Ok(Ok(msh)) => msh,
        Ok(Err(reason)) if looks_truncated(bytes) => {
            return Err(fail(format!(
                "cannot parse the mesh: the file is truncated (it does not end with a $End... \
                 line); re-export it from gmsh. Parser error: {reason}"
            )));
        }
        Ok(Err(reason)) if reason.contains("parametric") => {
            return Err(fail(format!(
                "cannot parse the mesh: it contains parametric node coordinates, which are not \
                 supported; save it with `Mesh.SaveParametric = 0` (the default). Parser error: \
                 {reason}"
            )));
        }
        Ok(Err(reason)) => {
            return Err(fail(format!(
                "cannot parse the mesh (corrupt or unsupported MSH 4.1 content): {reason}"
            )));
        }
        Err(_) => {
            return Err(fail(
                "cannot parse the mesh: the MSH parser (mshio) crashed on this file, which is \
                 probably truncated or corrupt; re-export it from gmsh"
                    .into(),
            ));
        }
    };

    let entities = msh.data.entities.as_ref().ok_or_else(|| {
        fail("the file has no $Entities section (physical groups cannot be read)".into())
    })?;
    let nodes = msh
        .data
        .nodes
        .as_ref()
        .ok_or_else(|| fail("the file has no $Nodes section".into()))?;
    let elements = msh
        .data
        .elements
        .as_ref()
        .ok_or_else(|| fail("the file has no $Elements section".into()))?;

    // --- nodes ---------------------------------------------------------------------------
    let tags = read_node_tags(bytes, &header).map_err(&fail)?;
    // Our reading of the tags must describe the same blocks as mshio's.
    if tags.len() != nodes.node_blocks.len()
        || tags.iter().zip(&nodes.node_blocks).any(|(t, b)| {
            t.len() != b.nodes.len() || (t.dim, t.entity) != (b.entity_dim, b.entity_tag)
        })
    {
        return Err(fail(
            "the $Nodes section is inconsistent (node tag lists do not match the node blocks)"
                .into(),
        ));
    }
    let node_count: usize = tags.iter().map(NodeTags::len).sum();
    if node_count >= u32::MAX as usize {
        return Err(fail(format!("too many nodes ({node_count})")));
    }
    let mut mesh = Mesh {
        path: path.to_path_buf(),
        nodes: Vec::with_capacity(node_count),
        node_tags: Vec::with_capacity(node_count),
        ..Mesh::default()
    };
    let mut zs = Vec::with_capacity(node_count);
    for (block, block_tags) in nodes.node_blocks.iter().zip(&tags) {
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
    if let Some(i) = (0..node_count).find(|&i| !finite(i)) {
        return Err(fail(format!(
            "node {} has a non-finite coordinate",
            mesh.node_tags[i]
        )));
    }
    let size = model_size(&mesh.nodes);
    if let Some(i) = zs.iter().position(|z| z.abs() > 1e-9 * size) {
        return Err(fail(format!(
            "node {} has z = {:e}: the mesh must lie in the x-y plane (z = 0)",
            mesh.node_tags[i], zs[i]
        )));
    }
    let index = TagIndex::new(&mesh.node_tags).map_err(&fail)?;

    // --- elements ------------------------------------------------------------------------
    for block in &elements.element_blocks {
        let kind = match block.element_type {
            ElementType::Qua8 => Some(CellKind::Quad8),
            ElementType::Tri6 => Some(CellKind::Tri6),
            ElementType::Lin3 | ElementType::Pnt => None,
            other => {
                let tag = block.elements.first().map_or(0, |e| e.element_tag);
                return Err(fail(unsupported_element_message(other, tag)));
            }
        };
        let entity = block.entity_tag;
        let lookup = |element_tag: u64, node_tag: u64| {
            index.get(node_tag).ok_or_else(|| {
                fail(format!(
                    "element {element_tag} references node {node_tag}, which is not in the \
                     $Nodes section"
                ))
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
        return Err(fail(
            "the mesh has no surface cells (8-node quads or 6-node triangles): mesh in 2D \
             (`gmsh -2`) and, if the .geo defines physical groups, put the surfaces in a \
             `Physical Surface` (gmsh then saves only grouped elements)"
                .into(),
        ));
    }

    // --- orientation ---------------------------------------------------------------------
    let tolerance = 1e-12 * size * size;
    for i in 0..mesh.cells.len() {
        let area = mesh.corner_area(&mesh.cells[i]);
        if area.abs() < tolerance || !area.is_finite() {
            let cell = &mesh.cells[i];
            let corners: Vec<String> = cell.nodes[..corner_count(cell.kind)]
                .iter()
                .map(|&n| {
                    let p = mesh.nodes[n as usize];
                    format!("({}, {})", p[0], p[1])
                })
                .collect();
            return Err(fail(format!(
                "element {} is degenerate: its corners {} enclose no area",
                cell.tag,
                corners.join(", ")
            )));
        }
        if area < 0.0 {
            reverse(&mut mesh.cells[i]);
            mesh.reoriented_cells += 1;
        }
    }

    // --- physical groups -----------------------------------------------------------------
    let names = read_physical_names(bytes, header.body_start).map_err(&fail)?;
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
    // Named groups whose entities were not saved still exist (with no entities), so that a
    // missing group is reported by `describe` rather than looking like a typo in the case file.
    for &key in names.keys() {
        groups.entry(key).or_default();
    }
    mesh.groups = groups
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
        .collect();

    Ok(mesh)
}

/// Extra geometric helpers of [`Mesh`] used by the reader and by [`describe`].
impl Mesh {
    /// Signed area of the corner polygon of `cell` (shoelace formula): positive when the
    /// corners run counter-clockwise. After [`read_msh`] it is positive for every cell.
    pub fn corner_area(&self, cell: &Cell) -> f64 {
        let n = corner_count(cell.kind);
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

/// Number of corner nodes (the first nodes of a cell in gmsh order).
fn corner_count(kind: CellKind) -> usize {
    match kind {
        CellKind::Quad8 => 4,
        CellKind::Tri6 => 3,
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

/// Largest extent of the node bounding box in x or y: the length scale of the relative
/// tolerances (planarity, degenerate cells). 0 for an empty mesh.
fn model_size(nodes: &[[f64; 2]]) -> f64 {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in nodes {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if nodes.is_empty() {
        0.0
    } else {
        (hi[0] - lo[0]).max(hi[1] - lo[1])
    }
}

/// Error message for an element type the solver cannot use.
fn unsupported_element_message(element_type: ElementType, tag: u64) -> String {
    let code = element_type as i32;
    match element_type {
        ElementType::Lin2 | ElementType::Tri3 | ElementType::Qua4 => {
            let name = match element_type {
                ElementType::Lin2 => "2-node line",
                ElementType::Tri3 => "3-node triangle",
                _ => "4-node quadrangle",
            };
            format!(
                "the mesh is first order (element {tag} is a {name}, gmsh type {code}), but \
                 asperity needs quadratic elements: {SECOND_ORDER_HINT}"
            )
        }
        ElementType::Qua9 => format!(
            "element {tag} is a 9-node quadrangle (gmsh type 10), which is not supported: \
             asperity uses 8-node quads (type 16); set `Mesh.SecondOrderIncomplete = 1` \
             (or pass `-setnumber Mesh.SecondOrderIncomplete 1` to gmsh)"
        ),
        other => format!(
            "element {tag} has gmsh type {code} ({other:?}), which is not supported: asperity \
             reads 8-node quads (type 16), 6-node triangles (9), 3-node lines (8) and points \
             (15) of a 2D mesh; 8-node quads need `Mesh.ElementOrder = 2` and \
             `Mesh.SecondOrderIncomplete = 1`"
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

/// Whether the file looks cut short: a complete MSH file ends with a `$End...` line. Lets
/// the parse error say "truncated" rather than leave the user guessing.
fn looks_truncated(bytes: &[u8]) -> bool {
    let body = trim(bytes);
    let last_line = body
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(body, |i| &body[i + 1..]);
    !last_line.starts_with(b"$End")
}

/// What we need of the `$MeshFormat` header.
#[derive(Debug)]
struct Header {
    /// `None` for ascii files, otherwise the binary number layout.
    binary: Option<Binary>,
    /// Offset just after `$EndMeshFormat`.
    body_start: usize,
}

/// Number layout of a binary MSH file (ints are 4 bytes, doubles 8).
#[derive(Clone, Copy, Debug)]
struct Binary {
    size_t: usize,
    little_endian: bool,
}

/// Reads and checks the `$MeshFormat` header. Doing this before mshio gives precise messages
/// (MSH 2.2, not an MSH file) and avoids mshio's panics on unusual `size_t` sizes.
fn read_header(bytes: &[u8]) -> std::result::Result<Header, String> {
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(0);
    let line_end = |from: usize| {
        bytes[from..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| from + i)
    };
    let first_end = line_end(start);
    if trim(&bytes[start..first_end]) != b"$MeshFormat" {
        return Err("not a gmsh MSH file (it does not start with $MeshFormat)".into());
    }
    let second = (first_end + 1).min(bytes.len());
    let second_end = line_end(second);
    let text = String::from_utf8_lossy(&bytes[second..second_end]);
    let fields: Vec<&str> = text.split_whitespace().collect();
    if fields.len() < 3 {
        return Err("the $MeshFormat header is incomplete (truncated file?)".into());
    }
    let version = fields[0];
    if version != "4.1" {
        let kind = if version.starts_with('2') {
            format!("MSH {version}")
        } else {
            format!("MSH version {version}")
        };
        return Err(format!(
            "{kind} is not supported: re-mesh with gmsh -format msh41 or \
             Mesh.MshFileVersion = 4.1"
        ));
    }
    let size_t: usize = fields[2].parse().map_err(|_| {
        format!(
            "invalid data size `{}` in the $MeshFormat header",
            fields[2]
        )
    })?;
    let mut pos = (second_end + 1).min(bytes.len());
    let binary = match fields[1] {
        "0" => None,
        "1" => {
            if size_t != 4 && size_t != 8 {
                return Err(format!(
                    "binary MSH files with {size_t}-byte size_t values are not supported \
                     (gmsh writes 8)"
                ));
            }
            let one: [u8; 4] = bytes
                .get(pos..pos + 4)
                .and_then(|b| b.try_into().ok())
                .ok_or("the $MeshFormat header is incomplete (truncated file?)")?;
            let little_endian = if i32::from_le_bytes(one) == 1 {
                true
            } else if i32::from_be_bytes(one) == 1 {
                false
            } else {
                return Err("cannot detect the byte order of the binary MSH file".into());
            };
            pos += 4;
            Some(Binary {
                size_t,
                little_endian,
            })
        }
        other => {
            return Err(format!(
                "invalid file type `{other}` in the $MeshFormat header (0 ascii, 1 binary)"
            ));
        }
    };
    let end = find_line(bytes, pos, b"$EndMeshFormat")
        .ok_or("the $MeshFormat header has no $EndMeshFormat (truncated file?)")?;
    Ok(Header {
        binary,
        body_start: end,
    })
}

/// Checks the counts in the `$Nodes` and `$Elements` headers: mshio computes `count - 1` on
/// them, which panics (debug builds) when a section declares zero entries.
fn check_section_counts(bytes: &[u8], header: &Header) -> std::result::Result<(), String> {
    for (section, what) in [(&b"$Nodes"[..], "nodes"), (&b"$Elements"[..], "elements")] {
        let Some(at) = find_line(bytes, header.body_start, section) else {
            continue; // missing sections are reported after parsing
        };
        let mut cursor = Cursor {
            bytes,
            pos: at,
            binary: header.binary,
        };
        let _blocks = cursor.size_t();
        if cursor.size_t() == Some(0) {
            return Err(format!(
                "the {} section contains no {what}: the mesh is empty (was it meshed?)",
                String::from_utf8_lossy(section)
            ));
        }
    }
    Ok(())
}

/// The node tags of one block of the `$Nodes` section, with the block's entity (to check
/// that they describe the same block as mshio's).
struct NodeTags {
    dim: i32,
    entity: i32,
    tags: Vec<u64>,
}

impl NodeTags {
    fn len(&self) -> usize {
        self.tags.len()
    }
}

/// Reads the node tags of every block of the `$Nodes` section, in file order.
///
/// mshio keeps the tags only when they are sparse; dense tags may still be permuted with
/// respect to the file order, so we always read them here. Only called after mshio parsed the
/// file successfully, so the section structure is known to be sound.
fn read_node_tags(bytes: &[u8], header: &Header) -> std::result::Result<Vec<NodeTags>, String> {
    let broken = || "cannot read the node tags of the $Nodes section (corrupt file?)".to_string();
    let at = find_line(bytes, header.body_start, b"$Nodes").ok_or_else(broken)?;
    let mut c = Cursor {
        bytes,
        pos: at,
        binary: header.binary,
    };
    let blocks = c.size_t().ok_or_else(broken)?;
    let _count = c.size_t().ok_or_else(broken)?;
    let _min = c.size_t().ok_or_else(broken)?;
    let _max = c.size_t().ok_or_else(broken)?;
    // Each block takes several bytes: a larger count is corrupt (and must not drive an
    // allocation).
    if blocks > bytes.len() as u64 {
        return Err(broken());
    }
    let mut all = Vec::with_capacity(blocks as usize);
    for _ in 0..blocks {
        let int = |c: &mut Cursor| c.int().and_then(|v| i32::try_from(v).ok());
        let dim = int(&mut c).ok_or_else(broken)?;
        let entity = int(&mut c).ok_or_else(broken)?;
        let parametric = int(&mut c).ok_or_else(broken)?;
        let n = c.size_t().ok_or_else(broken)?;
        if parametric != 0 || n > bytes.len() as u64 {
            return Err(broken());
        }
        let mut tags = Vec::with_capacity(n as usize);
        for _ in 0..n {
            tags.push(c.size_t().ok_or_else(broken)?);
        }
        c.skip_doubles(3 * n as usize).ok_or_else(broken)?;
        all.push(NodeTags { dim, entity, tags });
    }
    Ok(all)
}

/// Reads `$PhysicalNames` (`count`, then lines `dim tag "name"`) into a map (dim, tag) → name.
/// The section is optional; it is ASCII even in binary files.
fn read_physical_names(
    bytes: &[u8],
    from: usize,
) -> std::result::Result<HashMap<(u8, i32), String>, String> {
    let mut names = HashMap::new();
    let Some(start) = find_line(bytes, from, b"$PhysicalNames") else {
        return Ok(names);
    };
    let end = find_line(bytes, start, b"$EndPhysicalNames")
        .ok_or("the $PhysicalNames section has no $EndPhysicalNames")?;
    // `end` is just after the end tag line: cut the tag line off.
    let body = &bytes[start..end];
    let body = &body[..body.len() - trailing_line_len(body)];
    let text = String::from_utf8_lossy(body);
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let count: usize = lines
        .next()
        .and_then(|l| l.parse().ok())
        .ok_or("the $PhysicalNames section does not start with the number of names")?;
    let mut found = 0;
    for line in lines {
        let bad = || format!("malformed $PhysicalNames line `{line}` (expected: dim tag \"name\")");
        let mut fields = line.splitn(3, char::is_whitespace);
        let dim: u8 = fields.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
        let tag: i32 = fields
            .next()
            .and_then(|s| s.trim().parse().ok())
            .ok_or_else(bad)?;
        let name = fields.next().map(str::trim).ok_or_else(bad)?;
        let name = name
            .strip_prefix('"')
            .and_then(|n| n.strip_suffix('"'))
            .ok_or_else(bad)?;
        names.insert((dim, tag), name.to_string());
        found += 1;
    }
    if found != count {
        return Err(format!(
            "the $PhysicalNames section announces {count} names but contains {found}"
        ));
    }
    Ok(names)
}

/// Length of the last line of `body` including its line break (the `$End...` tag line).
fn trailing_line_len(body: &[u8]) -> usize {
    let without_break = body.strip_suffix(b"\n").unwrap_or(body);
    match without_break.iter().rposition(|&b| b == b'\n') {
        Some(i) => body.len() - i - 1,
        None => body.len(),
    }
}

/// Offset just after the first line, at or after `from`, that is exactly `tag` (optionally
/// surrounded by blanks). Section tags always start a line; in binary files a false match
/// inside binary data is astronomically unlikely, and the node tags read from the match are
/// cross-checked against mshio's node blocks anyway.
fn find_line(bytes: &[u8], from: usize, tag: &[u8]) -> Option<usize> {
    let mut line_start = from.min(bytes.len());
    while line_start < bytes.len() {
        let line_end = bytes[line_start..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| line_start + i);
        if trim(&bytes[line_start..line_end]) == tag {
            return Some((line_end + 1).min(bytes.len()));
        }
        line_start = line_end + 1;
    }
    None
}

/// `line` without leading and trailing ASCII whitespace (including `\r`).
fn trim(line: &[u8]) -> &[u8] {
    let start = line
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(line.len());
    let end = line
        .iter()
        .rposition(|b| !b.is_ascii_whitespace())
        .map_or(start, |i| i + 1);
    &line[start..end]
}

/// A minimal reader of MSH numbers, ascii (whitespace-separated tokens) or binary.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    binary: Option<Binary>,
}

impl Cursor<'_> {
    /// Next whitespace-separated ascii token.
    fn token(&mut self) -> Option<&[u8]> {
        let rest = self.bytes.get(self.pos..)?;
        let start = rest.iter().position(|b| !b.is_ascii_whitespace())?;
        let len = rest[start..]
            .iter()
            .position(u8::is_ascii_whitespace)
            .unwrap_or(rest.len() - start);
        self.pos += start + len;
        Some(&rest[start..start + len])
    }

    /// Next `n` raw bytes (binary files).
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let slice = self.bytes.get(self.pos..self.pos.checked_add(n)?)?;
        self.pos += n;
        Some(slice)
    }

    fn size_t(&mut self) -> Option<u64> {
        match self.binary {
            None => std::str::from_utf8(self.token()?).ok()?.parse().ok(),
            Some(b) => {
                let raw = self.take(b.size_t)?;
                let mut buf = [0u8; 8];
                if b.little_endian {
                    buf[..raw.len()].copy_from_slice(raw);
                    Some(u64::from_le_bytes(buf))
                } else {
                    buf[8 - raw.len()..].copy_from_slice(raw);
                    Some(u64::from_be_bytes(buf))
                }
            }
        }
    }

    fn int(&mut self) -> Option<i64> {
        match self.binary {
            None => std::str::from_utf8(self.token()?).ok()?.parse().ok(),
            Some(b) => {
                let raw: [u8; 4] = self.take(4)?.try_into().ok()?;
                Some(i64::from(if b.little_endian {
                    i32::from_le_bytes(raw)
                } else {
                    i32::from_be_bytes(raw)
                }))
            }
        }
    }

    fn skip_doubles(&mut self, n: usize) -> Option<()> {
        match self.binary {
            None => {
                for _ in 0..n {
                    self.token()?;
                }
            }
            Some(_) => {
                self.take(n.checked_mul(8)?)?;
            }
        }
        Some(())
    }
}

/// Map from gmsh node tag to node index. A flat vector when the tags are dense enough (the
/// common case: one array read per element node instead of a hash lookup), a hash map
/// otherwise (e.g. a few nodes with huge tags).
enum TagIndex {
    Dense { min: u64, index: Vec<u32> },
    Sparse(HashMap<u64, u32>),
}

impl TagIndex {
    const NONE: u32 = u32::MAX;

    fn new(tags: &[u64]) -> std::result::Result<Self, String> {
        let duplicate = |t: u64| format!("node tag {t} appears twice in the $Nodes section");
        let (Some(&min), Some(&max)) = (tags.iter().min(), tags.iter().max()) else {
            return Ok(TagIndex::Dense {
                min: 0,
                index: Vec::new(),
            });
        };
        let span = max - min;
        if span <= 2 * tags.len() as u64 + 1024 {
            let mut index = vec![Self::NONE; span as usize + 1];
            for (i, &t) in tags.iter().enumerate() {
                let slot = &mut index[(t - min) as usize];
                if *slot != Self::NONE {
                    return Err(duplicate(t));
                }
                *slot = i as u32;
            }
            Ok(TagIndex::Dense { min, index })
        } else {
            let mut index = HashMap::with_capacity(tags.len());
            for (i, &t) in tags.iter().enumerate() {
                if index.insert(t, i as u32).is_some() {
                    return Err(duplicate(t));
                }
            }
            Ok(TagIndex::Sparse(index))
        }
    }

    fn get(&self, tag: u64) -> Option<u32> {
        match self {
            TagIndex::Dense { min, index } => {
                let i = *index.get(usize::try_from(tag.checked_sub(*min)?).ok()?)?;
                (i != Self::NONE).then_some(i)
            }
            TagIndex::Sparse(map) => map.get(&tag).copied(),
        }
    }
}

/// A human-readable report of `mesh` for `asperity mesh-info`: sizes, element counts, the
/// physical groups with their element counts, and problems that would make a model fail or
/// behave unexpectedly (unused nodes, empty groups, degenerate or clockwise cells, cells in no
/// physical surface, ambiguous group names).
pub fn describe(mesh: &Mesh) -> String {
    let mut out = String::new();
    let quads = mesh
        .cells
        .iter()
        .filter(|c| c.kind == CellKind::Quad8)
        .count();
    let tris = mesh.cells.len() - quads;
    let _ = writeln!(out, "mesh: {}", mesh.path.display());
    let _ = writeln!(out, "nodes: {}", mesh.nodes.len());
    let _ = writeln!(
        out,
        "cells: {} (quad8: {quads}, tri6: {tris})",
        mesh.cells.len()
    );
    let _ = writeln!(out, "lines: {}", mesh.lines.len());
    let _ = writeln!(out, "points: {}", mesh.points.len());
    if !mesh.nodes.is_empty() {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &mesh.nodes {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let _ = writeln!(
            out,
            "bounding box: x [{}, {}], y [{}, {}]; typical element size {:.4}",
            lo[0],
            hi[0],
            lo[1],
            hi[1],
            mesh.typical_size()
        );
    }
    let _ = writeln!(
        out,
        "cells reoriented to counter-clockwise: {}",
        mesh.reoriented_cells
    );

    let mut problems: Vec<String> = Vec::new();
    let _ = writeln!(out, "physical groups: {}", mesh.groups.len());
    if !mesh.groups.is_empty() {
        let width = mesh
            .groups
            .iter()
            .map(|g| g.name.len())
            .max()
            .unwrap_or(4)
            .max(4);
        let _ = writeln!(
            out,
            "  dim  {:>5}  {:<width$}  elements  entities",
            "tag", "name"
        );
        for g in &mesh.groups {
            let (count, what) = match g.dim {
                0 => (mesh.points_in(g).count(), "points"),
                1 => (mesh.lines_in(g).count(), "lines"),
                2 => (mesh.cells_in(g).count(), "cells"),
                _ => (0, "elements"),
            };
            let entities: Vec<String> = g.entities.iter().map(i32::to_string).collect();
            let _ = writeln!(
                out,
                "  {:>3}  {:>5}  {:<width$}  {:>8}  {}",
                g.dim,
                g.tag,
                g.name,
                count,
                entities.join(" ")
            );
            if count == 0 {
                problems.push(format!(
                    "physical group \"{}\" (dim {}, tag {}) has no {what}",
                    g.name, g.dim, g.tag
                ));
            }
        }
    }
    let mut seen = HashSet::new();
    for g in &mesh.groups {
        if !seen.insert((g.dim, g.name.as_str())) {
            problems.push(format!(
                "several physical groups of dimension {} are called \"{}\"",
                g.dim, g.name
            ));
        }
    }

    let mut used = vec![false; mesh.nodes.len()];
    let nodes_of_elements = mesh
        .cells
        .iter()
        .flat_map(|c| c.nodes().iter().copied())
        .chain(mesh.lines.iter().flat_map(|l| l.nodes))
        .chain(mesh.points.iter().map(|p| p.node));
    for n in nodes_of_elements {
        if let Some(u) = used.get_mut(n as usize) {
            *u = true;
        }
    }
    let unused: Vec<u64> = (0..mesh.nodes.len())
        .filter(|&i| !used[i])
        .map(|i| mesh.node_tags.get(i).copied().unwrap_or(i as u64))
        .collect();
    if !unused.is_empty() {
        problems.push(format!(
            "{} nodes are used by no element (tags {})",
            unused.len(),
            list_some(&unused)
        ));
    }

    let size = model_size(&mesh.nodes);
    let tolerance = 1e-12 * size * size;
    let (mut degenerate, mut clockwise) = (Vec::new(), Vec::new());
    for c in &mesh.cells {
        let area = mesh.corner_area(c);
        if area.is_nan() || area.abs() < tolerance {
            degenerate.push(c.tag);
        } else if area < 0.0 {
            clockwise.push(c.tag);
        }
    }
    if !degenerate.is_empty() {
        problems.push(format!(
            "{} degenerate cells (zero-area corner polygon): elements {}",
            degenerate.len(),
            list_some(&degenerate)
        ));
    }
    if !clockwise.is_empty() {
        problems.push(format!(
            "{} clockwise cells: elements {}",
            clockwise.len(),
            list_some(&clockwise)
        ));
    }

    let surfaces: HashSet<i32> = mesh
        .groups
        .iter()
        .filter(|g| g.dim == 2)
        .flat_map(|g| g.entities.iter().copied())
        .collect();
    if surfaces.is_empty() {
        problems.push("no physical surface: bodies cannot be defined".into());
    } else {
        let orphans: Vec<u64> = mesh
            .cells
            .iter()
            .filter(|c| !surfaces.contains(&c.entity))
            .map(|c| c.tag)
            .collect();
        if !orphans.is_empty() {
            problems.push(format!(
                "{} cells are in no physical surface: elements {}",
                orphans.len(),
                list_some(&orphans)
            ));
        }
    }

    if problems.is_empty() {
        let _ = writeln!(out, "problems: none");
    } else {
        let _ = writeln!(out, "problems: {}", problems.len());
        for p in &problems {
            let _ = writeln!(out, "  - {p}");
        }
    }
    out
}

/// The first few numbers of `values`, comma-separated, with an ellipsis if there are more.
fn list_some(values: &[u64]) -> String {
    const SHOWN: usize = 10;
    let mut s: Vec<String> = values.iter().take(SHOWN).map(u64::to_string).collect();
    if values.len() > SHOWN {
        s.push("...".into());
    }
    s.join(", ")
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
        s += "$Entities\n0 1 1 0\n1 0 0 0 1 1 0 1 2 0\n1 0 0 0 1 1 0 1 1 0\n$EndEntities\n";
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
        parse(Path::new("test.msh"), text.as_bytes())
    }

    fn error_of(text: &str) -> String {
        match parse_str(text) {
            Ok(_) => panic!("parsed without error"),
            Err(e) => e.to_string(),
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
        assert!(
            e.contains("test.msh") && e.contains("node 103") && e.contains("x-y plane"),
            "{e}"
        );

        let e = error_of(&msh(
            &quad_nodes(),
            &quad(vec![101, 102, 103, 77, 105, 106, 107, 108]),
        ));
        assert!(e.contains("element 9 references node 77"), "{e}");

        let mut nodes = quad_nodes();
        nodes[1].0 = 101;
        let e = error_of(&msh(&nodes, &quad((101..=108).collect())));
        assert!(e.contains("node tag 101 appears twice"), "{e}");

        // All corners on one line: zero area.
        let mut nodes = quad_nodes();
        nodes[2].1 = [3.0, 0.0, 0.0];
        nodes[3].1 = [1.5, 0.0, 0.0];
        let e = error_of(&msh(&nodes, &quad((101..=108).collect())));
        assert!(
            e.contains("element 9 is degenerate") && e.contains("(3, 0)"),
            "{e}"
        );

        let e = error_of(&msh(
            &quad_nodes(),
            &[(1, 8, vec![(1, vec![101, 102, 105])])],
        ));
        assert!(e.contains("no surface cells"), "{e}");

        let e = error_of(&msh(
            &quad_nodes(),
            &[(2, 3, vec![(1, vec![101, 102, 103, 104])])],
        ));
        assert!(
            e.contains("first order") && e.contains("SecondOrderIncomplete = 1"),
            "{e}"
        );

        let e = error_of(&msh(
            &quad_nodes(),
            &[(2, 16, vec![]), (3, 4, vec![(1, vec![1; 4])])],
        ));
        assert!(
            e.contains("gmsh type 4") && e.contains("not supported"),
            "{e}"
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
            assert!(e.contains(&format!("no {section} section")), "{e}");
        }
        let e = error_of(&full.replace("4.1 0 8", "4.0 0 8"));
        assert!(e.contains("MSH version 4.0 is not supported"), "{e}");
        let e = error_of(&full.replace("4.1 0 8", "4.1 7 8"));
        assert!(e.contains("invalid file type"), "{e}");
        let e = error_of(&full.replace("4.1 0 8", "4.1 0 99999999999999999999999"));
        assert!(e.contains("invalid data size"), "{e}");
        let e = error_of(&full.replace("\"edge\"", "edge"));
        assert!(e.contains("malformed $PhysicalNames line"), "{e}");
        let e = error_of("  \n\t\n");
        assert!(e.contains("empty"), "{e}");
    }

    /// Inputs on which mshio 0.4.2 itself panics: the pre-checks must turn them into errors.
    #[test]
    fn mshio_panic_inputs_are_errors() {
        // Binary file with 3-byte size_t: mshio hits `unimplemented!`.
        let mut binary = b"$MeshFormat\n4.1 1 3\n".to_vec();
        binary.extend_from_slice(&1i32.to_le_bytes());
        binary.extend_from_slice(b"\n$EndMeshFormat\n");
        let e = parse(Path::new("b.msh"), &binary).unwrap_err().to_string();
        assert!(e.contains("3-byte size_t"), "{e}");

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
        assert!(e.contains("contains no nodes"), "{e}");
        let start = full.find("$Elements").unwrap();
        let empty_elements = format!("{}$Elements\n0 0 1 1\n$EndElements\n", &full[..start]);
        let e = error_of(&empty_elements);
        assert!(e.contains("contains no elements"), "{e}");
    }

    /// Cuts and corrupts the fixture `name` at every `stride`-th byte and checks that parsing
    /// gives an error (or, for harmless edits, a mesh), never a panic — neither ours nor
    /// mshio's (which `catch_unwind` would report as a crash).
    fn never_panics(name: &str, stride: usize) {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
        let bytes = std::fs::read(dir.join(name)).unwrap();
        let check = |data: &[u8]| {
            if let Err(e) = parse(Path::new(name), data) {
                let e = e.to_string();
                assert!(!e.contains("crashed"), "mshio panicked: {e}");
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
        let report = describe(&mesh);
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
}
