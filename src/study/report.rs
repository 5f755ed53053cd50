//! The report of a convergence study: the console table, `convergence.csv` and the plot.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::analysis::Convergence;
use crate::config::{QuantityKind, QuantitySpec, Statistic};
use crate::output::csv::{Cell, CsvTable, write_csv};
use crate::{Result, python};

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
        QuantityKind::SlipLength => format!("slip length of '{}' [mm]", get(&q.pair)),
        QuantityKind::OpenLength => format!("open length of '{}' [mm]", get(&q.pair)),
        QuantityKind::ContactArea => format!("contact area of '{}' [mm²]", get(&q.pair)),
        QuantityKind::MaxSlip => format!("largest slip of '{}' [mm]", get(&q.pair)),
        QuantityKind::NodeDisplacement => {
            format!(
                "displacement of node {}, {comp} [mm]",
                q.node.unwrap_or_default()
            )
        }
        QuantityKind::RelativeDisplacement => {
            format!(
                "mean relative displacement of '{}', {comp} [mm]",
                get(&q.pair)
            )
        }
        QuantityKind::Stiffness => format!("stiffness of '{}', {comp} [N/mm]", get(&q.pair)),
        QuantityKind::Twist => format!("twist angle of '{}' [rad]", get(&q.group)),
    }
}

/// The columns of `convergence.csv`.
const COLUMNS: [&str; 17] = [
    "quantity",
    "kind",
    "level",
    "h",
    "unknowns",
    "seconds",
    "value",
    "difference",
    "error_reference",
    "error_extrapolated",
    "reference",
    "extrapolated",
    "error_estimate",
    "order",
    "order_reference",
    "tolerance",
    "status",
];

/// Writes `convergence.csv`: one row per quantity and level (empty cells where a value does
/// not apply).
pub(super) fn write_table(report: &Report) -> Result<()> {
    let mut table = CsvTable::<Cell>::new(COLUMNS);
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
            table.rows.push(vec![
                q.name.as_str().into(),
                q.kind.as_str().into(),
                (l.level as f64).into(),
                l.size.into(),
                (l.unknowns as f64).into(),
                // Milliseconds are enough for a wall-clock time.
                ((l.seconds * 1e3).round() / 1e3).into(),
                v.into(),
                (k > 0).then(|| c.differences[k - 1]).into(),
                q.reference.map(|r| v - r).into(),
                c.extrapolated.map(|x| v - x).into(),
                q.reference.into(),
                c.extrapolated.into(),
                c.error_estimate.into(),
                c.order.into(),
                c.reference_order.into(),
                q.tolerance.into(),
                status.into(),
            ]);
        }
    }
    write_csv(&report.csv, &table)
}

/// Makes `convergence.png` with `pipelines/plot_convergence.py`; returns its path, or why it
/// was skipped and the command to make it.
pub(super) fn plot(out: &Path) -> String {
    match python::run_script("plot_convergence.py", out, "convergence.png") {
        Ok(()) => out.join("convergence.png").display().to_string(),
        Err(skipped) => skipped,
    }
}
