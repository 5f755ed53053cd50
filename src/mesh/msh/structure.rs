//! A structural walk of the `$Entities`, `$Nodes` and `$Elements` sections before mshio sees
//! the file: a reader that believes no header.
//!
//! mshio 0.4 (on nom 5) preallocates every list with the count its header announces, so a
//! header claiming 10¹² nodes aborts the program on a failed allocation, and it never
//! compares a section's total with its blocks. Here every count is checked against the bytes
//! that are left before anything sized by it is allocated (each item takes at least a few
//! bytes), the totals and tag ranges of the headers against the blocks, every block's
//! entity against `$Entities`, its dimension against its element type, and element tags for
//! duplicates. The node tags read on the way are returned (mshio drops dense ones).

use std::collections::BTreeSet;

use super::Fault;
use super::scan::{Cursor, Header, NodeTags, find_line};
use crate::error::{MeshEntity, MeshProblem};

const ENTITIES: &str = "$Entities";
const NODES: &str = "$Nodes";
const ELEMENTS: &str = "$Elements";

/// What the walk found: the node tags per block, in file order.
pub(super) struct Structure {
    pub(super) node_tags: Vec<NodeTags>,
}

/// Walks the three sections; see the module documentation.
pub(super) fn check_structure(bytes: &[u8], header: &Header) -> Result<Structure, Fault> {
    let start = |section: &'static str| {
        find_line(bytes, header.body_start, section.as_bytes()).ok_or_else(|| {
            let message = match section {
                ENTITIES => "the file has no $Entities section (physical groups cannot be read)",
                NODES => "the file has no $Nodes section",
                _ => "the file has no $Elements section",
            };
            Fault::new(
                MeshProblem::MissingSection,
                Some(MeshEntity::Section(section)),
                message,
            )
        })
    };
    let (entities_at, nodes_at, elements_at) = (start(ENTITIES)?, start(NODES)?, start(ELEMENTS)?);
    let cursor = |pos| Cursor::new(bytes, pos, header.binary);
    let declared = walk_entities(&mut cursor(entities_at))?;
    let node_tags = walk_nodes(&mut cursor(nodes_at), &declared)?;
    walk_elements(&mut cursor(elements_at), &declared)?;
    Ok(Structure { node_tags })
}

/// The entities declared in `$Entities`: (dimension, tag).
type Declared = BTreeSet<(i32, i32)>;

fn fault(section: &'static str, problem: MeshProblem, message: String) -> Fault {
    Fault::new(problem, Some(MeshEntity::Section(section)), message)
}

fn corrupt(section: &'static str, what: &str) -> Fault {
    fault(
        section,
        MeshProblem::Corrupt,
        format!("cannot read {what} in the {section} section (truncated or corrupt file?)"),
    )
}

/// Reads a count of items that each take at least `tokens` numbers (`bytes_each` bytes in a
/// binary file) and checks that so many items fit in the rest of the file.
fn count(
    c: &mut Cursor,
    section: &'static str,
    what: &str,
    tokens: usize,
    bytes_each: usize,
) -> Result<usize, Fault> {
    let n = c.size_t().ok_or_else(|| corrupt(section, what))?;
    // An ascii number takes at least one digit and one separator.
    let least = if c.is_binary() {
        bytes_each
    } else {
        2 * tokens
    };
    let fits = (c.remaining() / least.max(1)) as u64;
    if n > fits {
        return Err(fault(
            section,
            MeshProblem::CountMismatch,
            format!(
                "the {section} section announces {n} {what}, but the rest of the file can hold at \
                 most {fits}"
            ),
        ));
    }
    Ok(n as usize)
}

fn int(c: &mut Cursor, section: &'static str, what: &str) -> Result<i32, Fault> {
    c.int()
        .and_then(|v| i32::try_from(v).ok())
        .ok_or_else(|| corrupt(section, what))
}

