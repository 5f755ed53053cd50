//! An upper bound on a linear bulk's largest strain increment from the nodal displacement
//! increments alone, so that a converged increment whose force is K·u needs no element
//! loop for its plausibility check (`[solver] max_strain_increment`,
//! [`crate::solver::diagnosis::implausible_increment`]).
//!
//! At an integration point p of a cell the strain increment is Δε_p = B_p Δu_e (B̄ with the
//! B-bar formulation, the twist rows included). Splitting the cell's nodal increments into
//! their mean t (per displacement component) and the rest,
//!
//! ```text
//! Δε_p = B_p (Δu_e − t) + C_p t,   C_p = Σ_nodes B_p (the response to a uniform t),
//! ‖Δε_p‖₂ ≤ ‖B_p‖_F ‖Δu_e − t‖₂ + Σ_c ‖C_p,c‖₂ |t_c|,
//! ```
//!
//! where C_p vanishes on the rows that a translation does not strain (all of them in a
//! plane analysis; all but the hoop row in axisymmetry, where a radial translation is the
//! hoop strain u_r / r), so a body moving as a whole is not mistaken for a strained one. The
//! equivalent strain √(⅔ Δε:Δε) (engineering shears halved) is at most √(⅔) ‖Δε‖₂, and in
//! plane stress the out-of-plane strain −ν/(1−ν)(Δε_xx + Δε_yy) the material adds is at
//! most √2 times the in-plane norm (|ν/(1−ν)| < 1 for −1 < ν < ½), a factor √3 in all.
//! Each cell keeps the largest ‖B_p‖_F and ‖C_p,c‖₂ (c: each displacement component) over
//! its points: 32 bytes per cell.
//!
//! The bound is only a filter: an increment whose bound exceeds the limit gets the exact
//! largest strain increment from its point states, so every verdict is the one the point
//! states give.

use rayon::prelude::*;

use crate::element::kinematics::{PointKinematics, cell_kinematics};
use crate::model::Model;
use crate::solver::energy::largest;

/// Relative margin on the bound against the rounding of its own arithmetic.
const ROUNDING_MARGIN: f64 = 1e-12;

/// Per cell, the constants of the bound (module docs).
#[derive(Clone, Debug)]
pub struct StrainBound {
    /// The largest ‖B_p‖_F and ‖C_p,c‖₂ (c = x, y, θ) over each cell's points, already
    /// scaled by the equivalent-strain factor.
    cells: Vec<[f64; 4]>,
}

impl StrainBound {
    /// The constants of `model`'s cells: one pass over their integration points (the
    /// kinematics, no material).
    pub fn new(model: &Model) -> Self {
        let continuum = &model.continuum;
        let analysis = &continuum.analysis;
        let d = analysis.dofs_per_node();
        let out_of_plane = if analysis.is_plane_stress() {
            3f64.sqrt()
        } else {
            1.0
        };
        let scale = (2.0f64 / 3.0).sqrt() * out_of_plane * (1.0 + ROUNDING_MARGIN);
        let cells = (continuum.cells.par_iter())
            .map(|cell| {
                let formulation = continuum.formulations[cell.body as usize];
                let points = cell_kinematics(analysis, cell.kind, &cell.coords, formulation);
                let nodes = cell.kind.node_count();
                let mut constants = [0.0f64; 4];
                for pk in points.iter() {
                    let relative = pk.b.norm().hypot(pk.twist.norm());
                    let uniform = uniform_response(pk, nodes, d);
                    for (k, v) in constants
                        .iter_mut()
                        .zip(std::iter::once(relative).chain(uniform))
                    {
                        *k = k.max(scale * v);
                    }
                }
                constants
            })
            .collect();
        Self { cells }
    }

    /// The bound on the largest equivalent strain increment of any integration point from
    /// the displacements `u_old` to `u` (all dofs). NaN if a displacement is not a number.
    pub fn of(&self, model: &Model, u: &[f64], u_old: &[f64]) -> f64 {
        (0..self.cells.len())
            .into_par_iter()
            .with_min_len(256)
            .map(|e| self.of_cell(model, e, u, u_old))
            .reduce(|| 0.0, largest)
    }

    /// The bound on the largest equivalent strain increment of cell `e`'s integration points
    /// from the displacements `u_old` to `u` (all dofs). NaN if a displacement is not a
    /// number.
    pub fn of_cell(&self, model: &Model, e: usize, u: &[f64], u_old: &[f64]) -> f64 {
        let d = model.continuum.analysis.dofs_per_node();
        let cell = &model.continuum.cells[e];
        let [relative, ref uniform @ ..] = self.cells[e];
        let nodes = &cell.nodes[..cell.kind.node_count()];
        let increment = |n: u32, c: usize| {
            let dof = d * n as usize + c;
            u[dof] - u_old[dof]
        };
        let mut mean = [0.0; 3];
        for &n in nodes {
            for (c, m) in mean.iter_mut().enumerate().take(d) {
                *m += increment(n, c);
            }
        }
        mean.iter_mut().for_each(|m| *m /= nodes.len() as f64);
        let mut spread = 0.0;
        for &n in nodes {
            for (c, m) in mean.iter().enumerate().take(d) {
                spread += (increment(n, c) - m).powi(2);
            }
        }
        let translation: f64 = uniform.iter().zip(mean).map(|(c, m)| c * m.abs()).sum();
        relative * spread.sqrt() + translation
    }
}

/// ‖C_p,c‖₂: the norm of the strain of a unit uniform translation of the cell's nodes in
/// each displacement component c (x, y, and θ with twist; 0 for a component the analysis
/// does not have).
fn uniform_response(pk: &PointKinematics, nodes: usize, d: usize) -> [f64; 3] {
    let plane = |c: usize| -> f64 {
        let column: nalgebra::SVector<f64, 4> = (0..nodes)
            .map(|i| pk.b.column(2 * i + c).into_owned())
            .sum();
        column.norm()
    };
    let twist = || -> f64 {
        let column: nalgebra::SVector<f64, 2> =
            (0..nodes).map(|i| pk.twist.column(i).into_owned()).sum();
        column.norm()
    };
    [plane(0), plane(1), if d == 3 { twist() } else { 0.0 }]
}
