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

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Instant;

use crate::case::{Case, Component, QuantityKind, QuantitySpec, Statistic};
use crate::contact::ContactStatus;
use crate::element::Analysis;
use crate::element::interface6::interface_point;
use crate::model::{INTERFACE_POINTS, Model};
use crate::output::atomic::write_atomically;
use crate::pipeline;
use crate::post::interface::{InterfaceOutput, resultants};
use crate::post::reactions;
use crate::solver::stepping::StepResult;
use crate::{Error, Result};

/// Memory estimate per unknown for scheduling levels. Measured peak resident memory of whole
/// runs: 2.7 kB per unknown (flat punch, 7·10⁵ unknowns: 1.9 GB; tapered joint with friction,
/// 9·10⁴ unknowns: 0.26 GB), most of it the Cholesky factor (BENCHMARKS.md); 4 kB leaves a
/// margin for the slower-than-linear growth of the fill.
pub const BYTES_PER_UNKNOWN: u64 = 4096;

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

/// Parses a command-line quantity `name:kind:key=value,key=value`, e.g.
/// `u_bore:displacement:point=bore_point,component=x,reference=0.0123`. The keys are those of
/// `[[quantity]]`; `x`, `y`, `reference`, `tolerance` and `min_order` are numbers.
pub fn parse_quantity(text: &str) -> std::result::Result<QuantitySpec, String> {
    let bad =
        |why: String| format!("--quantity '{text}': {why} (syntax: name:kind:key=value,key=value)");
    let mut parts = text.splitn(3, ':');
    let name = parts.next().unwrap_or_default().trim();
    let kind = parts.next().ok_or_else(|| bad("no kind".into()))?.trim();
    let mut table = toml::Table::new();
    table.insert("name".into(), toml::Value::String(name.into()));
    table.insert("kind".into(), toml::Value::String(kind.into()));
    for item in parts.next().unwrap_or_default().split(',') {
        if item.trim().is_empty() {
            continue;
        }
        let (key, value) = item
            .split_once('=')
            .ok_or_else(|| bad(format!("'{item}' is not key=value")))?;
        let (key, value) = (key.trim(), value.trim());
        let value = if ["x", "y", "reference", "tolerance", "min_order"].contains(&key) {
            toml::Value::Float(
                value
                    .parse()
                    .map_err(|_| bad(format!("{key} = '{value}' is not a number")))?,
            )
        } else {
            toml::Value::String(value.into())
        };
        if table.insert(key.into(), value).is_some() {
            return Err(bad(format!("`{key}` is given twice")));
        }
    }
    serde::Deserialize::deserialize(toml::Value::Table(table))
        .map_err(|e: toml::de::Error| bad(e.to_string().trim().replace('\n', " ")))
}

/// The pass criteria of a quantity.
#[derive(Clone, Copy, Debug)]
pub struct Criteria {
    pub reference: Option<f64>,
    pub tolerance: f64,
    pub min_order: Option<f64>,
}

impl From<&QuantitySpec> for Criteria {
    fn from(q: &QuantitySpec) -> Self {
        Self {
            reference: q.reference,
            tolerance: q.tolerance,
            min_order: q.min_order,
        }
    }
}

/// Convergence analysis of one quantity over the levels (coarse to fine).
#[derive(Clone, Debug)]
pub struct Convergence {
    pub values: Vec<f64>,
    /// Relative mesh sizes h_k.
    pub h: Vec<f64>,
    /// d_k = q_{k+1} − q_k.
    pub differences: Vec<f64>,
    /// Observed order from the three finest levels (None: round-off or not converged).
    pub order: Option<f64>,
    /// Order fitted to the error against the reference over all levels.
    pub reference_order: Option<f64>,
    /// Richardson-extrapolated value (None when not converged).
    pub extrapolated: Option<f64>,
    /// |q∞ − q_f|.
    pub error_estimate: Option<f64>,
    /// |d_f| / |q_f|.
    pub relative_change: f64,
    /// |q_f − ref| / |ref| (absolute error if ref = 0).
    pub reference_error: Option<f64>,
    /// False when the differences do not decrease.
    pub converged: bool,
    /// One reason per failed check (empty: the quantity passes).
    pub failures: Vec<String>,
    /// Remarks that do not fail the quantity.
    pub notes: Vec<String>,
}

