//! Mesh-convergence studies (`asperity converge`): a case's `.geo` script is meshed at
//! `levels` sizes, each `ratio` times finer than the one before, every level is solved, the
//! case's quantities of interest are evaluated at the end of the last step, and for each
//! quantity the values, successive differences, observed order of convergence and the
//! Richardson-extrapolated value with an error estimate are reported, checked against the
//! quantity's tolerances and written to `convergence.csv` (and `convergence.png` when a
//! Python with matplotlib is found).
//!
//! ## The numbers
//! Level k = 0 … N−1 is meshed with gmsh size factor h_k = size / r^k (the case's
//! `[mesh] size`, r = `ratio`), so h_k is the mesh size relative to the case's. With the values
//! q_k and differences d_k = q_{k+1} − q_k:
//! - observed order p = ln(|d_{N−3}| / |d_{N−2}|) / ln r from the three finest levels (the
//!   order of the error if q_k = q + C h_k^p);
//! - Richardson extrapolation q∞ = q_f + d_f / (r^p − 1), with q_f the finest value and d_f
//!   the last difference, and the error estimate |q∞ − q_f| of the finest level;
//! - with a reference value, the order fitted to log |q_k − ref| against log h_k over all
//!   levels (least squares), and the relative error |q_f − ref| / |ref| of the finest level.
//!
//! A quantity whose differences do not decrease (p ≤ 0 or not finite), or grow anywhere
//! along the levels (|d_{k+1}| > |d_k|), is *not converged*.
//! Levels are solved to the relative-norm criteria (`[solver] force_tolerance`, default 1e-8)
//! in addition to the engineering ones. Differences below 1e-10 of the values, or below that
//! force tolerance, cannot be told from round-off and solver error: such a quantity is exact on every level (an order cannot be measured and is not
//! checked).
//!
//! ## Checks (exit status)
//! A quantity passes when it converges, the relative change |d_f| / |q_f| between the two
//! finest levels is at most its `tolerance`, the relative error of the finest level against
//! `reference` (if given) is at most `tolerance`, and the observed order p (from the
//! differences) is at least `min_order` (if given). The order fitted to the reference is
//! reported only: a reference that is itself an approximation (a half-space solution for a
//! finite model, say) leaves an error that does not vanish with h.
//!
//! ## Running levels in parallel
//! Up to `jobs` levels (default: the number of cores) are solved at once, finest first, as
//! tasks of one `rayon` scope on the global pool (the pool the assembly and the linear
//! solver share). The calling thread meshes the levels one after another, finest first, and
//! hands each to the pool once it fits: a level's memory is estimated as
//! [`BYTES_PER_UNKNOWN`] × 2 × nodes (meshing first gives the exact size, so no extrapolation
//! from a coarser level is needed) and reserved from a budget of half of the memory available
//! ([`crate::memory`]: the machine's, the cgroup's or the address space's, unlimited where none
//! can be read); a level whose estimate exceeds the whole budget runs alone. Only the calling
//! thread waits for memory, never a pool thread, so a pool thread that picks up another level
//! while it waits inside the solver cannot block the level it interrupted. After a level fails, no further level is started.

use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

mod analysis;
mod report;
mod schedule;

pub use analysis::{Convergence, Criteria, analyse};
pub use report::{Level, Report};
pub use schedule::BYTES_PER_UNKNOWN;

use crate::config::{Case, QuantitySpec};
use crate::mesh::Mesh;
use crate::model::ModelSpec;
use crate::post::quantities::evaluate;
use crate::run::{
    self,
    folder::{self, OutputFolder, OutputMode},
};
use crate::{Error, Result};
use report::{plot, write_table};
use schedule::Gate;

/// Relative size of differences below which they are round-off.
pub const ROUND_OFF: f64 = 1e-10;

/// Settings of a study.
#[derive(Clone, Debug)]
pub struct Options {
    /// Number of mesh levels (at least 3).
    pub levels: usize,
    /// Refinement ratio between successive levels (> 1).
    pub ratio: f64,
    /// Output folder: `level_k/` per level, `convergence.csv`, `convergence.png`.
    pub out: PathBuf,
    /// Quantities from the command line, added to the case's (replacing one of the same name).
    pub quantities: Vec<QuantitySpec>,
    /// Levels solved at once (default: the number of cores).
    pub jobs: Option<usize>,
    /// Make `convergence.png` (needs a Python with matplotlib).
    pub plot: bool,
}

/// The most levels a study may have.
pub const MAX_LEVELS: usize = 20;

