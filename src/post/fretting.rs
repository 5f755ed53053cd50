//! The per-contact fretting tables of a run: the hysteresis loop of each pair (one row per
//! output frame), the results of every simulated load cycle (one row per cycle and pair), and
//! the wear-depth profile of each pair that wears at every cycle end, and the local loops of the
//! points a case traces (`hysteresis_points`), written as `hysteresis_<pair>.csv`,
//! `point_loops_<pair>.csv`, `cycles.csv` and `wear_<pair>.csv`. Each table is formatted row
//! by row as the frames come and handed to the writer to append ([`GrowingCsv`]): no row is
//! kept once handed over, so that memory does not grow with the frames.

use crate::contact::{CIRCUMFERENTIAL, ContactStatus, InterfaceState};
use crate::element::interface6::{chord_length, interface_point};
use crate::element::set::INTERFACE_POINTS;
use crate::model::Model;

use crate::Result;
use crate::output::csv::{Cell, GrowingCsv};
use crate::post::interface::{InterfaceOutput, torques};
use crate::solver::state::StepResult;

/// A fretting table of a run; the output folder names its file
/// ([`crate::run::folder::RunFile::Fretting`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrettingTable<'a> {
    /// The hysteresis loop of the pair of this name.
    Hysteresis(&'a str),
    /// The local loops of the traced points of the pair of this name.
    PointLoops(&'a str),
    /// The results of every simulated load cycle, all pairs.
    Cycles,
    /// The wear-depth profile of the pair of this name.
    Wear(&'a str),
}

/// What names a table's rows in an error about a value that is not finite.
fn table_label(table: &str, pair: &str) -> std::path::PathBuf {
    format!("{table} table of contact '{pair}'").into()
}

/// An empty table of `columns`, followed by `twist_columns` when `twist`.
fn growing(columns: &[&str], twist_columns: &[&str], twist: bool) -> GrowingCsv {
    let extra = if twist { twist_columns } else { &[] };
    let columns: Vec<String> = columns.iter().chain(extra).map(|c| c.to_string()).collect();
    GrowingCsv::new(&columns)
}

/// Columns of `hysteresis_<pair>.csv`: the frame (pseudo-time of the output), where it lies
/// in the load history, the pair's tangential force ∫ p_T dA and normal force ∫ |p_N| dA (N,
/// totals over the circle in axisymmetry) and the area-weighted mean tangential relative
/// displacement u_T of its closed points (mm).
pub const HYSTERESIS: [&str; 8] = [
    "frame",
    "analysis_step",
    "cycle",
    "cycles",
    "step_time",
    "tangential_force",
    "normal_force",
    "relative_slip",
];

/// Columns `hysteresis_<pair>.csv` appends with twist: the pair's circumferential force
/// ∫ p_θ dA (N), the area-weighted mean circumferential relative displacement u_θ of its
/// closed points (mm) and the torque it transmits (N·mm, [`crate::post::interface::torques`]):
/// torque against the twist is the torsional fretting loop.
pub const HYSTERESIS_TWIST: [&str; 3] = ["tangential_force_theta", "relative_slip_theta", "torque"];

/// Columns of `point_loops_<pair>.csv`: per output frame and traced point (numbered
/// from 1 in the order of the case's `hysteresis_points`) where the frame lies in the load
/// history as in [`HYSTERESIS`], the point's position (side B, mm), its contact stresses
/// p_T and p_N (MPa, p_N < 0 in compression), its tangential relative displacement u_T and
/// its plastic slip u_T^p (mm): p_T against u_T is the point's local fretting loop.
pub const POINT_LOOPS: [&str; 12] = [
    "frame",
    "analysis_step",
    "cycle",
    "cycles",
    "step_time",
    "point",
    "x",
    "y",
    "shear_stress",
    "normal_stress",
    "tangential_displacement",
    "plastic_slip",
];

/// Columns `point_loops_<pair>.csv` appends with twist: p_θ (MPa), u_θ and u_θ^p (mm).
pub const POINT_LOOPS_TWIST: [&str; 3] = [
    "shear_stress_theta",
    "tangential_displacement_theta",
    "plastic_slip_theta",
];

/// An interface integration point whose local loop is traced: its index into the interface
/// states and its position (side B, mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TracedPoint {
    pub state: usize,
    pub position: [f64; 2],
}

/// Why a wanted point cannot be traced: it lies `distance` (mm) from the nearest integration
/// point of its pair, at `nearest`, farther than that point's element length `length`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OffContact {
    pub distance: f64,
    pub nearest: [f64; 2],
    pub length: f64,
}

