//! The whole run of a case: mesh (gmsh or an .msh file) → model → load steps → output files.
//! Each phase is timed under its name; the numbers end up in the [`RunSummary`].
//!
//! Files written to the output folder:
//! - `mesh.msh` when the case meshes a `.geo` script;
//! - `bodies_NNNN.vtu` per converged step and `results.pvd` listing them (time = step
//!   number, since load factors may go down again when unloading);
//! - `interface_NNNN.vtu` (when the case has contact pairs): the contact fields on the
//!   interface, listed in `results.pvd` as a second part;
//! - `contact_<pair>_NNNN.csv`: the contact fields along each pair's curve;
//! - `history.csv`: per step the load factor, increments, Newton iterations, final residual,
//!   the reaction force of every support and the resultant forces of every contact pair;
//! - `summary.json` ([`Summary`]): the model size, every converged step, totals and timings,
//!   and whether the run converged or failed (with the error), for scripts.
//!
//! Every file but `summary.json` is rewritten after each converged step, so a run that stops
//! early leaves the results of all converged steps on disk; `summary.json` is written at the
//! end, also when a run fails.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::config::{Case, LinearSolverKind, SolverSpec};
use crate::element::Analysis;
use crate::mesh::{Mesh, gmsh, msh};
use crate::model::{Model, ModelSpec};
use crate::output::csv::{CsvTable, write_csv};
use crate::output::pvd::{PvdEntry, write_pvd};
use crate::output::summary::{
    ContactResultant, Force, ModelSize, Named, Status, StepSummary, Summary,
};
use crate::output::vtu::write_vtu;
use crate::post::interface::{InterfaceOutput, resultants};
use crate::post::{BodyPoints, body_grid, reactions};
use crate::solver::newton::{LinearSolver, NewtonSettings};
use crate::solver::stepping::{RunStatistics, StepResult, run_steps};
use crate::{Error, Result};

/// What a run did, for the closing summary.
#[derive(Clone, Debug)]
pub struct RunSummary {
    pub out_dir: PathBuf,
    pub nodes: usize,
    pub cells: usize,
    /// Unknowns (free degrees of freedom).
    pub dofs: usize,
    pub mesh_seconds: f64,
    pub model_seconds: f64,
    pub stats: RunStatistics,
    /// Reaction of each support at the last step: (name, [F_x, F_y]).
    pub reactions: Vec<(String, [f64; 2])>,
}

impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.stats;
        writeln!(
            f,
            "model: {} nodes, {} elements, {} unknowns",
            self.nodes, self.cells, self.dofs
        )?;
        writeln!(
            f,
            "steps: {} converged in {} increments ({} cut-backs), {} Newton iterations ({} unsymmetric \
             solves, {} BiCGSTAB iterations); final relative residual {:.2e}",
            s.steps,
            s.increments,
            s.cutbacks,
            s.iterations,
            s.unsymmetric_solves,
            s.krylov_iterations,
            s.last_residual
        )?;
        writeln!(
            f,
            "time [s]: mesh {:.3}, model {:.3}, ordering+symbolic {:.3}, assembly {:.3}, factorisation {:.3}, solve {:.3}, output {:.3}",
            self.mesh_seconds,
            self.model_seconds,
            s.symbolic_seconds,
            s.assembly_seconds,
            s.factorization_seconds,
            s.solve_seconds,
            s.output_seconds
        )?;
        for (name, r) in &self.reactions {
            writeln!(
                f,
                "reaction '{name}': Fx = {:.6e} N, Fy = {:.6e} N",
                r[0], r[1]
            )?;
        }
        write!(f, "results: {}", self.out_dir.join("results.pvd").display())
    }
}