/// `$Entities`: four counts, then points (tag, x y z, physical tags) and curves, surfaces,
/// volumes (tag, bounding box, physical tags, bounding entities).
fn walk_entities(c: &mut Cursor) -> Result<Declared, Fault> {
    let (int_bytes, size_t) = (4, c.size_t_bytes());
    let mut counts = [0; 4];
    for (dim, slot) in counts.iter_mut().enumerate() {
        let (tokens, bytes) = if dim == 0 {
            (5, int_bytes + 24 + size_t)
        } else {
            (9, int_bytes + 48 + 2 * size_t)
        };
        *slot = count(c, ENTITIES, "entities", tokens, bytes)?;
    }
    let mut declared = Declared::new();
    for (dim, &n) in counts.iter().enumerate() {
        for _ in 0..n {
            let tag = int(c, ENTITIES, "an entity tag")?;
            let doubles = if dim == 0 { 3 } else { 6 };
            c.skip_doubles(doubles)
                .ok_or_else(|| corrupt(ENTITIES, "an entity's coordinates"))?;
            let lists = if dim == 0 { 1 } else { 2 };
            for _ in 0..lists {
                let len = count(c, ENTITIES, "tags of an entity", 1, int_bytes)?;
                for _ in 0..len {
                    int(c, ENTITIES, "a physical or bounding tag")?;
                }
            }
            if !declared.insert((dim as i32, tag)) {
                return Err(fault(
                    ENTITIES,
                    MeshProblem::DuplicateEntity,
                    format!("entity {tag} of dimension {dim} is declared twice in $Entities"),
                ));
            }
        }
    }
    Ok(declared)
}

/// The section header shared by `$Nodes` and `$Elements`: block count, total, min and max tag.
struct SectionHeader {
    blocks: usize,
    total: u64,
    min: u64,
    max: u64,
}

fn section_header(
    c: &mut Cursor,
    section: &'static str,
    block_tokens: usize,
    block_bytes: usize,
) -> Result<SectionHeader, Fault> {
    let blocks = count(c, section, "blocks", block_tokens, block_bytes)?;
    let mut next = || {
        c.size_t()
            .ok_or_else(|| corrupt(section, "the section header"))
    };
    Ok(SectionHeader {
        blocks,
        total: next()?,
        min: next()?,
        max: next()?,
    })
}

/// Checks the header's total and tag range against the tags found in the blocks.
fn check_totals(section: &'static str, h: &SectionHeader, tags: &[u64]) -> Result<(), Fault> {
    let mismatch = |message: String| fault(section, MeshProblem::CountMismatch, message);
    if tags.len() as u64 != h.total {
        return Err(mismatch(format!(
            "the {section} header announces {} entries, but its blocks hold {}",
            h.total,
            tags.len()
        )));
    }
    let (min, max) = (tags.iter().min(), tags.iter().max());
    if let (Some(&min), Some(&max)) = (min, max)
        && (min, max) != (h.min, h.max)
    {
        return Err(mismatch(format!(
            "the {section} header gives tags {}..={}, but the blocks hold tags {min}..={max}",
            h.min, h.max
        )));
    }
    Ok(())
}

/// The entity of a block must be declared in `$Entities`: otherwise its physical group is
/// unknown and would silently be lost.
fn check_declared(
    section: &'static str,
    declared: &Declared,
    dim: i32,
    entity: i32,
) -> Result<(), Fault> {
    if !(0..=3).contains(&dim) {
        return Err(fault(
            section,
            MeshProblem::Corrupt,
            format!("a block of the {section} section has dimension {dim} (must be 0 to 3)"),
        ));
    }
    if !declared.contains(&(dim, entity)) {
        return Err(fault(
            section,
            MeshProblem::UndeclaredEntity,
            format!(
                "a block of the {section} section belongs to entity {entity} of dimension {dim}, \
                 which $Entities does not declare (its physical group would be lost)"
            ),
        ));
    }
    Ok(())
}

/// `$Nodes`: blocks of (dim, entity, parametric, count), then the tags, then the coordinates.
fn walk_nodes(c: &mut Cursor, declared: &Declared) -> Result<Vec<NodeTags>, Fault> {
    let size_t = c.size_t_bytes();
    let header = section_header(c, NODES, 4, 12 + size_t)?;
    if header.total == 0 {
        return Err(empty(NODES, "nodes"));
    }
    let mut blocks = Vec::with_capacity(header.blocks);
    let mut all = Vec::new();
    for _ in 0..header.blocks {
        let dim = int(c, NODES, "a block header")?;
        let entity = int(c, NODES, "a block header")?;
        let parametric = int(c, NODES, "a block header")?;
        if parametric != 0 {
            return Err(fault(
                NODES,
                MeshProblem::Parametric,
                "the mesh contains parametric node coordinates, which are not supported; save \
                 it with `Mesh.SaveParametric = 0` (the default)"
                    .into(),
            ));
        }
        check_declared(NODES, declared, dim, entity)?;
        let n = count(c, NODES, "nodes in a block", 4, size_t + 24)?;
        let mut tags = Vec::with_capacity(n);
        for _ in 0..n {
            tags.push(c.size_t().ok_or_else(|| corrupt(NODES, "a node tag"))?);
        }
        c.skip_doubles(3 * n)
            .ok_or_else(|| corrupt(NODES, "node coordinates"))?;
        all.extend_from_slice(&tags);
        blocks.push(NodeTags { dim, entity, tags });
    }
    check_totals(NODES, &header, &all)?;
    Ok(blocks)
}

