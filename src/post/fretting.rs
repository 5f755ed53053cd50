//! The per-contact fretting tables of a run: the hysteresis loop of each pair (one row per
//! output frame), the results of every simulated load cycle (one row per cycle and pair), and
//! the wear-depth profile of each pair that wears at every cycle end, and the local loops of the
//! points a case traces (`hysteresis_points`). They are kept as rows of numbers (the restart
//! record stores them like `history.csv`'s rows) and turned into CSV tables for
//! `hysteresis_<pair>.csv`, `point_loops_<pair>.csv`, `cycles.csv` and
//! `wear_<pair>.csv`.

use crate::contact::{ContactStatus, InterfaceState};
use crate::element::interface6::{chord_length, interface_point};
use crate::element::set::{ContactPair, INTERFACE_POINTS};
use crate::model::Model;
use std::path::Path;

use crate::Result;
use crate::output::csv::{Cell, CsvTable, GrowingCsv};
use crate::output::writer::Content;
use crate::post::interface::InterfaceOutput;
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

/// A table of numbers as cells.
fn cell_table(columns: &[&str], rows: &[Vec<f64>]) -> CsvTable<Cell> {
    CsvTable {
        columns: columns.iter().map(|c| c.to_string()).collect(),
        rows: rows
            .iter()
            .map(|r| r.iter().map(|&v| Cell::Number(v)).collect())
            .collect(),
    }
}

/// An empty hysteresis table's text.
fn hysteresis_csv() -> GrowingCsv {
    GrowingCsv::new(&HYSTERESIS.map(String::from))
}

