//! The ordered pairing recipe: two faces that do not touch initially (a Hertz-type gap) but
//! carry the same number of nodes, paired in order along the curves; the initial gap becomes
//! the offset.

use std::collections::HashMap;

use super::{Ctx, InterfaceTopology, Sides};
use crate::Result;
use crate::mesh::Line3;

/// Chains both curves, pairs their nodes in order (reversing A if its ends are closer to B's
/// ends that way) and makes one element per B line.
pub(super) fn ordered(ctx: &Ctx, s: &Sides) -> Result<InterfaceTopology> {
    let mut a = chain(ctx, &s.a_lines, &s.a_name, "side A")?;
    let b = chain(ctx, &s.b_lines, &s.b_name, "side B")?;
    if a.nodes.len() != b.nodes.len() {
        return Err(ctx.err(format!(
            "the Ordered recipe pairs nodes one to one, but side A curve '{}' has {} nodes \
             ({} elements) and side B curve '{}' has {} nodes ({} elements); mesh both with \
             the same number of points (e.g. Transfinite Curve)",
            s.a_name,
            a.nodes.len(),
            a.lines.len(),
            s.b_name,
            b.nodes.len(),
            b.lines.len()
        )));
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

/// A curve as one open polyline.
pub(super) struct Chain {
    /// Nodes in order along the curve: end, mid, end, mid, ..., end (2 × lines + 1).
    pub(super) nodes: Vec<u32>,
    /// Index (into the curve's lines) of the k-th line along the chain.
    pub(super) lines: Vec<usize>,
}

/// Chains the lines of one curve into a single open polyline, or says why they are not one.
pub(super) fn chain(ctx: &Ctx, lines: &[Line3], curve: &str, role: &str) -> Result<Chain> {
    let mut at: HashMap<u32, Vec<usize>> = HashMap::new();
    for (i, l) in lines.iter().enumerate() {
        at.entry(l.nodes[0]).or_default().push(i);
        at.entry(l.nodes[1]).or_default().push(i);
    }
    let mut ends: Vec<u32> = Vec::new();
    for (&node, ls) in &at {
        match ls.len() {
            1 => ends.push(node),
            2 => {}
            n => {
                return Err(ctx.err(format!(
                    "{role} curve '{curve}' branches at {} ({n} line elements meet there); \
                     the Ordered recipe needs one open chain of lines",
                    ctx.node(node)
                )));
            }
        }
    }
    ends.sort_unstable();
    let Some(&start) = ends.first() else {
        return Err(ctx.err(format!(
            "{role} curve '{curve}' is closed (it has no end point); the Ordered recipe needs \
             one open chain of lines"
        )));
    };
    let mut used = vec![false; lines.len()];
    let mut result = Chain {
        nodes: vec![start],
        lines: Vec::with_capacity(lines.len()),
    };
    let mut node = start;
    while let Some(&i) = at[&node].iter().find(|&&i| !used[i]) {
        used[i] = true;
        let l = &lines[i];
        let next = if l.nodes[0] == node {
            l.nodes[1]
        } else {
            l.nodes[0]
        };
        result.nodes.extend([l.nodes[2], next]);
        result.lines.push(i);
        node = next;
    }
    if result.lines.len() != lines.len() {
        let stray = &lines[used.iter().position(|u| !u).unwrap_or(0)];
        return Err(ctx.err(format!(
            "{role} curve '{curve}' is not one connected chain: it has {} end points ({}) \
             and its {} is not connected to the chain starting at {}; the Ordered recipe \
             needs one open chain of lines (make one physical curve per contact face)",
            ends.len(),
            ends.iter()
                .map(|&e| ctx.node(e))
                .collect::<Vec<_>>()
                .join(", "),
            ctx.line(stray),
            ctx.node(start)
        )));
    }
    Ok(result)
}
