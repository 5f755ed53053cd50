//! The columns of `history.csv`: one row per output frame with the load factors, the solver's
//! counters, the reactions, the contact resultants, the requested quantities, where the frame
//! lies in the load history, the energy balance, the prescribed displacements of the driven
//! supports and per contact pair its stick, slip and open extent and its dissipation. Supports,
//! loads and pairs are named by the user's `name` (their group where they have none), as in
//! `summary.json` and the log.

use std::io::BufRead;
use std::path::Path;

use crate::config::Case;
use crate::model::Model;
use crate::output::summary::{ContactResultant, Displacement, Force, Named, StepSummary};
use crate::post::quantities::PairQuantities;
use crate::solver::state::StepResult;
use crate::{Error, Result};

/// The columns of `history.csv` before the reactions: where each value of a row is, so that
/// a resumed run can read the summary's step records back from the file.
pub(super) struct HistoryLayout {
    /// Per-load factors: the amplitude of each support and load that has its own history.
    load_factors: Vec<usize>,
    supports: usize,
    pairs: usize,
    /// The prescribed components of the driven supports: (support, component).
    driven: Vec<(usize, usize)>,
    /// Index of the first per-pair quantity ([`PAIR_QUANTITIES`]).
    pair_start: usize,
    /// Values of a row.
    columns: usize,
}

/// Trailing columns per contact pair, `<pair>_<quantity>`: the extent of its sticking,
/// slipping and open parts (`_length` in mm along side B in a plane analysis, `_area` in mm²
/// in axisymmetry), the friction it dissipated since the start and since the previous row
/// (N·mm).
const PAIR_QUANTITIES: [&str; 5] = [
    "stick",
    "slip",
    "open",
    "dissipation",
    "dissipation_increment",
];

/// Leading columns: step, time, load_factor, then the per-load factors, then these.
const COUNTERS: [&str; 4] = ["increments", "cutbacks", "iterations", "residual"];

/// Trailing columns: where the frame lies in the load history
/// ([`crate::model::timeline::Frame`]).
const FRAME_COLUMNS: [&str; 4] = ["analysis_step", "cycle", "cycles", "step_time"];
/// Trailing columns: the energy balance of the run so far (N·mm; see the README).
const ENERGY_COLUMNS: [&str; 4] = [
    "external_work",
    "stored_energy",
    "dissipation",
    "energy_imbalance",
];

impl HistoryLayout {
    pub(super) fn new(case: &Case, model: &Model) -> (Self, Vec<String>) {
        let mut columns: Vec<String> = ["step", "time", "load_factor"].map(String::from).into();
        let mut load_factors = Vec::new();
        for (column, amplitude) in model.schedule.columns() {
            columns.push(column.clone());
            load_factors.push(*amplitude);
        }
        columns.extend(COUNTERS.map(String::from));
        for s in &model.supports {
            columns.push(format!("reaction_{}_x", s.name));
            columns.push(format!("reaction_{}_y", s.name));
        }
        for p in &model.interface.pairs {
            for quantity in [
                "normal_force",
                "tangential_force",
                "force_on_b_x",
                "force_on_b_y",
            ] {
                columns.push(format!("{}_{quantity}", p.name));
            }
        }
        columns.extend(case.history.iter().map(|q| q.name.clone()));
        columns.extend(FRAME_COLUMNS.map(String::from));
        columns.extend(ENERGY_COLUMNS.map(String::from));
        let mut driven = Vec::new();
        for (i, s) in model.supports.iter().enumerate() {
            for (c, value) in s.values.iter().enumerate() {
                if s.is_driven() && value.is_some() {
                    columns.push(format!("displacement_{}_{}", s.name, ["x", "y"][c]));
                    driven.push((i, c));
                }
            }
        }
        let pair_start = columns.len();
        let extent = if model.analysis.is_axisymmetric() {
            "area"
        } else {
            "length"
        };
        for p in &model.interface.pairs {
            for quantity in PAIR_QUANTITIES {
                let unit = if quantity.contains("dissipation") {
                    String::new()
                } else {
                    format!("_{extent}")
                };
                columns.push(format!("{}_{quantity}{unit}", p.name));
            }
        }
        let layout = Self {
            load_factors,
            supports: model.supports.len(),
            pairs: model.interface.pairs.len(),
            driven,
            pair_start,
            columns: columns.len(),
        };
        (layout, columns)
    }

    /// Refuses a case whose `history.csv` would have two columns of one name: a
    /// `[[history]]` entry named like a column the table has anyway (`time`,
    /// `reaction_<support>_y`, ...) would be read in place of it by any reader that keys
    /// columns by name.
    pub(super) fn check_unique(case: &Case, model: &Model) -> Result<()> {
        let (_, columns) = Self::new(case, model);
        let mut seen = std::collections::BTreeSet::new();
        let Some(column) = columns.iter().find(|c| !seen.insert(c.as_str())) else {
            return Ok(());
        };
        let entry = case.history.iter().position(|q| &q.name == column);
        let message = match entry {
            Some(i) => format!(
                "history[{i}].name = {column:?}: history.csv has a column `{column}` already \
                 (docs/guide/outputs.md): give the entry another name"
            ),
            None => format!(
                "two columns of history.csv would be named `{column}`: rename a support, \
                 load or contact pair"
            ),
        };
        Err(Error::Case {
            path: case.path.clone(),
            message,
        })
    }

