//! The whole run of a case: mesh (gmsh or an .msh file) → model → load steps → output files.
//! Each phase is timed under its name; the numbers end up in the [`RunSummary`].
//!
//! The jobs are split by what they own: [`folder`] every file name of a run and the manifest
//! of what it wrote (the only place that creates, lists or removes run files), `writer` the
//! files of each converged step, `history` the columns of `history.csv`, `summary`
//! `summary.json`, `info` `run.json`, [`progress`] the progress bar and the log sinks; this
//! file strings mesh, model, stepping and writer together.
//!
//! Files written to the output folder (README "Output"):
//! - `run_files.txt`: the manifest, every file below that the run wrote (see [`folder`]);
//! - `log.txt`: the log, at INFO level or more detailed;
//! - `run.json`: what made the results — the case file's text, program version,
//!   command line, start and end, host, threads;
//! - `mesh.msh` when the case meshes a `.geo` script;
//! - per output frame `frame_NNNN.vtm`, which `results.pvd` lists (time = step number, since
//!   load factors may go down again when unloading): the frame's bodies and contact pairs by
//!   name, each cell in one VTU file — `bodies_NNNN.vtu` for a model of one body, else
//!   `bodies_NNNN_K.vtu` per body — with the nodal reaction forces and the step's FieldData
//!   (`TimeValue`, `step`, `load_factor`), see [`crate::post::step_grids`];
//! - when the case has contact pairs, `interface_NNNN.vtu` (one pair) or
//!   `interface_NNNN_K.vtu` (per pair): the contact fields and the side-B displacement on the
//!   interface;
//! - `contact_<pair>_NNNN.csv`: the contact fields along each pair's curve;
//! - `history.csv`: a step-0 row, then per step the pseudo-time, the global and per-load
//!   factors, increments, cut-backs, Newton iterations, final residual, the reaction force
//!   of every support, the resultant forces of every contact pair and the case's
//!   `[[history]]` quantities;
//! - `restart.bin` ([`crate::output::restart`]): the state of the last converged increment,
//!   from which `--resume` continues, with the length and checksum of every growing table;
//!   `restart_energy.bin`, the energy marks of the cycle ends it grows by (kept out of the
//!   record so that the record's size does not grow with the run);
//! - `hysteresis_<pair>.csv`, `point_loops_<pair>.csv`, `cycles.csv`, `wear_<pair>.csv`: the
//!   fretting tables ([`crate::post::fretting`]);
//! - `summary.json` ([`Summary`]): the model size, every converged step, totals and timings,
//!   and whether the run converged or failed (with the error), for scripts.
//!
//! A step's files are committed together: its VTU and CSV files first (each replaced
//! atomically), then the new rows appended to the growing tables (`history.csv`, the fretting
//! tables), then the restart record, and last `results.pvd` (rewritten while short, then each
//! time it grows by an eighth, and at the end); a run killed at any moment leaves complete
//! files but perhaps a partial last row, which `--resume` cuts back to the record's lengths,
//! and the series lists only steps whose files exist.
//! When a step fails after some of its sub-increments converged, the last of them is written
//! as that step (its fractional pseudo-time in `history.csv` and `results.pvd` tells it apart).

pub mod folder;
mod history;
mod info;
pub mod progress;
mod summary;
mod writer;

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::config::{Case, LinearSolverKind, SolverSpec};
use crate::mesh::{Mesh, gmsh, msh};
use crate::model::{Model, ModelSpec};
use crate::output::restart::{ContinuumStates, Record, read_record};
use crate::output::summary::Summary;
use crate::solver::newton::{LinearSolver, NewtonSettings};
use crate::solver::state::{RunStatistics, Solution, StepResult};
use crate::solver::stepping::run_steps_from;
use crate::{Error, Result};
use folder::{FolderPlan, OutputFolder, OutputMode, RunFile};
use info::RunInfo;
use summary::{
    analysis_steps, complete_summary, describe_model, write_summary, write_summary_after_failure,
};
use writer::{StepWriter, traced_points};

