//! The files of every converged step: [`StepWriter`] queues a step's VTU and CSV files, its
//! restart record, the growing tables and the indexes on the background writer, in the order
//! that keeps the folder consistent at every moment (see [`crate::run`]).

use std::time::Instant;

use super::Session;
use super::folder::{OutputFolder, RunFile};
use super::history::HistoryLayout;
use super::progress::{RunBar, progress_bar};
use crate::config::{Case, CycleFrames};
use crate::model::Model;
use crate::output::csv::{CsvTable, GrowingCsv};
use crate::output::pvd::PvdEntry;
use crate::output::restart::{OutputView, Record};
use crate::output::summary::{EnergyMark, Summary};
use crate::output::writer::{Content, RecordWriter};
use crate::post::fretting::{FrettingTables, TracedPoint, trace_point};
use crate::post::interface::{InterfaceOutput, resultants};
use crate::post::quantities::evaluate;
use crate::post::{BodyPoints, StepInfo, reactions, step_grids};
use crate::solver::newton::NewtonLog;
use crate::solver::state::{Observer, Progress, Resume, Solution, StepResult};
use crate::{Error, Result};

/// Writes the files of each converged step and the restart record of each converged
/// increment, keeps the series and history up to date, and records the steps in the
/// summary.
pub(super) struct StepWriter<'m, 's, F> {
    case: &'m Case,
    model: &'m Model,
    points: BodyPoints,
    interface: InterfaceOutput,
    folder: &'m OutputFolder,
    /// The contact pairs' names (part of file names).
    pairs: Vec<String>,
    vtu: bool,
    /// Field output at every frame of a cyclic step (`[output] cycle_frames = "all"`).
    all_frames: bool,
    /// The case's text when restart records are kept.
    case_text: Option<&'m str>,
    layout: HistoryLayout,
    series: Vec<PvdEntry>,
    history: CsvTable,
    /// `history.csv`'s text, grown with `history` (see [`GrowingCsv`]).
    history_text: GrowingCsv,
    fretting: FrettingTables,
    pub(super) summary: &'s mut Summary,
    pub(super) last_reactions: Vec<[f64; 2]>,
    pub(super) bar: RunBar,
    /// Writes the files in the background, in the order they are queued.
    records: RecordWriter,
    /// Seconds spent on the records of sub-increments since the last step, counted with
    /// that step's output time.
    increment_seconds: f64,
    on_step: F,
}

/// The interface points whose local loops the contacts of `case` trace (`hysteresis_points`),
/// per pair of `model`: the integration point nearest to each given point, which must lie
/// within one element length of it.
pub(super) fn traced_points(case: &Case, model: &Model) -> Result<Vec<Vec<TracedPoint>>> {
    let contacts = case.contacts.iter().enumerate();
    contacts
        .map(|(j, contact)| {
            let points = contact.hysteresis_points.iter().enumerate();
            points
                .map(|(k, &wanted)| {
                    trace_point(model, j, wanted).map_err(|off| {
                        case.invalid(
                            format!("contact[{j}].hysteresis_points[{k}]"),
                            format!("[{}, {}]", wanted[0], wanted[1]),
                            format!(
                                "the point lies {:.4} mm from the nearest point of contact '{}' \
                                 (at ({:.4}, {:.4})), farther than that element's length \
                                 {:.4} mm: give a point on the contact",
                                off.distance,
                                model.interface.pairs[j].name,
                                off.nearest[0],
                                off.nearest[1],
                                off.length
                            ),
                        )
                    })
                })
                .collect()
        })
        .collect()
}

