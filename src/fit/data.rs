//! Measured curves: CSV files with named columns and their units in a header comment,
//!
//! ```text
//! # units: time = s, closure = um, pressure = MPa
//! time,closure,pressure
//! 0.0,0.0,0.0
//! ```
//!
//! read with the `csv` crate (quoted fields; blank lines and lines starting with `#` are
//! skipped; a UTF-8 byte-order mark is skipped too). Values are converted to asperity's units (mm, N,
//! MPa) on reading. Rows are the test's history in order; a `time` column, where there is one,
//! must increase strictly. Column names must be unique, every value a finite number, also
//! after its unit is converted.

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
    /// Reads `path`: UTF-8 text, with or without a byte-order mark, of at most
    /// [`crate::config::MAX_INPUT_BYTES`].
    pub fn read(path: &Path) -> Result<Self> {
        let bytes = crate::config::read_bounded(path, "not a measured curve")?;
        if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
            return Err(bad(
                path,
                "encoding",
                "",
                "UTF-16 text (it starts with a UTF-16 byte-order mark): save the file as UTF-8",
            ));
        }
        let text = String::from_utf8(bytes).map_err(|e| {
            let offset = e.utf8_error().valid_up_to();
            bad(
                path,
                "encoding",
                "",
                format!(
                    "not UTF-8 text (an invalid byte at offset {offset}): save the file as UTF-8"
                ),
            )
        })?;
        Self::parse(&text, path)
    }

    /// Parses CSV text (`path` for messages); a leading UTF-8 byte-order mark is skipped.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let text = text.strip_prefix('\u{FEFF}').unwrap_or(text);
        let units = units(text, path)?;
        // Comment lines become blank lines, which the reader skips: the csv crate's own
        // comment option would drop them from its line count and byte offsets.
        let text: String = text
            .split_inclusive('\n')
            .map(|l| {
                if l.trim_start().starts_with('#') {
                    if l.ends_with('\n') { "\n" } else { "" }
                } else {
                    l
                }
            })
            .collect();
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(csv::Trim::All)
            .from_reader(text.as_bytes());
        // The file line of a record at byte offset `byte`: the reader's offset is where it
        // resumed reading, before the blank lines it skipped.
        let line_starts: Vec<usize> = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        let line_of = |byte: u64| {
            let rest = text.get(byte as usize..).unwrap_or_default();
            let start = byte as usize + rest.len() - rest.trim_start().len();
            line_starts.partition_point(|&s| s <= start)
        };
        let mut columns: Option<Vec<String>> = None;
        let (mut rows, mut lines) = (Vec::new(), Vec::new());
        for record in reader.records() {
            let record = record.map_err(|e| {
                let line = e.position().map_or(0, |p| line_of(p.byte()));
                bad(path, format!("line {line}"), "", e.to_string())
            })?;
            let line = record.position().map_or(0, |p| line_of(p.byte()));
            if record.iter().all(str::is_empty) {
                continue;
            }
            let Some(names) = &columns else {
                columns = Some(header(&record, line, path)?);
                continue;
            };
            if record.len() != names.len() {
                return Err(bad(
                    path,
                    format!("line {line}"),
                    record.iter().collect::<Vec<_>>().join(","),
                    format!("has {} values, the header {}", record.len(), names.len()),
                ));
            }
            let mut row = Vec::with_capacity(record.len());
            for (name, field) in names.iter().zip(record.iter()) {
                let key = || format!("column '{name}', line {line}");
                let v: f64 = field
                    .parse()
                    .map_err(|_| bad(path, key(), field, "not a number"))?;
                if !v.is_finite() {
                    return Err(bad(
                        path,
                        key(),
                        field,
                        "must be a finite number (NaN, infinity, or beyond the ±1.8e308 of a double)",
                    ));
                }
                row.push(v);
            }
            rows.push(row);
            lines.push(line);
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

    /// File line number (1-based) of each row.
    pub fn lines(&self) -> &[usize] {
        &self.lines
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
        self.rows
            .iter()
            .zip(&self.lines)
            .map(|(r, line)| {
                let v = r[j] * factor;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(bad(
                        &self.path,
                        format!("column '{name}', line {line}"),
                        format!("{:e}", r[j]),
                        format!("overflows when converted from {unit} to asperity's unit"),
                    ))
                }
            })
            .collect()
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

/// The units declared in `# units: name = unit, ...` comment lines of `text`.
fn units(text: &str, path: &Path) -> Result<BTreeMap<String, String>> {
    let mut units = BTreeMap::new();
    let declarations = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix('#'))
        .filter_map(|c| c.trim().strip_prefix("units:"));
    for list in declarations {
        for item in list.split(',').filter(|s| !s.trim().is_empty()) {
            let (name, unit) = item
                .split_once('=')
                .ok_or_else(|| bad(path, "units", item.trim(), "expected `column = unit`"))?;
            units.insert(name.trim().to_string(), unit.trim().to_string());
        }
    }
    Ok(units)
}

/// The column names of header `record` (on line `line`): each named, none twice.
fn header(record: &csv::StringRecord, line: usize, path: &Path) -> Result<Vec<String>> {
    let names: Vec<String> = record.iter().map(str::to_string).collect();
    for (k, name) in names.iter().enumerate() {
        if name.is_empty() {
            return Err(bad(
                path,
                format!("header, line {line}"),
                record.iter().collect::<Vec<_>>().join(","),
                format!("column {} has no name", k + 1),
            ));
        }
        if let Some(first) = names[..k].iter().position(|n| n == name) {
            return Err(bad(
                path,
                format!("column '{name}'"),
                "",
                format!(
                    "appears twice in the header (columns {} and {}, line {line}): which one is meant is \
                     ambiguous; rename or remove one",
                    first + 1,
                    k + 1
                ),
            ));
        }
    }
    Ok(names)
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
        assert_eq!(key_of("a,b,a\n1,2,3\n"), "column 'a'");
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

    /// A byte-order mark, blank lines, quoted fields and comments between the rows are read
    /// as a spreadsheet writes them; a value that overflows on conversion names its line.
    #[test]
    fn bom_quotes_and_blank_lines_are_read_and_overflow_is_an_error() {
        let text = "\u{FEFF}# units: a = m, b = MPa\n\n\"a\",b\n1e-3,\"2\"\n\n# a note\n2e-3 , 3\n";
        let t = Table::parse(text, Path::new("d.csv")).unwrap();
        assert_eq!(t.column("a", Dimension::Length).unwrap(), vec![1.0, 2.0]);
        assert_eq!(t.column("b", Dimension::Stress).unwrap(), vec![2.0, 3.0]);
        assert_eq!(t.lines(), &[4, 7]);
        let t = Table::parse("# units: a = m\na\n1\n1e306\n", Path::new("d.csv")).unwrap();
        let Err(Error::InvalidParameter { key, .. }) = t.column("a", Dimension::Length) else {
            panic!()
        };
        assert_eq!(key, "column 'a', line 4");
        assert_eq!(key_of("a\n1e400\n"), "column 'a', line 2");
    }
}
