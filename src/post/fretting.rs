//! The per-contact fretting tables of a run: the hysteresis loop of each pair (one row per
//! output frame), the results of every simulated load cycle (one row per cycle and pair), and
//! the wear-depth profile of each pair that wears at every cycle end. They are kept as rows of
//! numbers (the restart record stores them like `history.csv`'s rows) and turned into CSV
//! tables for `hysteresis_<pair>.csv`, `cycles.csv` and `wear_<pair>.csv`, written for the
//! models where some pair wears.

use crate::contact::{ContactStatus, InterfaceState};
use crate::element::interface6::interface_point;
use crate::element::set::INTERFACE_POINTS;
use crate::model::Model;
use std::path::Path;

use crate::Result;
use crate::output::csv::{Cell, CsvTable, GrowingCsv};
use crate::output::restart::Content;
use crate::post::interface::InterfaceOutput;
use crate::solver::stepping::StepResult;

/// The cycle table's file name.
pub const CYCLES_FILE: &str = "cycles.csv";

/// The hysteresis table's file name of pair `pair`.
pub fn hysteresis_file(pair: &str) -> String {
    format!("hysteresis_{pair}.csv")
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

/// The wear-profile table's file name of pair `pair`.
pub fn wear_file(pair: &str) -> String {
    format!("wear_{pair}.csv")
}

/// Whether `name` is one of the fretting tables' files.
pub fn is_fretting_file(name: &str) -> bool {
    name == CYCLES_FILE
        || ["hysteresis_", "wear_"].iter().any(|p| {
            name.strip_prefix(p)
                .is_some_and(|r| r.len() > 4 && r.ends_with(".csv"))
        })
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

/// Columns of `cycles.csv`: per simulated cycle and pair, the friction work of the cycle
/// ∫ (dissipation of the cycle) dA (N·mm), the friction work of the re-equilibrium after its
/// wear jump (N·mm: the bodies re-seat on the worn faces, a slip spread over the jumped
/// cycles in reality; 0 without a jump), the worn volume ∫ (h_A + h_B) dA (mm³, with 2πr in
/// axisymmetry) and the largest depth (mm) after the cycle (and its jump).
pub const CYCLES: [&str; 8] = [
    "analysis_step",
    "cycle",
    "cycles",
    "contact",
    "dissipation",
    "settling_dissipation",
    "worn_volume",
    "max_wear_depth",
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
        }
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
            text.push(Path::new(&hysteresis_file(&pair.name)), &row)?;
            rows.push(row);
        }
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

    /// The rows for a restart record: the hysteresis tables, the cycle table, the wear
    /// tables.
    pub fn rows(&self) -> Vec<Vec<Vec<f64>>> {
        let mut out = self.hysteresis.clone();
        out.push(self.cycles.clone());
        out.extend(self.wear.iter().cloned());
        out
    }

    /// Takes over the rows of a restart record ([`Self::rows`]); `None` (nothing changed)
    /// when they do not fit the model's pairs and the tables' columns.
    pub fn restore(&mut self, mut rows: Vec<Vec<Vec<f64>>>) -> Option<()> {
        let pairs = self.hysteresis.len();
        if rows.len() != 2 * pairs + 1 {
            return None;
        }
        let wear = rows.split_off(pairs + 1);
        let cycles = rows.pop()?;
        let fits = |table: &[Vec<f64>], width: usize| table.iter().all(|r| r.len() == width);
        let ok = rows.iter().all(|t| fits(t, HYSTERESIS.len()))
            && fits(&cycles, CYCLES.len())
            && cycles.iter().all(|r| (r[CONTACT] as usize) < pairs)
            && wear.iter().all(|t| fits(t, WEAR.len()));
        if !ok {
            return None;
        }
        let mut texts = Vec::with_capacity(rows.len());
        for table in &rows {
            let mut text = hysteresis_csv();
            for row in table {
                text.push(Path::new("hysteresis"), row).ok()?;
            }
            texts.push(text);
        }
        self.hysteresis = rows;
        self.hysteresis_text = texts;
        self.cycles = cycles;
        self.wear = wear;
        Some(())
    }

    /// The tables' files: (file name, table) of every pair of `model`; a wear table only for
    /// a pair that wears.
    pub fn files(&self, model: &Model) -> Vec<(String, CsvTable<Cell>)> {
        let pairs = &model.interface.pairs;
        let hysteresis = pairs.iter().zip(&self.hysteresis);
        let mut out: Vec<(String, CsvTable<Cell>)> = hysteresis
            .map(|(p, rows)| (hysteresis_file(&p.name), cell_table(&HYSTERESIS, rows)))
            .collect();
        out.extend(self.cycle_files(model));
        out
    }

    /// [`Self::files`] as the writer takes them: the hysteresis tables as the text grown
    /// frame by frame, the per-cycle tables as tables.
    pub fn contents(&self, model: &Model) -> Vec<(String, Content)> {
        let pairs = &model.interface.pairs;
        let hysteresis = pairs.iter().zip(&self.hysteresis_text);
        let mut out: Vec<(String, Content)> = hysteresis
            .map(|(p, text)| {
                (
                    hysteresis_file(&p.name),
                    Content::Text(text.bytes().to_vec()),
                )
            })
            .collect();
        let cycle_files = self.cycle_files(model).into_iter();
        out.extend(cycle_files.map(|(name, table)| (name, Content::Table(table))));
        out
    }

    /// The per-cycle tables: `cycles.csv` (when the model has pairs) and the wear profile
    /// of each pair that wears.
    fn cycle_files(&self, model: &Model) -> Vec<(String, CsvTable<Cell>)> {
        let table = cell_table;
        let pairs = &model.interface.pairs;
        let mut out = Vec::new();
        if !pairs.is_empty() {
            let mut cycles = table(&CYCLES, &self.cycles);
            for (row, numbers) in cycles.rows.iter_mut().zip(&self.cycles) {
                row[CONTACT] = Cell::Text(pairs[numbers[CONTACT] as usize].name.clone());
            }
            out.push((CYCLES_FILE.to_string(), cycles));
        }
        for (p, rows) in pairs.iter().zip(&self.wear) {
            if p.wear().is_some() {
                out.push((wear_file(&p.name), table(&WEAR, rows)));
            }
        }
        out
    }
}