impl<'m, 's, F: FnMut(&Model, &StepResult) -> Result<()>> StepWriter<'m, 's, F> {
    pub(super) fn new(
        case: &'m Case,
        model: &'m Model,
        session: &'m Session,
        summary: &'s mut Summary,
        traced: Vec<Vec<TracedPoint>>,
        on_step: F,
    ) -> Self {
        let (layout, columns) = HistoryLayout::new(case, model);
        Self {
            case,
            model,
            points: BodyPoints::new(model),
            interface: InterfaceOutput::new(model),
            folder: session.folder,
            pairs: model
                .interface
                .pairs
                .iter()
                .map(|p| p.name.clone())
                .collect(),
            vtu: case.output.vtu,
            all_frames: case.output.cycle_frames == CycleFrames::All,
            case_text: session.restart.map(|r| r.case_text.as_str()),
            layout,
            series: Vec::new(),
            history_text: GrowingCsv::new(&columns),
            history: CsvTable::new(columns),
            fretting: FrettingTables::new(model).with_points(traced),
            summary,
            last_reactions: Vec::new(),
            bar: progress_bar(session.progress, model.schedule.steps()),
            records: RecordWriter::default(),
            increment_seconds: 0.0,
            on_step,
        }
    }

    /// Writes `history.csv` with the row of the unloaded state (step 0).
    pub(super) fn write_start(&mut self) -> Result<()> {
        let model = self.model;
        let solution = Solution::new(model);
        let zero = vec![0.0; model.dofs.dof_count()];
        let start = StepResult {
            frame: crate::model::timeline::Frame::default(),
            step: 0,
            load_factor: 0.0,
            newton: NewtonLog::default(),
            increments: 0,
            cutbacks: 0,
            solution: &solution,
            internal_force: &zero,
            external_force: &zero,
        };
        let row = self.row(&start, 0.0)?;
        self.push_history(row)?;
        self.write_indexes()
    }

    /// Takes over the output state of a restart `record`: the history rows, series and
    /// step records of its steps; removes the files of later steps and rewrites the
    /// indexes. Returns the run to continue.
    pub(super) fn restore(&mut self, record: Record) -> Result<Resume> {
        let Record { resume, output } = record;
        let mut tables = output.tables.into_iter();
        let record_path = self.folder.dir().join(RunFile::Restart.name());
        let missing = |what: &str| Error::Restart {
            path: record_path.clone(),
            reason: format!("the record has no {what} table"),
        };
        let history = tables.next().ok_or_else(|| missing("history"))?;
        let energy = tables.next().ok_or_else(|| missing("energy"))?;
        self.fretting
            .restore(tables.collect())
            .ok_or_else(|| Error::Restart {
                path: record_path.clone(),
                reason: "its fretting tables do not match the case's contact pairs".into(),
            })?;
        let marks: Option<Vec<EnergyMark>> =
            energy.iter().map(|row| EnergyMark::from_row(row)).collect();
        self.summary.energy.marks = marks.ok_or_else(|| Error::Restart {
            path: record_path.clone(),
            reason: "its energy rows have the wrong length".into(),
        })?;
        if history
            .iter()
            .any(|row| row.len() != self.history.columns.len())
        {
            return Err(Error::Restart {
                path: record_path,
                reason: "its history rows do not match the case's columns".into(),
            });
        }
        self.history_text = GrowingCsv::new(&self.history.columns);
        let history_path = self.folder.path(RunFile::History)?;
        for row in &history {
            self.history_text.push(&history_path, row)?;
        }
        self.history.rows = history;
        self.series = output.series;
        for row in self.history.rows.iter().filter(|r| r[0] > 0.0) {
            let step = self.layout.step_summary(self.model, row);
            self.summary.push_step(step);
        }
        self.folder
            .remove_steps_from(resume.state.step, &self.pairs)?;
        self.write_indexes()?;
        self.bar.0.inc(resume.state.step as u64 - 1);
        tracing::info!(
            step = resume.state.step,
            time = resume.state.time,
            "resuming from the restart record"
        );
        Ok(resume)
    }