/// The integration point of pair `pair` of `model` nearest to `wanted` (mm), which must lie
/// within one element length of it (a point on the contact curve always does).
pub fn trace_point(
    model: &Model,
    pair: usize,
    wanted: [f64; 2],
) -> std::result::Result<TracedPoint, OffContact> {
    let interface = &model.interface;
    let mut best = (f64::INFINITY, 0, [0.0; 2], 0.0);
    for e in interface.pairs[pair].elements.clone() {
        let length = chord_length(&interface.elements[e].b_coords);
        for g in 0..INTERFACE_POINTS {
            let x = interface.point_position(e, g);
            let distance = (x[0] - wanted[0]).hypot(x[1] - wanted[1]);
            if distance < best.0 {
                best = (distance, e * INTERFACE_POINTS + g, x, length);
            }
        }
    }
    let (distance, state, position, length) = best;
    if distance <= length {
        Ok(TracedPoint { state, position })
    } else {
        Err(OffContact {
            distance,
            nearest: position,
            length,
        })
    }
}

/// Columns of `cycles.csv`: per simulated cycle and pair, the friction work of the cycle
/// ∫ (dissipation of the cycle) dA (N·mm), the friction work of the re-equilibrium after its
/// wear jump (N·mm: the bodies re-seat on the worn faces, a slip spread over the jumped
/// cycles in reality; 0 without a jump), the worn volume ∫ (h_A + h_B) dA (mm³, with 2πr in
/// axisymmetry) and the largest depth (mm) after the cycle (and its jump), and the largest
/// share of the stability limit the jump added at a point (0 without a jump; at most 1).
pub const CYCLES: [&str; 9] = [
    "analysis_step",
    "cycle",
    "cycles",
    "contact",
    "dissipation",
    "settling_dissipation",
    "worn_volume",
    "max_wear_depth",
    "jump_limit_share",
];

/// The columns `cycles.csv` adds per body when some body can flow plastically
/// ([`crate::solver::shakedown::BodyCycle`]): `<body>_plastic_dissipation` (N·mm),
/// `<body>_ratchet_strain` (the largest net equivalent plastic strain change of the cycle
/// at a point), `<body>_plastic_strain_increment` (the largest increase of ε̄ᵖ over the
/// cycle at a point) and, in a cyclic step, `<body>_verdict` (the shakedown verdict the
/// step would get if it ended with this cycle, [`crate::solver::shakedown::Readings`]). A
/// model without contact pairs has one row per cycle, with the `contact` columns empty.
pub const BODY_CYCLE_COLUMNS: [&str; 4] = [
    "plastic_dissipation",
    "ratchet_strain",
    "plastic_strain_increment",
    "verdict",
];

/// Columns of `wear_<pair>.csv`: the profile along side A at each cycle end.
pub const WEAR: [&str; 8] = [
    "analysis_step",
    "cycles",
    "s",
    "x",
    "y",
    "wear_a",
    "wear_b",
    "wear_depth",
];

/// Integrals over one pair's points.
#[derive(Clone, Copy, Debug, Default)]
struct PairSums {
    tangential_force: f64,
    normal_force: f64,
    closed_area: f64,
    slip_area: f64,
    tangential_force_theta: f64,
    slip_area_theta: f64,
    cycle_dissipation: f64,
    settling_dissipation: f64,
    worn_volume: f64,
    max_depth: f64,
}

/// The integrals of every pair at a state whose cycle (if it just ended) stood for `jump`
/// cycles.
fn pair_sums(model: &Model, states: &[InterfaceState], jump: f64) -> Vec<PairSums> {
    let mut out = vec![PairSums::default(); model.interface.pairs.len()];
    for (e, element) in model.interface.elements.iter().enumerate() {
        let sums = &mut out[element.pair as usize];
        for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
            let da = interface_point(&model.analysis, &element.b_coords, xi, w).da;
            let s = &states[e * INTERFACE_POINTS + g];
            sums.tangential_force += s.stress[0] * da;
            sums.normal_force -= s.stress[1] * da;
            sums.tangential_force_theta += s.stress[CIRCUMFERENTIAL] * da;
            if s.status != ContactStatus::Open {
                sums.closed_area += da;
                sums.slip_area += s.relative[0] * da;
                sums.slip_area_theta += s.relative[CIRCUMFERENTIAL] * da;
            }
            let h = &s.history;
            sums.cycle_dissipation += h.last_cycle_dissipation * da;
            // What the point dissipated since its cycle started beyond the cycle's own
            // dissipation extrapolated over the jump: the re-equilibrium after the jump.
            let settling =
                h.dissipation - h.cycle_start_dissipation - jump * h.last_cycle_dissipation;
            sums.settling_dissipation += settling * da;
            sums.worn_volume += s.history.depth() * da;
            sums.max_depth = sums.max_depth.max(s.history.depth());
        }
    }
    out
}