/// Runs the study of `case` and writes `convergence.csv` (and `convergence.png`).
pub fn run(case: &Case, options: &Options) -> Result<Report> {
    let start = Instant::now();
    let err = |message: String| Error::Case {
        path: case.path.clone(),
        message,
    };
    if case.mesh.geo.is_none() {
        return Err(err(
            "asperity converge needs a case that meshes a .geo script ([mesh] geo = ...), since only a script \
             can be meshed at other sizes; this case reads a fixed .msh file"
                .into(),
        ));
    }
    if options.levels < 3 {
        return Err(err(format!(
            "--levels {}: the observed order needs at least 3 levels",
            options.levels
        )));
    }
    if options.levels > MAX_LEVELS {
        return Err(err(format!(
            "--levels {}: at most {MAX_LEVELS} (each level's folder is made before the first is \
             meshed; the finest of 20 levels at --ratio 2 has 2^38 times the coarsest's elements)",
            options.levels
        )));
    }
    if !(options.ratio > 1.0 && options.ratio.is_finite()) {
        return Err(err(format!(
            "--ratio {}: the refinement ratio must be greater than 1",
            options.ratio
        )));
    }
    let mut quantities = case.quantities.clone();
    for q in &options.quantities {
        q.check(case).map_err(err)?;
        match quantities.iter_mut().find(|p| p.name == q.name) {
            Some(p) => *p = q.clone(),
            None => quantities.push(q.clone()),
        }
    }
    if quantities.is_empty() {
        return Err(err(
            "no quantities of interest: add [[quantity]] sections to the case or --quantity on the command line"
                .into(),
        ));
    }
    std::fs::create_dir_all(&options.out).map_err(|e| Error::io(&options.out, e))?;
    let n = options.levels;
    // Every level's folder is taken over before any level is meshed, as a run takes over
    // its folder with --force: a refused one leaves the study as it was.
    let mut folders: Vec<Option<OutputFolder>> = (0..n)
        .map(|k| level_folder(case, options, k).map(Some))
        .collect::<Result<_>>()?;

    let jobs = options
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .clamp(1, n);
    let gate = Gate::new(crate::memory::available().map_or(u64::MAX, |m| m / 2), jobs);
    let cancel = AtomicBool::new(false);
    let results: Mutex<Vec<Option<Result<Level>>>> = Mutex::new((0..n).map(|_| None).collect());
    let finish = |k: usize, result: Result<Level>| {
        if result.is_err() {
            cancel.store(true, Ordering::Relaxed);
        }
        results.lock().expect("results")[k] = Some(result);
    };
    rayon::in_place_scope(|scope| {
        let mut finer: Option<(usize, usize)> = None;
        for k in (0..n).rev() {
            if cancel.load(Ordering::Relaxed) {
                break;
            }
            let folder = folders[k].take().expect("each level's folder is used once");
            let meshed = match mesh_level(case, options, k, folder) {
                Ok(meshed) => meshed,
                Err(e) => {
                    finish(k, Err(e));
                    break;
                }
            };
            let nodes = meshed.mesh.nodes.len();
            if let Some((finer_nodes, finer_k)) = finer.filter(|&(f, _)| nodes >= f) {
                finish(
                    k,
                    Err(err(same_mesh(options, k, finer_k, nodes, finer_nodes))),
                );
                break;
            }
            finer = Some((nodes, k));
            let estimate = BYTES_PER_UNKNOWN * 2 * meshed.mesh.nodes.len() as u64;
            let permit = gate.acquire(k, estimate);
            if cancel.load(Ordering::Relaxed) {
                break;
            }
            let (quantities, finish) = (&quantities, &finish);
            scope.spawn(move |_| {
                let result = solve_level(meshed, quantities);
                drop(permit);
                if let Ok(l) = &result {
                    report_level(l);
                }
                finish(k, result);
            });
        }
    });
    let mut levels = Vec::with_capacity(n);
    for (k, r) in results
        .into_inner()
        .expect("results")
        .into_iter()
        .enumerate()
    {
        match r {
            Some(Ok(l)) => levels.push(l),
            Some(Err(e)) => {
                return Err(Error::StudyLevel {
                    case: case.path.clone(),
                    level: k,
                    size: level_size(case, options.ratio, k),
                    source: Box::new(e),
                });
            }
            None => {} // skipped after another level failed
        }
    }
    let h: Vec<f64> = levels.iter().map(|l| l.size).collect();
    let analyses = (0..quantities.len())
        .map(|i| {
            let q: Vec<f64> = levels.iter().map(|l| l.values[i]).collect();
            analyse(
                &q,
                &h,
                options.ratio,
                &Criteria::new(&quantities[i], case.solver.force_tolerance),
            )
        })
        .collect();
    let mut report = Report {
        case: case.path.clone(),
        ratio: options.ratio,
        quantities,
        levels,
        results: analyses,
        csv: options.out.join("convergence.csv"),
        plot: String::new(),
        seconds: 0.0,
    };
    write_table(&report)?;
    report.plot = if options.plot {
        plot(&options.out)
    } else {
        "not made (--no-plot)".into()
    };
    report.seconds = start.elapsed().as_secs_f64();
    Ok(report)
}

