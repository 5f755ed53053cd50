//! The split pairing recipe: one conforming mesh with one physical curve between two bodies;
//! the curve's nodes are duplicated (as gmsh's `Plugin(Crack)` would do) and body B is moved
//! onto the copies.

use std::collections::{HashMap, HashSet};

use super::{Ctx, InterfaceTopology};
use crate::Result;
use crate::error::TopologyProblem;
use crate::mesh::Mesh;
use crate::mesh::topology::{EdgeUse, cell_edges, edge_key};

/// What [`apply_split`] will do, fully checked.
pub(super) struct SplitPlan {
    /// Nodes to duplicate (order of first appearance in the curve's lines); copy k becomes
    /// node `first_new + k` with tag `first_tag + k`.
    duplicated: Vec<u32>,
    first_tag: u64,
    /// Surface entities of body B.
    b_entities: HashSet<i32>,
    /// Curve entities of the split curve (its lines stay with A).
    curve_entities: HashSet<i32>,
    /// Per element: the A line as walked counter-clockwise around body B, i.e. [from, to, mid]
    /// of the body B cell's walk; the B side is its copy.
    a_sides: Vec<[u32; 3]>,
}

/// Checks a Split pair: the curve exists, both bodies exist and are case bodies, and every
/// line of the curve is the edge of exactly one body A cell and one body B cell.
pub(super) fn plan_split(
    ctx: &Ctx,
    curve: &str,
    body_a: &str,
    body_b: &str,
    bodies: &[&str],
) -> Result<SplitPlan> {
    let (curve_group, lines) = ctx.curve_lines(curve, "split")?;
    let group_a = ctx.surface(body_a)?;
    let group_b = ctx.surface(body_b)?;
    for body in [body_a, body_b] {
        if !bodies.contains(&body) {
            return Err(ctx.err(
                TopologyProblem::BodyNotInCase,
                format!(
                    "body '{body}' of the split curve '{curve}' is not one of the case's bodies ({})",
                    bodies.join(", ")
                ),
            ));
        }
    }
    if body_a == body_b {
        return Err(ctx.err(
            TopologyProblem::SameBody,
            format!(
                "body_a and body_b are the same surface '{body_a}'; the Split recipe separates \
                 two different physical surfaces"
            ),
        ));
    }
    if let Some(e) = group_a
        .entities
        .iter()
        .find(|e| group_b.entities.contains(e))
    {
        return Err(ctx.err(
            TopologyProblem::SharedEntity,
            format!(
                "bodies '{body_a}' and '{body_b}' share surface entity {e}; they must not overlap"
            ),
        ));
    }
    // Body index 0 = A, 1 = B; cells of other surfaces are ignored.
    let mut body_of = HashMap::new();
    for (b, group) in [group_a, group_b].into_iter().enumerate() {
        for &e in &group.entities {
            body_of.insert(e, b);
        }
    }
    let edges = ctx.edges(&body_of, lines.iter());
    let mut a_sides = Vec::with_capacity(lines.len());
    for l in &lines {
        let uses = edges.find(l.nodes[0], l.nodes[1], l.nodes[2]);
        let in_a: Vec<&EdgeUse> = uses.iter().filter(|u| u.body == 0).collect();
        let in_b: Vec<&EdgeUse> = uses.iter().filter(|u| u.body == 1).collect();
        let (ua, ub) = match (in_a.as_slice(), in_b.as_slice()) {
            ([ua], [ub]) => (ua, ub),
            _ => {
                return Err(ctx.err_at(
                    TopologyProblem::NotBetweenBodies,
                    None,
                    Some(l.tag),
                    format!(
                        "curve '{curve}' is not between bodies '{body_a}' and '{body_b}': its {} \
                         is an edge of {} element(s) of '{body_a}' and {} of '{body_b}' \
                         (exactly one of each is needed)",
                        ctx.line(l),
                        in_a.len(),
                        in_b.len()
                    ),
                ));
            }
        };
        if ua.from == ub.from {
            return Err(ctx.err_at(
                TopologyProblem::Overlap,
                None,
                Some(l.tag),
                format!(
                    "bodies '{body_a}' and '{body_b}' lie on the same side of curve '{curve}' \
                     at its {} (elements {} and {}): the bodies overlap",
                    ctx.line(l),
                    ctx.mesh.cells[ua.cell].tag,
                    ctx.mesh.cells[ub.cell].tag
                ),
            ));
        }
        a_sides.push([ub.from, ub.to, ub.mid]);
    }
    let duplicated = {
        let mut seen = HashSet::new();
        let mut nodes = Vec::new();
        for l in &lines {
            for n in l.nodes {
                if seen.insert(n) {
                    nodes.push(n);
                }
            }
        }
        nodes
    };
    let max_tag = ctx.mesh.node_tags.iter().copied().max().unwrap_or(0);
    let first_tag = max_tag.checked_add(1);
    let fits = first_tag
        .and_then(|t| t.checked_add(duplicated.len() as u64))
        .is_some()
        && ctx.mesh.nodes.len() + duplicated.len() < u32::MAX as usize;
    let (Some(first_tag), true) = (first_tag, fits) else {
        return Err(ctx.err(
            TopologyProblem::TooManyNodes,
            format!(
                "no room for {} more nodes (largest node tag {max_tag}, {} nodes)",
                duplicated.len(),
                ctx.mesh.nodes.len()
            ),
        ));
    };
    Ok(SplitPlan {
        duplicated,
        first_tag,
        b_entities: group_b.entities.iter().copied().collect(),
        curve_entities: curve_group.entities.iter().copied().collect(),
        a_sides,
    })
}