/// What a run did, for the closing summary.
#[derive(Clone, Debug)]
pub struct RunSummary {
    pub out_dir: PathBuf,
    pub nodes: usize,
    pub cells: usize,
    /// Unknowns (free degrees of freedom).
    pub dofs: usize,
    pub mesh_seconds: f64,
    /// The part of `mesh_seconds` spent in gmsh (`None`: the case names a `.msh` file).
    pub gmsh_seconds: Option<f64>,
    pub model_seconds: f64,
    pub stats: RunStatistics,
    /// Reaction of each support at the last step: (name, force and, with twist, torque).
    pub reactions: Vec<(String, crate::output::summary::Force)>,
}

/// The conduction's part of the closing summary's times: only a run with conducting bodies
/// has it.
fn conduction_phase(work: &crate::solver::conduction::ConductionWork) -> String {
    if work.factorisation.calls > 0 {
        format!(", conduction {:.3}", work.seconds())
    } else {
        String::new()
    }
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
            "time [s]: mesh {:.3}{}, model {:.3}, ordering+symbolic {:.3}, assembly {:.3}, factorisation {:.3}, solve {:.3}, output {:.3}{}",
            self.mesh_seconds,
            self.gmsh_seconds
                .map_or(String::new(), |g| format!(" (gmsh {g:.3})")),
            self.model_seconds,
            s.symbolic_seconds,
            s.assembly_seconds,
            s.factorization_seconds,
            s.solve_seconds,
            s.output_seconds,
            conduction_phase(&s.work.conduction)
        )?;
        for (name, r) in &self.reactions {
            write!(
                f,
                "reaction '{name}': Fx = {:.6e} N, Fy = {:.6e} N",
                r.x, r.y
            )?;
            match r.torque {
                Some(t) => writeln!(f, ", T = {t:.6e} N·mm")?,
                None => writeln!(f)?,
            }
        }
        let series = self.out_dir.join(RunFile::Series.name());
        write!(f, "results: {}", series.display())
    }
}

/// How long obtaining a run's mesh took: in all (gmsh, reading, interface insertion) and in
/// gmsh (`None` when the case names a `.msh` file; 0 when the mesh came from the mesh cache).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MeshTime {
    pub seconds: f64,
    pub gmsh: Option<f64>,
}

/// Obtains the case's mesh: reads its `.msh` file, or meshes its `.geo` script with gmsh into
/// the folder's `mesh.msh` first (or copies it there from the mesh cache,
/// [`crate::mesh::cache`]). Returns the mesh and the seconds spent in gmsh, if it ran.
pub fn load_mesh(case: &Case, folder: &OutputFolder) -> Result<(Mesh, Option<f64>)> {
    let (path, gmsh_seconds) = match (&case.mesh.file, &case.mesh.geo) {
        (Some(file), _) => (case.resolve(file), None),
        (None, Some(geo)) => {
            check_parameters(case, &case.resolve(geo))?;
            let params: Vec<(String, f64)> = case
                .mesh
                .parameters
                .iter()
                .map(|(k, v)| (k.clone(), *v))
                .collect();
            let meshed = gmsh::mesh_geo(
                &case.resolve(geo),
                case.mesh.size,
                &params,
                &folder.path(RunFile::Mesh)?,
            )
            .map_err(|e| match e {
                // Stopped while gmsh ran (its probes mesh in a temporary folder).
                Error::Interrupted { step, resume, .. } => Error::Interrupted {
                    step,
                    dir: folder.dir().to_path_buf(),
                    resume,
                },
                e => e,
            })?;
            (meshed.path, Some(meshed.gmsh_seconds))
        }
        (None, None) => {
            return Err(Error::Case {
                path: case.path.clone(),
                message: "[mesh] has no source".into(),
            });
        }
    };
    Ok((msh::read_msh(&path)?, gmsh_seconds))
}

