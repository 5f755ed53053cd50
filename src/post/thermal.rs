//! Temperature output: the bodies' `temperature` (change from the reference, K) and
//! `heat_flux` (−k ∇T, W/mm², averaged at a node over its conducting cells), and at the
//! side-B nodes of the conducting contact pairs the joint's `joint_heat_flux` (W/mm², from
//! side A to side B), `joint_conductance` (W/(mm²·K)) and `temperature_jump` (T_A − T_B, K).
//! A joint node shows its paired nodes' temperatures and the conductance of the integration
//! point nearest to it (for the default Newton-Cotes rule the point at the node).

use crate::element::set::INTERFACE_POINTS;
use crate::model::Model;
use crate::output::{Field, Grid};
use crate::post::BodyPoints;
use crate::solver::state::Solution;

/// Names of the joint fields, in the order of [`joint_values`].
pub const JOINT_FIELDS: [&str; 3] = ["joint_heat_flux", "joint_conductance", "temperature_jump"];

/// Adds `temperature` (and `heat_flux` with conduction) to the bodies' `grid` of `points`.
pub fn add_body_fields(grid: &mut Grid, model: &Model, points: &BodyPoints, solution: &Solution) {
    let thermal = &solution.thermal;
    if !model.has_temperature() {
        return;
    }
    let field = &thermal.field;
    let temperature = points
        .points
        .iter()
        .map(|&(b, n)| match field.bodies.get(b as usize) {
            Some(Some(uniform)) => *uniform,
            _ => field.nodal.get(n as usize).copied().unwrap_or(0.0),
        })
        .collect();
    grid.point_data
        .push(Field::scalar("temperature", temperature));
    if let (Some(c), Some(heat)) = (&model.thermal.conduction, &thermal.heat) {
        let flux = c.nodal_flux(&model.continuum, &heat.nodal);
        let values = points
            .points
            .iter()
            .flat_map(|&(_, n)| [flux[n as usize][0], flux[n as usize][1], 0.0])
            .collect();
        grid.point_data.push(Field::new(
            "heat_flux",
            3,
            crate::output::FieldValues::F64(values),
        ));
    }
}

/// The joint values ([`JOINT_FIELDS`]) at every side-B node `node` of pair `pair`, or
/// `None` when no pair conducts heat.
pub fn joint_values(model: &Model, solution: &Solution) -> Option<JointValues> {
    let c = model
        .thermal
        .conduction
        .as_ref()
        .filter(|c| c.is_coupled())?;
    let heat = solution.thermal.heat.as_ref()?;
    let mut values = JointValues::default();
    c.for_joint_points(
        &model.interface,
        &solution.interface_committed,
        &heat.nodal,
        |at| {
            let element = &model.interface.elements[at.slot / INTERFACE_POINTS];
            let points = element.rule.points();
            let g = at.slot % INTERFACE_POINTS;
            // The node this point is nearest to (b0, b1, mid at ξ = −1, 1, 0).
            let i = [-1.0, 1.0, 0.0]
                .iter()
                .enumerate()
                .min_by(|a, b| {
                    (a.1 - points[g].0)
                        .abs()
                        .total_cmp(&(b.1 - points[g].0).abs())
                })
                .map(|(i, _)| i)
                .expect("three nodes");
            let (a, b) = (at.nodes[i] as usize, at.nodes[i + 3] as usize);
            let jump = heat.nodal[a] - heat.nodal[b];
            let h = at.point.conductance;
            values
                .at
                .insert((at.pair, at.nodes[i + 3]), [h * jump, h, jump]);
        },
    );
    Some(values)
}

/// Joint values by (pair, side-B node).
#[derive(Clone, Debug, Default)]
pub struct JointValues {
    pub at: std::collections::HashMap<(usize, u32), [f64; 3]>,
}

impl JointValues {
    /// The values at side-B node `node` of pair `pair` (0 where the pair does not conduct).
    pub fn get(&self, pair: usize, node: u32) -> [f64; 3] {
        self.at.get(&(pair, node)).copied().unwrap_or_default()
    }
}
