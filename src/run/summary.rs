//! `summary.json`: the model, every converged step, totals and timings, and how the run ended.

use super::RunSummary;
use super::folder::{OutputFolder, RunFile};
use crate::Result;
use crate::element::Analysis;
use crate::model::{Model, Schedule};
use crate::output::atomic::write_atomically;
use crate::output::summary::{ModelSize, Status, Summary};

/// Records the analysis and size of the built `model` in `summary`.
pub(super) fn describe_model(summary: &mut Summary, model: &Model, model_seconds: f64) {
    let (analysis, thickness) = match model.analysis {
        Analysis::PlaneStress { thickness } => ("plane_stress", Some(thickness)),
        Analysis::PlaneStrain { thickness } => ("plane_strain", Some(thickness)),
        Analysis::Axisymmetric => ("axisymmetric", None),
    };
    summary.analysis = Some(analysis);
    summary.model = Some(ModelSize {
        nodes: model.mesh.nodes.len(),
        elements: model.continuum.cells.len(),
        interface_elements: model.interface.elements.len(),
        unknowns: model.dofs.free_count(),
        thickness,
    });
    summary.seconds.model = Some(model_seconds);
    let steps = model.schedule.timeline().steps();
    summary.energy.step_names = steps.iter().map(|plan| plan.name.clone()).collect();
}

/// Completes `summary` with the counters and timings of the converged `run`.
pub(super) fn complete_summary(summary: &mut Summary, run: &RunSummary) {
    let s = &run.stats;
    summary.status = Status::Converged;
    summary.totals.steps = s.steps;
    summary.totals.increments = s.increments;
    summary.totals.cutbacks = s.cutbacks;
    summary.totals.iterations = s.iterations;
    summary.totals.unsymmetric_solves = Some(s.unsymmetric_solves);
    summary.totals.krylov_iterations = Some(s.krylov_iterations);
    let seconds = &mut summary.seconds;
    seconds.symbolic = Some(s.symbolic_seconds);
    seconds.assembly = Some(s.assembly_seconds);
    seconds.factorisation = Some(s.factorization_seconds);
    seconds.solve = Some(s.solve_seconds);
    seconds.output = Some(s.output_seconds);
    summary.final_residual = Some(s.last_residual);
}

/// One analysis step in `summary.json` (`"analysis_steps"`): a `[steps]` schedule is one
/// step of its steps' increments.
#[derive(Clone, Debug, serde::Serialize)]
pub(super) struct AnalysisStepSummary {
    name: String,
    /// Its first output frame (1-based step number of `history.csv` and the step files).
    first_frame: usize,
    /// Output frames (increments × simulated cycles).
    frames: usize,
    /// Load cycles it stands for.
    cycles: usize,
    simulated_cycles: usize,
    cycles_per_jump: usize,
}

/// The analysis steps of a schedule as `summary.json` lists them.
pub(super) fn analysis_steps(schedule: &Schedule) -> Vec<AnalysisStepSummary> {
    let steps = schedule.timeline().steps().iter();
    steps
        .map(|s| AnalysisStepSummary {
            name: s.name.clone(),
            first_frame: s.first + 1,
            frames: s.frames(),
            cycles: s.cycles,
            simulated_cycles: s.simulated(),
            cycles_per_jump: s.cycles_per_jump,
        })
        .collect()
}

/// `summary.json`: the run's [`Summary`] followed by its analysis steps.
#[derive(serde::Serialize)]
struct SummaryFile<'a> {
    #[serde(flatten)]
    summary: &'a Summary,
    analysis_steps: &'a [AnalysisStepSummary],
}

/// Writes the folder's `summary.json` (atomically).
pub(super) fn write_summary(
    summary: &Summary,
    analysis_steps: &[AnalysisStepSummary],
    folder: &OutputFolder,
) -> Result<()> {
    let path = folder.path(RunFile::Summary)?;
    let file = SummaryFile {
        summary,
        analysis_steps,
    };
    // Streamed into the file: a run of many frames lists them all (~600 bytes each).
    write_atomically(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, &file).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
}

/// Writes the summary of a failed run; a failure to write it is logged, since the run's own
/// error is the one to report.
pub(super) fn write_summary_after_failure(summary: &Summary, folder: &OutputFolder) {
    if let Err(e) = write_summary(summary, &[], folder) {
        tracing::warn!("{e}");
    }
}