impl Convergence {
    /// Whether the quantity passes its checks.
    pub fn passed(&self) -> bool {
        self.failures.is_empty()
    }
}

/// Analyses the values `q` at relative sizes `h` (coarse to fine, refined by `ratio` each
/// time; at least three levels) against `criteria`.
pub fn analyse(q: &[f64], h: &[f64], ratio: f64, criteria: &Criteria) -> Convergence {
    assert!(q.len() >= 3 && q.len() == h.len(), "three or more levels");
    let n = q.len();
    let d: Vec<f64> = q.windows(2).map(|w| w[1] - w[0]).collect();
    let scale = q.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let floor = ROUND_OFF * scale;
    let (qf, dc, df) = (q[n - 1], d[n - 3], d[n - 2]);
    let mut c = Convergence {
        values: q.to_vec(),
        h: h.to_vec(),
        differences: d.clone(),
        order: None,
        reference_order: None,
        extrapolated: None,
        error_estimate: None,
        relative_change: if qf != 0.0 { (df / qf).abs() } else { df.abs() },
        reference_error: None,
        converged: true,
        failures: Vec::new(),
        notes: Vec::new(),
    };
    if df.abs() <= floor {
        // Exact to round-off on the finest levels: nothing to extrapolate.
        c.extrapolated = Some(qf);
        c.error_estimate = Some(df.abs());
        c.notes.push(if dc.abs() <= floor {
            "no change beyond round-off: exact on these meshes".into()
        } else {
            "the finest difference is round-off: converged faster than measurable".into()
        });
    } else {
        let p = (dc.abs() / df.abs()).ln() / ratio.ln();
        c.order = p.is_finite().then_some(p);
        // Growing differences anywhere (above round-off) mean the sequence does not settle.
        let growth = d
            .windows(2)
            .position(|w| w[0].abs() > floor && w[1].abs() > w[0].abs());
        if !p.is_finite() || p <= 0.0 {
            c.converged = false;
            c.failures.push(format!(
                "not converged: the differences do not decrease (|d| = {:.3e} then {:.3e}, observed order {p:.2})",
                dc.abs(),
                df.abs()
            ));
        } else if let Some(k) = growth {
            c.converged = false;
            c.failures.push(format!(
                "not converged: the differences grow from levels {}-{} to {}-{} (|d| = {:.3e} then {:.3e})",
                k,
                k + 1,
                k + 1,
                k + 2,
                d[k].abs(),
                d[k + 1].abs()
            ));
        } else {
            let extrapolated = qf + df / (ratio.powf(p) - 1.0);
            c.extrapolated = Some(extrapolated);
            c.error_estimate = Some((extrapolated - qf).abs());
            if dc * df < 0.0 {
                c.notes.push(
                    "the differences alternate in sign: order and extrapolation are unreliable"
                        .into(),
                );
            }
        }
    }
    if c.relative_change > criteria.tolerance {
        c.failures.push(format!(
            "relative change between the two finest levels {:.2e} > tolerance {:.1e}",
            c.relative_change, criteria.tolerance
        ));
    }
    if let Some(reference) = criteria.reference {
        let error = |v: f64| {
            if reference != 0.0 {
                ((v - reference) / reference).abs()
            } else {
                (v - reference).abs()
            }
        };
        let e = error(qf);
        c.reference_error = Some(e);
        // Fit over the levels whose error is above round-off.
        let points: Vec<(f64, f64)> = q
            .iter()
            .zip(h)
            .filter(|(v, _)| (*v - reference).abs() > floor)
            .map(|(v, h)| (h.ln(), error(*v).ln()))
            .collect();
        let signed: Vec<f64> = q
            .iter()
            .map(|v| v - reference)
            .filter(|e| e.abs() > floor)
            .collect();
        if signed.windows(2).any(|w| w[0] * w[1] < 0.0) {
            c.notes.push(
                "the error against the reference changes sign along the levels (oscillation, or a reference that \
                 is not the limit of the model: a modelling error), so no order is fitted to it"
                    .into(),
            );
        } else if points.len() >= 2 {
            c.reference_order = Some(slope(&points));
        }
        if e > criteria.tolerance {
            c.failures.push(format!(
                "relative error of the finest level against the reference {reference} is {e:.2e} > tolerance {:.1e}",
                criteria.tolerance
            ));
        }
    }
    if let (Some(min), Some(p)) = (criteria.min_order, c.order)
        && c.converged
        && p < min
    {
        c.failures
            .push(format!("observed order {p:.2} < min_order {min}"));
    }
    c
}

