//! Loads: the load histories (amplitudes over the analysis steps) and the consistent nodal
//! forces of pressures, tractions, torques and point forces.

use super::timeline::{StepPlan, Timeline};
use super::{LineLoad, Load, LoadKind, Model, boundary_group};
use crate::element::Analysis;
use crate::element::quadrature::GAUSS3;
use crate::element::set::ContinuumSet;
use crate::element::shape::line3;
use crate::error::{GroupKind, GroupProblem, LoadPoint, MeshEntity};
use crate::mesh::Mesh;
use crate::mesh::topology::EdgeIndex;
use crate::{Error, Result};

/// A piecewise-linear multiplier over the local time u ∈ [u₀, u_last] of one step (or one
/// cycle of it, see [`super::timeline`]): through the knots (u_i, v_i), constant beyond
/// them.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    u: Vec<f64>,
    v: Vec<f64>,
}

impl Table {
    /// Knots `u` (strictly increasing, at least one) and values `v` of the same length.
    pub fn new(u: Vec<f64>, v: Vec<f64>) -> Self {
        debug_assert!(!u.is_empty() && u.len() == v.len());
        Self { u, v }
    }

    /// A constant value over `increments`.
    pub fn constant(value: f64, increments: usize) -> Self {
        Self::ramp(value, value, increments)
    }

    /// From `from` at u = 0 linearly to `to` at u = `increments`.
    pub fn ramp(from: f64, to: f64, increments: usize) -> Self {
        Self::new(vec![0.0, increments as f64], vec![from, to])
    }

    /// The value at local time `u`. A knot belongs to the segment that ends there (as a
    /// step's end belongs to the step), so at u = u_i the value is v_{i−1} + 1·(v_i − v_{i−1}).
    pub fn value(&self, u: f64) -> f64 {
        if self.u.len() == 1 {
            return self.v[0];
        }
        let (u0, last) = (self.u[0], self.u[self.u.len() - 1]);
        let u = u.clamp(u0, last);
        let i = self
            .u
            .partition_point(|&x| x < u)
            .clamp(1, self.u.len() - 1);
        let theta = (u - self.u[i - 1]) / (self.u[i] - self.u[i - 1]);
        self.v[i - 1] + theta * (self.v[i] - self.v[i - 1])
    }

    /// The first knot strictly between `from` and `to` (more than `eps` inside), if any.
    fn knot_between(&self, from: f64, to: f64, eps: f64) -> Option<f64> {
        let i = self.u.partition_point(|&x| x <= from + eps);
        self.u.get(i).copied().filter(|&x| x < to - eps)
    }
}

/// The history of one load or support as the case gives it.
#[derive(Clone, Debug, PartialEq)]
pub enum History {
    /// The global load factor of `[steps]` (a zero support of `[[step]]`).
    Global,
    /// Its own multiplier: one table per analysis step, and the `history.csv` column that
    /// shows it (`factor_<role>_<name>`).
    Own { column: String, tables: Vec<Table> },
}

/// Load histories ("amplitudes") over the case's [`Timeline`]: amplitude 0 is the global load
/// factor of a `[steps]` schedule (zero with `[[step]]`, where nothing follows it), and every
/// support or load with its own history adds one. Each amplitude is piecewise linear in the
/// local time of every step (repeated in each cycle of a cyclic step) and is evaluated
/// exactly at any pseudo-time, so that an increment cut back into sub-increments moves every
/// load along its own amplitude, and the stepping can end sub-increments at the amplitudes'
/// breakpoints ([`Schedule::next_time`]).
#[derive(Clone, Debug)]
pub struct Schedule {
    timeline: Timeline,
    /// Per amplitude, one table per step.
    amplitudes: Vec<Vec<Table>>,
    /// The `[steps]` load factors (exact at the end of each step); `None` with `[[step]]`,
    /// whose load factor is the total analysis time.
    factors: Option<Vec<f64>>,
    /// `history.csv` columns of the own histories: (column, amplitude).
    columns: Vec<(String, usize)>,
}

/// Breakpoints closer than this (in output increments) to a sub-increment's start or end do
/// not end a sub-increment.
const KNOT_TOLERANCE: f64 = 1e-9;

/// How far back (in output increments) [`Schedule::leaves_direction`] looks for the loads'
/// direction before an increment: far above the round-off of a pseudo-time, far below any
/// increment.
const DIRECTION_PROBE: f64 = 1e-6;