    /// Writes the files of a converged step (or of the last converged sub-increment of a
    /// failed step, `progress` `None`), then the restart record, then the indexes.
    pub(super) fn step(&mut self, step: &StepResult, progress: Option<&Progress>) -> Result<f64> {
        let start = Instant::now();
        let fields = self.all_frames || self.model.schedule.timeline().is_end_frame(step.step);
        let row = self.write_step_files(step, step.step as f64, fields)?;
        self.push_history(row)?;
        // Before the restart record, which keeps the marks for a resumed run's summary.
        let total = step.solution.energy.total;
        if let Some(mark) = EnergyMark::at(&step.frame, step.step, total) {
            self.summary.energy.push(mark);
        }
        if let Some(p) = progress {
            self.queue_record(p)?;
        }
        self.write_indexes()?;
        let last = self
            .history
            .rows
            .last()
            .map(Vec::as_slice)
            .unwrap_or_default();
        let summary = self.layout.step_summary(self.model, last);
        self.last_reactions = summary
            .reactions
            .0
            .iter()
            .map(|(_, f)| [f.x, f.y])
            .collect();
        self.summary.push_step(summary);
        (self.on_step)(self.model, step)?;
        if super::progress::stop_requested() {
            return Err(self.interrupted(step.step));
        }
        self.bar.0.inc(1);
        self.bar.0.set_message(self.progress_message(step));
        Ok(start.elapsed().as_secs_f64() + std::mem::take(&mut self.increment_seconds))
    }

    /// The error that stops the run after step `step` when a stop was asked for: its files
    /// are committed; a run that keeps restart records can be resumed from it.
    fn interrupted(&self, step: usize) -> Error {
        Error::Interrupted {
            step,
            dir: self.folder.dir().to_path_buf(),
            resume: self.case_text.map(|_| self.case.path.clone()),
        }
    }

    /// The progress bar's message: the load factor, and in a case of several analysis steps
    /// or cycles the step's name and the cycle.
    fn progress_message(&self, step: &StepResult) -> String {
        let timeline = self.model.schedule.timeline();
        let f = &step.frame;
        match timeline.steps().get(f.analysis_step.wrapping_sub(1)) {
            Some(plan) if timeline.steps().len() > 1 || plan.is_cyclic() => format!(
                "{} cycle {}/{} ({} of {} cycles)",
                plan.name,
                f.cycle,
                plan.simulated(),
                f.cycles,
                plan.cycles
            ),
            _ => format!("load factor {}", step.load_factor),
        }
    }

    /// Queues the files of a state at pseudo-time `time` (each complete or absent once
    /// written; not yet listed anywhere): with `fields` its VTU and contact CSV files;
    /// returns its history row.
    fn write_step_files(&mut self, step: &StepResult, time: f64, fields: bool) -> Result<Vec<f64>> {
        let (mut post, mut vtu) = (0.0, 0.0);
        let start = Instant::now();
        let mut entries = Vec::new();
        if self.vtu && fields {
            let info = StepInfo {
                step: step.step,
                time,
                load_factor: step.load_factor,
            };
            let t = Instant::now();
            let (bodies, interface) =
                step_grids(self.model, &self.points, &self.interface, step, info);
            post += t.elapsed().as_secs_f64();
            let t = Instant::now();
            let parts = [
                ("bodies", RunFile::Bodies(step.step), Some(bodies)),
                ("interface", RunFile::Interface(step.step), interface),
            ];
            for (part, (name, file, grid)) in parts.into_iter().enumerate() {
                let Some(grid) = grid else { continue };
                self.records
                    .queue(self.folder.path(file)?, Content::Vtu(grid));
                entries.push(PvdEntry {
                    time,
                    part: part as u32,
                    name: name.into(),
                    file: file.name().into(),
                });
            }
            vtu += t.elapsed().as_secs_f64();
        }
        let tables = if fields {
            self.interface.fretting_tables(self.model, step.solution)
        } else {
            Vec::new()
        };
        for (pair, table) in self.model.interface.pairs.iter().zip(tables) {
            let file = RunFile::Contact(&pair.name, step.step);
            self.records
                .queue(self.folder.path(file)?, Content::Csv(table));
        }
        self.fretting
            .record(self.model, &self.interface, step, time)?;
        let row = self.row(step, time)?;
        self.series.extend(entries);
        tracing::debug!(
            step = step.step,
            post,
            vtu,
            rest = start.elapsed().as_secs_f64() - post - vtu,
            "output seconds (body recovery, VTU files queued, contact tables)"
        );
        Ok(row)
    }