/// Least-squares slope of y against x.
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let sxy: f64 = points.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = points.iter().map(|(x, _)| (x - mx).powi(2)).sum();
    sxy / sxx
}

/// What was run at one level.
#[derive(Clone, Debug)]
pub struct Level {
    pub level: usize,
    /// gmsh size factor.
    pub size: f64,
    pub unknowns: usize,
    /// Wall-clock seconds of the level (mesh, solve, output).
    pub seconds: f64,
    /// One value per quantity.
    pub values: Vec<f64>,
}

/// The outcome of a study.
#[derive(Clone, Debug)]
pub struct Report {
    pub case: PathBuf,
    pub ratio: f64,
    pub quantities: Vec<QuantitySpec>,
    pub levels: Vec<Level>,
    /// One per quantity.
    pub results: Vec<Convergence>,
    pub csv: PathBuf,
    /// What happened to the PNG (written, or why not).
    pub plot: String,
    pub seconds: f64,
}

impl Report {
    /// One line per failing quantity: `name: reason; reason`.
    pub fn failures(&self) -> Vec<String> {
        self.quantities
            .iter()
            .zip(&self.results)
            .filter(|(_, r)| !r.passed())
            .map(|(q, r)| format!("{}: {}", q.name, r.failures.join("; ")))
            .collect()
    }
}

impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "convergence study of {}: {} levels, ratio {}, {:.1} s",
            self.case.display(),
            self.levels.len(),
            self.ratio,
            self.seconds
        )?;
        for l in &self.levels {
            writeln!(
                f,
                "  level {}: size {:.6}, {} unknowns, {:.2} s",
                l.level, l.size, l.unknowns, l.seconds
            )?;
        }
        for (q, c) in self.quantities.iter().zip(&self.results) {
            writeln!(f)?;
            writeln!(f, "{} ({})", q.name, describe(q))?;
            let with_ref = q.reference.is_some();
            writeln!(
                f,
                "  {:>5} {:>10} {:>22} {:>12} {}",
                "level",
                "h",
                "value",
                "difference",
                if with_ref {
                    "   error vs reference"
                } else {
                    ""
                }
            )?;
            for (k, (v, h)) in c.values.iter().zip(&c.h).enumerate() {
                let d = if k > 0 {
                    format!("{:12.4e}", c.differences[k - 1])
                } else {
                    format!("{:>12}", "")
                };
                let e = q
                    .reference
                    .map(|r| format!(" {:12.4e}", v - r))
                    .unwrap_or_default();
                writeln!(f, "  {k:>5} {h:>10.6} {v:>22.14e} {d}{e}")?;
            }
            let order = |p: Option<f64>| p.map_or("n/a".into(), |p| format!("{p:.2}"));
            let mut line = format!("  observed order {}", order(c.order));
            if with_ref {
                let _ = write!(
                    line,
                    ", fitted to the reference {}",
                    order(c.reference_order)
                );
            }
            writeln!(f, "{line}")?;
            if let (Some(x), Some(e)) = (c.extrapolated, c.error_estimate) {
                writeln!(f, "  extrapolated {x:.14e} ± {e:.2e}")?;
            }
            let mut line = format!(
                "  relative change between the two finest levels {:.2e} (tolerance {:.1e})",
                c.relative_change, q.tolerance
            );
            if let (Some(r), Some(e)) = (q.reference, c.reference_error) {
                let _ = write!(line, "; reference {r:.14e}, relative error {e:.2e}");
            }
            writeln!(f, "{line}")?;
            for n in &c.notes {
                writeln!(f, "  note: {n}")?;
            }
            if c.passed() {
                writeln!(f, "  ok")?;
            } else {
                writeln!(f, "  FAILED: {}", c.failures.join("; "))?;
            }
        }
        writeln!(f)?;
        writeln!(f, "summary:")?;
        let width = self
            .quantities
            .iter()
            .map(|q| q.name.len())
            .max()
            .unwrap_or(0);
        for (q, c) in self.quantities.iter().zip(&self.results) {
            let mut line = format!(
                "  {:<6} {:<width$}  order {:>5}",
                if c.passed() { "ok" } else { "FAILED" },
                q.name,
                c.order.map_or("n/a".into(), |p| format!("{p:.2}"))
            );
            if let (Some(x), Some(e)) = (c.extrapolated, c.error_estimate) {
                let _ = write!(line, "  extrapolated {x:.10e} ± {e:.1e}");
            }
            let _ = write!(line, "  change {:.1e}", c.relative_change);
            if let Some(e) = c.reference_error {
                let _ = write!(line, "  error vs reference {e:.1e}");
            }
            if !c.converged {
                line.push_str("  NOT CONVERGED");
            }
            writeln!(f, "{line}")?;
        }
        writeln!(f, "table: {}", self.csv.display())?;
        write!(f, "plot: {}", self.plot)
    }
}