/// Obtains the case's mesh: reads its `.msh` file, or meshes its `.geo` script with gmsh into
/// `out_dir/mesh.msh` first.
pub fn load_mesh(case: &Case, out_dir: &Path) -> Result<Mesh> {
    let path = match (&case.mesh.file, &case.mesh.geo) {
        (Some(file), _) => case.resolve(file),
        (None, Some(geo)) => {
            let params: Vec<(String, f64)> = case
                .mesh
                .parameters
                .iter()
                .map(|(k, v)| (k.clone(), *v))
                .collect();
            gmsh::mesh_geo(
                &case.resolve(geo),
                case.mesh.size,
                &params,
                &out_dir.join("mesh.msh"),
            )?
        }
        (None, None) => {
            return Err(Error::Case {
                path: case.path.clone(),
                message: "[mesh] has no source".into(),
            });
        }
    };
    msh::read_msh(&path)
}

/// Runs `case`, writing results to `out_dir`. `progress` shows a progress bar over the steps.
pub fn run(case: &Case, out_dir: &Path, progress: bool) -> Result<RunSummary> {
    let spec = ModelSpec::new(case)?; // bad parameters fail before gmsh runs
    let (mesh, mesh_seconds) = mesh_case(case, out_dir)?;
    run_model(case, spec, mesh, mesh_seconds, out_dir, progress, |_, _| {
        Ok(())
    })
}

/// Obtains the case's mesh into `out_dir` ([`load_mesh`]) and the seconds it took. If that
/// fails, `out_dir/summary.json` says so (status `failed`, the error, no model).
pub fn mesh_case(case: &Case, out_dir: &Path) -> Result<(Mesh, f64)> {
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(out_dir, e))?;
    let t = Instant::now();
    match load_mesh(case, out_dir) {
        Ok(mesh) => Ok((mesh, t.elapsed().as_secs_f64())),
        Err(e) => {
            let mut summary = Summary::new(&case.path);
            summary.seconds.mesh = t.elapsed().as_secs_f64();
            summary.seconds.total = summary.seconds.mesh;
            summary.fail(&e);
            write_summary_after_failure(&summary, out_dir);
            Err(e)
        }
    }
}

/// Runs `case` on an already loaded `mesh` (from [`load_mesh`], which took `mesh_seconds`),
/// writing results to `out_dir`, and calls `on_step` with the model and every converged step
/// after its files are written (e.g. to evaluate quantities in memory; an error stops the run).
/// `summary.json` is written whether the run converges or fails.
pub fn run_mesh(
    case: &Case,
    mesh: Mesh,
    mesh_seconds: f64,
    out_dir: &Path,
    progress: bool,
    on_step: impl FnMut(&Model, &StepResult) -> Result<()>,
) -> Result<RunSummary> {
    let spec = ModelSpec::new(case)?;
    run_model(case, spec, mesh, mesh_seconds, out_dir, progress, on_step)
}

/// [`run_mesh`] with the model's spec already made from `case` (by [`ModelSpec::new`]).
pub fn run_model(
    case: &Case,
    spec: ModelSpec,
    mesh: Mesh,
    mesh_seconds: f64,
    out_dir: &Path,
    progress: bool,
    on_step: impl FnMut(&Model, &StepResult) -> Result<()>,
) -> Result<RunSummary> {
    let start = Instant::now();
    let mut summary = Summary::new(&case.path);
    summary.seconds.mesh = mesh_seconds;
    let result = solve(case, spec, mesh, out_dir, progress, &mut summary, on_step);
    summary.seconds.total = mesh_seconds + start.elapsed().as_secs_f64();
    match &result {
        Ok(run) => {
            complete_summary(&mut summary, run);
            summary.write(&out_dir.join("summary.json"))?;
        }
        Err(e) => {
            summary.fail(e);
            write_summary_after_failure(&summary, out_dir);
        }
    }
    result
}

