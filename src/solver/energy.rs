//! The energy balance of a run (issue: cyclic loading): external work, stored elastic
//! energy, plastic and frictional dissipation, accumulated over the converged increments.
//! The imbalance of these terms is a convergence check a user can read.
//!
//! (Interface defined ahead of its implementation; see [`EnergyLedger::record_increment`].)

use crate::model::Model;

/// Energy totals from the unloaded start (N·mm = mJ; per unit thickness as the forces are).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy {
    /// Work of the external forces and of the reactions at prescribed displacements.
    pub external_work: f64,
    /// Elastic energy stored in the bodies.
    pub elastic_energy: f64,
    /// Elastic energy stored in the interfaces.
    pub interface_energy: f64,
    /// Plastic work of the bodies.
    pub plastic_dissipation: f64,
    /// Frictional dissipation ∫ p_T du_T^p over the interfaces.
    pub friction_dissipation: f64,
    /// Energy removed with worn material (pressure times wear depth).
    pub wear_work: f64,
    /// Dissipation of the time discretisation itself (vanishes as increments shrink).
    pub numerical_dissipation: f64,
}

/// The running energy totals and what the next increment's trapezoidal work needs of the
/// last converged state.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EnergyLedger {
    pub total: Energy,
    /// Total nodal force (external loads at free dofs, reactions at prescribed dofs) of the
    /// last converged state; empty before the first increment.
    pub previous_force: Vec<f64>,
}

impl EnergyLedger {
    /// Adds the converged increment from the committed to the trial states of `solution`
    /// (displacements from `u_old` to `solution.u`); `external_force` and `internal_force`
    /// are those of the converged state over all dofs.
    pub fn record_increment(
        &mut self,
        _model: &Model,
        _solution: &crate::solver::stepping::Solution,
        _u_old: &[f64],
        _external_force: &[f64],
        _internal_force: &[f64],
    ) {
    }
}