impl Schedule {
    /// The `[steps]` schedule: one step of `factors.len()` increments, the global factor 0
    /// at τ = 0 and `factors[j − 1]` at τ = j.
    pub fn new(factors: Vec<f64>) -> Self {
        let n = factors.len();
        let timeline = Timeline::new(vec![StepPlan::new("step-1".into(), n, 1, 1)]);
        let global = factor_table(&factors);
        Self {
            timeline,
            amplitudes: vec![vec![global]],
            factors: Some(factors),
            columns: Vec::new(),
        }
    }

    /// The schedule of `[[step]]` analysis steps (the supports' and loads' amplitudes are
    /// added as the model is built).
    pub fn with_steps(timeline: Timeline) -> Self {
        let zero = timeline
            .steps()
            .iter()
            .map(|s| Table::constant(0.0, s.increments))
            .collect();
        Self {
            timeline,
            amplitudes: vec![zero],
            factors: None,
            columns: Vec::new(),
        }
    }

    /// Adds a history's amplitude and returns its index (0, the global one, for
    /// [`History::Global`]).
    pub(super) fn add(&mut self, history: &History) -> usize {
        match history {
            History::Own { column, tables } => {
                self.amplitudes.push(tables.clone());
                let k = self.amplitudes.len() - 1;
                self.columns.push((column.clone(), k));
                k
            }
            History::Global => 0,
        }
    }

    /// The analysis steps and cycles.
    pub fn timeline(&self) -> &Timeline {
        &self.timeline
    }

    /// Number of output increments (frames) over all steps and simulated cycles.
    pub fn steps(&self) -> usize {
        self.timeline.frames()
    }

    /// The `history.csv` columns of the loads and supports with their own history, with
    /// their amplitude.
    pub fn columns(&self) -> &[(String, usize)] {
        &self.columns
    }

    /// The load factor at the end of output increment `step` (1-based): the `[steps]`
    /// factor, or the total analysis time with `[[step]]`.
    pub fn load_factor(&self, step: usize) -> f64 {
        match &self.factors {
            Some(f) => f[step - 1],
            None => self.timeline.analysis_time(step as f64),
        }
    }

    /// The load factor at pseudo-time `time` (as [`Self::load_factor`]).
    pub fn load_factor_at(&self, time: f64) -> f64 {
        match &self.factors {
            Some(_) => self.value(0, time),
            None => self.timeline.analysis_time(time),
        }
    }

    /// The state at pseudo-time `time` in the user's terms, as a point of the step (and
    /// cycle) of the increment that ends at `target` (so that a step's start is 0 % of it,
    /// not 100 % of the one before): the `[[step]]`'s name, the fraction of it reached and
    /// the multipliers of the own histories; the load factor of the `[steps]` form.
    pub fn load_point(&self, time: f64, target: f64) -> LoadPoint {
        let p = self.timeline.locate(target);
        let plan = &self.timeline.steps()[p.step];
        let n = plan.increments as f64;
        let u = time - (target - p.u);
        let named = self.factors.is_none();
        LoadPoint {
            step: named.then(|| (plan.name.clone(), p.step)),
            increment: target.ceil().max(1.0) as usize,
            cycle: (named && plan.is_cyclic()).then_some((p.cycle, plan.simulated())),
            step_time: (u / n).clamp(0.0, 1.0),
            load_factor: self.load_factor_at(time),
            multipliers: self
                .columns
                .iter()
                .map(|(column, k)| (column.clone(), self.value(*k, time)))
                .collect(),
        }
    }

    /// The increment solves each step needs before any cut-back: in every simulated cycle,
    /// its output increments and one more for every amplitude breakpoint inside an increment
    /// (each ends a sub-increment, [`Self::next_time`]).
    pub fn planned_solves(&self) -> Vec<usize> {
        let steps = self.timeline.steps().iter().enumerate();
        steps
            .map(|(i, plan)| {
                let end = plan.increments as f64;
                let mut inside: Vec<f64> = self
                    .amplitudes
                    .iter()
                    .flat_map(|tables| tables[i].u.iter().copied())
                    .filter(|&u| {
                        u > KNOT_TOLERANCE
                            && u < end - KNOT_TOLERANCE
                            && (u - u.round()).abs() > KNOT_TOLERANCE
                    })
                    .collect();
                inside.sort_by(f64::total_cmp);
                inside.dedup_by(|a, b| (*a - *b).abs() <= KNOT_TOLERANCE);
                (plan.increments + inside.len()).saturating_mul(plan.simulated())
            })
            .collect()
    }