/// An empty table of traced points' text.
fn point_loops_csv() -> GrowingCsv {
    GrowingCsv::new(&POINT_LOOPS.map(String::from))
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

/// Index of `point` in [`POINT_LOOPS`].
const POINT: usize = 5;

/// Index of `contact` in [`CYCLES`] (kept as the pair's index in the rows).
const CONTACT: usize = 3;

/// Integrals over one pair's points.
#[derive(Clone, Copy, Debug, Default)]
struct PairSums {
    tangential_force: f64,
    normal_force: f64,
    closed_area: f64,
    slip_area: f64,
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
            if s.status != ContactStatus::Open {
                sums.closed_area += da;
                sums.slip_area += s.relative[0] * da;
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

/// The fretting tables of a run, as rows of numbers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrettingTables {
    /// Rows of [`HYSTERESIS`] per pair.
    hysteresis: Vec<Vec<Vec<f64>>>,
    /// The same rows as CSV text, grown row by row (the table is written after every frame).
    hysteresis_text: Vec<GrowingCsv>,
    /// Rows of [`CYCLES`] (the contact as its pair index).
    cycles: Vec<Vec<f64>>,
    /// Rows of [`WEAR`] per pair (empty for pairs that do not wear).
    wear: Vec<Vec<Vec<f64>>>,
    /// The traced points of each pair, their rows of [`POINT_LOOPS`] and those rows as
    /// CSV text.
    traced: Vec<Vec<TracedPoint>>,
    points: Vec<Vec<Vec<f64>>>,
    points_text: Vec<GrowingCsv>,
}

impl FrettingTables {
    /// Empty tables for the pairs of `model`.
    pub fn new(model: &Model) -> Self {
        let pairs = model.interface.pairs.len();
        Self {
            hysteresis: vec![Vec::new(); pairs],
            hysteresis_text: vec![hysteresis_csv(); pairs],
            cycles: Vec::new(),
            wear: vec![Vec::new(); pairs],
            traced: vec![Vec::new(); pairs],
            points: vec![Vec::new(); pairs],
            points_text: vec![point_loops_csv(); pairs],
        }
    }

    /// The tables with the local loops of `traced` points, per pair (in the model's order).
    pub fn with_points(mut self, traced: Vec<Vec<TracedPoint>>) -> Self {
        debug_assert_eq!(traced.len(), self.traced.len());
        self.traced = traced;
        self
    }

    /// Adds the rows of output frame `step` at pseudo-time `time`: a hysteresis row per
    /// pair, and at the end of a cycle (`step.frame.cycle_end`) a cycle row per pair and the
    /// wear profile of each pair that wears. Fails, naming the hysteresis file, on a value
    /// that is not finite.
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
        let tables = self.hysteresis.iter_mut().zip(&mut self.hysteresis_text);
        for (((rows, text), s), pair) in tables.zip(&sums).zip(&model.interface.pairs) {
            let slip = if s.closed_area > 0.0 {
                s.slip_area / s.closed_area
            } else {
                0.0
            };
            let mut row = vec![time];
            row.extend(position);
            row.extend([frame.step_time, s.tangential_force, s.normal_force, slip]);
            text.push(&table_label("hysteresis", &pair.name), &row)?;
            rows.push(row);
        }
        self.record_points(model, step, time)?;
        if !frame.cycle_end {
            return Ok(());
        }
        for (p, s) in sums.iter().enumerate() {
            let mut row = position.to_vec();
            row.extend([
                p as f64,
                s.cycle_dissipation,
                s.settling_dissipation,
                s.worn_volume,
                s.max_depth,
                step.solution.jump_use.get(p).copied().unwrap_or(0.0),
            ]);
            self.cycles.push(row);
        }
        for (p, pair) in model.interface.pairs.iter().enumerate() {
            if pair.wear().is_none() {
                continue;
            }
            let profile = interface.wear_profile(model, step.solution, p);
            self.wear[p].extend(profile.into_iter().map(|v| {
                let mut row = vec![frame.analysis_step as f64, frame.cycles];
                row.extend(v);
                row
            }));
        }
        Ok(())
    }

    /// The rows of the traced points of every pair at output frame `step` (pseudo-time
    /// `time`).
    fn record_points(&mut self, model: &Model, step: &StepResult, time: f64) -> Result<()> {
        let frame = step.frame;
        let tables = self.points.iter_mut().zip(&mut self.points_text);
        for ((rows, text), (traced, pair)) in
            tables.zip(self.traced.iter().zip(&model.interface.pairs))
        {
            for (i, point) in traced.iter().enumerate() {
                let s = &step.solution.interface_committed[point.state];
                let row = vec![
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
                    s.plastic_slip,
                ];
                text.push(&table_label("point loops", &pair.name), &row)?;
                rows.push(row);
            }
        }
        Ok(())
    }

    /// The tables of a restart record, in order: the hysteresis tables, the cycle table, the
    /// wear tables, the traced points' tables.
    pub fn tables(&self) -> impl Iterator<Item = &[Vec<f64>]> {
        let hysteresis = self.hysteresis.iter().map(Vec::as_slice);
        let wear = self.wear.iter().map(Vec::as_slice);
        let points = self.points.iter().map(Vec::as_slice);
        hysteresis
            .chain(std::iter::once(self.cycles.as_slice()))
            .chain(wear)
            .chain(points)
    }

    /// [`Self::tables`] as owned rows (what a record gives back).
    pub fn rows(&self) -> Vec<Vec<Vec<f64>>> {
        self.tables().map(<[Vec<f64>]>::to_vec).collect()
    }

    /// Takes over the rows of a restart record ([`Self::rows`]); `None` (nothing changed)
    /// when they do not fit the model's pairs and the tables' columns.
    pub fn restore(&mut self, mut rows: Vec<Vec<Vec<f64>>>) -> Option<()> {
        let pairs = self.hysteresis.len();
        if rows.len() != 3 * pairs + 1 {
            return None;
        }
        let points = rows.split_off(2 * pairs + 1);
        let wear = rows.split_off(pairs + 1);
        let cycles = rows.pop()?;
        let fits = |table: &[Vec<f64>], width: usize| table.iter().all(|r| r.len() == width);
        // Each frame adds one row per traced point, numbered 1..n.
        let traced_fit =
            points
                .iter()
                .zip(&rows)
                .zip(&self.traced)
                .all(|((table, loop_rows), traced)| {
                    fits(table, POINT_LOOPS.len())
                        && table.len() == traced.len() * loop_rows.len()
                        && table
                            .iter()
                            .enumerate()
                            .all(|(i, r)| r[POINT] == (i % traced.len().max(1) + 1) as f64)
                });
        let ok = rows.iter().all(|t| fits(t, HYSTERESIS.len()))
            && fits(&cycles, CYCLES.len())
            && cycles.iter().all(|r| (r[CONTACT] as usize) < pairs)
            && wear.iter().all(|t| fits(t, WEAR.len()))
            && traced_fit;
        if !ok {
            return None;
        }
        let hysteresis_text = grown(&rows, hysteresis_csv)?;
        let points_text = grown(&points, point_loops_csv)?;
        self.hysteresis_text = hysteresis_text;
        self.points_text = points_text;
        self.hysteresis = rows;
        self.cycles = cycles;
        self.wear = wear;
        self.points = points;
        Some(())
    }

    /// The tables' files: (file name, table) of every pair of `model`; a wear table only for
    /// a pair that wears.
    pub fn files<'m>(&self, model: &'m Model) -> Vec<(FrettingTable<'m>, CsvTable<Cell>)> {
        let pairs = &model.interface.pairs;
        let hysteresis = pairs.iter().zip(&self.hysteresis);
        let mut out: Vec<(FrettingTable, CsvTable<Cell>)> = hysteresis
            .map(|(p, rows)| {
                let table = cell_table(&HYSTERESIS, rows);
                (FrettingTable::Hysteresis(&p.name), table)
            })
            .collect();
        let points = self.traced_pairs(model).map(|(p, rows, _)| {
            let table = cell_table(&POINT_LOOPS, rows);
            (FrettingTable::PointLoops(&p.name), table)
        });
        out.extend(points.collect::<Vec<_>>());
        out.extend(self.cycle_files(model));
        out
    }

    /// The pairs with traced points, with their rows and text.
    fn traced_pairs<'a, 'm>(
        &'a self,
        model: &'m Model,
    ) -> impl Iterator<Item = (&'m ContactPair, &'a Vec<Vec<f64>>, &'a GrowingCsv)> {
        let tables = self.points.iter().zip(&self.points_text);
        let pairs = model.interface.pairs.iter().zip(&self.traced);
        pairs
            .zip(tables)
            .filter(|((_, traced), _)| !traced.is_empty())
            .map(|((pair, _), (rows, text))| (pair, rows, text))
    }

    /// [`Self::files`] as the writer takes them: the hysteresis tables as the text grown
    /// frame by frame, the per-cycle tables as tables.
    pub fn contents<'m>(&self, model: &'m Model) -> Vec<(FrettingTable<'m>, Content)> {
        let pairs = &model.interface.pairs;
        let hysteresis = pairs.iter().zip(&self.hysteresis_text);
        let mut out: Vec<(FrettingTable, Content)> = hysteresis
            .map(|(p, text)| {
                let content = Content::Text(text.bytes().to_vec());
                (FrettingTable::Hysteresis(&p.name), content)
            })
            .collect();
        out.extend(self.traced_pairs(model).map(|(p, _, text)| {
            let content = Content::Text(text.bytes().to_vec());
            (FrettingTable::PointLoops(&p.name), content)
        }));
        let cycle_files = self.cycle_files(model).into_iter();
        out.extend(cycle_files.map(|(name, table)| (name, Content::Table(table))));
        out
    }

    /// The per-cycle tables: `cycles.csv` (when the model has pairs) and the wear profile
    /// of each pair that wears.
    fn cycle_files<'m>(&self, model: &'m Model) -> Vec<(FrettingTable<'m>, CsvTable<Cell>)> {
        let table = cell_table;
        let pairs = &model.interface.pairs;
        let mut out = Vec::new();
        if !pairs.is_empty() {
            let mut cycles = table(&CYCLES, &self.cycles);
            for (row, numbers) in cycles.rows.iter_mut().zip(&self.cycles) {
                row[CONTACT] = Cell::Text(pairs[numbers[CONTACT] as usize].name.clone());
            }
            out.push((FrettingTable::Cycles, cycles));
        }
        for (p, rows) in pairs.iter().zip(&self.wear) {
            if p.wear().is_some() {
                out.push((FrettingTable::Wear(&p.name), table(&WEAR, rows)));
            }
        }
        out
    }
}

/// The CSV texts of `tables`, grown row by row from `empty()`; `None` on a value that is not
/// finite.
fn grown(tables: &[Vec<Vec<f64>>], empty: fn() -> GrowingCsv) -> Option<Vec<GrowingCsv>> {
    tables
        .iter()
        .map(|table| {
            let mut text = empty();
            for row in table {
                text.push(Path::new("restart record"), row).ok()?;
            }
            Some(text)
        })
        .collect()
}
