//! Load cycles at the interface points: the per-cycle trackers of [`PointHistory`] and the
//! wear extrapolation ("cycle jumping") after a simulated cycle.
//!
//! The stepping loop calls [`start_cycle`] before the first increment of every simulated
//! cycle and of every step, and [`end_cycle`] right after committing the cycle's last
//! increment (before its output), so that every output record is a state to continue from
//! (through [`crate::solver::state::Solution`]'s hooks; these functions take the committed
//! interface states and the energy ledger only).
//!
//! **Cycle jumping.** A simulated cycle stands for ΔN cycles: the wear it added is
//! extrapolated linearly, h += (ΔN − 1)(h − h_cycle start) (explicit Euler in the cycle
//! number). Wear opens the gap, and the pressure at a point falls by k_eff per unit depth,
//! k_eff the stiffness of the interface and the two bodies in series. Archard's law then gives
//! dh/dN = k k_eff s (δ − h) (s the slip per cycle, δ − h = |p_N| / k_eff the closure left),
//! whose explicit Euler step has the amplification factor 1 − ΔN k k_eff s on the closure:
//! accurate and monotone (no overshoot of the unloaded state, hence no oscillation of the
//! pressure from jump to jump) when ΔN k k_eff s ≤ ½. Since ΔN k k_eff s (δ − h) is the depth
//! the jump adds, the bound reads: depth added ≤ `jump_limit` · |p_N| / k_eff, with
//! `jump_limit` = ½ by default. The energy law (dh = α |p_T Δu_T|, p_T = μ p_N in slip) is
//! the same with k = α μ.
//!
//! 1/k_eff = 1/k_N + c_B: the interface's tangent normal stiffness k_N and the compliance of
//! the bodies' surfaces c_B = ℓ / (π E*) to the shortest pressure wave the mesh resolves
//! (wavelength ℓ, the interface element's length; 1/E* = (1 − ν_A²)/E_A + (1 − ν_B²)/E_B,
//! E in plane stress; Westergaard's wavy surface, Johnson, *Contact Mechanics*, §13.2). Longer
//! waves meet a smaller stiffness πE*/λ, so the shortest one bounds the jump. A stiff penalty
//! interface (k_N ≫ πE*/ℓ) is thus limited by the bodies, not by its penalty. |p_N| / k_eff
//! is taken as its largest value over the cycle's increments (the states whose pressure the
//! wear increments use), so that a point loaded only in part of the cycle is bounded by the
//! closure it had while it wore.
//!
//! [`PointHistory`]: crate::contact::PointHistory

use crate::contact::{ContactStatus, InterfaceState, PointHistory};
use crate::element::set::INTERFACE_POINTS;
use crate::model::Model;
use crate::solver::energy::EnergyLedger;
use crate::{Error, Result};

/// Starts a load cycle (or a step) at every interface point of the committed `states`: the
/// cycle trackers restart from the current values (the caller makes the trial states follow).
pub fn start_cycle(states: &mut [InterfaceState]) {
    for s in states {
        restart_trackers(s);
    }
}

/// The trackers of a cycle starting at state `s`: no slip yet, the current shear as the
/// largest so far, no elastic closure yet (the increments record theirs, with the bodies'
/// compliance that only the element knows).
fn restart_trackers(s: &mut InterfaceState) {
    let closed = s.status != ContactStatus::Open;
    let h = &mut s.history;
    h.cycle_start_dissipation = h.dissipation;
    h.cycle_start_wear = h.wear;
    h.cycle_slip = 0.0;
    h.cycle_slip_range = [0.0; 2];
    h.cycle_max_shear = if closed { s.stress[0].abs() } else { 0.0 };
    h.cycle_elastic_closure = 0.0;
}

/// What the end of a cycle did.
#[derive(Clone, Debug, PartialEq)]
pub struct CycleEnd {
    /// Whether the jump added wear (then the worn gaps no longer match the converged
    /// displacements: the caller re-equilibrates).
    pub worn: bool,
    /// Per contact pair, the largest share of its stability limit the jump added at a point.
    pub jump_use: Vec<f64>,
}

/// Ends a simulated load cycle that stands for `jump_cycles` ≥ 1 cycles at the committed
/// interface `states`: the last-cycle results are stored and the wear (and dissipation) of
/// the cycle is extrapolated over the `jump_cycles − 1` cycles not simulated, its work moved
/// to the wear work of `energy`. Errs, leaving the states unchanged, when the depth a jump
/// adds exceeds the stability limit at some point ([`Error::WearJump`]) or the total depth
/// would exceed the pair's `max_depth` ([`Error::WornThrough`]); the caller adds the step
/// with [`Error::in_analysis_step`].
pub fn end_cycle(
    model: &Model,
    states: &mut [InterfaceState],
    energy: &mut EnergyLedger,
    jump_cycles: f64,
) -> Result<CycleEnd> {
    let extra = (jump_cycles - 1.0).max(0.0);
    let jump_use = check_jump(model, states, jump_cycles, extra)?;
    let mut worn = false;
    for (point, s) in states.iter_mut().enumerate() {
        let [a, b] = cycle_wear(&s.history);
        close_cycle(&mut s.history, extra);
        if extra > 0.0 && a + b > 0.0 {
            // The jump's wear takes its work out of the interface's stored energy.
            energy.record_wear_jump(model, point, s, extra * (a + b));
            worn = true;
        }
    }
    Ok(CycleEnd { worn, jump_use })
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
/// Returns, per pair, the largest share depth / limit of a point (0 for a pair that does not
/// wear or a cycle without a jump).
fn check_jump(
    model: &Model,
    states: &[InterfaceState],
    jump_cycles: f64,
    extra: f64,
) -> Result<Vec<f64>> {
    let interface = &model.interface;
    let mut shares = vec![0.0; interface.pairs.len()];
    for (j, pair) in interface.pairs.iter().enumerate() {
        let Some(wear) = pair.wear() else { continue };
        for e in pair.elements.clone() {
            for g in 0..INTERFACE_POINTS {
                let h = &states[e * INTERFACE_POINTS + g].history;
                let [a, b] = cycle_wear(h);
                let depth = extra * (a + b);
                let limit = wear.jump_limit * h.cycle_elastic_closure;
                if depth > 0.0 {
                    shares[j] = f64::max(shares[j], depth / limit);
                }
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
    Ok(shares)
}