/// A short description of a quantity for the table.
fn describe(q: &QuantitySpec) -> String {
    let comp = q
        .component
        .map(|c| ["x", "y"][c.index()])
        .unwrap_or_default();
    let get = |o: &Option<String>| o.clone().unwrap_or_default();
    match q.kind {
        QuantityKind::Reaction => format!("reaction of '{}', {comp} [N]", get(&q.support)),
        QuantityKind::Displacement => format!("displacement of '{}', {comp} [mm]", get(&q.point)),
        QuantityKind::ContactPressure => {
            let at = match (q.statistic, q.x, q.y) {
                (Some(Statistic::Peak), ..) => "peak".into(),
                (Some(Statistic::Mean), ..) => "mean".into(),
                (_, Some(x), _) => format!("at x = {x}"),
                (_, _, Some(y)) => format!("at y = {y}"),
                _ => String::new(),
            };
            format!("contact pressure of '{}', {at} [MPa]", get(&q.pair))
        }
        QuantityKind::StickZone => format!("stick-zone length of '{}' [mm]", get(&q.pair)),
        QuantityKind::RelativeDisplacement => {
            format!(
                "mean relative displacement of '{}', {comp} [mm]",
                get(&q.pair)
            )
        }
        QuantityKind::Stiffness => format!("stiffness of '{}', {comp} [N/mm]", get(&q.pair)),
    }
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
                return Err(Error::External(format!(
                    "{}: level {k} (size {}) failed: {e}",
                    case.path.display(),
                    level_size(case, options.ratio, k)
                )));
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

/// Values of `quantities` for the converged `step` of `model`.
pub fn evaluate(quantities: &[QuantitySpec], model: &Model, step: &StepResult) -> Result<Vec<f64>> {
    let states = &step.solution.interface_committed;
    let u = &step.solution.u;
    let mut interface: Option<InterfaceOutput> = None;
    let pair_index = |q: &QuantitySpec| -> Result<usize> {
        let name = q.pair.as_deref().unwrap_or_default();
        model
            .interface
            .pairs
            .iter()
            .position(|p| p.name == name)
            .ok_or_else(|| Error::Model(format!("quantity '{}': no contact pair '{name}'", q.name)))
    };
    let comp = |q: &QuantitySpec| q.component.map_or(0, Component::index);
    let mut values = Vec::with_capacity(quantities.len());
    for q in quantities {
        let value = match q.kind {
            QuantityKind::Reaction => {
                let name = q.support.as_deref().unwrap_or_default();
                let i = model
                    .supports
                    .iter()
                    .position(|s| s.name == name)
                    .ok_or_else(|| {
                        Error::Model(format!("quantity '{}': no support '{name}'", q.name))
                    })?;
                reactions(model, step.internal_force, step.external_force)[i][comp(q)]
            }
            QuantityKind::Displacement => {
                let name = q.point.as_deref().unwrap_or_default();
                let group = model.mesh.group(0, name).ok_or_else(|| {
                    Error::Model(format!(
                        "quantity '{}': no physical point '{name}' in the mesh (physical points: {})",
                        q.name,
                        model.mesh.group_names(0)
                    ))
                })?;
                let nodes: Vec<u32> = model.mesh.points_in(group).collect();
                if nodes.is_empty() {
                    return Err(Error::Model(format!(
                        "quantity '{}': physical point '{name}' has no nodes",
                        q.name
                    )));
                }
                let c = comp(q);
                nodes.iter().map(|&n| u[2 * n as usize + c]).sum::<f64>() / nodes.len() as f64
            }
            QuantityKind::ContactPressure => {
                let p = pair_index(q)?;
                match q.statistic {
                    Some(Statistic::Mean) => {
                        let (mut force, mut area) = (0.0, 0.0);
                        for_points(model, p, |e, g, point| {
                            force -= states[e * INTERFACE_POINTS + g].stress[1] * point.da;
                            area += point.da;
                        });
                        force / area
                    }
                    statistic => {
                        let out = interface.get_or_insert_with(|| InterfaceOutput::new(model));
                        // Rows: arc_length, x, y, contact_normal_stress, contact_pressure, ...
                        let table = &out.tables(model, states)[p];
                        let pressure = |row: &Vec<f64>| row[4];
                        if statistic == Some(Statistic::Peak) {
                            table
                                .rows
                                .iter()
                                .map(pressure)
                                .fold(f64::NEG_INFINITY, f64::max)
                        } else {
                            let (col, at) = match (q.x, q.y) {
                                (Some(x), _) => (1, x),
                                (_, Some(y)) => (2, y),
                                _ => unreachable!("checked by QuantitySpec::check"),
                            };
                            interpolate(&table.rows, col, at, 4).ok_or_else(|| {
                                let (lo, hi) = table
                                    .rows
                                    .iter()
                                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                                        (a.min(r[col]), b.max(r[col]))
                                    });
                                Error::Model(format!(
                                    "quantity '{}': {} = {at} is outside pair '{}' ({lo} .. {hi})",
                                    q.name,
                                    ["", "x", "y"][col],
                                    model.interface.pairs[p].name
                                ))
                            })?
                        }
                    }
                }
            }
            QuantityKind::StickZone => {
                let p = pair_index(q)?;
                let mut length = 0.0;
                for_lengths(model, p, |e, g, dl| {
                    if states[e * INTERFACE_POINTS + g].status == ContactStatus::Stick {
                        length += dl;
                    }
                });
                length
            }
            QuantityKind::RelativeDisplacement | QuantityKind::Stiffness => {
                let p = pair_index(q)?;
                let c = comp(q);
                let (mut integral, mut length) = (0.0, 0.0);
                for_lengths(model, p, |e, g, dl| {
                    let element = &model.interface.elements[e];
                    let xi = element.rule.points()[g].0;
                    let (n, _) = crate::element::shape::line3(xi);
                    let relative: f64 = (0..3)
                        .map(|i| {
                            let (a, b) = (element.nodes[i] as usize, element.nodes[3 + i] as usize);
                            n[i] * (u[2 * b + c] - u[2 * a + c])
                        })
                        .sum();
                    integral += relative * dl;
                    length += dl;
                });
                let mean = integral / length;
                if q.kind == QuantityKind::Stiffness {
                    -resultants(model, states)[p][2 + c] / mean
                } else {
                    mean
                }
            }
        };
        if !value.is_finite() {
            return Err(Error::Model(format!(
                "quantity '{}' is not finite ({value}) at the last step",
                q.name
            )));
        }
        values.push(value);
    }
    Ok(values)
}

