//! Load cycles at the interface points: the per-cycle trackers of [`PointHistory`] and the
//! wear extrapolation ("cycle jumping") after a simulated cycle.
//!
//! (Interface defined ahead of its implementation.)
//!
//! [`PointHistory`]: crate::contact::PointHistory

use crate::Result;
use crate::model::Model;
use crate::solver::stepping::Solution;

/// Starts a load cycle (or a step) at every interface point of the committed state: the
/// cycle trackers restart from the current values.
pub fn start_cycle(_solution: &mut Solution) {}

/// Ends a simulated load cycle that stands for `jump_cycles` ≥ 1 cycles: the last-cycle
/// results are stored and the wear of the cycle is extrapolated over the `jump_cycles − 1`
/// cycles not simulated. Errs when the extrapolated depth exceeds the stability limit.
pub fn end_cycle(_model: &Model, _solution: &mut Solution, _jump_cycles: f64) -> Result<()> {
    Ok(())
}
