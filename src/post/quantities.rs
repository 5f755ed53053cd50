//! Quantities of interest evaluated in memory on a converged step: reactions, point
//! displacements, contact pressure statistics, stick-zone length, relative displacement and
//! stiffness of a contact pair.

use crate::Error;
use crate::Result;
use crate::config::{Component, QuantityKind, QuantitySpec, Statistic};
use crate::contact::ContactStatus;
use crate::element::Analysis;
use crate::element::interface6::interface_point;
use crate::element::set::INTERFACE_POINTS;
use crate::model::Model;
use crate::post::interface::{InterfaceOutput, resultants};
use crate::post::reactions;
use crate::solver::stepping::StepResult;

/// Values of `quantities` for the converged `step` of `model`.
pub fn evaluate(quantities: &[QuantitySpec], model: &Model, step: &StepResult) -> Result<Vec<f64>> {
    let states = &step.solution.interface_committed;
    let u = &step.solution.u;
    let mut interface: Option<InterfaceOutput> = None;
    let pair_index = |q: &QuantitySpec| -> Result<usize> {
        let name = q.pair.as_deref().unwrap_or_default();
        model
            .interface
            .pairs
            .iter()
            .position(|p| p.name == name)
            .ok_or_else(|| Error::Model(format!("quantity '{}': no contact pair '{name}'", q.name)))
    };
    let comp = |q: &QuantitySpec| q.component.map_or(0, Component::index);
    let mut values = Vec::with_capacity(quantities.len());
    for q in quantities {
        let value = match q.kind {
            QuantityKind::Reaction => {
                let name = q.support.as_deref().unwrap_or_default();
                let i = model
                    .supports
                    .iter()
                    .position(|s| s.name == name)
                    .ok_or_else(|| {
                        Error::Model(format!("quantity '{}': no support '{name}'", q.name))
                    })?;
                reactions(model, step.internal_force, step.external_force)[i][comp(q)]
            }
            QuantityKind::Displacement => {
                let name = q.point.as_deref().unwrap_or_default();
                let group = model.mesh.group(0, name).ok_or_else(|| {
                    Error::Model(format!(
                        "quantity '{}': no physical point '{name}' in the mesh (physical points: {})",
                        q.name,
                        model.mesh.group_names(0)
                    ))
                })?;
                let nodes: Vec<u32> = model.mesh.points_in(group).collect();
                if nodes.is_empty() {
                    return Err(Error::Model(format!(
                        "quantity '{}': physical point '{name}' has no nodes",
                        q.name
                    )));
                }
                let c = comp(q);
                nodes.iter().map(|&n| u[2 * n as usize + c]).sum::<f64>() / nodes.len() as f64
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
                    statistic => {
                        let out = interface.get_or_insert_with(|| InterfaceOutput::new(model));
                        // Rows: arc_length, x, y, contact_normal_stress, contact_pressure, ...
                        let table = &out.tables(model, states)[p];
                        let pressure = |row: &Vec<f64>| row[4];
                        if statistic == Some(Statistic::Peak) {
                            table
                                .rows
                                .iter()
                                .map(pressure)
                                .fold(f64::NEG_INFINITY, f64::max)
                        } else {
                            let (col, at) = match (q.x, q.y) {
                                (Some(x), _) => (1, x),
                                (_, Some(y)) => (2, y),
                                _ => unreachable!("checked by QuantitySpec::check"),
                            };
                            interpolate(&table.rows, col, at, 4).ok_or_else(|| {
                                let (lo, hi) = table
                                    .rows
                                    .iter()
                                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                                        (a.min(r[col]), b.max(r[col]))
                                    });
                                Error::Model(format!(
                                    "quantity '{}': {} = {at} is outside pair '{}' ({lo} .. {hi})",
                                    q.name,
                                    ["", "x", "y"][col],
                                    model.interface.pairs[p].name
                                ))
                            })?
                        }
                    }
                }
            }
            QuantityKind::StickZone => {
                let p = pair_index(q)?;
                let mut length = 0.0;
                for_lengths(model, p, |e, g, dl| {
                    if states[e * INTERFACE_POINTS + g].status == ContactStatus::Stick {
                        length += dl;
                    }
                });
                length
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
                            n[i] * (u[2 * b + c] - u[2 * a + c])
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
            return Err(Error::Model(format!(
                "quantity '{}' is not finite ({value}) at the last step",
                q.name
            )));
        }
        values.push(value);
    }
    Ok(values)
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

/// Linear interpolation of column `value` at coordinate `at` of column `col` between
/// successive rows (the first crossing along the curve).
fn interpolate(rows: &[Vec<f64>], col: usize, at: f64, value: usize) -> Option<f64> {
    let tol = 1e-9
        * rows
            .iter()
            .fold(0.0_f64, |m, r| m.max(r[col].abs()))
            .max(1.0);
    if let [row] = rows {
        return ((row[col] - at).abs() <= tol).then_some(row[value]);
    }
    rows.windows(2).find_map(|w| {
        let (a, b) = (w[0][col], w[1][col]);
        if (a - at).abs() <= tol {
            Some(w[0][value])
        } else if (b - at).abs() <= tol {
            Some(w[1][value])
        } else if (a - at) * (b - at) < 0.0 {
            let t = (at - a) / (b - a);
            Some(w[0][value] + t * (w[1][value] - w[0][value]))
        } else {
            None
        }
    })
}