/// Calls `f(element, point, geometry)` for every integration point of pair `p`.
fn for_points(
    model: &Model,
    p: usize,
    mut f: impl FnMut(usize, usize, &crate::element::interface6::InterfacePoint),
) {
    for e in model.interface.pairs[p].elements.clone() {
        let element = &model.interface.elements[e];
        for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
            f(
                e,
                g,
                &interface_point(&model.analysis, &element.b_coords, xi, w),
            );
        }
    }
}

/// Calls `f(element, point, dl)` with the length weight dl (along side B, not the area) of
/// every integration point of pair `p`.
fn for_lengths(model: &Model, p: usize, mut f: impl FnMut(usize, usize, f64)) {
    // A unit thickness turns the area weight into the length weight, also on the axis.
    let plane = Analysis::PlaneStrain { thickness: 1.0 };
    for e in model.interface.pairs[p].elements.clone() {
        let element = &model.interface.elements[e];
        for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
            f(e, g, interface_point(&plane, &element.b_coords, xi, w).da);
        }
    }
}

/// Linear interpolation of column `value` at coordinate `at` of column `col` between
/// successive rows (the first crossing along the curve).
fn interpolate(rows: &[Vec<f64>], col: usize, at: f64, value: usize) -> Option<f64> {
    let tol = 1e-9
        * rows
            .iter()
            .fold(0.0_f64, |m, r| m.max(r[col].abs()))
            .max(1.0);
    if let [row] = rows {
        return ((row[col] - at).abs() <= tol).then_some(row[value]);
    }
    rows.windows(2).find_map(|w| {
        let (a, b) = (w[0][col], w[1][col]);
        if (a - at).abs() <= tol {
            Some(w[0][value])
        } else if (b - at).abs() <= tol {
            Some(w[1][value])
        } else if (a - at) * (b - at) < 0.0 {
            let t = (at - a) / (b - a);
            Some(w[0][value] + t * (w[1][value] - w[0][value]))
        } else {
            None
        }
    })
}