/// The fretting tables of a run: the rows not yet handed to the writer.
#[derive(Clone, Debug)]
pub struct FrettingTables {
    /// [`HYSTERESIS`] per pair.
    hysteresis: Vec<GrowingCsv>,
    /// [`CYCLES`], all pairs, and [`BODY_CYCLE_COLUMNS`] per body when `bodies`.
    cycles: GrowingCsv,
    /// Whether `cycles.csv` has the bodies' columns (some body can flow plastically).
    bodies: bool,
    /// [`WEAR`] per pair (`None` for pairs that do not wear).
    wear: Vec<Option<GrowingCsv>>,
    /// The traced points of each pair and their table of [`POINT_LOOPS`] (`None` for a pair
    /// without traced points).
    traced: Vec<Vec<TracedPoint>>,
    points: Vec<Option<GrowingCsv>>,
    /// Whether the model has twist: the tables' circumferential columns.
    twist: bool,
}

impl FrettingTables {
    /// Empty tables for the pairs of `model`.
    pub fn new(model: &Model) -> Self {
        let pairs = &model.interface.pairs;
        let twist = model.analysis.has_twist();
        let bodies = model.continuum.materials.iter().any(|m| !m.is_linear());
        let mut cycles: Vec<String> = CYCLES.iter().map(|c| c.to_string()).collect();
        if bodies {
            for body in &model.bodies {
                cycles.extend(BODY_CYCLE_COLUMNS.iter().map(|c| format!("{body}_{c}")));
            }
        }
        Self {
            hysteresis: pairs
                .iter()
                .map(|_| growing(&HYSTERESIS, &HYSTERESIS_TWIST, twist))
                .collect(),
            cycles: GrowingCsv::new(&cycles),
            bodies,
            wear: pairs
                .iter()
                .map(|p| p.wear().map(|_| growing(&WEAR, &[], false)))
                .collect(),
            traced: vec![Vec::new(); pairs.len()],
            points: vec![None; pairs.len()],
            twist,
        }
    }

    /// The tables with the local loops of `traced` points, per pair (in the model's order).
    pub fn with_points(mut self, traced: Vec<Vec<TracedPoint>>) -> Self {
        debug_assert_eq!(traced.len(), self.traced.len());
        let twist = self.twist;
        self.points = traced
            .iter()
            .map(|t| (!t.is_empty()).then(|| growing(&POINT_LOOPS, &POINT_LOOPS_TWIST, twist)))
            .collect();
        self.traced = traced;
        self
    }

