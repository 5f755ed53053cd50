//! The files of a fit: `fit.json` (the [`FitResult`]), `curves.csv` (measured and fitted
//! values of every test), `law.toml` (the paste-ready `law = {...}` line) and, when a Python
//! with matplotlib is found, `fit.png` and `residuals.png` from `pipelines/fit/plot_fit.py`.

use std::fmt::Write as _;
use std::path::Path;

use super::{Estimate, FitResult, Outcome};
use crate::output::atomic::write_atomically;
use crate::output::csv::{Cell, CsvTable, write_csv};
use crate::python;
use crate::{Error, Result};

/// The files a fit writes into its folder.
const FIT_FILES: [&str; 5] = [FIT_JSON, CURVES, LAW, "fit.png", "residuals.png"];

/// The fit's result, its curves and its paste-ready law line.
const FIT_JSON: &str = "fit.json";
const CURVES: &str = "curves.csv";
const LAW: &str = "law.toml";

/// Refuses ([`Error::OutputForeign`]) a folder where the fit would replace a file no fit
/// wrote: a fit's file name is taken only in a folder whose `fit.json` is a fit's (an earlier
/// fit, whose files the new one replaces). Called before the fit runs and again before it
/// writes.
pub fn check_folder(out: &Path) -> Result<()> {
    let fit_json = out.join(FIT_JSON);
    let earlier_fit = std::fs::read_to_string(&fit_json)
        .ok()
        .and_then(|text| serde_json::from_str::<serde_json::Value>(&text).ok())
        .is_some_and(|v| v.get("fit_file").is_some() && v.get("chi_square").is_some());
    if earlier_fit {
        return Ok(());
    }
    match FIT_FILES.iter().find(|name| out.join(name).exists()) {
        Some(name) => Err(Error::OutputForeign {
            dir: out.to_path_buf(),
            file: out.join(name),
            reason: "a fit writes a file of this name, but the folder holds no fit's fit.json: \
                     move it away or choose another --out"
                .into(),
        }),
        None => Ok(()),
    }
}

/// Writes the result's files into `out`; returns what happened to the plots. Everything is
/// checked before the first file is written (a non-finite number is an error and leaves no
/// file; a file of a fit's name that no fit wrote is refused, [`check_folder`]), `fit.json` is
/// written last, and each file atomically: a folder with `fit.json` has the complete set.
pub fn write(result: &FitResult, out: &Path, plot_too: bool) -> Result<String> {
    check_folder(out)?;
    let mut table = CsvTable::new(
        ["test", "x", "measured", "fitted", "sigma", "residual"]
            .map(String::from)
            .to_vec(),
    );
    for c in &result.curves {
        for i in 0..c.x.len() {
            table.rows.push(vec![
                Cell::Text(c.label.clone()),
                c.x[i].into(),
                c.measured[i].into(),
                c.fitted[i].into(),
                c.sigma[i].into(),
                ((c.fitted[i] - c.measured[i]) / c.sigma[i]).into(),
            ]);
        }
    }
    let numbers = result
        .parameters
        .iter()
        .map(|e| e.value)
        .chain([result.chi_square, result.scale, result.threshold])
        .chain(table.rows.iter().flatten().filter_map(|c| match c {
            Cell::Number(v) => Some(*v),
            _ => None,
        }));
    if let Some(v) = numbers.into_iter().find(|v| !v.is_finite()) {
        return Err(Error::External(format!(
            "the fit of {} produced a number that is not finite ({v}); no file written",
            result.fit_file.display()
        )));
    }
    let json = serde_json::to_string_pretty(result).map_err(|e| Error::External(e.to_string()))?;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    write_csv(&out.join(CURVES), &table)?;
    write_atomically(&out.join(LAW), |w| writeln!(w, "{}", result.snippet))?;
    write_atomically(&out.join(FIT_JSON), |w| w.write_all(json.as_bytes()))?;
    Ok(if plot_too {
        plot(out)
    } else {
        "not made (--no-plot)".into()
    })
}

/// The 95 % profile interval of `e`, one-sided where the profile does not cross.
fn interval(e: &Estimate) -> String {
    match (e.profile_lower_95, e.profile_upper_95) {
        (Some(a), Some(b)) => format!("[{a:.6e}, {b:.6e}]"),
        (Some(a), None) => format!("≥ {a:.6e}"),
        (None, Some(b)) => format!("≤ {b:.6e}"),
        (None, None) => "-".into(),
    }
}

/// The results (the warnings are printed apart: they go to standard error).
impl std::fmt::Display for FitResult {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "fit of {} ({}): {} points, {} free parameters, χ² = {:.6e} ({}), {} iterations ({:?})",
            self.fit_file.display(),
            self.law,
            self.points,
            self.free.len(),
            self.chi_square,
            if self.errors_stated {
                format!(
                    "χ²/dof = {:.3} with the stated errors",
                    self.chi_square / self.degrees_of_freedom as f64
                )
            } else {
                "errors estimated from the residuals".into()
            },
            self.iterations,
            self.stop
        )?;
        let s = &self.starts;
        let failed = s
            .runs
            .iter()
            .filter(|r| r.outcome == Outcome::Failed)
            .count();
        writeln!(
            f,
            "starts: {} (the fit file's and {} more); {} reached the best χ² (within {} s²), {} stopped higher, {} failed",
            s.count,
            s.count - 1,
            s.same_minimum,
            s.tolerance,
            s.count - s.same_minimum - failed,
            failed
        )?;
        writeln!(
            f,
            "  {:<18} {:>14} {:>12}   {:<30} verdict",
            "parameter",
            "value",
            "std. error",
            format!("95 % interval (profile)")
        )?;
        for e in &self.parameters {
            let mut line = format!("  {:<18} {:>14.6e}", e.name, e.value);
            match e.verdict {
                None => line.push_str("        fixed"),
                Some(v) => {
                    let se = e
                        .standard_error
                        .map_or_else(|| "-".into(), |s| format!("{s:.3e}"));
                    let _ = write!(line, " {se:>12}   {:<30} {v}", interval(e));
                }
            }
            writeln!(f, "{line}")?;
        }
        for p in &self.penalty_defaults {
            let d = &p.default;
            for name in &d.parameters {
                writeln!(
                    f,
                    "  {name:<18} {:>14.6e}        fixed at {}'s default for contact '{}': {} E*/h \
                     (E* = {:.6e} MPa, h = {:.4e} mm), MPa/mm",
                    d.stiffness, p.test, d.contact, d.factor, d.surface_modulus, d.element_length
                )?;
            }
        }
        writeln!(
            f,
            "  (profile intervals: where χ²/s² rises by {:.3} above its minimum; s² = {:.6e})",
            self.threshold, self.scale
        )?;
        writeln!(f, "correlation ({}):", self.free.join(", "))?;
        for row in &self.correlation {
            let cells: Vec<String> = row
                .iter()
                .map(|c| c.map_or("     -".into(), |c| format!("{c:+.3}")))
                .collect();
            writeln!(f, "  {}", cells.join(" "))?;
        }
        write!(f, "{}", self.snippet)
    }
}

fn plot(out: &Path) -> String {
    python::run_script("fit/plot_fit.py", out, "fit.png, residuals.png").map_or_else(
        |skipped| skipped,
        |()| format!("fit.png, residuals.png in {}", out.display()),
    )
}