/// The model, the load steps and their files: the work of [`run_mesh`], which writes the
/// summary.
fn solve(
    case: &Case,
    spec: ModelSpec,
    mesh: Mesh,
    out_dir: &Path,
    progress: bool,
    summary: &mut Summary,
    mut on_step: impl FnMut(&Model, &StepResult) -> Result<()>,
) -> Result<RunSummary> {
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(out_dir, e))?;
    let t = Instant::now();
    let model = Model::build(mesh, spec)?;
    let model_seconds = t.elapsed().as_secs_f64();
    tracing::info!(
        nodes = model.mesh.nodes.len(),
        elements = model.continuum.cells.len(),
        unknowns = model.dofs.free_count(),
        "model built ({})",
        model.analysis.name()
    );
    describe_model(summary, &model, model_seconds);
    let bar = progress_bar(progress, model.schedule.steps());
    let mut writer = StepWriter::new(&model, out_dir, case.output.vtu, summary);
    let mut last_reactions = Vec::new();
    let (_, stats) = run_steps(&model, &newton_settings(&case.solver), |step| {
        let t = Instant::now();
        last_reactions = writer.write(step)?;
        on_step(&model, step)?;
        bar.inc(1);
        bar.set_message(format!("load factor {}", step.load_factor));
        Ok(t.elapsed().as_secs_f64())
    })?;
    bar.finish_and_clear();
    Ok(RunSummary {
        out_dir: out_dir.to_path_buf(),
        nodes: model.mesh.nodes.len(),
        cells: model.continuum.cells.len(),
        dofs: model.dofs.free_count(),
        mesh_seconds: summary.seconds.mesh,
        model_seconds,
        stats,
        reactions: model
            .supports
            .iter()
            .map(|s| s.name.clone())
            .zip(last_reactions)
            .collect(),
    })
}

/// The Newton settings of a case's `[solver]` table (the numerics never read the case file).
pub fn newton_settings(spec: &SolverSpec) -> NewtonSettings {
    NewtonSettings {
        max_iterations: spec.max_iterations,
        criteria: crate::solver::newton::Criteria {
            residual: spec.residual_tolerance,
            late_residual: spec.late_residual_tolerance,
            late_iteration: spec.late_iteration,
            correction: spec.correction_tolerance,
            zero_flux: spec.zero_flux,
            zero_flux_correction: spec.zero_flux_correction_tolerance,
            linear_residual: spec.linear_residual_tolerance,
            average_force: spec.average_force,
            relative_norms: spec.relative_norms,
        },
        force_tolerance: spec.force_tolerance,
        displacement_tolerance: spec.displacement_tolerance,
        max_cutbacks: spec.max_cutbacks,
        contact_algorithm: spec.contact_algorithm.into(),
        linear_solver: match spec.linear_solver {
            LinearSolverKind::Condensed => LinearSolver::Condensed,
            LinearSolverKind::Krylov => LinearSolver::Krylov,
        },
        extrapolate: spec.extrapolate,
    }
}

// --- summary.json ---------------------------------------------------------------------------

/// Records the analysis and size of the built `model` in `summary`.
fn describe_model(summary: &mut Summary, model: &Model, model_seconds: f64) {
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
}

/// Completes `summary` with the counters and timings of the converged `run`.
fn complete_summary(summary: &mut Summary, run: &RunSummary) {
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

/// Writes the summary of a failed run; a failure to write it is logged, since the run's own
/// error is the one to report.
fn write_summary_after_failure(summary: &Summary, out_dir: &Path) {
    if let Err(e) = summary.write(&out_dir.join("summary.json")) {
        tracing::warn!("{e}");
    }
}

fn progress_bar(enabled: bool, steps: usize) -> indicatif::ProgressBar {
    if !enabled {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(steps as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} step {pos}/{len} [{elapsed_precise}] {wide_bar} {msg}",
        )
        .expect("valid progress template"),
    );
    bar
}