    /// Adds the rows of output frame `step` at pseudo-time `time`: a hysteresis row per
    /// pair, and at the end of a cycle (`step.frame.cycle_end`) a cycle row per pair and the
    /// wear profile of each pair that wears. Fails, naming the table, on a value that is not
    /// finite.
    pub fn record(
        &mut self,
        model: &Model,
        interface: &InterfaceOutput,
        step: &StepResult,
        time: f64,
    ) -> Result<()> {
        let frame = step.frame;
        let jump = model.schedule.timeline().ends_cycle(step.step).unwrap_or(1);
        let sums = pair_sums(model, &step.solution.interface_committed, jump as f64);
        let position = [frame.analysis_step as f64, frame.cycle as f64, frame.cycles];
        let pairs = &model.interface.pairs;
        let twist = model.analysis.has_twist();
        let torque = if twist {
            torques(model, &step.solution.interface_committed)
        } else {
            Vec::new()
        };
        let mean = |sum: f64, area: f64| if area > 0.0 { sum / area } else { 0.0 };
        for (p, ((table, s), pair)) in self.hysteresis.iter_mut().zip(&sums).zip(pairs).enumerate()
        {
            let slip = mean(s.slip_area, s.closed_area);
            let mut row = vec![time];
            row.extend(position);
            row.extend([frame.step_time, s.tangential_force, s.normal_force, slip]);
            if twist {
                let slip_theta = mean(s.slip_area_theta, s.closed_area);
                row.extend([s.tangential_force_theta, slip_theta, torque[p]]);
            }
            table.push(&table_label("hysteresis", &pair.name), &row)?;
        }
        self.record_points(model, step, time)?;
        if !frame.cycle_end {
            return Ok(());
        }
        let body_cells: Vec<Cell> = if self.bodies {
            let cycles = &step.solution.internal.cycles;
            let timeline = model.schedule.timeline();
            let plan = timeline.steps().get(frame.analysis_step.wrapping_sub(1));
            let cyclic = plan.is_some_and(|p| p.is_cyclic());
            cycles
                .last
                .iter()
                .zip(&cycles.readings)
                .flat_map(|(c, readings)| {
                    [
                        Cell::Number(c.plastic_dissipation),
                        Cell::Number(c.ratchet_strain),
                        Cell::Number(c.plastic_strain_increment),
                        if cyclic {
                            Cell::Text(readings.verdict().into())
                        } else {
                            Cell::Empty
                        },
                    ]
                })
                .collect()
        } else {
            Vec::new()
        };
        for (p, (s, pair)) in sums.iter().zip(pairs).enumerate() {
            let mut row: Vec<Cell> = position.map(Cell::Number).to_vec();
            row.push(Cell::Text(pair.name.clone()));
            row.extend(
                [
                    s.cycle_dissipation,
                    s.settling_dissipation,
                    s.worn_volume,
                    s.max_depth,
                    step.solution.jump_use.get(p).copied().unwrap_or(0.0),
                ]
                .map(Cell::Number),
            );
            row.extend(body_cells.iter().cloned());
            self.cycles.push(&table_label("cycles", &pair.name), &row)?;
        }
        if pairs.is_empty() && self.bodies {
            let mut row: Vec<Cell> = position.map(Cell::Number).to_vec();
            row.extend(std::iter::repeat_n(Cell::Empty, 6));
            row.extend(body_cells);
            self.cycles
                .push(std::path::Path::new("cycles table"), &row)?;
        }
        for (p, (table, pair)) in self.wear.iter_mut().zip(pairs).enumerate() {
            let Some(table) = table else { continue };
            for v in interface.wear_profile(model, step.solution, p) {
                let mut row = vec![frame.analysis_step as f64, frame.cycles];
                row.extend(v);
                table.push(&table_label("wear", &pair.name), &row)?;
            }
        }
        Ok(())
    }

    /// The rows of the traced points of every pair at output frame `step` (pseudo-time
    /// `time`).
    fn record_points(&mut self, model: &Model, step: &StepResult, time: f64) -> Result<()> {
        let frame = step.frame;
        let pairs = self.traced.iter().zip(&model.interface.pairs);
        for (table, (traced, pair)) in self.points.iter_mut().zip(pairs) {
            let Some(table) = table else { continue };
            for (i, point) in traced.iter().enumerate() {
                let s = &step.solution.interface_committed[point.state];
                let mut row = vec![
                    time,
                    frame.analysis_step as f64,
                    frame.cycle as f64,
                    frame.cycles,
                    frame.step_time,
                    (i + 1) as f64,
                    point.position[0],
                    point.position[1],
                    s.stress[0],
                    s.stress[1],
                    s.relative[0],
                    s.plastic_slip[0],
                ];
                if model.analysis.has_twist() {
                    row.extend([
                        s.stress[CIRCUMFERENTIAL],
                        s.relative[CIRCUMFERENTIAL],
                        s.plastic_slip[1],
                    ]);
                }
                table.push(&table_label("point loops", &pair.name), &row)?;
            }
        }
        Ok(())
    }

    /// The tables' files of the pairs of `model` (the model the tables were made for), in
    /// order: the hysteresis loop of every pair, the local loops of each pair with traced
    /// points, `cycles.csv` (when the model has pairs) and the wear profile of each pair that
    /// wears; each with its rows not yet handed to the writer.
    pub fn files<'m>(&mut self, model: &'m Model) -> Vec<(FrettingTable<'m>, &mut GrowingCsv)> {
        let pairs = &model.interface.pairs;
        let hysteresis = pairs.iter().zip(&mut self.hysteresis);
        let mut out: Vec<(FrettingTable, &mut GrowingCsv)> = hysteresis
            .map(|(p, table)| (FrettingTable::Hysteresis(&p.name), table))
            .collect();
        let points = pairs.iter().zip(&mut self.points);
        out.extend(points.filter_map(|(p, table)| {
            table
                .as_mut()
                .map(|table| (FrettingTable::PointLoops(&p.name), table))
        }));
        if !pairs.is_empty() || self.bodies {
            out.push((FrettingTable::Cycles, &mut self.cycles));
        }
        let wear = pairs.iter().zip(&mut self.wear);
        out.extend(wear.filter_map(|(p, table)| {
            table
                .as_mut()
                .map(|table| (FrettingTable::Wear(&p.name), table))
        }));
        out
    }
}
