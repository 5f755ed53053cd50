//! Measured curves: CSV files with named columns and their units in a header comment,
//!
//! ```text
//! # units: time = s, closure = um, pressure = MPa
//! time,closure,pressure
//! 0.0,0.0,0.0
//! ```
//!
//! Values are converted to asperity's units (mm, N, MPa) on reading. Rows are the test's
//! history in order; a `time` column, where there is one, must increase strictly.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// What a column measures, and so which units it may be given in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dimension {
    Length,
    Stress,
    Force,
    /// A count or ratio (step numbers, load factors).
    Number,
}

impl Dimension {
    /// The factor converting `unit` to asperity's unit of this dimension.
    fn factor(self, unit: &str) -> Option<f64> {
        let unit = unit.replace('µ', "u").replace('²', "2");
        Some(match (self, unit.as_str()) {
            (Dimension::Length, "mm") => 1.0,
            (Dimension::Length, "um") => 1e-3,
            (Dimension::Length, "m") => 1e3,
            (Dimension::Stress, "MPa" | "N/mm2") => 1.0,
            (Dimension::Stress, "kPa") => 1e-3,
            (Dimension::Stress, "Pa") => 1e-6,
            (Dimension::Stress, "GPa") => 1e3,
            (Dimension::Force, "N") => 1.0,
            (Dimension::Force, "kN") => 1e3,
            (Dimension::Number, "1" | "-") => 1.0,
            _ => return None,
        })
    }

    fn accepted(self) -> &'static str {
        match self {
            Dimension::Length => "mm, um, m",
            Dimension::Stress => "MPa, N/mm2, kPa, Pa, GPa",
            Dimension::Force => "N, kN",
            Dimension::Number => "1, -",
        }
    }
}

/// A measured table, as read.
#[derive(Clone, Debug)]
pub struct Table {
    pub path: PathBuf,
    columns: Vec<String>,
    units: BTreeMap<String, String>,
    rows: Vec<Vec<f64>>,
    /// File line number (1-based) of each row.
    lines: Vec<usize>,
}

/// A bad data file: `Error::InvalidParameter` with the file and the column (and row) as key.
fn bad(
    path: &Path,
    key: impl Into<String>,
    value: impl Into<String>,
    reason: impl Into<String>,
) -> Error {
    Error::InvalidParameter {
        path: path.to_path_buf(),
        key: key.into(),
        value: value.into(),
        reason: reason.into(),
    }
}