/// Refuses a `[mesh] parameters` name that the `.geo` script never mentions (a misspelt
/// `N_typo` for the script's `n`): gmsh would set it and mesh with the script's own value,
/// silently. A script that includes other files may define it there: then a warning only.
fn check_parameters(case: &Case, geo: &Path) -> Result<()> {
    if case.mesh.parameters.is_empty() || !geo.is_file() {
        return Ok(());
    }
    let bytes = crate::config::read_bounded(geo, "not a gmsh script")?;
    let script = String::from_utf8_lossy(&bytes);
    let is_word = |c: char| c.is_alphanumeric() || c == '_';
    let mentions = |name: &str| {
        script.match_indices(name).any(|(i, _)| {
            let before = script[..i].chars().next_back();
            let after = script[i + name.len()..].chars().next();
            !before.is_some_and(is_word) && !after.is_some_and(is_word)
        })
    };
    for (name, value) in &case.mesh.parameters {
        if mentions(name) {
            continue;
        }
        let reason = format!(
            "the script {} never mentions {name}, so the value would have no effect (a \
             misspelt name?)",
            geo.display()
        );
        if script.contains("Include") {
            tracing::warn!("mesh.parameters.{name}: {reason}, unless a file it includes does");
        } else {
            return Err(Error::InvalidParameter {
                path: case.path.clone(),
                key: format!("mesh.parameters.{name}"),
                value: value.to_string(),
                reason,
            });
        }
    }
    Ok(())
}

/// The output folder of `case` when the command line names none: its `[output] dir`
/// (relative to the case file), else `out/<case file stem>` next to the case file, so that
/// two case files of the same name in different folders never share results.
pub fn default_out_dir(case: &Case) -> PathBuf {
    match &case.output.dir {
        Some(dir) => case.resolve(dir),
        None => case
            .base_dir
            .join("out")
            .join(case.path.file_stem().unwrap_or_default()),
    }
}

/// How [`run_with`] runs a case.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Show a progress bar over the steps.
    pub progress: bool,
    pub mode: OutputMode,
    /// The command line, for `run.json`.
    pub command_line: Vec<String>,
}

/// Runs `case`, writing results to `out_dir`, which must not hold an earlier run's results
/// ([`OutputMode::Fresh`]). `progress` shows a progress bar over the steps.
pub fn run(case: &Case, out_dir: &Path, progress: bool) -> Result<RunSummary> {
    let options = RunOptions {
        progress,
        mode: OutputMode::Fresh,
        command_line: std::env::args().collect(),
    };
    run_with(case, out_dir, &options, |_| Ok(()))
}

/// What a run of `case` may write into its folder and must not touch there.
pub fn folder_plan(case: &Case) -> FolderPlan {
    let inputs = [
        Some(&case.path),
        case.mesh.file.as_ref(),
        case.mesh.geo.as_ref(),
    ];
    FolderPlan {
        pairs: case.contacts.iter().map(|c| c.name()).collect(),
        inputs: inputs
            .into_iter()
            .flatten()
            .map(|p| case.resolve(p))
            .collect(),
        meshes: case.mesh.file.is_none() && case.mesh.geo.is_some(),
    }
}

