//! The ordered pairing recipe: two faces that do not touch initially (a Hertz-type gap) but
//! carry the same number of nodes, paired in order along the curves; the initial gap becomes
//! the offset.

use super::{Ctx, InterfaceTopology, Sides};
use crate::Result;
use crate::error::TopologyProblem;
use crate::mesh::Line3;
use crate::mesh::topology::{Chain, curve_chains};

/// Chains both curves, pairs their nodes in order (reversing A if its ends are closer to B's
/// ends that way) and makes one element per B line.
pub(super) fn ordered(ctx: &Ctx, s: &Sides) -> Result<InterfaceTopology> {
    let mut a = chain(ctx, &s.a_lines, &s.a_name, "side A")?;
    let b = chain(ctx, &s.b_lines, &s.b_name, "side B")?;
    if a.nodes.len() != b.nodes.len() {
        return Err(ctx.err(
            TopologyProblem::CountMismatch,
            format!(
                "the Ordered recipe pairs nodes one to one, but side A curve '{}' has {} nodes \
                 ({} elements) and side B curve '{}' has {} nodes ({} elements); mesh both with \
                 the same number of points (e.g. Transfinite Curve)",
                s.a_name,
                a.nodes.len(),
                a.lines.len(),
                s.b_name,
                b.nodes.len(),
                b.lines.len()
            ),
        ));
    }
    let x = |i: u32| ctx.mesh.nodes[i as usize];
    let d = |p: u32, q: u32| (x(p)[0] - x(q)[0]).hypot(x(p)[1] - x(q)[1]);
    let (a_first, a_last) = (a.nodes[0], a.nodes[a.nodes.len() - 1]);
    let (b_first, b_last) = (b.nodes[0], b.nodes[b.nodes.len() - 1]);
    if d(a_last, b_first) + d(a_first, b_last) < d(a_first, b_first) + d(a_last, b_last) {
        a.nodes.reverse();
    }
    let mut topology = InterfaceTopology::default();
    for (k, &line) in b.lines.iter().enumerate() {
        let bn = [b.nodes[2 * k], b.nodes[2 * k + 2], b.nodes[2 * k + 1]];
        let an = [a.nodes[2 * k], a.nodes[2 * k + 2], a.nodes[2 * k + 1]];
        let l = &s.b_lines[line];
        let (element, offsets) = ctx.element(&s.edges, an, bn, &s.b_owner[line], l)?;
        topology.elements.push(element);
        topology.offsets.push(offsets);
    }
    Ok(topology)
}

/// Chains the lines of one curve into a single open polyline, or says why they are not one.
pub(super) fn chain(ctx: &Ctx, lines: &[Line3], curve: &str, role: &str) -> Result<Chain> {
    let nodes: Vec<[u32; 3]> = lines.iter().map(|l| l.nodes).collect();
    let one_chain = "the Ordered recipe needs one open chain of lines";
    let mut pieces = curve_chains(&nodes).map_err(|branch| {
        ctx.err_at(
            TopologyProblem::Branch,
            Some(branch.node),
            None,
            format!(
                "{role} curve '{curve}' branches at {} ({} line elements meet there); {one_chain}",
                ctx.node(branch.node),
                branch.lines
            ),
        )
    })?;
    if pieces.first().is_none_or(|c| c.closed) {
        return Err(ctx.err(
            TopologyProblem::Closed,
            format!("{role} curve '{curve}' is closed (it has no end point); {one_chain}"),
        ));
    }
    if pieces.len() > 1 {
        let mut ends: Vec<u32> = pieces
            .iter()
            .filter(|c| !c.closed)
            .flat_map(|c| [c.nodes[0], c.nodes[c.nodes.len() - 1]])
            .collect();
        ends.sort_unstable();
        let start = pieces[0].nodes[0];
        let mut in_first = vec![false; lines.len()];
        for &i in &pieces[0].lines {
            in_first[i] = true;
        }
        let stray = &lines[in_first.iter().position(|&u| !u).unwrap_or(0)];
        return Err(ctx.err_at(
            TopologyProblem::Disconnected,
            None,
            Some(stray.tag),
            format!(
                "{role} curve '{curve}' is not one connected chain: it has {} end points ({}) \
                 and its {} is not connected to the chain starting at {}; {one_chain} (make one \
                 physical curve per contact face)",
                ends.len(),
                ends.iter()
                    .map(|&e| ctx.node(e))
                    .collect::<Vec<_>>()
                    .join(", "),
                ctx.line(stray),
                ctx.node(start)
            ),
        ));
    }
    Ok(pieces.swap_remove(0))
}