impl Table {
    /// Reads `path`.
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::parse(&text, path)
    }

    /// Parses CSV text (`path` for messages).
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let mut units = BTreeMap::new();
        let mut columns: Option<Vec<String>> = None;
        let (mut rows, mut lines) = (Vec::new(), Vec::new());
        for (i, line) in text.lines().enumerate() {
            let line = line.trim();
            if let Some(comment) = line.strip_prefix('#') {
                if let Some(list) = comment.trim().strip_prefix("units:") {
                    for item in list.split(',').filter(|s| !s.trim().is_empty()) {
                        let (name, unit) = item.split_once('=').ok_or_else(|| {
                            bad(path, "units", item.trim(), "expected `column = unit`")
                        })?;
                        units.insert(name.trim().to_string(), unit.trim().to_string());
                    }
                }
                continue;
            }
            if line.is_empty() {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let Some(names) = &columns else {
                columns = Some(fields.iter().map(|s| s.to_string()).collect());
                continue;
            };
            if fields.len() != names.len() {
                return Err(bad(
                    path,
                    format!("line {}", i + 1),
                    line,
                    format!("has {} values, the header {}", fields.len(), names.len()),
                ));
            }
            let mut row = Vec::with_capacity(fields.len());
            for (name, field) in names.iter().zip(&fields) {
                let v: f64 = field.parse().map_err(|_| {
                    bad(
                        path,
                        format!("column '{name}', line {}", i + 1),
                        *field,
                        "not a number",
                    )
                })?;
                if !v.is_finite() {
                    return Err(bad(
                        path,
                        format!("column '{name}', line {}", i + 1),
                        *field,
                        "must be a finite number (NaN or infinity in the data)",
                    ));
                }
                row.push(v);
            }
            rows.push(row);
            lines.push(i + 1);
        }
        let columns =
            columns.ok_or_else(|| bad(path, "header", "", "the file has no header line"))?;
        if rows.is_empty() {
            return Err(bad(path, "rows", "", "the file has no data rows"));
        }
        let table = Self {
            path: path.to_path_buf(),
            columns,
            units,
            rows,
            lines,
        };
        if table.columns.iter().any(|c| c == "time") {
            table.check_increasing("time")?;
        }
        Ok(table)
    }

    /// The number of data rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether there are no rows (never: reading refuses such a file).
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The column `name` in asperity's units; its unit must be declared in the header
    /// comment and be one of `dimension`'s.
    pub fn column(&self, name: &str, dimension: Dimension) -> Result<Vec<f64>> {
        let j = self.columns.iter().position(|c| c == name).ok_or_else(|| {
            bad(
                &self.path,
                format!("column '{name}'"),
                "",
                format!("missing (the columns are: {})", self.columns.join(", ")),
            )
        })?;
        let unit = self.units.get(name).ok_or_else(|| {
            bad(
                &self.path,
                format!("column '{name}'"),
                "",
                format!(
                    "no unit: declare it in a header comment, e.g. `# units: {name} = {}`",
                    dimension.accepted().split(',').next().unwrap_or_default()
                ),
            )
        })?;
        let factor = dimension.factor(unit).ok_or_else(|| {
            bad(
                &self.path,
                format!("units.{name}"),
                unit.as_str(),
                format!(
                    "unknown unit for this column (use one of {})",
                    dimension.accepted()
                ),
            )
        })?;
        Ok(self.rows.iter().map(|r| r[j] * factor).collect())
    }

    /// Checks that column `name` increases strictly down the file.
    fn check_increasing(&self, name: &str) -> Result<()> {
        let j = self
            .columns
            .iter()
            .position(|c| c == name)
            .expect("checked");
        for k in 1..self.rows.len() {
            if self.rows[k][j] <= self.rows[k - 1][j] {
                return Err(bad(
                    &self.path,
                    format!("column '{name}', line {}", self.lines[k]),
                    self.rows[k][j].to_string(),
                    format!(
                        "must increase down the file (the row before has {})",
                        self.rows[k - 1][j]
                    ),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key_of(text: &str) -> String {
        match Table::parse(text, Path::new("d.csv")) {
            Err(Error::InvalidParameter { key, .. }) => key,
            other => panic!("expected an invalid-data error, got {other:?}"),
        }
    }

    #[test]
    fn units_are_converted() {
        let t = Table::parse(
            "# units: closure = um, pressure = kPa\nclosure,pressure\n1.5,2000\n",
            Path::new("d.csv"),
        )
        .unwrap();
        assert_eq!(
            t.column("closure", Dimension::Length).unwrap(),
            vec![1.5e-3]
        );
        assert_eq!(t.column("pressure", Dimension::Stress).unwrap(), vec![2.0]);
    }

    #[test]
    fn bad_files_name_the_column_and_line() {
        assert_eq!(
            key_of("# units: a = mm\na,b\n1,nan\n"),
            "column 'b', line 3"
        );
        assert_eq!(
            key_of("# units: time = 1\ntime,x\n0,1\n2,1\n1,1\n"),
            "column 'time', line 5"
        );
        assert_eq!(key_of("a,b\n1,2,3\n"), "line 2");
        let t = Table::parse("# units: a = mm\na\n1\n", Path::new("d.csv")).unwrap();
        let Err(Error::InvalidParameter { key, .. }) = t.column("b", Dimension::Length) else {
            panic!()
        };
        assert_eq!(key, "column 'b'");
        let Err(Error::InvalidParameter { key, .. }) = t.column("a", Dimension::Stress) else {
            panic!()
        };
        assert_eq!(key, "units.a");
    }
}
