//! Quantities of interest evaluated in memory on a converged step, from typed model and
//! interface data (no result tables read back): reactions, point displacements, contact
//! pressure statistics, the contact extent of a pair (area, stick / slip / open lengths, max
//! slip), relative displacement and stiffness of a pair, and the displacement of one node.

use crate::Error;
use crate::Result;
use crate::config::{Component, QuantityKind, QuantitySpec, Statistic};
use crate::contact::{ContactStatus, InterfaceState};
use crate::element::Analysis;
use crate::element::interface6::interface_point;
use crate::element::set::INTERFACE_POINTS;
use crate::model::Model;
use crate::post::interface::{ContactExtent, FIELDS, InterfaceOutput, contact_extent, resultants};
use crate::post::reactions;
use crate::solver::state::StepResult;

/// Values of `quantities` for the converged `step` of `model`.
pub fn evaluate(quantities: &[QuantitySpec], model: &Model, step: &StepResult) -> Result<Vec<f64>> {
    let states = &step.solution.interface_committed;
    let u = &step.solution.u;
    let mut interface: Option<InterfaceOutput> = None;
    let mut extents: Option<Vec<ContactExtent>> = None;
    let pair_index = |q: &QuantitySpec| -> Result<usize> {
        let name = q.pair.as_deref().unwrap_or_default();
        model
            .interface
            .pairs
            .iter()
            .position(|p| p.name == name)
            .ok_or_else(|| quantity_error(q, format!("no contact pair '{name}'")))
    };
    let comp = |q: &QuantitySpec| q.component.map_or(0, Component::index);
    let dofs = model.analysis.dofs_per_node();
    let mut values = Vec::with_capacity(quantities.len());
    for q in quantities {
        let value = match q.kind {
            QuantityKind::Reaction => {
                let name = q.support.as_deref().unwrap_or_default();
                let i = support_index(model, name)
                    .ok_or_else(|| quantity_error(q, format!("no support '{name}'")))?;
                reactions(model, step.internal_force, step.external_force)[i][comp(q)]
            }
            QuantityKind::Displacement => {
                let name = q.point.as_deref().unwrap_or_default();
                let group = model.mesh.group(0, name).ok_or_else(|| {
                    quantity_error(
                        q,
                        format!(
                            "no physical point '{name}' in the mesh (physical points: {})",
                            model.mesh.group_names(0)
                        ),
                    )
                })?;
                let nodes: Vec<u32> = model.mesh.points_in(group).collect();
                if nodes.is_empty() {
                    return Err(quantity_error(
                        q,
                        format!("physical point '{name}' has no nodes"),
                    ));
                }
                let c = comp(q);
                nodes.iter().map(|&n| u[dofs * n as usize + c]).sum::<f64>() / nodes.len() as f64
            }
            QuantityKind::ContactPressure => {
                let p = pair_index(q)?;
                match q.statistic {
                    Some(Statistic::Mean) => {
                        let (mut force, mut area) = (0.0, 0.0);
                        for_points(model, p, |e, g, point| {
                            force -= states[e * INTERFACE_POINTS + g].stress[1] * point.da;
                            area += point.da;
                        });
                        force / area
                    }
                    Some(Statistic::Peak) => {
                        let out = interface.get_or_insert_with(|| InterfaceOutput::new(model));
                        out.nodal(model, states)[p]
                            .iter()
                            .map(|n| n.values[PRESSURE])
                            .fold(f64::NEG_INFINITY, f64::max)
                    }
                    _ => {
                        let (axis, at) = match (q.x, q.y) {
                            (Some(x), _) => (0, x),
                            (_, Some(y)) => (1, y),
                            _ => unreachable!("checked by QuantitySpec::check"),
                        };
                        let out = interface.get_or_insert_with(|| InterfaceOutput::new(model));
                        let curve = pressure_along(out, model, states, p, axis);
                        interpolate(&curve, at).ok_or_else(|| {
                            let (lo, hi) = curve
                                .iter()
                                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &(c, _)| {
                                    (a.min(c), b.max(c))
                                });
                            quantity_error(
                                q,
                                format!(
                                    "{} = {at} is outside pair '{}' ({lo} .. {hi})",
                                    ["x", "y"][axis],
                                    model.interface.pairs[p].name
                                ),
                            )
                        })?
                    }
                }
            }
            QuantityKind::StickZone
            | QuantityKind::SlipLength
            | QuantityKind::OpenLength
            | QuantityKind::ContactArea
            | QuantityKind::MaxSlip => {
                let p = pair_index(q)?;
                let x = &extents.get_or_insert_with(|| contact_extent(model, states))[p];
                match q.kind {
                    QuantityKind::StickZone => x.stick_length,
                    QuantityKind::SlipLength => x.slip_length,
                    QuantityKind::OpenLength => x.open_length,
                    QuantityKind::ContactArea => x.area,
                    _ => x.max_slip,
                }
            }
            QuantityKind::NodeDisplacement => {
                let tag = q.node.unwrap_or_default();
                let n = model
                    .mesh
                    .node_tags
                    .iter()
                    .position(|&t| t == tag)
                    .ok_or_else(|| quantity_error(q, format!("no node {tag} in the mesh")))?;
                u[dofs * n + comp(q)]
            }
            QuantityKind::Twist => {
                let name = q.group.as_deref().unwrap_or_default();
                twist_angle(model, u, name).map_err(|reason| quantity_error(q, reason))?
            }
            QuantityKind::RelativeDisplacement | QuantityKind::Stiffness => {
                let p = pair_index(q)?;
                let c = comp(q);
                let (mut integral, mut length) = (0.0, 0.0);
                for_lengths(model, p, |e, g, dl| {
                    let element = &model.interface.elements[e];
                    let xi = element.rule.points()[g].0;
                    let (n, _) = crate::element::shape::line3(xi);
                    let relative: f64 = (0..3)
                        .map(|i| {
                            let (a, b) = (element.nodes[i] as usize, element.nodes[3 + i] as usize);
                            n[i] * (u[dofs * b + c] - u[dofs * a + c])
                        })
                        .sum();
                    integral += relative * dl;
                    length += dl;
                });
                let mean = integral / length;
                if q.kind == QuantityKind::Stiffness {
                    -resultants(model, states)[p][2 + c] / mean
                } else {
                    mean
                }
            }
        };
        if !value.is_finite() {
            return Err(quantity_error(
                q,
                format!("not finite ({value}) at the last step"),
            ));
        }
        values.push(value);
    }
    Ok(values)
}