/// Writes the files of each converged step, keeps the series and history up to date, and
/// records the step in the summary.
struct StepWriter<'m, 's> {
    model: &'m Model,
    points: BodyPoints,
    interface: InterfaceOutput,
    out_dir: PathBuf,
    vtu: bool,
    series: Vec<PvdEntry>,
    history: CsvTable,
    summary: &'s mut Summary,
}

impl<'m, 's> StepWriter<'m, 's> {
    fn new(model: &'m Model, out_dir: &Path, vtu: bool, summary: &'s mut Summary) -> Self {
        let mut columns: Vec<String> = [
            "step",
            "load_factor",
            "increments",
            "iterations",
            "residual",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
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
        Self {
            model,
            points: BodyPoints::new(model),
            interface: InterfaceOutput::new(model),
            out_dir: out_dir.to_path_buf(),
            vtu,
            series: Vec::new(),
            history: CsvTable {
                columns,
                rows: Vec::new(),
            },
            summary,
        }
    }

    /// Writes the step's files; returns the reactions of the supports.
    fn write(&mut self, step: &StepResult) -> Result<Vec<[f64; 2]>> {
        let start = Instant::now();
        let (mut post, mut vtu) = (0.0, 0.0);
        let reactions = reactions(self.model, step.internal_force, step.external_force);
        let states = &step.solution.interface_committed;
        if self.vtu {
            let name = format!("bodies_{:04}.vtu", step.step);
            let t = Instant::now();
            let grid = body_grid(
                self.model,
                &self.points,
                &step.solution.u,
                &step.solution.committed,
            );
            post += t.elapsed().as_secs_f64();
            let t = Instant::now();
            write_vtu(&self.out_dir.join(&name), &grid)?;
            vtu += t.elapsed().as_secs_f64();
            self.series.push(PvdEntry {
                time: step.step as f64,
                part: 0,
                name: "bodies".into(),
                file: name.into(),
            });
            if !self.model.interface.elements.is_empty() {
                let name = format!("interface_{:04}.vtu", step.step);
                let t = Instant::now();
                write_vtu(
                    &self.out_dir.join(&name),
                    &self.interface.grid(self.model, states),
                )?;
                vtu += t.elapsed().as_secs_f64();
                self.series.push(PvdEntry {
                    time: step.step as f64,
                    part: 1,
                    name: "interface".into(),
                    file: name.into(),
                });
            }
            write_pvd(&self.out_dir.join("results.pvd"), &self.series)?;
        }
        let tables = self.interface.tables(self.model, states);
        for (pair, table) in self.model.interface.pairs.iter().zip(&tables) {
            write_csv(
                &self
                    .out_dir
                    .join(format!("contact_{}_{:04}.csv", pair.name, step.step)),
                table,
            )?;
        }
        let residual = *step.newton.residuals.last().unwrap_or(&0.0);
        let resultants = resultants(self.model, states);
        let mut row = vec![
            step.step as f64,
            step.load_factor,
            step.increments as f64,
            step.newton.iterations as f64,
            residual,
        ];
        row.extend(reactions.iter().flatten());
        row.extend(resultants.iter().flatten());
        self.history.rows.push(row);
        write_csv(&self.out_dir.join("history.csv"), &self.history)?;
        self.summary.push_step(StepSummary {
            step: step.step,
            load_factor: step.load_factor,
            increments: step.increments,
            cutbacks: step.cutbacks,
            iterations: step.newton.iterations,
            residual,
            reactions: Named(
                self.model
                    .supports
                    .iter()
                    .zip(&reactions)
                    .map(|(s, r)| (s.name.clone(), Force { x: r[0], y: r[1] }))
                    .collect(),
            ),
            contact: Named(
                self.model
                    .interface
                    .pairs
                    .iter()
                    .zip(&resultants)
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
        });
        tracing::debug!(
            step = step.step,
            post,
            vtu,
            rest = start.elapsed().as_secs_f64() - post - vtu,
            "output seconds (body recovery, VTU files, interface/CSV/PVD)"
        );
        Ok(reactions)
    }
}