    /// Value of amplitude `k` at pseudo-time `time`.
    pub fn value(&self, k: usize, time: f64) -> f64 {
        let p = self.timeline.locate(time);
        self.amplitudes[k][p.step].value(p.u)
    }

    /// Whether the increment from pseudo-time `from` to `to` leaves the direction in which
    /// the loads moved up to `from`: some amplitude that changes over the increment was
    /// constant or moved the other way just before `from` (a load reversal, or a load that
    /// starts moving). Sub-increments end on the amplitudes' breakpoints, so each amplitude is
    /// linear on both sides of `from` and the one-sided differences give its directions.
    pub fn leaves_direction(&self, from: f64, to: f64) -> bool {
        if from <= 0.0 {
            return true;
        }
        let before = (from - DIRECTION_PROBE).max(0.0);
        (0..self.amplitudes.len()).any(|k| {
            let ahead = self.value(k, to) - self.value(k, from);
            let behind = self.value(k, from) - self.value(k, before);
            ahead != 0.0 && ahead * behind <= 0.0
        })
    }

    /// How much the load level changes from pseudo-time `from` to `to` (for the secant
    /// stiffness of the collapse check): the change of the global factor with `[steps]`,
    /// the Euclidean norm of the change of every own multiplier with `[[step]]`.
    pub fn load_change(&self, from: f64, to: f64) -> f64 {
        if self.factors.is_some() {
            return self.value(0, to) - self.value(0, from);
        }
        let (a, b) = (self.timeline.locate(from), self.timeline.locate(to));
        self.amplitudes[1..]
            .iter()
            .map(|tables| {
                let d = tables[b.step].value(b.u) - tables[a.step].value(a.u);
                d * d
            })
            .sum::<f64>()
            .sqrt()
    }

    /// The end of the next sub-increment from pseudo-time `time` towards `target` (the end
    /// of output increment `target`) with size `size`: `target` when within 1e-12 of it,
    /// else the first breakpoint of an amplitude inside the interval when there is one (so
    /// that no peak or reversal of a load is cut off), else `time + size`.
    pub fn next_time(&self, time: f64, size: f64, target: f64) -> f64 {
        let end = if time + size >= target - 1e-12 {
            target
        } else {
            time + size
        };
        let p = self.timeline.locate(target);
        let base = target - p.u;
        let (from, to) = (time - base, end - base);
        self.amplitudes
            .iter()
            .filter_map(|tables| tables[p.step].knot_between(from, to, KNOT_TOLERANCE))
            .reduce(f64::min)
            .map_or(end, |u| base + u)
    }
}

/// The `[steps]` table of factors: 0 at u = 0, `factors[j − 1]` at u = j.
fn factor_table(factors: &[f64]) -> Table {
    let u = (0..=factors.len()).map(|j| j as f64).collect();
    let v = std::iter::once(0.0)
        .chain(factors.iter().copied())
        .collect();
    Table::new(u, v)
}

/// A load's or support's own `[steps]` factors as a history showing in column `column`.
pub fn factors_history(column: String, factors: &[f64]) -> History {
    History::Own {
        column,
        tables: vec![factor_table(factors)],
    }
}

impl Model {
    /// Sets the prescribed components of `u` to their values at pseudo-time `time`.
    pub fn apply_prescribed(&self, time: f64, u: &mut [f64]) {
        for &(dof, value, k) in &self.prescribed {
            u[dof] = value * self.schedule.value(k, time);
        }
    }

    /// External nodal forces over all dofs at pseudo-time `time`.
    pub fn external_force(&self, time: f64, f: &mut [f64]) {
        f.fill(0.0);
        for &(dof, value, k) in &self.nodal_loads {
            f[dof] += value * self.schedule.value(k, time);
        }
    }
}