/// The twist angle of the physical curve or point `name`: the mean of u_θ / r over its nodes
/// off the axis (radians), or why there is none.
fn twist_angle(model: &Model, u: &[f64], name: &str) -> std::result::Result<f64, String> {
    if !model.analysis.has_twist() {
        return Err("the twist angle needs [analysis] twist = true".into());
    }
    let mesh = &model.mesh;
    let nodes: Vec<u32> = match (mesh.group(1, name), mesh.group(0, name)) {
        (Some(curve), _) => mesh.lines_in(curve).flat_map(|l| l.nodes).collect(),
        (None, Some(point)) => mesh.points_in(point).collect(),
        (None, None) => {
            return Err(format!(
                "no physical curve or point '{name}' in the mesh (curves: {}; points: {})",
                mesh.group_names(1),
                mesh.group_names(0)
            ));
        }
    };
    let mut nodes = nodes;
    nodes.sort_unstable();
    nodes.dedup();
    // On the axis u_θ = 0 and u_θ / r means nothing.
    let axis = 1e-9 * model.size;
    let angles: Vec<f64> = nodes
        .iter()
        .map(|&n| (n as usize, mesh.nodes[n as usize][0]))
        .filter(|&(_, r)| r > axis)
        .map(|(n, r)| u[3 * n + 2] / r)
        .collect();
    if angles.is_empty() {
        return Err(format!("'{name}' has no node off the axis"));
    }
    Ok(angles.iter().sum::<f64>() / angles.len() as f64)
}

/// What a contact pair does at a state: the extent of its sticking, slipping and open parts
/// (lengths along side B in mm in a plane analysis, areas ∫ 2πr dl in mm² in axisymmetry: they
/// add up to the pair's length or area) and the friction it dissipated since the start,
/// ∫ D dA in N·mm (D the points' accumulated ∫ p_T du_Tᵖ, counting the cycles a wear jump
/// stands for; per unit thickness as the forces are).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairQuantities {
    pub stick: f64,
    pub slip: f64,
    pub open: f64,
    pub dissipation: f64,
}

/// The [`PairQuantities`] of every pair of `model` at interface `states`.
pub fn pair_quantities(model: &Model, states: &[InterfaceState]) -> Vec<PairQuantities> {
    // A unit thickness turns the area weight into the length weight, also on the axis.
    let plane = Analysis::PlaneStrain { thickness: 1.0 };
    let extent = if model.analysis.is_axisymmetric() {
        &model.analysis
    } else {
        &plane
    };
    let mut out = vec![PairQuantities::default(); model.interface.pairs.len()];
    for (e, element) in model.interface.elements.iter().enumerate() {
        let q = &mut out[element.pair as usize];
        for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
            let state = &states[e * INTERFACE_POINTS + g];
            let d = interface_point(extent, &element.b_coords, xi, w).da;
            *match state.status {
                ContactStatus::Stick => &mut q.stick,
                ContactStatus::Slip => &mut q.slip,
                ContactStatus::Open => &mut q.open,
            } += d;
            let da = interface_point(&model.analysis, &element.b_coords, xi, w).da;
            q.dissipation += state.history.dissipation * da;
        }
    }
    out
}

