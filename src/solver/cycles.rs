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
//! closure it had while it wore. `jump_limit` ≤ 1 (checked with the case): beyond 1 the
//! jump overshoots the unloaded state of the shortest wave, beyond 2 the overshoot grows.
//!
//! **One place, one rate.** The bodies resist only modes of the surface. The two integration
//! points at a corner node shared by two elements are one place of it; a difference between
//! their depths meets k_N alone, which a stiff penalty makes far stiffer than k_eff, so a jump
//! extrapolating each point's own rate would amplify it (see `jump_depths`, and
//! docs/fretting.md, "Cycle jumping"). The jump extrapolates the place's mean rate instead.
//!
//! **Wear the model cannot hold.** A depth beyond the extent of the body behind the surface
//! ([`Error::WornBeyondBody`]) stops the run at a cycle's end, jump or not; after a jump and
//! its re-equilibrium the energy balance is checked ([`check_jump_energy`]).
//!
//! [`PointHistory`]: crate::contact::PointHistory

use std::collections::HashMap;

use crate::contact::{ContactStatus, InterfaceState, PointHistory, length, tangential};
use crate::element::interface6::interface_point;
use crate::element::set::INTERFACE_POINTS;
use crate::model::Model;
use crate::solver::energy::{Energy, EnergyLedger, JUMP_BALANCE_TOLERANCE};
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
    h.cycle_slip = [0.0; 2];
    h.cycle_slip_ends = [[0.0; 2]; 2];
    h.cycle_max_shear = if closed {
        length(tangential(s.stress))
    } else {
        0.0
    };
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
/// to the wear work of `energy`. The points at one place of the surface (a corner node shared
/// by two elements) are extrapolated with their common wear rate (`surface_places`).
/// Errs, leaving the states unchanged, when the depth a jump adds exceeds the stability limit
/// at some place ([`Error::WearJump`]), or the total depth would exceed the pair's
/// `max_depth` ([`Error::WornThrough`]) or the extent of the body behind the worn surface
/// ([`Error::WornBeyondBody`]); the caller adds the step with [`Error::in_analysis_step`].
pub fn end_cycle(
    model: &Model,
    states: &mut [InterfaceState],
    energy: &mut EnergyLedger,
    jump_cycles: f64,
) -> Result<CycleEnd> {
    let extra = (jump_cycles - 1.0).max(0.0);
    let jumps = jump_depths(model, states, extra);
    let jump_use = check_jump(model, states, &jumps, jump_cycles)?;
    let mut worn = false;
    for (point, (s, jump)) in states.iter_mut().zip(&jumps).enumerate() {
        close_cycle(&mut s.history, extra, jump.added);
        let depth = jump.added[0] + jump.added[1];
        if depth > 0.0 {
            // The jump's wear takes its work out of the interface's stored energy.
            energy.record_wear_jump(model, point, s, depth);
            worn = true;
        }
    }
    Ok(CycleEnd { worn, jump_use })
}

/// Checks the energy balance `energy` of the run after a wear jump over `jump_cycles` cycles
/// and the re-equilibrium that followed it ([`Energy::balanced_after_jump`]); `jump_use` is
/// the share of its stability limit each pair's jump used, the pair using most is named.
/// The caller adds the step with [`Error::in_analysis_step`].
pub fn check_jump_energy(
    model: &Model,
    energy: &Energy,
    jump_use: &[f64],
    jump_cycles: f64,
) -> Result<()> {
    if energy.balanced_after_jump() {
        return Ok(());
    }
    let pairs = &model.interface.pairs;
    let contact_index = (0..pairs.len())
        .filter(|&j| pairs[j].wear().is_some())
        .max_by(|&i, &j| {
            let share = |k: usize| jump_use.get(k).copied().unwrap_or(0.0);
            share(i).total_cmp(&share(j))
        })
        .unwrap_or(0);
    Err(Error::WearEnergy {
        contact: pairs[contact_index].name.clone(),
        contact_index,
        step_index: None,
        jump_cycles,
        interface_energy: energy.interface_energy,
        imbalance: energy.imbalance(),
        wear_work: energy.wear_work,
        external_work: energy.external_work,
        tolerance: JUMP_BALANCE_TOLERANCE,
    })
}

/// The wear a jump adds at an interface point and what bounds it.
#[derive(Clone, Copy, Debug, Default)]
struct PointJump {
    /// Depth (A, B) the jump adds, mm.
    added: [f64; 2],
    /// The elastic closure the stability limit is a fraction of, mm.
    closure: f64,
}

