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
//! Differences below 1e-10 of the values are round-off: such a quantity is exact on every
//! level (an order cannot be measured and is not checked).
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
//! Up to `jobs` levels (default: the number of cores) run at once, finest first. After
//! meshing, a level's memory is estimated as [`BYTES_PER_UNKNOWN`] × 2 × nodes and reserved
//! from a budget of half of `MemAvailable` in `/proc/meminfo` (unlimited where that cannot be
//! read): a level starts only when its estimate fits next to the levels running, and a
//! level whose estimate exceeds the whole budget runs alone. Meshing first gives the exact
//! size of a level, so no extrapolation from the coarser level is needed.

use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

mod analysis;
mod report;
mod schedule;

pub use analysis::{Convergence, Criteria, analyse};
pub use report::{Level, Report};
pub use schedule::{BYTES_PER_UNKNOWN, available_memory};

use crate::config::{Case, QuantitySpec};
use crate::output::atomic::write_atomically;
use crate::pipeline;
use crate::post::quantities::evaluate;
use crate::{Error, Result};
use report::{plot, write_table};
use schedule::MemoryGate;

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
    let jobs = options
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .clamp(1, n);
    let gate = MemoryGate::new(available_memory().map_or(u64::MAX, |m| m / 2));
    let queue = Mutex::new((0..n).collect::<Vec<usize>>()); // popped finest first
    let cancel = AtomicBool::new(false);
    // Progress lines as the levels finish, on a terminal only (the report lists them anyway).
    let terminal = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let results: Mutex<Vec<Option<Result<Level>>>> = Mutex::new((0..n).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| {
                loop {
                    let Some(k) = queue.lock().expect("queue").pop() else {
                        break;
                    };
                    if cancel.load(Ordering::Relaxed) {
                        break;
                    }
                    let result = run_level(case, &quantities, options, k, &gate);
                    match &result {
                        Ok(l) => {
                            let line = format!(
                                "level {k}: size {:.6}, {} unknowns, {:.2} s",
                                l.size, l.unknowns, l.seconds
                            );
                            tracing::info!("{line}");
                            if terminal {
                                eprintln!("{line}");
                            }
                        }
                        Err(_) => cancel.store(true, Ordering::Relaxed),
                    }
                    results.lock().expect("results")[k] = Some(result);
                }
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
            analyse(&q, &h, options.ratio, &Criteria::from(&quantities[i]))
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

/// Meshes, solves and evaluates level `k`.
fn run_level(
    case: &Case,
    quantities: &[QuantitySpec],
    options: &Options,
    k: usize,
    gate: &MemoryGate,
) -> Result<Level> {
    let start = Instant::now();
    let mut case = case.clone();
    case.mesh.size = level_size(&case, options.ratio, k);
    let dir = options.out.join(format!("level_{k}"));
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let mesh = pipeline::load_mesh(&case, &dir)?;
    let mesh_seconds = start.elapsed().as_secs_f64();
    let estimate = BYTES_PER_UNKNOWN * 2 * mesh.nodes.len() as u64;
    let _permit = gate.acquire(k, estimate);
    let mut values = None;
    let summary = pipeline::run_mesh(&case, mesh, mesh_seconds, &dir, false, |model, step| {
        if step.step == model.schedule.steps() {
            values = Some(evaluate(quantities, model, step)?);
        }
        Ok(())
    })?;
    let summary_path = dir.join("summary.txt");
    write_atomically(&summary_path, |w| writeln!(w, "{summary}"))?;
    Ok(Level {
        level: k,
        size: case.mesh.size,
        unknowns: summary.dofs,
        seconds: start.elapsed().as_secs_f64(),
        values: values.expect("the last step was evaluated"),
    })
}
