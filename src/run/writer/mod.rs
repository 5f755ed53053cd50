//! The files of every converged step: [`StepWriter`] queues a step's VTU and CSV files, its
//! restart record, the growing tables and the indexes on the background writer, in the order
//! that keeps the folder consistent at every moment (see [`crate::run`]).

mod frames;

use std::sync::Arc;
use std::time::Instant;

use super::Session;
use super::folder::{OutputFolder, RunFile};
use super::history::{HistoryLayout, read_rows};
use super::progress::{RunBar, progress_bar};
use crate::config::{Case, CycleFrames};
use crate::model::Model;
use crate::output::SplitPlan;
use crate::output::append::{self, AppendedFile};
use crate::output::csv::GrowingCsv;
use crate::output::pvd::PvdEntry;
use crate::output::restart::ContinuumStates;
use crate::output::restart::{
    ENERGY_MARKS, OutputState, Record, encode_energy_mark, read_energy_marks,
};
use crate::output::summary::{EnergyMark, Summary};
use crate::output::writer::{Content, RecordWriter};
use crate::post::fretting::{FrettingTables, TracedPoint, trace_point};
use crate::post::interface::{InterfaceOutput, resultants};
use crate::post::quantities::{evaluate, pair_quantities};
use crate::post::{BodyPoints, reactions};
use crate::solver::newton::NewtonLog;
use crate::solver::state::{Observer, Progress, Resume, Solution, StepResult};
use crate::{Error, Result};
use frames::frame_entry;

/// Writes the files of each converged step and the restart record of each converged
/// increment, keeps the series and history up to date, and records the steps in the
/// summary.
pub(super) struct StepWriter<'m, 's, F> {
    case: &'m Case,
    model: &'m Model,
    points: BodyPoints,
    interface: InterfaceOutput,
    /// How the frames' grids of the bodies and of the contacts are divided into one file per
    /// body and per pair, made at the first frame (their cells are the same in every frame).
    splits: [Option<Arc<SplitPlan>>; 2],
    folder: &'m OutputFolder,
    vtu: bool,
    /// Field output at every frame of a cyclic step (`[output] cycle_frames = "all"`).
    all_frames: bool,
    /// The case's text when restart records are kept.
    case_text: Option<&'m str>,
    layout: HistoryLayout,
    /// The files that grow by rows.
    tables: GrowingTables,
    /// The last row of `history.csv` (the summary's record of the last step).
    last_row: Vec<f64>,
    pub(super) summary: &'s mut Summary,
    pub(super) last_reactions: Vec<crate::output::summary::Force>,
    pub(super) bar: RunBar,
    /// Writes the files in the background, in the order they are queued, and keeps the
    /// series up to date.
    out: Committer,
    /// Seconds spent on the records of sub-increments since the last step, counted with
    /// that step's output time.
    increment_seconds: f64,
    on_step: F,
}

/// The files of a run that grow by rows, appended to as the frames come
/// ([`crate::output::append`]): `history.csv`, the fretting tables and, when the run keeps
/// restart records, the energy marks the record continues.
struct GrowingTables {
    history: GrowingCsv,
    fretting: FrettingTables,
    energy: Option<AppendedFile>,
}

impl GrowingTables {
    /// The files with their appended bytes, in a fixed order (the order of the restart
    /// record's marks).
    fn files<'m>(&mut self, model: &'m Model) -> Vec<(RunFile<'m>, &mut AppendedFile)> {
        let mut files = vec![(RunFile::History, self.history.file())];
        let fretting = self.fretting.files(model).into_iter();
        files.extend(fretting.map(|(table, csv)| (RunFile::Fretting(table), csv.file())));
        if let Some(energy) = &mut self.energy {
            files.push((RunFile::RestartEnergy, energy));
        }
        files
    }
}