/// Runs `case` into `out_dir` as `options` say: checks the case, takes over the folder
/// ([`OutputFolder::open`]), writes `run.json`, meshes, solves and writes every converged
/// increment's files and restart record.
/// `folder_ready` is called once the folder is the run's (an earlier run's results refused or
/// removed), before anything else is written: the CLI opens its `log.txt` there.
pub fn run_with(
    case: &Case,
    out_dir: &Path,
    options: &RunOptions,
    folder_ready: impl FnOnce(&OutputFolder) -> Result<()>,
) -> Result<RunSummary> {
    let spec = ModelSpec::new(case)?; // bad parameters fail before gmsh runs
    check_history(case)?;
    let case_text = std::fs::read_to_string(&case.path).map_err(|e| Error::io(&case.path, e))?;
    let folder = OutputFolder::open(out_dir, options.mode, &folder_plan(case))?;
    if folder.resumable() {
        // A record of another case refuses the resume before the earlier run's files (its
        // summary, run.json, log and mesh) are touched.
        let record = folder.dir().join(RunFile::Restart.name());
        crate::output::restart::check_record(&record, &case_text)?;
    }
    folder_ready(&folder)?;
    let info = RunInfo::new(case, &case_text, options);
    info.write(&folder)?;
    let info = std::cell::RefCell::new(info);
    let restart = Restart {
        case_text,
        resume: folder.resumable(),
    };
    let result = mesh_case(case, &folder).and_then(|(mesh, mesh_time)| {
        let session = Session {
            folder: &folder,
            progress: options.progress,
            restart: Some(&restart),
            info: Some(&info),
        };
        run_session(case, spec, mesh, mesh_time, &session, |_, _| Ok(()))
    });
    let mut info = info.into_inner();
    info.finish(&result);
    if let Err(e) = info.write(&folder) {
        tracing::warn!("{e}");
    }
    result
}

/// Obtains the case's mesh into `folder` ([`load_mesh`]) and the seconds it took. If that
/// fails, the folder's `summary.json` says so (status `failed`, the error, no model).
pub fn mesh_case(case: &Case, folder: &OutputFolder) -> Result<(Mesh, MeshTime)> {
    let t = Instant::now();
    match load_mesh(case, folder) {
        Ok((mesh, gmsh)) => Ok((
            mesh,
            MeshTime {
                seconds: t.elapsed().as_secs_f64(),
                gmsh,
            },
        )),
        Err(e) => {
            let mut summary = Summary::new(&case.path);
            summary.seconds.mesh = t.elapsed().as_secs_f64();
            summary.seconds.total = summary.seconds.mesh;
            summary.fail(&e);
            write_summary_after_failure(&summary, folder);
            Err(e)
        }
    }
}

/// Runs `case` on an already loaded `mesh` (from [`load_mesh`], which took `mesh_time`),
/// writing results to `folder`, and calls `on_step` with the model and every converged step
/// once its files are committed to the background writer (e.g. to evaluate quantities in
/// memory; an error stops the run).
/// `summary.json` is written whether the run converges or fails. No restart record is kept
/// (a convergence study's levels are not resumed).
pub fn run_mesh(
    case: &Case,
    mesh: Mesh,
    mesh_time: MeshTime,
    folder: &OutputFolder,
    progress: bool,
    on_step: impl FnMut(&Model, &StepResult) -> Result<()>,
) -> Result<RunSummary> {
    let spec = ModelSpec::new(case)?;
    run_model(case, spec, mesh, mesh_time, folder, progress, on_step)
}

/// [`run_mesh`] with the model's spec already made from `case` (by [`ModelSpec::new`]).
pub fn run_model(
    case: &Case,
    spec: ModelSpec,
    mesh: Mesh,
    mesh_time: MeshTime,
    folder: &OutputFolder,
    progress: bool,
    on_step: impl FnMut(&Model, &StepResult) -> Result<()>,
) -> Result<RunSummary> {
    check_history(case)?;
    let session = Session {
        folder,
        progress,
        restart: None,
        info: None,
    };
    run_session(case, spec, mesh, mesh_time, &session, on_step)
}

/// Where and how a run writes: its folder, the progress bar, the restart records (none
/// for a study's levels) and `run.json` (none for a study's levels), which records what the
/// model building chose.
struct Session<'a> {
    folder: &'a OutputFolder,
    progress: bool,
    restart: Option<&'a Restart>,
    info: Option<&'a std::cell::RefCell<RunInfo>>,
}

