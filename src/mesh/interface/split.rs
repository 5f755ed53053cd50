//! The split pairing recipe: one conforming mesh with one physical curve between two bodies;
//! the curve's nodes are duplicated (as gmsh's `Plugin(Crack)` would do) and body B is moved
//! onto the copies.

use std::collections::{HashMap, HashSet};

use super::{Ctx, InterfaceTopology};
use crate::Result;
use crate::error::TopologyProblem;
use crate::mesh::topology::{EdgeIndex, EdgeUse, cell_edges, edge_key};
use crate::mesh::{CellKind, Mesh};

/// What [`apply_split`] will do, fully checked.
pub(super) struct SplitPlan {
    /// Nodes to duplicate (order of first appearance in the curve's lines); copy k becomes
    /// node `first_new + k` with tag `first_tag + k`.
    duplicated: Vec<u32>,
    first_tag: u64,
    /// Surface entities of bodies A and B.
    a_entities: HashSet<i32>,
    b_entities: HashSet<i32>,
    /// Curve entities of the split curve (its lines stay with A).
    curve_entities: HashSet<i32>,
    /// Per element: body A's nodes of the line as walked counter-clockwise around body B,
    /// i.e. [from, to, mid] of the body B cell's walk.
    a_sides: Vec<[u32; 3]>,
    /// The same for body B's nodes: equal to A's where the split is still to copy them, B's
    /// own copy where an earlier split (of a curve ending there) made one.
    b_sides: Vec<[u32; 3]>,
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
    // Edges are looked up by the nodes the split copies came from, so that a line whose end
    // an earlier split (of an adjacent curve) gave body B a copy of still finds both cells.
    let origin = |mut n: u32| {
        while let Some(&from) = ctx.mesh.split_copies.get(&n) {
            n = from;
        }
        n
    };
    let mut wanted = vec![false; ctx.mesh.nodes.len()];
    for l in &lines {
        wanted[origin(l.nodes[0]) as usize] = true;
        wanted[origin(l.nodes[1]) as usize] = true;
    }
    let cells: Vec<(usize, usize, CellKind, [u32; 8])> = ctx
        .mesh
        .cells
        .iter()
        .enumerate()
        .filter_map(|(i, c)| {
            let body = *body_of.get(&c.entity)?;
            Some((i, body, c.kind, c.nodes.map(origin)))
        })
        .collect();
    let edges = EdgeIndex::new(cells.iter().map(|(i, b, k, n)| (*i, *b, *k, n)), &wanted);
    // The cell's own node whose origin is `n`.
    let own = |cell: usize, n: u32| {
        let nodes = &ctx.mesh.cells[cell].nodes;
        *nodes.iter().find(|&&m| origin(m) == n).unwrap_or(&n)
    };
    let mut a_sides = Vec::with_capacity(lines.len());
    let mut b_sides = Vec::with_capacity(lines.len());
    for l in &lines {
        let [p, q, m] = l.nodes.map(origin);
        let uses = edges.find(p, q, m);
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
        let walk = [ub.from, ub.to, ub.mid];
        let (a, b) = (walk.map(|n| own(ua.cell, n)), walk.map(|n| own(ub.cell, n)));
        // Only a split of this very line separates its mid node.
        if a[2] != b[2] {
            return Err(ctx.err_at(
                TopologyProblem::AlreadySplit,
                None,
                Some(l.tag),
                format!(
                    "curve '{curve}' was already split by another contact pair at its {}: \
                     each curve may join the bodies once",
                    ctx.line(l)
                ),
            ));
        }
        a_sides.push(a);
        b_sides.push(b);
    }
    let duplicated = {
        let mut seen = HashSet::new();
        let mut nodes = Vec::new();
        for (a, b) in a_sides.iter().zip(&b_sides) {
            for (&na, &nb) in a.iter().zip(b) {
                if na == nb && seen.insert(na) {
                    nodes.push(na);
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
        a_entities: group_a.entities.iter().copied().collect(),
        b_entities: group_b.entities.iter().copied().collect(),
        curve_entities: curve_group.entities.iter().copied().collect(),
        a_sides,
        b_sides,
    })
}

/// Duplicates the curve's nodes and moves body B onto the copies (cannot fail: all checks
/// were made in [`plan_split`]).
///
/// - Every node of the curve's lines is copied, **end points included**, always: where the
///   curve reaches a free boundary the bodies must be able to separate there too (gmsh's
///   `Plugin(Crack)` needs `OpenBoundaryPhysicalGroup` for the same effect). Where the curve
///   instead ends at another A–B boundary that is not part of the curve, this opens a gap of
///   one node there: make the curve cover the whole A–B boundary, or make that boundary a
///   contact pair of its own. A node an earlier split already gave body B a copy of (the
///   shared end of two adjacent contact curves) is not copied again: the pair joins A's
///   node to B's existing copy.
/// - Every cell of body B using a copied node is re-pointed to the copy; cells of other
///   bodies stay with the originals (with body A).
/// - A line of any group (other than the split curve's own lines, which stay with A) is
///   re-pointed when its re-pointed edge is an edge of a body B cell and its own edge is no
///   edge of a body A cell, i.e. when it bounds body B only (e.g. B's outer side touching
///   the curve's end, so that loads and supports on it act on B's copy); a line between A
///   and B (another contact curve) stays with A like the curve's own.
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
    // Edges of the re-pointed B cells that touch a copy, and of the A cells that touch a
    // copied node: (sorted ends, mid).
    let mut b_edges: HashSet<((u32, u32), u32)> = HashSet::new();
    let mut a_edges: HashSet<((u32, u32), u32)> = HashSet::new();
    for cell in mesh.cells.iter_mut() {
        if plan.a_entities.contains(&cell.entity) {
            let n = cell.kind.node_count();
            if cell.nodes[..n].iter().any(|k| copy.contains_key(k)) {
                for (from, to, mid) in cell_edges(cell.kind, &cell.nodes) {
                    a_edges.insert((edge_key(from, to), mid));
                }
            }
            continue;
        }
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
        let own = line.nodes;
        if b_edges.contains(&(edge_key(moved[0], moved[1]), moved[2]))
            && !a_edges.contains(&(edge_key(own[0], own[1]), own[2]))
        {
            line.nodes = moved;
        }
    }
    for (&original, &made) in &copy {
        mesh.split_copies.insert(made, original);
    }
    let mut topology = InterfaceTopology::default();
    for (a, b) in plan.a_sides.into_iter().zip(plan.b_sides) {
        let b = b.map(|n| copy.get(&n).copied().unwrap_or(n));
        topology.elements.push([a[0], a[1], a[2], b[0], b[1], b[2]]);
        topology.offsets.push([[0.0; 2]; 3]);
    }
    topology
}