/// Entries of `results.pvd` that are always rewritten at once (about 100 kB); beyond them
/// the series is rewritten when it has grown by an eighth, so that writing it costs time
/// linear in its length over a run (see [`StepWriter::queue_series`]).
const SERIES_AT_ONCE: usize = 1000;

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
        let case_text = session.restart.map(|r| r.case_text.as_str());
        let energy = case_text.map(|_| {
            let mut marks = AppendedFile::default();
            marks.push(ENERGY_MARKS);
            marks
        });
        Self {
            case,
            model,
            points: BodyPoints::new(model),
            interface: InterfaceOutput::new(model),
            splits: [None, None],
            folder: session.folder,
            vtu: case.output.vtu,
            all_frames: case.output.cycle_frames == CycleFrames::All,
            case_text,
            layout,
            tables: GrowingTables {
                history: GrowingCsv::new(&columns),
                fretting: FrettingTables::new(model).with_points(traced),
                energy,
            },
            last_row: Vec::new(),
            summary,
            last_reactions: Vec::new(),
            bar: progress_bar(session.progress, model.schedule.steps()),
            out: Committer::default(),
            increment_seconds: 0.0,
            on_step,
        }
    }

    /// Writes `history.csv` with the row of the unloaded state (step 0).
    pub(super) fn write_start(&mut self) -> Result<()> {
        let model = self.model;
        // The history row reads no integration-point state.
        let solution = Solution::without_point_states(model);
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
        self.write_indexes(false)
    }

    /// Takes over the output state of a restart `record`: continues each growing file where
    /// the record left it (checked against its checksum, cut back to its length), reads the
    /// summary's step records and energy marks back from them, removes the files of later
    /// steps and rewrites the series. Returns the run to continue.
    pub(super) fn restore(&mut self, record: Record) -> Result<Resume> {
        let Record { resume, output } = record;
        self.continue_files(&output)?;
        let history = self.folder.path(RunFile::History)?;
        let columns = self.layout.columns();
        let (model, layout, summary) = (self.model, &self.layout, &mut *self.summary);
        let mut last = Vec::new();
        read_rows(&history, columns, |row| {
            if row[0] > 0.0 {
                summary.push_step(layout.step_summary(model, row));
            }
            last = row.to_vec();
        })?;
        self.last_row = last;
        if self.tables.energy.is_some() {
            let path = self.folder.path(RunFile::RestartEnergy)?;
            let marks: Option<Vec<EnergyMark>> = read_energy_marks(&path)?
                .iter()
                .map(|row| EnergyMark::from_row(row))
                .collect();
            self.summary.energy.marks = marks.ok_or_else(|| Error::Restart {
                path,
                reason: "its energy marks have the wrong length".into(),
            })?;
        }
        // The verdicts of the cyclic steps already finished travel in the record (a run
        // resumed after its last step writes no step that would bring them).
        self.summary
            .shakedown
            .clone_from(&resume.solution.internal.cycles.verdicts);
        for step in 1..resume.state.step {
            if self.vtu && self.has_fields(step) {
                self.out.series.push(frame_entry(step, step as f64));
            }
        }
        self.folder.remove_steps_from(resume.state.step)?;
        self.write_indexes(true)?;
        self.bar.0.inc(resume.state.step as u64 - 1);
        tracing::info!(
            step = resume.state.step,
            time = resume.state.time,
            "resuming from the restart record"
        );
        Ok(resume)
    }

    /// Continues each growing file at its mark in `output`: all are checked before any is
    /// cut back, so that a refused record leaves the folder as it was.
    fn continue_files(&mut self, output: &OutputState) -> Result<()> {
        let record = self.folder.dir().join(RunFile::Restart.name());
        let mut files = Vec::new();
        for (file, appended) in self.tables.files(self.model) {
            files.push((file.name(), self.folder.path(file)?, appended));
        }
        let names = |names: Vec<&str>| names.join(", ");
        let ours = names(files.iter().map(|(name, ..)| name.as_str()).collect());
        let recorded = names(output.files.iter().map(|(name, _)| name.as_str()).collect());
        if ours != recorded {
            return Err(Error::Restart {
                path: record,
                reason: format!(
                    "it continues the tables {recorded}; the case writes {ours}: run without \
                     --resume"
                ),
            });
        }
        for ((_, path, _), (_, mark)) in files.iter().zip(&output.files) {
            if let Some(reason) = append::check(path, *mark)? {
                return Err(Error::Restart {
                    path: path.clone(),
                    reason: format!("{reason}; run without --resume"),
                });
            }
        }
        for ((_, path, appended), (_, mark)) in files.into_iter().zip(&output.files) {
            append::truncate(&path, *mark)?;
            *appended = AppendedFile::continued(*mark);
        }
        Ok(())
    }

    /// Writes the files of a converged step (or of the last converged sub-increment of a
    /// failed step, `progress` `None`), then the restart record, then the indexes.
    pub(super) fn step(&mut self, step: &StepResult, progress: Option<&Progress>) -> Result<f64> {
        let start = Instant::now();
        let fields = self.has_fields(step.step);
        let row = self.write_step_files(step, step.step as f64, fields)?;
        self.push_history(row)?;
        // Before the restart record, which counts the marks for a resumed run's summary.
        let total = step.solution.energy.total;
        if let Some(mark) = EnergyMark::at(&step.frame, step.step, total) {
            if let Some(energy) = &mut self.tables.energy {
                let path = self.folder.path(RunFile::RestartEnergy)?;
                energy.push(&encode_energy_mark(&path, &mark.to_row())?);
            }
            self.summary.energy.push(mark);
        }
        let verdicts = &step.solution.internal.cycles.verdicts;
        if self.summary.shakedown.len() != verdicts.len() {
            self.summary.shakedown.clone_from(verdicts);
        }
        self.queue_appends()?;
        if let Some(p) = progress {
            self.queue_record(p)?;
        }
        self.queue_series(false)?;
        self.out.commit()?;
        let summary = self.layout.step_summary(self.model, &self.last_row);
        self.last_reactions = summary.reactions.0.iter().map(|(_, f)| *f).collect();
        self.summary.push_step(summary);
        (self.on_step)(self.model, step)?;
        if super::progress::stop_requested() {
            return Err(self.interrupted(step.step));
        }
        self.bar.0.inc(1);
        self.bar.0.set_message(self.progress_message(step));
        Ok(start.elapsed().as_secs_f64() + std::mem::take(&mut self.increment_seconds))
    }

    /// Whether output step `step` gets field output (VTU, contact tables): every step, or in
    /// a cyclic step with `cycle_frames = "ends"` those of its first and last cycle and the
    /// last of every other cycle.
    fn has_fields(&self, step: usize) -> bool {
        self.all_frames || self.model.schedule.timeline().is_end_frame(step)
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
        let pairs = pair_quantities(model, &step.solution.interface_committed);
        let pairs: Vec<_> = pairs
            .into_iter()
            .enumerate()
            .map(|(p, q)| {
                let before = self.layout.dissipation(&self.last_row, p);
                (q, q.dissipation - before)
            })
            .collect();
        Ok(self.layout.row(model, step, time, values, &pairs))
    }

    /// Queues the restart record of a converged increment (when the run keeps them), after
    /// the rows appended so far, whose files' lengths and checksums it keeps.
    fn queue_record(&mut self, progress: &Progress) -> Result<()> {
        let Some(case_text) = self.case_text else {
            return Ok(());
        };
        let files = self.tables.files(self.model).into_iter();
        let output = OutputState {
            files: files.map(|(file, f)| (file.name(), f.mark())).collect(),
        };
        self.out.records.queue_record(
            &self.folder.path(RunFile::Restart)?,
            case_text,
            progress,
            &output,
            ContinuumStates::of(self.model),
        )
    }

    /// Writes the restart record of a converged sub-increment (in the background).
    fn write_record(&mut self, progress: &Progress) -> Result<()> {
        let start = Instant::now();
        self.queue_record(progress)?;
        self.out.commit()?;
        self.increment_seconds += start.elapsed().as_secs_f64();
        Ok(())
    }

    /// Adds a row to `history.csv`.
    fn push_history(&mut self, row: Vec<f64>) -> Result<()> {
        self.tables
            .history
            .push(&self.folder.path(RunFile::History)?, &row)?;
        self.last_row = row;
        Ok(())
    }

    /// Queues the rows added to the growing files since the last commit, to be appended.
    fn queue_appends(&mut self) -> Result<()> {
        for (file, appended) in self.tables.files(self.model) {
            if let Some(append) = appended.take() {
                self.out
                    .records
                    .queue(self.folder.path(file)?, Content::Append(append));
            }
        }
        Ok(())
    }

    /// Queues `results.pvd` when it lacks entries and is due ([`Committer::queue_series`]).
    fn queue_series(&mut self, now: bool) -> Result<()> {
        if self.vtu && !self.out.series.is_empty() && self.out.series_path.is_none() {
            self.out.series_path = Some(self.folder.path(RunFile::Series)?);
        }
        self.out.queue_series(now);
        Ok(())
    }

    /// Queues the rows added since the last commit and the series (`now`: also when it is
    /// not due), and commits them.
    fn write_indexes(&mut self, now: bool) -> Result<()> {
        self.queue_appends()?;
        self.queue_series(now)?;
        self.out.commit()
    }

    /// Writes the series if it lacks entries, waits for the files being written; returns
    /// the seconds waited.
    pub(super) fn finish(&mut self) -> Result<f64> {
        let start = Instant::now();
        self.write_indexes(true)?;
        self.out.records.finish()?;
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

    /// The point states are read by the field output alone (the bodies' VTU grids, the F3
    /// column of the contact tables); the history row, the summary and the restart record
    /// do not read them.
    fn reads_point_states(&self, step: usize) -> bool {
        self.has_fields(step)
    }

    /// The last converged sub-increment of a failed step: its files and index entries at
    /// its fractional pseudo-time (no restart record: a resumed run retries the step).
    fn partial_step(&mut self, step: &StepResult, time: f64) -> Result<()> {
        let row = self.write_step_files(step, time, true)?;
        self.push_history(row)?;
        self.write_indexes(true)
    }
}

