//! The whole run of a case: mesh (gmsh or an .msh file) → model → load steps → output files.
//! Each phase is timed under its name; the numbers end up in the [`RunSummary`].
//!
//! Files written to the output folder (README "Output"):
//! - `run.json` ([`RunInfo`]): what made the results — the case file's text, program version,
//!   command line, start and end, host, threads;
//! - `mesh.msh` when the case meshes a `.geo` script;
//! - `bodies_NNNN.vtu` per converged step and `results.pvd` listing them (time = step
//!   number, since load factors may go down again when unloading), with the nodal reaction
//!   forces and the step's FieldData (`TimeValue`, `step`, `load_factor`), see
//!   [`step_grids`];
//! - `interface_NNNN.vtu` (when the case has contact pairs): the contact fields and the
//!   side-B displacement on the interface, listed in `results.pvd` as a second part;
//! - `contact_<pair>_NNNN.csv`: the contact fields along each pair's curve;
//! - `history.csv`: a step-0 row, then per step the pseudo-time, the global and per-load
//!   factors, increments, cut-backs, Newton iterations, final residual, the reaction force
//!   of every support, the resultant forces of every contact pair and the case's
//!   `[[history]]` quantities;
//! - `restart.bin` ([`crate::output::restart`]): the state of the last converged increment,
//!   from which `--resume` continues;
//! - `summary.json` ([`Summary`]): the model size, every converged step, totals and timings,
//!   and whether the run converged or failed (with the error), for scripts.
//!
//! A step's files are committed together: its VTU and CSV files first, then the restart
//! record, then `history.csv`, and last `results.pvd`, each replaced atomically; a run killed
//! at any moment leaves complete files, and the indexes list only steps whose files exist.
//! When a step fails after some of its sub-increments converged, the last of them is written
//! as that step (its fractional pseudo-time in `history.csv` and `results.pvd` tells it apart).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use indicatif::ProgressBar;

use crate::config::{Case, CycleFrames, LinearSolverKind, SolverSpec};
use crate::element::Analysis;
use crate::mesh::{Mesh, gmsh, msh};
use crate::model::{Model, ModelSpec, Schedule};
use crate::output::atomic::write_text;
use crate::output::csv::{CsvTable, GrowingCsv};
use crate::output::pvd::PvdEntry;
use crate::output::restart::{
    Content, OutputView, RESTART_FILE, Record, RecordWriter, read_record,
};
use crate::output::summary::{
    ContactResultant, EnergyMark, Force, ModelSize, Named, Status, StepSummary, Summary,
};
use crate::post::fretting::{FrettingTables, TracedPoint, is_fretting_file, trace_point};
use crate::post::interface::{InterfaceOutput, resultants};
use crate::post::quantities::evaluate;
use crate::post::{BodyPoints, StepInfo, reactions, step_grids};
use crate::solver::newton::{LinearSolver, NewtonLog, NewtonSettings};
use crate::solver::stepping::{
    Observer, Progress, Resume, RunStatistics, Solution, StepResult, run_steps_from,
};
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

/// How a run treats an output folder that holds the files of an earlier run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OutputMode {
    /// Refuse ([`Error::OutputExists`]): results are never overwritten by accident.
    #[default]
    Fresh,
    /// Remove the earlier run's files (and only those, [`is_run_file`]) first.
    Force,
    /// Continue the earlier run from its restart record; start over when it has none (it
    /// was stopped before its first increment converged).
    Resume,
}

