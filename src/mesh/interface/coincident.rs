//! The coincident pairing recipe: two bodies meshed separately, each contact face its own
//! physical curve; nodes coincide up to round-off and are paired by coordinates.

use std::collections::HashMap;

use super::{COINCIDENT_TOLERANCE, Ctx, InterfaceTopology, Sides};
use crate::Result;
use crate::error::TopologyProblem;

/// Pairs every B node with the A node at the same place (hash grid, linear time), then makes
/// one element per B line.
pub(super) fn coincident(ctx: &Ctx, s: &Sides) -> Result<InterfaceTopology> {
    let tolerance = COINCIDENT_TOLERANCE * ctx.mesh.typical_size();
    if !(tolerance > 0.0 && tolerance.is_finite()) {
        return Err(ctx.err(
            TopologyProblem::NoScale,
            "the mesh has no cells of positive size to scale the tolerance",
        ));
    }
    let partner = pair_by_coordinates(ctx, s, tolerance)?;
    let mut topology = InterfaceTopology::default();
    for (line, owner) in s.b_lines.iter().zip(&s.b_owner) {
        let a = line.nodes.map(|b| partner[&b]);
        let (element, offsets) = ctx.element(&s.edges, a, line.nodes, owner, line)?;
        topology.elements.push(element);
        topology.offsets.push(offsets);
    }
    Ok(topology)
}

/// Map B node → A node within `tolerance`; every node of both sides paired exactly once.
fn pair_by_coordinates(ctx: &Ctx, s: &Sides, tolerance: f64) -> Result<HashMap<u32, u32>> {
    let x = |i: u32| ctx.mesh.nodes[i as usize];
    // Grid cells of the tolerance's size: a partner lies in the 3×3 block around a node.
    // (`as i64` saturates, so far-away coordinates cannot overflow.)
    let cell_of = |p: [f64; 2]| {
        (
            (p[0] / tolerance).floor() as i64,
            (p[1] / tolerance).floor() as i64,
        )
    };
    let mut grid: HashMap<(i64, i64), Vec<u32>> = HashMap::with_capacity(s.a_nodes.len());
    for &a in &s.a_nodes {
        grid.entry(cell_of(x(a))).or_default().push(a);
    }
    let counts = format!(
        "side A '{}' has {} nodes, side B '{}' has {}",
        s.a_name,
        s.a_nodes.len(),
        s.b_name,
        s.b_nodes.len()
    );
    let mut partner = HashMap::with_capacity(s.b_nodes.len());
    let mut partner_of_a: HashMap<u32, u32> = HashMap::with_capacity(s.a_nodes.len());
    for &b in &s.b_nodes {
        let p = x(b);
        let (cx, cy) = cell_of(p);
        let mut candidates = Vec::new();
        for gx in cx.saturating_sub(1)..=cx.saturating_add(1) {
            for gy in cy.saturating_sub(1)..=cy.saturating_add(1) {
                for &a in grid.get(&(gx, gy)).into_iter().flatten() {
                    let q = x(a);
                    if (p[0] - q[0]).hypot(p[1] - q[1]) <= tolerance {
                        candidates.push(a);
                    }
                }
            }
        }
        match candidates.as_slice() {
            [] => {
                return Err(ctx.err_at(
                    TopologyProblem::Unpaired,
                    Some(b),
                    None,
                    format!(
                        "side B curve '{}': {} has no coincident node on side A curve '{}' \
                         (tolerance {tolerance:.1e} mm; {counts}): the faces are not meshed \
                         alike; give both curves the same points, or use the Ordered recipe for \
                         faces with a gap",
                        s.b_name,
                        ctx.node(b),
                        s.a_name
                    ),
                ));
            }
            [a] => {
                if let Some(&other) = partner_of_a.get(a) {
                    return Err(ctx.err_at(
                        TopologyProblem::Ambiguous,
                        Some(*a),
                        None,
                        format!(
                            "pairing is ambiguous: {} and {} of side B curve '{}' both coincide \
                             with {} of side A curve '{}' (tolerance {tolerance:.1e} mm)",
                            ctx.node(other),
                            ctx.node(b),
                            s.b_name,
                            ctx.node(*a),
                            s.a_name
                        ),
                    ));
                }
                partner_of_a.insert(*a, b);
                partner.insert(b, *a);
            }
            [first, second, ..] => {
                return Err(ctx.err_at(
                    TopologyProblem::Ambiguous,
                    Some(b),
                    None,
                    format!(
                        "pairing is ambiguous: {} of side B curve '{}' coincides with {} and {} \
                         of side A curve '{}' (tolerance {tolerance:.1e} mm)",
                        ctx.node(b),
                        s.b_name,
                        ctx.node(*first),
                        ctx.node(*second),
                        s.a_name
                    ),
                ));
            }
        }
    }
    if let Some(&a) = s.a_nodes.iter().find(|a| !partner_of_a.contains_key(a)) {
        return Err(ctx.err_at(
            TopologyProblem::Unpaired,
            Some(a),
            None,
            format!(
                "side A curve '{}': {} has no coincident node on side B curve '{}' (unpaired; \
                 tolerance {tolerance:e} mm; {counts}): the faces are not meshed alike",
                s.a_name,
                ctx.node(a),
                s.b_name
            ),
        ));
    }
    Ok(partner)
}