/// Duplicates the curve's nodes and moves body B onto the copies (cannot fail: all checks
/// were made in [`plan_split`]).
///
/// - Every node of the curve's lines is copied, **end points included**, always: where the
///   curve reaches a free boundary the bodies must be able to separate there too (gmsh's
///   `Plugin(Crack)` needs `OpenBoundaryPhysicalGroup` for the same effect). Where the curve
///   instead ends at another A–B boundary that is not part of the curve, this opens a gap of
///   one node there: make the curve cover the whole A–B boundary.
/// - Every cell of body B using a copied node is re-pointed to the copy; cells of other
///   bodies stay with the originals (with body A).
/// - A line of any group (other than the split curve's own lines, which stay with A) is
///   re-pointed when its re-pointed edge is an edge of a body B cell, i.e. when it bounds
///   body B (e.g. B's outer side touching the curve's end, so that loads and supports on it
///   act on B's copy).
/// - Point elements stay with the original node (body A): put a point load or support meant
///   for B on a point that is not on the curve.
pub(super) fn apply_split(mesh: &mut Mesh, plan: SplitPlan) -> InterfaceTopology {
    let first_new = mesh.nodes.len() as u32;
    let copy: HashMap<u32, u32> = plan
        .duplicated
        .iter()
        .enumerate()
        .map(|(k, &n)| (n, first_new + k as u32))
        .collect();
    for (k, &n) in plan.duplicated.iter().enumerate() {
        let p = mesh.nodes[n as usize];
        mesh.nodes.push(p);
        mesh.node_tags.push(plan.first_tag + k as u64);
    }
    // Edges of the re-pointed B cells that touch a copy: (sorted ends, mid).
    let mut b_edges: HashSet<((u32, u32), u32)> = HashSet::new();
    for cell in mesh.cells.iter_mut() {
        if !plan.b_entities.contains(&cell.entity) {
            continue;
        }
        let n = cell.kind.node_count();
        let mut touched = false;
        for slot in &mut cell.nodes[..n] {
            if let Some(&c) = copy.get(slot) {
                *slot = c;
                touched = true;
            }
        }
        if touched {
            for (from, to, mid) in cell_edges(cell.kind, &cell.nodes) {
                if from >= first_new || to >= first_new || mid >= first_new {
                    b_edges.insert((edge_key(from, to), mid));
                }
            }
        }
    }
    for line in mesh.lines.iter_mut() {
        if plan.curve_entities.contains(&line.entity)
            || !line.nodes.iter().any(|n| copy.contains_key(n))
        {
            continue;
        }
        let moved = line.nodes.map(|n| copy.get(&n).copied().unwrap_or(n));
        if b_edges.contains(&(edge_key(moved[0], moved[1]), moved[2])) {
            line.nodes = moved;
        }
    }
    let mut topology = InterfaceTopology::default();
    for a in plan.a_sides {
        let b = a.map(|n| copy[&n]);
        topology.elements.push([a[0], a[1], a[2], b[0], b[1], b[2]]);
        topology.offsets.push([[0.0; 2]; 3]);
    }
    topology
}