impl OutputMode {
    /// The mode of the command line's `--force` and `--resume` (exclusive).
    pub fn from_flags(force: bool, resume: bool) -> Self {
        match (force, resume) {
            (true, _) => OutputMode::Force,
            (false, true) => OutputMode::Resume,
            (false, false) => OutputMode::Fresh,
        }
    }
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

/// Runs `case` into `out_dir` as `options` say: checks the case, prepares the folder
/// ([`OutputMode`]), writes `run.json`, meshes, solves and writes every converged increment's
/// files and restart record.
/// `folder_ready` is called once `out_dir` is the run's (an earlier run's results refused or
/// removed), before anything else is written: the CLI opens its `log.txt` there.
pub fn run_with(
    case: &Case,
    out_dir: &Path,
    options: &RunOptions,
    folder_ready: impl FnOnce(&Path) -> Result<()>,
) -> Result<RunSummary> {
    let spec = ModelSpec::new(case)?; // bad parameters fail before gmsh runs
    check_history(case)?;
    let case_text = std::fs::read_to_string(&case.path).map_err(|e| Error::io(&case.path, e))?;
    prepare_output(out_dir, options.mode)?;
    folder_ready(out_dir)?;
    let mut info = RunInfo::new(case, &case_text, options);
    info.write(out_dir)?;
    let restart = Restart {
        case_text,
        resume: options.mode == OutputMode::Resume,
    };
    let result = mesh_case(case, out_dir).and_then(|(mesh, mesh_seconds)| {
        let session = Session {
            out_dir,
            progress: options.progress,
            restart: Some(&restart),
        };
        run_session(case, spec, mesh, mesh_seconds, &session, |_, _| Ok(()))
    });
    info.finish(&result);
    if let Err(e) = info.write(out_dir) {
        tracing::warn!("{e}");
    }
    result
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
/// once its files are committed to the background writer (e.g. to evaluate quantities in
/// memory; an error stops the run).
/// `summary.json` is written whether the run converges or fails. No restart record is kept
/// (a convergence study's levels are not resumed).
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
    check_history(case)?;
    let session = Session {
        out_dir,
        progress,
        restart: None,
    };
    run_session(case, spec, mesh, mesh_seconds, &session, on_step)
}

/// Where and how a run writes: its folder, the progress bar, and the restart records (none
/// for a study's levels).
struct Session<'a> {
    out_dir: &'a Path,
    progress: bool,
    restart: Option<&'a Restart>,
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
    mesh_seconds: f64,
    session: &Session,
    on_step: impl FnMut(&Model, &StepResult) -> Result<()>,
) -> Result<RunSummary> {
    let start = Instant::now();
    let out_dir = session.out_dir;
    let mut summary = Summary::new(&case.path);
    summary.seconds.mesh = mesh_seconds;
    let steps = analysis_steps(&spec.schedule);
    let result = solve(case, spec, mesh, session, &mut summary, on_step);
    summary.seconds.total = mesh_seconds + start.elapsed().as_secs_f64();
    match &result {
        Ok(run) => {
            complete_summary(&mut summary, run);
            write_summary(&summary, &steps, out_dir)?;
        }
        Err(e) => {
            summary.fail(e);
            if let Err(e) = write_summary(&summary, &steps, out_dir) {
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
    let out_dir = session.out_dir;
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
    let record = match session.restart {
        Some(r) if r.resume => resume_record(&model, out_dir, &r.case_text)?,
        _ => None,
    };
    let settings = newton_settings(&case.solver);
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
    stats.output_seconds += writer.finish()?;
    writer.bar.finish();
    Ok(RunSummary {
        out_dir: out_dir.to_path_buf(),
        nodes: model.mesh.nodes.len(),
        cells: model.continuum.cells.len(),
        dofs: model.dofs.free_count(),
        mesh_seconds: writer.summary.seconds.mesh,
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

/// The restart record in `out_dir` for resuming `model`, or `None` (with a warning) when
/// there is none: the run then starts over.
fn resume_record(model: &Model, out_dir: &Path, case_text: &str) -> Result<Option<Record>> {
    let path = out_dir.join(RESTART_FILE);
    if !path.is_file() {
        tracing::warn!(
            "{}: no restart record (the run stopped before its first increment converged); \
             starting from the beginning",
            path.display()
        );
        return Ok(None);
    }
    read_record(&path, case_text, &Solution::new(model)).map(Some)
}

/// Checks the case's `[[history]]` requests as the quantities they are.
fn check_history(case: &Case) -> Result<()> {
    crate::config::history::check(case)
}

// --- the output folder ------------------------------------------------------------------------

/// Names of the single files a run writes (besides the per-step ones, [`is_run_file`]).
/// `log.txt` is not among them: the logging set-up opens it before the run starts.
const RUN_FILES: [&str; 6] = [
    "run.json",
    "summary.json",
    "results.pvd",
    "history.csv",
    "mesh.msh",
    RESTART_FILE,
];

/// Whether `name` is a file a run writes: one of `RUN_FILES`, a step's file
/// (`bodies_NNNN.vtu`, `interface_NNNN.vtu`, `contact_<pair>_NNNN.csv`), or the hidden
/// temporary file of one of these that a killed run left (`.NAME.XXXXXX.tmp`).
pub fn is_run_file(name: &str) -> bool {
    step_of_file(name).is_some()
        || RUN_FILES.contains(&name)
        || is_fretting_file(name)
        || temporary_of(name).is_some()
}

/// The step number of a step's file name.
fn step_of_file(name: &str) -> Option<usize> {
    let digits = match name
        .strip_prefix("contact_")
        .and_then(|r| r.strip_suffix(".csv"))
    {
        Some(rest) => match rest.rsplit_once('_') {
            Some((pair, digits)) if !pair.is_empty() => digits,
            _ => return None,
        },
        None => ["bodies_", "interface_"]
            .iter()
            .find_map(|p| name.strip_prefix(p)?.strip_suffix(".vtu"))?,
    };
    if digits.len() >= 4 && digits.bytes().all(|b| b.is_ascii_digit()) {
        digits.parse().ok()
    } else {
        None
    }
}

/// The run file whose temporary file `name` is ([`crate::output`]'s atomic writer names them
/// `.NAME.XXXXXX.tmp`).
fn temporary_of(name: &str) -> Option<&str> {
    let inner = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (target, _random) = inner.rsplit_once('.')?;
    (step_of_file(target).is_some() || RUN_FILES.contains(&target)).then_some(target)
}

/// The run files in `dir` (none if it does not exist).
fn run_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let entries = match std::fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(Error::io(dir, e)),
    };
    let mut files = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let name = entry.file_name();
        if name.to_str().is_some_and(is_run_file) && entry.path().is_file() {
            files.push(entry.path());
        }
    }
    files.sort();
    Ok(files)
}

/// Prepares `dir` for a run in `mode`: refuses a folder with an earlier run's files
/// (`Fresh`), removes them (`Force`, and `Resume` without a restart record), or removes only
/// the temporary files a killed run left (`Resume`). Other files are never touched.
pub fn prepare_output(dir: &Path, mode: OutputMode) -> Result<()> {
    let files = run_files(dir)?;
    let resumable = dir.join(RESTART_FILE).is_file();
    let remove = |keep: &dyn Fn(&str) -> bool| -> Result<()> {
        for f in &files {
            let name = f.file_name().and_then(|n| n.to_str()).unwrap_or_default();
            if !keep(name) {
                std::fs::remove_file(f).map_err(|e| Error::io(f, e))?;
            }
        }
        Ok(())
    };
    match mode {
        OutputMode::Fresh if !files.is_empty() => Err(Error::OutputExists {
            dir: dir.to_path_buf(),
            files: files.len(),
            example: files[0]
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        }),
        OutputMode::Fresh => Ok(()),
        OutputMode::Resume if resumable => remove(&|name| temporary_of(name).is_none()),
        OutputMode::Force | OutputMode::Resume => remove(&|_| false),
    }
}

/// Removes the files of steps from `first` on (written after the restart record a run
/// resumes from, or of a step that failed).
fn remove_step_files(dir: &Path, first: usize) -> Result<()> {
    for f in run_files(dir)? {
        let name = f.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        if step_of_file(name).is_some_and(|s| s >= first) {
            std::fs::remove_file(&f).map_err(|e| Error::io(&f, e))?;
        }
    }
    Ok(())
}

// --- run.json ---------------------------------------------------------------------------------

/// The contents of `run.json`: what made the results in the folder.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RunInfo {
    /// `asperity`.
    pub program: &'static str,
    pub version: &'static str,
    pub command_line: Vec<String>,
    /// The case file (absolute where it can be made so) and its text.
    pub case_file: PathBuf,
    pub case: String,
    /// The folder the command ran in.
    pub working_directory: Option<PathBuf>,
    /// UTC, RFC 3339.
    pub start: String,
    /// `null` while the run goes on (or if it was killed).
    pub end: Option<String>,
    pub host: String,
    /// Threads of the parallel assembly and solves.
    pub threads: usize,
    /// Whether the run continued from a restart record.
    pub resumed: bool,
    /// `running`, `converged` or `failed`.
    pub status: &'static str,
    pub error: Option<String>,
}

impl RunInfo {
    fn new(case: &Case, case_text: &str, options: &RunOptions) -> Self {
        Self {
            program: "asperity",
            version: env!("CARGO_PKG_VERSION"),
            command_line: options.command_line.clone(),
            case_file: std::path::absolute(&case.path).unwrap_or_else(|_| case.path.clone()),
            case: case_text.to_string(),
            working_directory: std::env::current_dir().ok(),
            start: utc_now(),
            end: None,
            host: host_name(),
            threads: rayon::current_num_threads(),
            resumed: options.mode == OutputMode::Resume,
            status: "running",
            error: None,
        }
    }

    fn finish<T>(&mut self, result: &Result<T>) {
        self.end = Some(utc_now());
        self.status = if result.is_ok() {
            "converged"
        } else {
            "failed"
        };
        self.error = result.as_ref().err().map(ToString::to_string);
    }

    fn write(&self, dir: &Path) -> Result<()> {
        let path = dir.join("run.json");
        let text = serde_json::to_string_pretty(self)
            .map_err(|e| Error::io(&path, std::io::Error::other(e)))?;
        write_text(&path, &text)
    }
}

/// The machine's name (Linux; `unknown` elsewhere).
fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .ok()
        .filter(|h| !h.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "unknown".into())
}

/// The current time as RFC 3339 UTC with seconds (`2026-11-23T12:45:48Z`).
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rest) = (secs / 86_400, secs % 86_400);
    let (y, m, d) = civil_from_days(days as i64);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rest / 3600,
        rest % 3600 / 60,
        rest % 60
    )
}

