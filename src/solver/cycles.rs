//! Load cycles at the interface points: the per-cycle trackers of [`PointHistory`] and the
//! wear extrapolation ("cycle jumping") after a simulated cycle.
//!
//! The stepping loop calls [`start_cycle`] before the first increment of every simulated
//! cycle and of every step, and [`end_cycle`] right after committing the cycle's last
//! increment (before its output), so that every output record is a state to continue from.
//!
//! **Cycle jumping.** A simulated cycle stands for ΔN cycles: the wear it added is
//! extrapolated linearly, h += (ΔN − 1)(h − h_cycle start) (explicit Euler in the cycle
//! number). With the local pressure p = k_N(δ − h) of a point whose surfaces wear, Archard's
//! law gives dh/dN = k k_N s (δ − h) (s the slip per cycle), whose explicit Euler step has the
//! amplification factor 1 − ΔN k k_N s on the distance δ − h to wear-out: accurate and
//! monotone (no overshoot of the unloaded state, hence no oscillation of the pressure from
//! jump to jump) when ΔN k k_N s ≤ ½. Since ΔN k k_N s (δ − h) is the depth the jump adds and
//! δ − h = |p_N| / k_N, the bound reads: depth added ≤ `jump_limit` · |p_N| / k_N, with
//! `jump_limit` = ½ by default. The compliance of the bodies only lowers the effective
//! stiffness seen by the point, so the bound is conservative. |p_N| / k_N is taken as its
//! largest value in the cycle, so that a point loaded only in part of the cycle is bounded by
//! the closure it had while it wore.
//!
//! [`PointHistory`]: crate::contact::PointHistory

use crate::contact::{ContactStatus, InterfaceState, PointHistory};
use crate::element::set::INTERFACE_POINTS;
use crate::model::Model;
use crate::solver::stepping::Solution;
use crate::{Error, Result};

/// Starts a load cycle (or a step) at every interface point of the committed state: the
/// cycle trackers restart from the current values (trial states follow).
pub fn start_cycle(solution: &mut Solution) {
    for s in &mut solution.interface_committed {
        restart_trackers(s);
    }
    solution
        .interface_trial
        .copy_from_slice(&solution.interface_committed);
}

/// The trackers of a cycle starting at state `s`: no slip yet, the current shear and elastic
/// closure as the extremes so far.
fn restart_trackers(s: &mut InterfaceState) {
    let closed = s.status != ContactStatus::Open;
    let h = &mut s.history;
    h.cycle_start_dissipation = h.dissipation;
    h.cycle_start_wear = h.wear;
    h.cycle_slip = 0.0;
    h.cycle_slip_range = [0.0; 2];
    h.cycle_max_shear = if closed { s.stress[0].abs() } else { 0.0 };
    h.cycle_elastic_closure = if closed && s.stiffness[1] > 0.0 {
        s.stress[1].abs() / s.stiffness[1]
    } else {
        0.0
    };
}

/// Ends a simulated load cycle that stands for `jump_cycles` ≥ 1 cycles: the last-cycle
/// results are stored and the wear (and dissipation) of the cycle is extrapolated over the
/// `jump_cycles − 1` cycles not simulated. Errs, leaving the solution unchanged, when the
/// depth a jump adds exceeds the stability limit at some point ([`Error::WearJump`]) or the
/// total depth would exceed the pair's `max_depth` ([`Error::WornThrough`]); the caller adds
/// the step with [`Error::in_analysis_step`].
pub fn end_cycle(model: &Model, solution: &mut Solution, jump_cycles: f64) -> Result<()> {
    let extra = (jump_cycles - 1.0).max(0.0);
    check_jump(model, &solution.interface_committed, jump_cycles, extra)?;
    for (point, s) in solution.interface_committed.iter_mut().enumerate() {
        let [a, b] = cycle_wear(&s.history);
        close_cycle(&mut s.history, extra);
        if extra > 0.0 && a + b > 0.0 {
            // The jump's wear takes its work out of the interface's stored energy.
            (solution.energy).record_wear_jump(model, point, s, extra * (a + b));
        }
    }
    solution
        .interface_trial
        .copy_from_slice(&solution.interface_committed);
    Ok(())
}

/// Wear depth (A, B) added since the cycle started.
fn cycle_wear(h: &PointHistory) -> [f64; 2] {
    [
        h.wear[0] - h.cycle_start_wear[0],
        h.wear[1] - h.cycle_start_wear[1],
    ]
}

/// Stores the cycle's results and extrapolates its wear and dissipation over `extra` more
/// cycles.
fn close_cycle(h: &mut PointHistory, extra: f64) {
    let added = cycle_wear(h);
    let dissipated = h.dissipation - h.cycle_start_dissipation;
    h.last_cycle_dissipation = dissipated;
    h.last_cycle_slip_amplitude = 0.5 * (h.cycle_slip_range[1] - h.cycle_slip_range[0]);
    h.last_cycle_max_shear = h.cycle_max_shear;
    h.last_cycle_wear = added;
    h.wear = [h.wear[0] + extra * added[0], h.wear[1] + extra * added[1]];
    h.dissipation += extra * dissipated;
}

/// The stability limit and the wear-through depth at every point of a pair that wears.
fn check_jump(
    model: &Model,
    states: &[InterfaceState],
    jump_cycles: f64,
    extra: f64,
) -> Result<()> {
    let interface = &model.interface;
    for (j, pair) in interface.pairs.iter().enumerate() {
        let Some(wear) = pair.wear() else { continue };
        for e in pair.elements.clone() {
            for g in 0..INTERFACE_POINTS {
                let h = &states[e * INTERFACE_POINTS + g].history;
                let [a, b] = cycle_wear(h);
                let depth = extra * (a + b);
                let limit = wear.jump_limit * h.cycle_elastic_closure;
                if depth > limit {
                    return Err(Error::WearJump {
                        contact: pair.name.clone(),
                        contact_index: j,
                        step_index: None,
                        position: interface.point_position(e, g),
                        jump_cycles,
                        depth,
                        limit,
                        jump_limit: wear.jump_limit,
                    });
                }
                let total = h.depth() + depth;
                if let Some(max_depth) = wear.max_depth.filter(|&m| total > m) {
                    return Err(Error::WornThrough {
                        contact: pair.name.clone(),
                        contact_index: j,
                        step_index: None,
                        position: interface.point_position(e, g),
                        depth: total,
                        max_depth,
                    });
                }
            }
        }
    }
    Ok(())
}