/// Wear depth (A, B) added since the cycle started.
fn cycle_wear(h: &PointHistory) -> [f64; 2] {
    [
        h.wear[0] - h.cycle_start_wear[0],
        h.wear[1] - h.cycle_start_wear[1],
    ]
}

/// The depth a jump over `extra` cycles adds at every point, and the closure bounding it:
/// `extra` times the cycle's wear, and the point's largest elastic closure of the cycle,
/// both averaged (weighted by the points' areas) over the points at the same place of the
/// surface.
///
/// Why the average: the two integration points at a corner node shared by two elements move
/// with the same node pair, so a difference between their depths is resisted by the
/// interface's k_N alone (one point's gap opens, the other's closes, and the bodies see only
/// their sum). Under a stiff penalty k_N is far stiffer than the k_eff of the stability
/// limit, and a jump extrapolating each point's own wear multiplies such a difference by
/// 1 − ΔN k k_N s ≈ 1 − `jump_limit` k_N / k_eff each time (−5 to −40 for common penalties):
/// the points drift apart until one is open and the other carries the pressure of both. That
/// difference is no mode of the surface (one place, one depth); it comes from the kink of the
/// element frames at the node, and the simulated cycles keep it small and stable (one cycle
/// multiplies it by 1 − k k_N s, close to 1). The jump therefore extrapolates the place's
/// wear rate and leaves the points' differences to the simulated cycles; the worn volume is
/// that of the points' own rates.
fn jump_depths(model: &Model, states: &[InterfaceState], extra: f64) -> Vec<PointJump> {
    let interface = &model.interface;
    let (place, places) = surface_places(model);
    // Per place: area-weighted sums of the cycle's wear (A, B) and closure, and the area.
    let mut sums = vec![[0.0; 4]; places];
    for (i, s) in states.iter().enumerate() {
        let (e, g) = (i / INTERFACE_POINTS, i % INTERFACE_POINTS);
        let element = &interface.elements[e];
        let (xi, w) = element.rule.points()[g];
        let da = interface_point(&interface.analysis, &element.b_coords, xi, w).da;
        let [a, b] = cycle_wear(&s.history);
        let sum = &mut sums[place[i]];
        sum[0] += da * a;
        sum[1] += da * b;
        sum[2] += da * s.history.cycle_elastic_closure;
        sum[3] += da;
    }
    place
        .iter()
        .zip(states)
        .map(|(&p, s)| {
            let [a, b, closure, area] = sums[p];
            if area > 0.0 {
                PointJump {
                    added: [extra * a / area, extra * b / area],
                    closure: closure / area,
                }
            } else {
                // A point of no area (on the axis) is a place of its own.
                let [a, b] = cycle_wear(&s.history);
                PointJump {
                    added: [extra * a, extra * b],
                    closure: s.history.cycle_elastic_closure,
                }
            }
        })
        .collect()
}

/// The place of the surface of every interface point (index into the interface states) and
/// the number of places: the end points of Newton–Cotes elements at the same node pair of
/// the same contact pair share a place; every other point has its own.
fn surface_places(model: &Model) -> (Vec<usize>, usize) {
    let interface = &model.interface;
    let mut at_node: HashMap<(u32, u32, u32), usize> = HashMap::new();
    let mut place = Vec::with_capacity(interface.elements.len() * INTERFACE_POINTS);
    let mut places = 0;
    for element in &interface.elements {
        for &(xi, _) in element.rule.points() {
            // Line order: ξ = −1 at the first end node, ξ = +1 at the second.
            let end = [-1.0, 1.0].iter().position(|&x| x == xi);
            let mut new_place = || {
                places += 1;
                places - 1
            };
            place.push(match end {
                Some(i) => {
                    let key = (element.pair, element.nodes[i], element.nodes[3 + i]);
                    *at_node.entry(key).or_insert_with(new_place)
                }
                None => new_place(),
            });
        }
    }
    (place, places)
}

/// Stores the cycle's results and extrapolates its dissipation over `extra` more cycles and
/// its wear by the depth `added` (A, B) of the jump.
fn close_cycle(h: &mut PointHistory, extra: f64, added: [f64; 2]) {
    let worn = cycle_wear(h);
    let dissipated = h.dissipation - h.cycle_start_dissipation;
    h.last_cycle_dissipation = dissipated;
    h.last_cycle_slip_amplitude = h.cycle_slip_amplitude();
    h.last_cycle_max_shear = h.cycle_max_shear;
    h.last_cycle_wear = worn;
    h.wear = [h.wear[0] + added[0], h.wear[1] + added[1]];
    h.dissipation += extra * dissipated;
}