/// The proleptic Gregorian date of a day count since 1970-01-01 (H. Hinnant's
/// `civil_from_days`).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
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
    let steps = model.schedule.timeline().steps();
    summary.energy.step_names = steps.iter().map(|plan| plan.name.clone()).collect();
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

/// One analysis step in `summary.json` (`"analysis_steps"`): a `[steps]` schedule is one
/// step of its steps' increments.
#[derive(Clone, Debug, serde::Serialize)]
struct AnalysisStepSummary {
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
fn analysis_steps(schedule: &Schedule) -> Vec<AnalysisStepSummary> {
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

/// Writes `out_dir/summary.json` (atomically).
fn write_summary(
    summary: &Summary,
    analysis_steps: &[AnalysisStepSummary],
    out_dir: &Path,
) -> Result<()> {
    let path = out_dir.join("summary.json");
    let file = SummaryFile {
        summary,
        analysis_steps,
    };
    let json = serde_json::to_string_pretty(&file)
        .map_err(|e| Error::io(&path, std::io::Error::other(e)))?;
    write_text(&path, &(json + "\n"))
}

/// Writes the summary of a failed run; a failure to write it is logged, since the run's own
/// error is the one to report.
fn write_summary_after_failure(summary: &Summary, out_dir: &Path) {
    if let Err(e) = write_summary(summary, &[], out_dir) {
        tracing::warn!("{e}");
    }
}

/// The progress bar of the run in progress, if it is drawn: [`LogToStderr`] writes log lines
/// through it.
static ACTIVE_BAR: Mutex<Option<ProgressBar>> = Mutex::new(None);

/// stderr for log lines (`tracing_subscriber`'s `with_writer(|| LogToStderr)`): while a run
/// draws its progress bar on the terminal, each line is written with the bar hidden and the
/// bar redrawn below it ([`ProgressBar::suspend`]), so that lines and bar do not interleave.
/// Without a bar (stderr not a terminal, `-q`, no run) it is plain stderr.
pub struct LogToStderr;

impl Write for LogToStderr {
    fn write(&mut self, line: &[u8]) -> std::io::Result<usize> {
        let bar = ACTIVE_BAR.lock().unwrap_or_else(|e| e.into_inner()).clone();
        write_log_line(bar.as_ref(), &mut std::io::stderr(), line)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        std::io::stderr().flush()
    }
}

/// Writes a log `line` to `out`, with `bar` (when there is one) hidden meanwhile.
pub fn write_log_line(
    bar: Option<&ProgressBar>,
    out: &mut impl Write,
    line: &[u8],
) -> std::io::Result<usize> {
    match bar {
        Some(bar) => bar.suspend(|| out.write_all(line))?,
        None => out.write_all(line)?,
    }
    Ok(line.len())
}

/// The run's progress bar, registered for [`LogToStderr`] while it lives; dropping it (at the
/// end of the run, also a failed one) clears it from the terminal.
struct RunBar(ProgressBar);

impl RunBar {
    /// Clears the bar from the terminal; log lines go straight to stderr again.
    fn finish(&self) {
        *ACTIVE_BAR.lock().unwrap_or_else(|e| e.into_inner()) = None;
        self.0.finish_and_clear();
    }
}

impl Drop for RunBar {
    fn drop(&mut self) {
        self.finish();
    }
}

fn progress_bar(enabled: bool, steps: usize) -> RunBar {
    if !enabled {
        return RunBar(ProgressBar::hidden());
    }
    let bar = ProgressBar::new(steps as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} step {pos}/{len} [{elapsed_precise}] {wide_bar} {msg}",
        )
        .expect("valid progress template"),
    );
    *ACTIVE_BAR.lock().unwrap_or_else(|e| e.into_inner()) = Some(bar.clone());
    RunBar(bar)
}

