//! `summary.json`: the model, every converged step, totals and timings, and how the run ended.

use super::RunSummary;
use super::folder::{OutputFolder, RunFile};
use crate::Result;
use crate::element::Analysis;
use crate::model::{Model, Schedule};
use crate::output::atomic::write_atomically;
use crate::output::summary::{ModelSize, Named, Status, Summary};
use crate::solver::floor::Floor;

/// Records the analysis and size of the built `model` in `summary`.
pub(super) fn describe_model(summary: &mut Summary, model: &Model, model_seconds: f64) {
    let (analysis, thickness) = match model.analysis {
        Analysis::PlaneStress { thickness } => ("plane_stress", Some(thickness)),
        Analysis::PlaneStrain { thickness } => ("plane_strain", Some(thickness)),
        Analysis::Axisymmetric | Analysis::AxisymmetricTwist => ("axisymmetric", None),
    };
    summary.analysis = Some(analysis);
    summary.twist = model.analysis.has_twist();
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
    seconds.conduction = Some(s.work.conduction.seconds());
    // gmsh is not the method's work: out of the floor and out of the run it is compared with.
    let gmsh = seconds.gmsh.unwrap_or(0.0);
    summary.floor = Some(Floor::new(
        &s.work,
        seconds.mesh - gmsh,
        seconds.total - gmsh,
    ));
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
    /// Work of the loads and prescribed displacements done in the step (N·mm; `null` until
    /// the step's first cycle ended), as `energy.steps`' `external_work`.
    external_work: Option<f64>,
    /// Physical dissipation in the step (plastic, friction and wear work; N·mm), as
    /// `energy.steps`' terms.
    dissipation: Option<f64>,
    /// Friction dissipated on each contact pair in the step (N·mm; its frames'
    /// `dissipation_increment` summed, counting the cycles a wear jump stands for), by pair
    /// name, up to the step's last converged frame.
    contact_dissipation: Named<f64>,
}

impl AnalysisStepSummary {
    /// The step with what the converged frames and energy marks of `summary` say of it.
    fn with_results(&self, index: usize, summary: &Summary) -> Self {
        let mut step = self.clone();
        let energy = summary.energy.steps();
        if let Some((_, change)) = energy.iter().find(|(m, _)| m.analysis_step == index + 1) {
            step.external_work = Some(change.external_work);
            step.dissipation = Some(change.dissipation());
        }
        // The steps are in order of their frame: the last one before frame `k`.
        let before = |k: usize| {
            let i = summary.steps.partition_point(|s| s.step < k);
            i.checked_sub(1).map(|i| &summary.steps[i])
        };
        let last = before(self.first_frame + self.frames).filter(|s| s.step >= self.first_frame);
        if let Some(last) = last {
            let before = before(self.first_frame);
            let pairs = last.contact.0.iter().map(|(name, c)| {
                let start = before.and_then(|b| b.contact.0.iter().find(|(n, _)| n == name));
                let start = start.map_or(0.0, |(_, s)| s.dissipation);
                (name.clone(), c.dissipation - start)
            });
            step.contact_dissipation = Named(pairs.collect());
        }
        step
    }
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
            external_work: None,
            dissipation: None,
            contact_dissipation: Named::default(),
        })
        .collect()
}

/// `summary.json`: the run's [`Summary`] followed by its analysis steps.
#[derive(serde::Serialize)]
struct SummaryFile<'a> {
    #[serde(flatten)]
    summary: &'a Summary,
    analysis_steps: Vec<AnalysisStepSummary>,
}

/// Writes the folder's `summary.json` (atomically).
pub(super) fn write_summary(
    summary: &Summary,
    analysis_steps: &[AnalysisStepSummary],
    folder: &OutputFolder,
) -> Result<()> {
    let path = folder.path(RunFile::Summary)?;
    let analysis_steps = analysis_steps.iter().enumerate();
    let file = SummaryFile {
        summary,
        analysis_steps: analysis_steps
            .map(|(i, step)| step.with_results(i, summary))
            .collect(),
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