/// The external nodal forces of the loads at load factor 1: (dof, force, amplitude), load
/// after load (adding their histories to `schedule`, in order).
pub(super) fn nodal_loads(
    mesh: &Mesh,
    analysis: Analysis,
    continuum: &ContinuumSet,
    specs: &[Load],
    in_body: &[bool],
    schedule: &mut Schedule,
) -> Result<Vec<(usize, f64, usize)>> {
    // The edges of the body cells that may carry a line load orient its outward normal.
    let mut wanted = vec![false; mesh.nodes.len()];
    for group in specs.iter().filter_map(|l| mesh.group(1, &l.group)) {
        for line in mesh.lines_in(group) {
            wanted[line.nodes[0] as usize] = true;
            wanted[line.nodes[1] as usize] = true;
        }
    }
    let cells = continuum.cells.iter().enumerate();
    let edges = EdgeIndex::new(
        cells.map(|(i, c)| (i, c.body as usize, c.kind, &c.nodes)),
        &wanted,
    );
    let mut nodal_loads = Vec::new();
    let mut load = vec![0.0; analysis.dofs_per_node() * mesh.nodes.len()];
    for spec in specs {
        load.fill(0.0);
        add_load(mesh, analysis, &edges, spec, in_body, &mut load)?;
        let amplitude = schedule.add(&spec.factors);
        nodal_loads.extend(
            load.iter()
                .enumerate()
                .filter(|(_, f)| **f != 0.0)
                .map(|(d, f)| (d, *f, amplitude)),
        );
    }
    Ok(nodal_loads)
}

/// Adds the consistent nodal forces of a load at load factor 1.
fn add_load(
    mesh: &Mesh,
    analysis: Analysis,
    edges: &EdgeIndex,
    spec: &Load,
    in_body: &[bool],
    load: &mut [f64],
) -> Result<()> {
    let group = boundary_group(mesh, &spec.group, "load")?;
    let wrong_kind = |expected, purpose| {
        let found = group.kind();
        let problem = GroupProblem::WrongKind { found, purpose };
        mesh.group_error("load", &spec.group, expected, problem)
    };
    let line_load = match spec.kind {
        LoadKind::Point(force) => {
            if group.dim != 0 {
                return Err(wrong_kind(GroupKind::Point, "a force"));
            }
            for n in mesh.points_in(group) {
                if !in_body[n as usize] {
                    return Err(Error::NotOnBody {
                        role: "load",
                        group: spec.group.clone(),
                        entity: MeshEntity::Node(mesh.node_tags[n as usize]),
                        position: mesh.nodes[n as usize],
                    });
                }
                let per_node = analysis.dofs_per_node();
                for (c, f) in force.iter().enumerate().take(per_node) {
                    load[per_node * n as usize + c] += f;
                }
            }
            return Ok(());
        }
        LoadKind::Line(line_load) => line_load,
    };
    if group.dim != 1 {
        return Err(wrong_kind(GroupKind::Curve, "a pressure or traction"));
    }
    let mut count = 0;
    for line in mesh.lines_in(group) {
        let nodes = edges.oriented(line).ok_or_else(|| Error::NotOnBody {
            role: "load",
            group: spec.group.clone(),
            entity: MeshEntity::Element(line.tag),
            position: mesh.nodes[line.nodes[0] as usize],
        })?;
        add_line_load(mesh, analysis, nodes, line_load, load);
        count += 1;
    }
    if count == 0 {
        let problem = GroupProblem::Empty;
        return Err(mesh.group_error("load", &spec.group, GroupKind::Curve, problem));
    }
    if let LineLoad::Torque(torque) = line_load {
        scale_to_torque(mesh, analysis, &spec.group, torque, load)?;
    }
    Ok(())
}

/// Scales the circumferential nodal forces of the unit distribution t_θ = r on a curve
/// (`load`, this load's forces alone) so that their moment about the axis, Σ r_n F_θn, is
/// exactly `torque`. The moment of the consistent forces equals ∫ t_θ r dA (r interpolated
/// by the same shape functions, integrated by the same rule), so the traction's moment is
/// `torque` too.
fn scale_to_torque(
    mesh: &Mesh,
    analysis: Analysis,
    group: &str,
    torque: f64,
    load: &mut [f64],
) -> Result<()> {
    let d = analysis.dofs_per_node();
    let moment: f64 = mesh
        .nodes
        .iter()
        .zip(load.chunks_exact(d))
        .map(|(x, f)| x[0] * f[2])
        .sum();
    if moment <= 0.0 {
        return Err(Error::InvalidParameter {
            path: std::path::PathBuf::new(),
            key: format!("load '{group}' torque"),
            value: torque.to_string(),
            reason: "the curve lies on the axis (r = 0), where a circumferential traction has no \
                     moment: apply the torque on a curve off the axis"
                .into(),
        });
    }
    let factor = torque / moment;
    for f in load.chunks_exact_mut(d) {
        f[2] *= factor;
    }
    Ok(())
}