    /// The history row of a state at pseudo-time `time`.
    fn row(&self, step: &StepResult, time: f64) -> Result<Vec<f64>> {
        let model = self.model;
        let reactions = reactions(model, step.internal_force, step.external_force);
        let resultants = resultants(model, &step.solution.interface_committed);
        let requested = evaluate(&self.case.history, model, step)?;
        let values = [
            reactions.as_flattened(),
            resultants.as_flattened(),
            &requested,
        ];
        Ok(self.layout.row(&model.schedule, step, time, values))
    }

    /// Queues the restart record of a converged increment (when the run keeps them).
    fn queue_record(&mut self, progress: &Progress) -> Result<()> {
        let Some(case_text) = self.case_text else {
            return Ok(());
        };
        let energy = self.energy_rows();
        let mut tables = vec![self.history.rows.as_slice(), energy.as_slice()];
        tables.extend(self.fretting.tables());
        let output = OutputView {
            tables,
            series: &self.series,
        };
        self.records.queue_record(
            &self.folder.path(RunFile::Restart)?,
            case_text,
            progress,
            &output,
        )
    }

    /// The energy marks of the summary as rows (the restart record's second table).
    fn energy_rows(&self) -> Vec<Vec<f64>> {
        let marks = &self.summary.energy.marks;
        marks.iter().map(EnergyMark::to_row).collect()
    }

    /// Writes the restart record of a converged sub-increment (in the background).
    fn write_record(&mut self, progress: &Progress) -> Result<()> {
        let start = Instant::now();
        self.queue_record(progress)?;
        self.records.commit()?;
        self.increment_seconds += start.elapsed().as_secs_f64();
        Ok(())
    }

    /// Adds a row to `history.csv`'s table and text.
    fn push_history(&mut self, row: Vec<f64>) -> Result<()> {
        self.history_text
            .push(&self.folder.path(RunFile::History)?, &row)?;
        self.history.rows.push(row);
        Ok(())
    }

    /// Queues `history.csv`, then `results.pvd`, after the step's files and record, and
    /// commits them: the series is the last file written for a step, so it lists only steps
    /// whose other files are complete.
    fn write_indexes(&mut self) -> Result<()> {
        for (table, content) in self.fretting.contents(self.model) {
            let path = self.folder.path(RunFile::Fretting(table))?;
            self.records.queue(path, content);
        }
        self.records.queue(
            self.folder.path(RunFile::History)?,
            Content::Text(self.history_text.bytes().to_vec()),
        );
        if self.vtu && !self.series.is_empty() {
            self.records.queue(
                self.folder.path(RunFile::Series)?,
                Content::Pvd(self.series.clone()),
            );
        }
        self.records.commit()
    }

    /// Waits for the files being written; returns the seconds waited.
    pub(super) fn finish(&mut self) -> Result<f64> {
        let start = Instant::now();
        self.records.finish()?;
        Ok(start.elapsed().as_secs_f64() + std::mem::take(&mut self.increment_seconds))
    }
}

impl<F: FnMut(&Model, &StepResult) -> Result<()>> Observer for StepWriter<'_, '_, F> {
    fn step(&mut self, step: &StepResult, progress: &Progress) -> Result<f64> {
        StepWriter::step(self, step, Some(progress))
    }

    fn increment(&mut self, progress: &Progress) -> Result<()> {
        self.write_record(progress)
    }

    /// The last converged sub-increment of a failed step: its files and index entries at
    /// its fractional pseudo-time (no restart record: a resumed run retries the step).
    fn partial_step(&mut self, step: &StepResult, time: f64) -> Result<()> {
        let row = self.write_step_files(step, time, true)?;
        self.push_history(row)?;
        self.write_indexes()
    }
}