/// The columns of `history.csv` before the reactions: where each value of a row is, so that
/// the summary's step records can be read back from the rows a restart record keeps.
struct HistoryLayout {
    /// Per-load factors: the amplitude of each support and load that has its own history.
    load_factors: Vec<usize>,
    supports: usize,
    pairs: usize,
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
    fn new(case: &Case, model: &Model) -> (Self, Vec<String>) {
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
        };
        (layout, columns)
    }

    /// The row of a state at pseudo-time `time`.
    fn row(
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
    fn step_summary(&self, model: &Model, row: &[f64]) -> StepSummary {
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

/// Writes the files of each converged step and the restart record of each converged
/// increment, keeps the series and history up to date, and records the steps in the
/// summary.
struct StepWriter<'m, 's, F> {
    case: &'m Case,
    model: &'m Model,
    points: BodyPoints,
    interface: InterfaceOutput,
    out_dir: PathBuf,
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
    summary: &'s mut Summary,
    last_reactions: Vec<[f64; 2]>,
    bar: RunBar,
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
fn traced_points(case: &Case, model: &Model) -> Result<Vec<Vec<TracedPoint>>> {
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
    fn new(
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
            out_dir: session.out_dir.to_path_buf(),
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
    fn write_start(&mut self) -> Result<()> {
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
    fn restore(&mut self, record: Record) -> Result<Resume> {
        let Record { resume, output } = record;
        let mut tables = output.tables.into_iter();
        let missing = |what: &str| Error::Restart {
            path: self.out_dir.join(RESTART_FILE),
            reason: format!("the record has no {what} table"),
        };
        let history = tables.next().ok_or_else(|| missing("history"))?;
        let energy = tables.next().ok_or_else(|| missing("energy"))?;
        self.fretting
            .restore(tables.collect())
            .ok_or_else(|| Error::Restart {
                path: self.out_dir.join(RESTART_FILE),
                reason: "its fretting tables do not match the case's contact pairs".into(),
            })?;
        let marks: Option<Vec<EnergyMark>> =
            energy.iter().map(|row| EnergyMark::from_row(row)).collect();
        self.summary.energy.marks = marks.ok_or_else(|| Error::Restart {
            path: self.out_dir.join(RESTART_FILE),
            reason: "its energy rows have the wrong length".into(),
        })?;
        if history
            .iter()
            .any(|row| row.len() != self.history.columns.len())
        {
            return Err(Error::Restart {
                path: self.out_dir.join(RESTART_FILE),
                reason: "its history rows do not match the case's columns".into(),
            });
        }
        self.history_text = GrowingCsv::new(&self.history.columns);
        for row in &history {
            self.history_text
                .push(&self.out_dir.join("history.csv"), row)?;
        }
        self.history.rows = history;
        self.series = output.series;
        for row in self.history.rows.iter().filter(|r| r[0] > 0.0) {
            let step = self.layout.step_summary(self.model, row);
            self.summary.push_step(step);
        }
        remove_step_files(&self.out_dir, resume.state.step)?;
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
    fn step(&mut self, step: &StepResult, progress: Option<&Progress>) -> Result<f64> {
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
        self.bar.0.inc(1);
        self.bar.0.set_message(self.progress_message(step));
        Ok(start.elapsed().as_secs_f64() + std::mem::take(&mut self.increment_seconds))
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
            let parts = [("bodies", Some(bodies)), ("interface", interface)];
            for (part, (name, grid)) in parts.into_iter().enumerate() {
                let Some(grid) = grid else { continue };
                let file = format!("{name}_{:04}.vtu", step.step);
                self.records
                    .queue(self.out_dir.join(&file), Content::Vtu(grid));
                entries.push(PvdEntry {
                    time,
                    part: part as u32,
                    name: name.into(),
                    file: file.into(),
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
            let file = format!("contact_{}_{:04}.csv", pair.name, step.step);
            self.records
                .queue(self.out_dir.join(file), Content::Csv(table));
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
            &self.out_dir.join(RESTART_FILE),
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
            .push(&self.out_dir.join("history.csv"), &row)?;
        self.history.rows.push(row);
        Ok(())
    }

    /// Queues `history.csv`, then `results.pvd`, after the step's files and record, and
    /// commits them: the series is the last file written for a step, so it lists only steps
    /// whose other files are complete.
    fn write_indexes(&mut self) -> Result<()> {
        for (file, content) in self.fretting.contents(self.model) {
            self.records.queue(self.out_dir.join(file), content);
        }
        self.records.queue(
            self.out_dir.join("history.csv"),
            Content::Text(self.history_text.bytes().to_vec()),
        );
        if self.vtu && !self.series.is_empty() {
            self.records.queue(
                self.out_dir.join("results.pvd"),
                Content::Pvd(self.series.clone()),
            );
        }
        self.records.commit()
    }

    /// Waits for the files being written; returns the seconds waited.
    fn finish(&mut self) -> Result<f64> {
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