/// The background writer of a run's files and the entries of its series (`results.pvd`).
#[derive(Debug, Default)]
struct Committer {
    records: RecordWriter,
    series: Vec<PvdEntry>,
    /// The entries the series written last lists.
    series_written: usize,
    /// The entries whose files were committed.
    series_committed: usize,
    /// `results.pvd` (`None`: the run writes no VTU files).
    series_path: Option<std::path::PathBuf>,
}

impl Committer {
    /// Commits the queued files ([`RecordWriter::commit`]).
    fn commit(&mut self) -> Result<()> {
        self.series_committed = self.series.len();
        self.records.commit()
    }

    /// Queues `results.pvd` when it lists fewer entries than the series has and it is due
    /// (`now`, or rewriting it costs little: while it is short, or once the entries it lacks
    /// are an eighth of those it lists, which keeps the cost of all rewrites linear in the
    /// series' length). It comes after the files of its entries, so it lists only steps whose
    /// files are complete.
    fn queue_series(&mut self, now: bool) {
        self.queue_entries(self.series.len(), now);
    }

    /// Queues `results.pvd` with the first `all` entries of the series when it is due.
    fn queue_entries(&mut self, all: usize, now: bool) {
        let written = self.series_written;
        let due = all > written && (now || all <= SERIES_AT_ONCE || 8 * (all - written) >= written);
        if let Some(path) = &self.series_path
            && due
        {
            let content = Content::Pvd(self.series[..all].to_vec());
            self.records.queue(path.clone(), content);
            self.series_written = all;
        }
    }
}

impl Drop for Committer {
    /// A run that stops early (an error, an interruption) still gets a series that lists
    /// every step whose files were committed (the background writer writes nothing after a
    /// failed commit, and finishes what was committed when it is dropped).
    fn drop(&mut self) {
        // Files queued but not committed belong to a step whose commit never came.
        self.records.discard_queued();
        self.queue_entries(self.series_committed, true);
        if let Err(e) = self.records.commit() {
            tracing::warn!("{e}");
        }
    }
}