fn empty(section: &'static str, what: &str) -> Fault {
    fault(
        section,
        MeshProblem::EmptySection,
        format!("the {section} section contains no {what}: the mesh is empty (was it meshed?)"),
    )
}

/// Dimension and node count of the gmsh element types mshio reads (gmsh's numbering,
/// `GmshDefines.h`); `None` for the others.
fn element_type(code: i32) -> Option<(i32, usize)> {
    Some(match code {
        15 => (0, 1),
        1 => (1, 2),
        8 => (1, 3),
        26 => (1, 4),
        27 => (1, 5),
        28 => (1, 6),
        2 => (2, 3),
        3 => (2, 4),
        9 => (2, 6),
        10 => (2, 9),
        16 => (2, 8),
        20 => (2, 9),
        21 => (2, 10),
        22 => (2, 12),
        23 | 24 => (2, 15),
        25 => (2, 21),
        4 => (3, 4),
        5 => (3, 8),
        6 => (3, 6),
        7 => (3, 5),
        11 => (3, 10),
        12 => (3, 27),
        14 => (3, 14),
        17 => (3, 20),
        18 => (3, 15),
        19 => (3, 13),
        _ => return None,
    })
}

/// `$Elements`: blocks of (dim, entity, type, count), then per element its tag and nodes.
fn walk_elements(c: &mut Cursor, declared: &Declared) -> Result<(), Fault> {
    let size_t = c.size_t_bytes();
    let header = section_header(c, ELEMENTS, 4, 12 + size_t)?;
    if header.total == 0 {
        return Err(empty(ELEMENTS, "elements"));
    }
    let mut tags = Vec::new();
    for _ in 0..header.blocks {
        let dim = int(c, ELEMENTS, "a block header")?;
        let entity = int(c, ELEMENTS, "a block header")?;
        let code = int(c, ELEMENTS, "a block header")?;
        let (type_dim, nodes) = element_type(code).ok_or_else(|| {
            fault(
                ELEMENTS,
                MeshProblem::UnsupportedElement,
                format!(
                    "a block of the $Elements section has gmsh element type {code}, which is not \
                     supported: asperity reads 8-node quads (type 16), 6-node triangles (9), \
                     3-node lines (8) and points (15)"
                ),
            )
        })?;
        if type_dim != dim {
            return Err(fault(
                ELEMENTS,
                MeshProblem::MixedDimension,
                format!(
                    "a block of entity {entity} is declared of dimension {dim} but holds elements \
                     of gmsh type {code}, which are of dimension {type_dim}"
                ),
            ));
        }
        check_declared(ELEMENTS, declared, dim, entity)?;
        let n = count(
            c,
            ELEMENTS,
            "elements in a block",
            1 + nodes,
            (1 + nodes) * size_t,
        )?;
        tags.reserve(n);
        for _ in 0..n {
            tags.push(
                c.size_t()
                    .ok_or_else(|| corrupt(ELEMENTS, "an element tag"))?,
            );
            for _ in 0..nodes {
                c.size_t()
                    .ok_or_else(|| corrupt(ELEMENTS, "an element's node tags"))?;
            }
        }
    }
    check_totals(ELEMENTS, &header, &tags)?;
    tags.sort_unstable();
    if let Some(pair) = tags.windows(2).find(|w| w[0] == w[1]) {
        return Err(Fault::new(
            MeshProblem::DuplicateElement,
            Some(MeshEntity::Element(pair[0])),
            format!(
                "element tag {} appears twice in the $Elements section",
                pair[0]
            ),
        ));
    }
    Ok(())
}