/// A run that keeps restart records: the case file's text they are checked against, and
/// whether to continue from the one on disk.
struct Restart {
    case_text: String,
    resume: bool,
}

/// Solves and writes the summary, also when the run fails.
fn run_session(
    case: &Case,
    spec: ModelSpec,
    mesh: Mesh,
    mesh_time: MeshTime,
    session: &Session,
    on_step: impl FnMut(&Model, &StepResult) -> Result<()>,
) -> Result<RunSummary> {
    let start = Instant::now();
    let mut summary = Summary::new(&case.path);
    summary.seconds.mesh = mesh_time.seconds;
    summary.seconds.gmsh = mesh_time.gmsh;
    let steps = analysis_steps(&spec.schedule);
    let result = solve(case, spec, mesh, session, &mut summary, on_step);
    summary.seconds.total = mesh_time.seconds + start.elapsed().as_secs_f64();
    match &result {
        Ok(run) => {
            complete_summary(&mut summary, run);
            write_summary(&summary, &steps, session.folder)?;
        }
        Err(e) => {
            summary.fail(e);
            if let Err(e) = write_summary(&summary, &steps, session.folder) {
                tracing::warn!("{e}");
            }
        }
    }
    result
}

/// The model, the load steps and their files: the work of [`run_session`], which writes the
/// summary.
fn solve(
    case: &Case,
    spec: ModelSpec,
    mesh: Mesh,
    session: &Session,
    summary: &mut Summary,
    on_step: impl FnMut(&Model, &StepResult) -> Result<()>,
) -> Result<RunSummary> {
    let folder = session.folder;
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
    if let Some(info) = session.info {
        info.borrow_mut().penalty_defaults = model.penalty_defaults.clone();
        info.borrow().write(folder)?;
    }
    let record = match session.restart {
        Some(r) if r.resume => Some(resume_record(&model, folder, &r.case_text)?),
        _ => None,
    };
    let settings = newton_settings(&case.solver);
    history::HistoryLayout::check_unique(case, &model)?;
    let traced = traced_points(case, &model)?;
    let mut writer = StepWriter::new(case, &model, session, summary, traced, on_step);
    let resume = match record {
        Some(record) => Some(writer.restore(record)?),
        None => {
            writer.write_start()?;
            None
        }
    };
    let mut stats = run_steps_from(&model, &settings, resume, &mut writer)?.1;
    stats.add_output(writer.finish()?, false);
    writer.bar.finish();
    Ok(RunSummary {
        out_dir: folder.dir().to_path_buf(),
        nodes: model.mesh.nodes.len(),
        cells: model.continuum.cells.len(),
        dofs: model.dofs.free_count(),
        mesh_seconds: writer.summary.seconds.mesh,
        gmsh_seconds: writer.summary.seconds.gmsh,
        model_seconds,
        stats,
        reactions: model
            .supports
            .iter()
            .map(|s| s.name.clone())
            .zip(writer.last_reactions)
            .collect(),
    })
}

/// The restart record in `folder` for resuming `model` (the folder has one: it was opened as
/// [`OutputFolder::resumable`]).
fn resume_record(model: &Model, folder: &OutputFolder, case_text: &str) -> Result<Record> {
    let path = folder.dir().join(RunFile::Restart.name());
    let states = ContinuumStates::of(model);
    read_record(&path, case_text, &Solution::new(model), states)
}

/// What `asperity check` checks of a built model beyond the model itself: the case's
/// `[[history]]` requests, and that they name columns of their own.
pub fn check_history_of(case: &Case, model: &Model) -> Result<()> {
    check_history(case)?;
    history::HistoryLayout::check_unique(case, model)
}

/// Checks the case's `[[history]]` requests as the quantities they are.
fn check_history(case: &Case) -> Result<()> {
    crate::config::history::check(case)
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
        interface_iterations: spec.interface_iterations,
    }
}