/// `MemAvailable` of /proc/meminfo in bytes.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// A memory budget shared by the levels running at once; finer levels are served first.
struct MemoryGate {
    budget: u64,
    state: Mutex<(u64, BTreeSet<usize>)>,
    changed: Condvar,
}

struct Permit<'a> {
    gate: &'a MemoryGate,
    amount: u64,
}

impl MemoryGate {
    fn new(budget: u64) -> Self {
        Self {
            budget,
            state: Mutex::new((budget, BTreeSet::new())),
            changed: Condvar::new(),
        }
    }

    /// Waits until `estimate` bytes (at most the whole budget: then the level runs alone) are
    /// free and no finer level is waiting.
    fn acquire(&self, level: usize, estimate: u64) -> Permit<'_> {
        let amount = estimate.min(self.budget);
        let mut state = self.state.lock().expect("memory gate");
        state.1.insert(level);
        while !(state.0 >= amount && state.1.last() == Some(&level)) {
            if state.0 < amount {
                tracing::info!(
                    "level {level}: waiting for {:.0} MB of memory ({:.0} MB free in the budget)",
                    amount as f64 / 1e6,
                    state.0 as f64 / 1e6
                );
            }
            state = self.changed.wait(state).expect("memory gate");
        }
        state.1.remove(&level);
        state.0 -= amount;
        self.changed.notify_all();
        Permit { gate: self, amount }
    }
}

impl Drop for Permit<'_> {
    fn drop(&mut self) {
        let mut state = self.gate.state.lock().expect("memory gate");
        state.0 += self.amount;
        self.gate.changed.notify_all();
    }
}