    /// Values of a row.
    pub(super) fn columns(&self) -> usize {
        self.columns
    }

    /// The friction pair `p` had dissipated at the row `row` (0 before the first row).
    pub(super) fn dissipation(&self, row: &[f64], p: usize) -> f64 {
        let column = self.pair_start + p * PAIR_QUANTITIES.len() + 3;
        row.get(column).copied().unwrap_or(0.0)
    }

    /// The row of a state at pseudo-time `time`; `pairs` holds per contact pair its
    /// [`PairQuantities`] and the friction dissipated since the previous row.
    pub(super) fn row(
        &self,
        model: &Model,
        step: &StepResult,
        time: f64,
        [reactions, resultants, requested]: [&[f64]; 3],
        pairs: &[(PairQuantities, f64)],
    ) -> Vec<f64> {
        let schedule = &model.schedule;
        let residual = *step.newton.residuals.last().unwrap_or(&0.0);
        let mut row = vec![step.step as f64, time, step.load_factor];
        row.extend(self.load_factors.iter().map(|&k| schedule.value(k, time)));
        row.extend([
            step.increments as f64,
            step.cutbacks as f64,
            step.newton.iterations as f64,
            residual,
        ]);
        row.extend(reactions);
        row.extend(resultants);
        row.extend(requested);
        let f = &step.frame;
        row.extend([
            f.analysis_step as f64,
            f.cycle as f64,
            f.cycles,
            f.step_time,
        ]);
        let energy = &step.solution.energy.total;
        row.extend([
            energy.external_work,
            energy.stored(),
            energy.dissipation(),
            energy.imbalance(),
        ]);
        row.extend(self.driven.iter().map(|&(i, c)| {
            let support = &model.supports[i];
            support.values[c].unwrap_or_default() * schedule.value(support.amplitude, time)
        }));
        for (q, increment) in pairs {
            row.extend([q.stick, q.slip, q.open, q.dissipation, *increment]);
        }
        row
    }

    /// The summary's record of the step whose history row is `row`.
    pub(super) fn step_summary(&self, model: &Model, row: &[f64]) -> StepSummary {
        let counters = 3 + self.load_factors.len();
        let [increments, cutbacks, iterations, residual] =
            std::array::from_fn(|i| row[counters + i]);
        let reactions = &row[counters + COUNTERS.len()..];
        let resultants = &reactions[2 * self.supports..2 * self.supports + 4 * self.pairs];
        let states = &row[self.pair_start..];
        StepSummary {
            step: row[0] as usize,
            load_factor: row[2],
            increments: increments as usize,
            cutbacks: cutbacks as usize,
            iterations: iterations as usize,
            residual,
            reactions: Named(
                model
                    .supports
                    .iter()
                    .zip(reactions.chunks_exact(2))
                    .map(|(s, r)| (s.name.clone(), Force { x: r[0], y: r[1] }))
                    .collect(),
            ),
            displacements: self.displacements(model, &row[self.pair_start - self.driven.len()..]),
            contact: Named(
                model
                    .interface
                    .pairs
                    .iter()
                    .zip(resultants.chunks_exact(4))
                    .zip(states.chunks_exact(PAIR_QUANTITIES.len()))
                    .map(|((p, r), q)| {
                        let resultant = ContactResultant {
                            normal_force: r[0],
                            tangential_force: r[1],
                            force_on_b_x: r[2],
                            force_on_b_y: r[3],
                            stick: q[0],
                            slip: q[1],
                            open: q[2],
                            dissipation: q[3],
                            dissipation_increment: q[4],
                        };
                        (p.name.clone(), resultant)
                    })
                    .collect(),
            ),
        }
    }
}

impl HistoryLayout {
    /// The prescribed displacements of the driven supports, from their `values` in the
    /// order of [`Self::driven`].
    fn displacements(&self, model: &Model, values: &[f64]) -> Named<Displacement> {
        let mut out: Vec<(String, Displacement)> = Vec::new();
        for (&(i, c), &v) in self.driven.iter().zip(values) {
            let name = &model.supports[i].name;
            if out.last().is_none_or(|(last, _)| last != name) {
                out.push((name.clone(), Displacement::default()));
            }
            let d = &mut out.last_mut().expect("pushed above").1;
            *[&mut d.x, &mut d.y][c] = Some(v);
        }
        Named(out)
    }
}

/// Calls `row` with every row of the `history.csv` at `path` (whose rows have `columns`
/// values), in order, without holding the file in memory. The numbers are read back bit for
/// bit (the file has them in their shortest round-trip form). A line that is not such a row
/// is an [`Error::Restart`] naming the file: only a resumed run reads the file back.
pub(super) fn read_rows(path: &Path, columns: usize, mut row: impl FnMut(&[f64])) -> Result<()> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut values = Vec::with_capacity(columns);
    for (i, line) in std::io::BufReader::new(file).lines().enumerate().skip(1) {
        let line = line.map_err(|e| Error::io(path, e))?;
        values.clear();
        values.extend(line.split(',').map(|c| c.parse().unwrap_or(f64::NAN)));
        if values.len() != columns || values.iter().any(|v| v.is_nan()) {
            return Err(Error::Restart {
                path: path.to_path_buf(),
                reason: format!("line {} is not a row of {columns} numbers", i + 1),
            });
        }
        row(&values);
    }
    Ok(())
}