/// Consistent nodal forces f_i = ∫ N_i t dA on one line, with dA = (thickness or 2πr) ds,
/// integrated by 3-point Gauss (exact for a pressure on a curved quadratic edge in
/// axisymmetry: degree 5). A torque adds the unit circumferential traction t_θ = r, which
/// [`scale_to_torque`] scales once the whole curve is loaded.
fn add_line_load(
    mesh: &Mesh,
    analysis: Analysis,
    nodes: [u32; 3],
    line_load: LineLoad,
    load: &mut [f64],
) {
    let x: Vec<[f64; 2]> = nodes.iter().map(|&n| mesh.nodes[n as usize]).collect();
    for &(xi, w) in &GAUSS3 {
        let (n, dn) = line3(xi);
        let (mut px, mut dx, mut dy) = (0.0, 0.0, 0.0);
        for i in 0..3 {
            px += n[i] * x[i][0];
            dx += dn[i] * x[i][0];
            dy += dn[i] * x[i][1];
        }
        // Tangent (dx, dy) runs counter-clockwise around the body, so (dy, −dx) is the
        // outward normal scaled by ds/dξ.
        let ds = || (dx * dx + dy * dy).sqrt();
        let t = match line_load {
            LineLoad::Pressure(p) => [-p * dy, p * dx, 0.0],
            LineLoad::Traction([tx, ty, tt]) => [tx, ty, tt].map(|c| c * ds()),
            LineLoad::Torque(_) => [0.0, 0.0, px * ds()],
        };
        let m = w * analysis.measure(px);
        let d = analysis.dofs_per_node();
        for i in 0..3 {
            let dof = d * nodes[i] as usize;
            for c in 0..d {
                load[dof + c] += n[i] * t[c] * m;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The `[steps]` amplitude as it was evaluated before analysis steps existed: knot
    /// `factors[j − 1]` at τ = j, linear in between, clamped.
    fn linear_in_steps(factors: &[f64], time: f64) -> f64 {
        let knot = |j: usize| if j == 0 { 0.0 } else { factors[j - 1] };
        let time = time.clamp(0.0, factors.len() as f64);
        let j = (time.ceil() as usize).max(1);
        let theta = time - (j - 1) as f64;
        knot(j - 1) + theta * (knot(j) - knot(j - 1))
    }

    #[test]
    fn a_steps_schedule_evaluates_bit_for_bit_as_the_linear_factors() {
        let factors = [0.1, 0.7, 1.0 / 3.0, -0.2, 0.0];
        let s = Schedule::new(factors.to_vec());
        for k in 0..=600 {
            let time = -0.5 + k as f64 / 97.0;
            let (a, b) = (s.value(0, time), linear_in_steps(&factors, time));
            assert_eq!(a.to_bits(), b.to_bits(), "τ = {time}");
        }
        assert_eq!(s.load_factor(3), 1.0 / 3.0);
        // No breakpoint lies inside a step of a [steps] schedule: sub-increments are halves.
        assert_eq!(s.next_time(1.0, 0.5, 2.0), 1.5);
        assert_eq!(s.next_time(1.5, 1.0, 2.0), 2.0);
    }

    #[test]
    fn sub_increments_end_on_the_breakpoints_of_every_cycle() {
        // One step of 2 increments per cycle, 3 cycles; breakpoints at step time 0.3 and 0.8
        // (u = 0.6 and 1.6).
        let timeline = Timeline::new(vec![StepPlan::new("s".into(), 2, 3, 1)]);
        let mut s = Schedule::with_steps(timeline);
        let table = Table::new(vec![0.0, 0.6, 1.6, 2.0], vec![0.0, 1.0, -1.0, 0.0]);
        s.add(&History::Own {
            column: "factor_load_x".into(),
            tables: vec![table],
        });
        // Second cycle (τ from 2 to 4): the first increment ends on the breakpoint 2.6.
        assert_eq!(s.next_time(2.0, 1.0, 3.0), 2.6);
        assert_eq!(s.next_time(2.6, 2.0, 3.0), 3.0);
        assert!((s.next_time(3.0, 1.0, 4.0) - 3.6).abs() < 1e-15);
        // The values at the breakpoints (up to the round-off of τ − cycle start), and the
        // ramps between them.
        assert!((s.value(1, 2.6) - 1.0).abs() < 1e-15);
        assert!((s.value(1, 4.8) - (1.0 - 2.0 * 0.2)).abs() < 1e-15);
        assert_eq!(s.value(1, 6.0), 0.0);
        assert_eq!(s.load_factor(3), 0.5);
    }
}