/// Writes `convergence.csv`: one row per quantity and level.
fn write_table(report: &Report) -> Result<()> {
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
    let mut text = String::from(
        "quantity,kind,level,h,unknowns,seconds,value,difference,error_reference,error_extrapolated,reference,\
         extrapolated,error_estimate,order,order_reference,tolerance,status\n",
    );
    for (q, c) in report.quantities.iter().zip(&report.results) {
        let status = if c.passed() {
            "ok"
        } else if c.converged {
            "failed"
        } else {
            "not_converged"
        };
        for (k, l) in report.levels.iter().enumerate() {
            let v = c.values[k];
            let _ = writeln!(
                text,
                "{},{},{},{},{},{:.3},{},{},{},{},{},{},{},{},{},{},{}",
                q.name,
                q.kind.as_str(),
                l.level,
                l.size,
                l.unknowns,
                l.seconds,
                v,
                opt((k > 0).then(|| c.differences[k - 1])),
                opt(q.reference.map(|r| v - r)),
                opt(c.extrapolated.map(|x| v - x)),
                opt(q.reference),
                opt(c.extrapolated),
                opt(c.error_estimate),
                opt(c.order),
                opt(c.reference_order),
                q.tolerance,
                status
            );
        }
    }
    write_atomically(&report.csv, |w| w.write_all(text.as_bytes()))
}

/// Makes `convergence.png` with `pipelines/plot_convergence.py`; returns what happened.
fn plot(out: &Path) -> String {
    let roots = [
        PathBuf::from(env!("CARGO_MANIFEST_DIR")),
        std::env::current_dir().unwrap_or_default(),
    ];
    let script = roots
        .iter()
        .map(|r| r.join("pipelines/plot_convergence.py"))
        .find(|p| p.is_file());
    let pythons = roots
        .iter()
        .map(|r| r.join(".venv/bin/python"))
        .filter(|p| p.is_file())
        .chain([PathBuf::from("python3")]);
    let how = format!(
        "make the venv with `make venv`, then run `.venv/bin/python pipelines/plot_convergence.py {}`",
        out.display()
    );
    let Some(script) = script else {
        return format!("skipped convergence.png: pipelines/plot_convergence.py not found; {how}");
    };
    let python = pythons.into_iter().find(|p| {
        std::process::Command::new(p)
            .args(["-c", "import matplotlib"])
            .output()
            .is_ok_and(|o| o.status.success())
    });
    let Some(python) = python else {
        return format!("skipped convergence.png: no Python with matplotlib found; {how}");
    };
    match std::process::Command::new(&python)
        .arg(&script)
        .arg(out)
        .output()
    {
        Ok(o) if o.status.success() => out.join("convergence.png").display().to_string(),
        Ok(o) => format!(
            "skipped convergence.png: {} failed: {}",
            script.display(),
            String::from_utf8_lossy(&o.stderr)
                .trim()
                .lines()
                .last()
                .unwrap_or_default()
        ),
        Err(e) => format!(
            "skipped convergence.png: cannot run {}: {e}",
            python.display()
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc;
    use std::time::Duration;

    #[test]
    fn a_level_larger_than_the_budget_runs_alone() {
        let gate = MemoryGate::new(10);
        let (tx, rx) = mpsc::channel();
        std::thread::scope(|s| {
            let big = gate.acquire(3, 100); // more than the budget: takes all of it
            s.spawn(|| {
                let _small = gate.acquire(1, 1);
                tx.send(()).unwrap();
            });
            assert!(
                rx.recv_timeout(Duration::from_millis(200)).is_err(),
                "ran beside the big level"
            );
            drop(big);
            rx.recv_timeout(Duration::from_secs(5))
                .expect("runs once the big level is done");
        });
        // Small levels share the budget.
        let a = gate.acquire(2, 4);
        let b = gate.acquire(1, 5);
        assert_eq!(gate.state.lock().unwrap().0, 1);
        drop((a, b));
        assert_eq!(gate.state.lock().unwrap().0, 10);
    }
}