/// The stability limit, the wear-through depth and the extent of the bodies at every point of
/// a pair that wears, for the depths `jumps` would add. Returns, per pair, the largest share
/// depth / limit of a point (0 for a pair that does not wear or a cycle without a jump).
fn check_jump(
    model: &Model,
    states: &[InterfaceState],
    jumps: &[PointJump],
    jump_cycles: f64,
) -> Result<Vec<f64>> {
    let interface = &model.interface;
    let mut shares = vec![0.0; interface.pairs.len()];
    let mut bodies = None;
    for (j, pair) in interface.pairs.iter().enumerate() {
        let Some(wear) = pair.wear() else { continue };
        let bodies = bodies.get_or_insert_with(|| BodyExtents::new(model));
        for e in pair.elements.clone() {
            for g in 0..INTERFACE_POINTS {
                let point = e * INTERFACE_POINTS + g;
                let (h, jump) = (&states[point].history, jumps[point]);
                let depth = jump.added[0] + jump.added[1];
                let limit = wear.jump_limit * jump.closure;
                if depth > 0.0 {
                    shares[j] = f64::max(shares[j], depth / limit);
                }
                let position = interface.point_position(e, g);
                if depth > limit {
                    return Err(Error::WearJump {
                        contact: pair.name.clone(),
                        contact_index: j,
                        step_index: None,
                        position,
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
                        position,
                        depth: total,
                        max_depth,
                    });
                }
                for side in 0..2 {
                    let depth = h.wear[side] + jump.added[side];
                    let Some((body, extent)) = bodies.behind(model, e, g, side) else {
                        continue;
                    };
                    if depth > extent {
                        return Err(Error::WornBeyondBody {
                            contact: pair.name.clone(),
                            contact_index: j,
                            step_index: None,
                            position,
                            body: model.bodies[body].clone(),
                            depth,
                            extent,
                        });
                    }
                }
            }
        }
    }
    Ok(shares)
}

/// Where the bodies are: the body holding each node and each body's bounding box, for the
/// wear-depth bound. A surface cannot be worn deeper than the body behind it; the body's
/// bounding box bounds that thickness from above at any shape (a robust proxy: the exact
/// thickness along the normal would need a ray cast through the mesh), so a depth beyond it
/// is certainly no result.
struct BodyExtents {
    owner: Vec<u32>,
    boxes: Vec<[[f64; 2]; 2]>,
}

impl BodyExtents {
    fn new(model: &Model) -> Self {
        let mut owner = vec![u32::MAX; model.mesh.nodes.len()];
        let empty = [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]];
        let mut boxes = vec![empty; model.bodies.len()];
        for cell in &model.continuum.cells {
            let count = cell.kind.node_count();
            let bounds = &mut boxes[cell.body as usize];
            for (&node, x) in cell.nodes[..count].iter().zip(&cell.coords) {
                owner[node as usize] = cell.body;
                for c in 0..2 {
                    bounds[0][c] = bounds[0][c].min(x[c]);
                    bounds[1][c] = bounds[1][c].max(x[c]);
                }
            }
        }
        Self { owner, boxes }
    }

    /// The body behind side `side` (0: A, 1: B) of point `g` of interface element `e`, and
    /// its extent behind the point along the normal (mm): the farthest corner of its
    /// bounding box, on the side away from the other body (the normal points into B).
    /// `None` for a face node in no body (the model refuses those).
    fn behind(&self, model: &Model, e: usize, g: usize, side: usize) -> Option<(usize, f64)> {
        let interface = &model.interface;
        let element = &interface.elements[e];
        let body = *self.owner.get(element.nodes[3 * side] as usize)?;
        let [low, high] = *self.boxes.get(body as usize)?;
        let (xi, w) = element.rule.points()[g];
        let p = interface_point(&interface.analysis, &element.b_coords, xi, w);
        let inward = if side == 0 { -1.0 } else { 1.0 };
        let extent = [[low[0], low[1]], [low[0], high[1]], [high[0], low[1]], high]
            .iter()
            .map(|c| inward * ((c[0] - p.x[0]) * p.normal[0] + (c[1] - p.x[1]) * p.normal[1]))
            .fold(0.0, f64::max);
        Some((body as usize, extent))
    }
}
