//! The files of a fit: `fit.json` (the [`FitResult`]), `curves.csv` (measured and fitted
//! values of every test), `law.toml` (the paste-ready `law = {...}` line) and, when a Python
//! with matplotlib is found, `fit.png` and `residuals.png` from `pipelines/fit/plot_fit.py`.

use std::fmt::Write as _;
use std::path::Path;

use super::FitResult;
use crate::output::atomic::write_atomically;
use crate::output::csv::{Cell, CsvTable, write_csv};
use crate::python;
use crate::{Error, Result};

/// Writes the result's files into `out`; returns what happened to the plots.
pub fn write(result: &FitResult, out: &Path, plot_too: bool) -> Result<String> {
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let json = serde_json::to_string_pretty(result).map_err(|e| Error::External(e.to_string()))?;
    write_atomically(&out.join("fit.json"), |w| w.write_all(json.as_bytes()))?;
    write_atomically(&out.join("law.toml"), |w| writeln!(w, "{}", result.snippet))?;
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
    write_csv(&out.join("curves.csv"), &table)?;
    Ok(if plot_too {
        plot(out)
    } else {
        "not made (--no-plot)".into()
    })
}

impl std::fmt::Display for FitResult {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "fit of {} ({}): {} points, {} free parameters, χ² = {:.6e} ({}), {} iterations ({})",
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
        writeln!(
            f,
            "  {:<18} {:>14} {:>12} {:>30}",
            "parameter", "value", "std. error", "95 % interval"
        )?;
        for e in &self.parameters {
            let mut line = format!("  {:<18} {:>14.6e}", e.name, e.value);
            match (e.free, e.standard_error) {
                (false, _) => line.push_str("        fixed"),
                (true, None) => line.push_str("  not identifiable"),
                (true, Some(s)) => {
                    let _ = write!(
                        line,
                        " {:>12.3e}   [{:.6e}, {:.6e}]",
                        s,
                        e.lower_95.unwrap_or(f64::NAN),
                        e.upper_95.unwrap_or(f64::NAN)
                    );
                }
            }
            writeln!(f, "{line}")?;
        }
        writeln!(f, "correlation ({}):", self.free.join(", "))?;
        for row in &self.correlation {
            let cells: Vec<String> = row
                .iter()
                .map(|c| c.map_or("     -".into(), |c| format!("{c:+.3}")))
                .collect();
            writeln!(f, "  {}", cells.join(" "))?;
        }
        for w in &self.warnings {
            writeln!(f, "WARNING: {w}")?;
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
