//! The columns of `history.csv`: one row per output frame with the load factors, the solver's
//! counters, the reactions, the contact resultants, the requested quantities, where the frame
//! lies in the load history and the energy balance.

use std::io::BufRead;
use std::path::Path;

use crate::config::Case;
use crate::model::{Model, Schedule};
use crate::output::summary::{ContactResultant, Force, Named, StepSummary};
use crate::solver::state::StepResult;
use crate::{Error, Result};

/// The columns of `history.csv` before the reactions: where each value of a row is, so that
/// a resumed run can read the summary's step records back from the file.
pub(super) struct HistoryLayout {
    /// Per-load factors: the amplitude of each support and load that has its own history.
    load_factors: Vec<usize>,
    supports: usize,
    pairs: usize,
    /// Values of a row.
    columns: usize,
}

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
        let layout = Self {
            load_factors,
            supports: model.supports.len(),
            pairs: model.interface.pairs.len(),
            columns: columns.len(),
        };
        (layout, columns)
    }

    /// Values of a row.
    pub(super) fn columns(&self) -> usize {
        self.columns
    }

    /// The row of a state at pseudo-time `time`.
    pub(super) fn row(
        &self,
        schedule: &Schedule,
        step: &StepResult,
        time: f64,
        [reactions, resultants, requested]: [&[f64]; 3],
    ) -> Vec<f64> {
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
        row
    }

    /// The summary's record of the step whose history row is `row`.
    pub(super) fn step_summary(&self, model: &Model, row: &[f64]) -> StepSummary {
        let counters = 3 + self.load_factors.len();
        let [increments, cutbacks, iterations, residual] =
            std::array::from_fn(|i| row[counters + i]);
        let reactions = &row[counters + COUNTERS.len()..];
        let resultants = &reactions[2 * self.supports..2 * self.supports + 4 * self.pairs];
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
            contact: Named(
                model
                    .interface
                    .pairs
                    .iter()
                    .zip(resultants.chunks_exact(4))
                    .map(|(p, r)| {
                        let resultant = ContactResultant {
                            normal_force: r[0],
                            tangential_force: r[1],
                            force_on_b_x: r[2],
                            force_on_b_y: r[3],
                        };
                        (p.name.clone(), resultant)
                    })
                    .collect(),
            ),
        }
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