fn level_size(case: &Case, ratio: f64, k: usize) -> f64 {
    case.mesh.size / ratio.powi(k as i32)
}

/// Prints that a level is done, on a terminal only (the report lists the levels anyway).
fn report_level(l: &Level) {
    let line = format!(
        "level {}: size {:.6}, {} unknowns, {:.2} s",
        l.level, l.size, l.unknowns, l.seconds
    );
    tracing::info!("{line}");
    if std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        eprintln!("{line}");
    }
}

/// A level with its mesh, ready to be solved.
struct Meshed {
    level: usize,
    case: Case,
    spec: ModelSpec,
    folder: OutputFolder,
    mesh: Mesh,
    mesh_time: run::MeshTime,
}

/// Level `k`'s folder `level_k/`, taken over as a run's with `--force`: only the files an
/// earlier study's run listed are removed, a file of the user's under a run file's name or a
/// symbolic link in a run file's place is refused, and the folder itself must not be a link
/// (the level would be written elsewhere).
fn level_folder(case: &Case, options: &Options, k: usize) -> Result<OutputFolder> {
    let dir = options.out.join(format!("level_{k}"));
    folder::refuse_linked_folder(
        &options.out,
        &dir,
        "a level's folder is a symbolic link, and a study never writes through one: remove \
         it or choose another study folder",
    )?;
    OutputFolder::open(&dir, OutputMode::Force, &run::folder_plan(case))
}

/// Why levels `k` and `finer_k` cannot both be in the study: level `k`'s mesh has no fewer
/// nodes than the finer level's (the script's counts did not follow the size factor).
fn same_mesh(options: &Options, k: usize, finer_k: usize, nodes: usize, finer: usize) -> String {
    format!(
        "level {k} has {nodes} nodes and the finer level {finer_k} {finer}: the mesh did not \
         get finer between them, so their difference says nothing about convergence (a script \
         whose counts round to the same integer at --ratio {}, or fixed counts); use a larger \
         --ratio, or make the script's counts follow the size factor",
        options.ratio
    )
}

/// Meshes level `k` into its `folder`.
fn mesh_level(case: &Case, options: &Options, k: usize, folder: OutputFolder) -> Result<Meshed> {
    let mut case = case.clone();
    case.mesh.size = level_size(&case, options.ratio, k);
    // The study measures discretisation error, which the engineering convergence criteria
    // (answers within ~1e-4 of a tight solve) could hide on fine levels: levels are solved to
    // the relative-norm criteria as well (the case's `force_tolerance`, else 1e-8), which is
    // the analysis' noise floor.
    case.solver.relative_norms = true;
    let spec = ModelSpec::new(&case)?; // bad parameters fail before gmsh runs
    let (mesh, mesh_time) = run::mesh_case(&case, &folder)?;
    Ok(Meshed {
        level: k,
        case,
        spec,
        folder,
        mesh,
        mesh_time,
    })
}

/// Solves a meshed level (its files, with `summary.json`, go to `level_k/`) and evaluates
/// the quantities at the last step.
fn solve_level(meshed: Meshed, quantities: &[QuantitySpec]) -> Result<Level> {
    let start = Instant::now();
    let Meshed {
        level,
        case,
        spec,
        folder,
        mesh,
        mesh_time,
    } = meshed;
    let mut values = None;
    let summary = run::run_model(
        &case,
        spec,
        mesh,
        mesh_time,
        &folder,
        false,
        |model, step| {
            if step.step == model.schedule.steps() {
                values = Some(evaluate(quantities, model, step)?);
            }
            Ok(())
        },
    )?;
    Ok(Level {
        level,
        size: case.mesh.size,
        unknowns: summary.dofs,
        seconds: mesh_time.seconds + start.elapsed().as_secs_f64(),
        values: values.expect("the last step was evaluated"),
    })
}