/// The support called `name`: by its name, else by its group when one support holds it.
fn support_index(model: &Model, name: &str) -> Option<usize> {
    let supports = &model.supports;
    supports.iter().position(|s| s.name == name).or_else(|| {
        let mut by_group = supports.iter().enumerate().filter(|(_, s)| s.group == name);
        match (by_group.next(), by_group.next()) {
            (Some((i, _)), None) => Some(i),
            _ => None,
        }
    })
}

/// Calls `f(element, point, geometry)` for every integration point of pair `p`.
fn for_points(
    model: &Model,
    p: usize,
    mut f: impl FnMut(usize, usize, &crate::element::interface6::InterfacePoint),
) {
    for e in model.interface.pairs[p].elements.clone() {
        let element = &model.interface.elements[e];
        for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
            f(
                e,
                g,
                &interface_point(&model.analysis, &element.b_coords, xi, w),
            );
        }
    }
}

/// Calls `f(element, point, dl)` with the length weight dl (along side B, not the area) of
/// every integration point of pair `p`.
fn for_lengths(model: &Model, p: usize, mut f: impl FnMut(usize, usize, f64)) {
    // A unit thickness turns the area weight into the length weight, also on the axis.
    let plane = Analysis::PlaneStrain { thickness: 1.0 };
    for e in model.interface.pairs[p].elements.clone() {
        let element = &model.interface.elements[e];
        for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
            f(e, g, interface_point(&plane, &element.b_coords, xi, w).da);
        }
    }
}

/// Index of `name` in [`FIELDS`], the order of [`NodalContact::values`]; a compile-time
/// error if there is no such field.
///
/// [`NodalContact::values`]: crate::post::interface::NodalContact::values
const fn field(name: &str) -> usize {
    let mut i = 0;
    while i < FIELDS.len() {
        let (a, b) = (FIELDS[i].as_bytes(), name.as_bytes());
        if a.len() == b.len() {
            let mut j = 0;
            while j < a.len() && a[j] == b[j] {
                j += 1;
            }
            if j == a.len() {
                return i;
            }
        }
        i += 1;
    }
    panic!("no such interface field")
}

/// The contact pressure −p_N in [`NodalContact::values`].
///
/// [`NodalContact::values`]: crate::post::interface::NodalContact::values
const PRESSURE: usize = field("contact_pressure");

/// (coordinate `axis` of the node, contact pressure) at the side-B nodes of pair `p`, in
/// order along the curve. The positions are the interface grid's points, which list every
/// pair's nodes in the order of [`InterfaceOutput::nodal`].
fn pressure_along(
    out: &InterfaceOutput,
    model: &Model,
    states: &[InterfaceState],
    p: usize,
    axis: usize,
) -> Vec<(f64, f64)> {
    let nodal = out.nodal(model, states);
    let first: usize = nodal[..p].iter().map(Vec::len).sum();
    let points = out.grid(model, states).points;
    nodal[p]
        .iter()
        .zip(&points[first..])
        .map(|(n, x)| (x[axis], n.values[PRESSURE]))
        .collect()
}

/// Linear interpolation of the values of `curve` (coordinate, value) at coordinate `at`
/// between successive points (the first crossing along the curve).
fn interpolate(curve: &[(f64, f64)], at: f64) -> Option<f64> {
    let tol = 1e-9 * curve.iter().fold(0.0_f64, |m, c| m.max(c.0.abs())).max(1.0);
    if let [(c, v)] = curve {
        return ((c - at).abs() <= tol).then_some(*v);
    }
    curve.windows(2).find_map(|w| {
        let ((a, va), (b, vb)) = (w[0], w[1]);
        if (a - at).abs() <= tol {
            Some(va)
        } else if (b - at).abs() <= tol {
            Some(vb)
        } else if (a - at) * (b - at) < 0.0 {
            let t = (at - a) / (b - a);
            Some(va + t * (vb - va))
        } else {
            None
        }
    })
}

/// The error of quantity `q` that cannot be evaluated for `reason`.
fn quantity_error(q: &QuantitySpec, reason: String) -> Error {
    Error::Quantity {
        name: q.name.clone(),
        reason,
    }
}
