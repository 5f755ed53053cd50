//! The one CSV writer: load-displacement history, interface stresses along a contact line,
//! the table of a convergence study.
//!
//! The format is the plain one that `pandas.read_csv`, `numpy.loadtxt(delimiter=",",
//! skiprows=1)` and spreadsheets read without options: one header line of column names,
//! then one line per row, values separated by commas, no index column, no quoting of
//! numbers. Numbers are written in Rust's shortest round-trip form, so reading a file back
//! gives bit-identical `f64`s.

use std::path::Path;

use super::append::{AppendedFile, FileMark};
use super::atomic::{invalid_data, write_bytes};
use crate::Result;

/// A table with named columns; the cells are numbers (`f64`, the default) or [`Cell`]s for
/// tables that also hold text and empty cells (`convergence.csv`).
#[derive(Clone, Debug, PartialEq)]
pub struct CsvTable<C = f64> {
    /// Column names, written as the header line.
    pub columns: Vec<String>,
    /// Rows, each with exactly `columns.len()` values.
    pub rows: Vec<Vec<C>>,
}

impl<C> Default for CsvTable<C> {
    fn default() -> Self {
        Self::new(Vec::<String>::new())
    }
}

impl<C> CsvTable<C> {
    /// An empty table with the given column names.
    pub fn new(columns: impl IntoIterator<Item = impl Into<String>>) -> Self {
        CsvTable {
            columns: columns.into_iter().map(Into::into).collect(),
            rows: Vec::new(),
        }
    }
}

/// A cell of a table that is not all numbers.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    Number(f64),
    /// Quoted when it contains a comma, quote or line break.
    Text(String),
    /// Written as nothing between the commas (a missing value: pandas reads NaN).
    Empty,
}

impl From<f64> for Cell {
    fn from(v: f64) -> Self {
        Cell::Number(v)
    }
}

impl From<Option<f64>> for Cell {
    fn from(v: Option<f64>) -> Self {
        v.map_or(Cell::Empty, Cell::Number)
    }
}

impl From<&str> for Cell {
    fn from(s: &str) -> Self {
        Cell::Text(s.to_string())
    }
}

/// What [`write_csv`] can write as a cell.
pub trait CsvCell {
    /// The number to check for finiteness, if the cell is a number.
    fn number(&self) -> Option<f64>;
    /// Appends the cell's text.
    fn push_to(&self, out: &mut String);
}

impl CsvCell for f64 {
    fn number(&self) -> Option<f64> {
        Some(*self)
    }
    fn push_to(&self, out: &mut String) {
        push_f64(out, *self);
    }
}

impl CsvCell for Cell {
    fn number(&self) -> Option<f64> {
        match self {
            Cell::Number(v) => Some(*v),
            _ => None,
        }
    }
    fn push_to(&self, out: &mut String) {
        match self {
            Cell::Number(v) => push_f64(out, *v),
            Cell::Text(s) => out.push_str(s),
            Cell::Empty => {}
        }
    }
}

/// Writes `table` to `path` (atomically, creating the parent directory).
///
/// Fails without touching `path` if a row does not have one value per column or a number is
/// NaN or infinite: such a value in a result table means the computation went wrong, and
/// writing it would only move the surprise into the plotting script.
pub fn write_csv<C: CsvCell>(path: &Path, table: &CsvTable<C>) -> Result<()> {
    let ncols = table.columns.len();
    for (r, row) in table.rows.iter().enumerate() {
        if row.len() != ncols {
            return Err(invalid_data(
                path,
                format!(
                    "row {r} has {} values but the table has {ncols} columns",
                    row.len()
                ),
            ));
        }
        let bad = row
            .iter()
            .enumerate()
            .find_map(|(c, v)| v.number().filter(|v| !v.is_finite()).map(|v| (c, v)));
        if let Some((c, v)) = bad {
            return Err(invalid_data(
                path,
                format!(
                    "column `{}`, row {r}: value {v} is not finite",
                    table.columns[c]
                ),
            ));
        }
    }

    // The csv crate does the quoting (RFC 4180: only fields with a comma, quote or line
    // break); the numbers are formatted here, in the shortest round-trip form.
    let text = csv_text(table).map_err(|e| invalid_data(path, e))?;
    write_bytes(path, &text)
}

/// A table that grows by rows and is written by appending them (`history.csv`, the fretting
/// tables): each row is checked and formatted once, when it is added, and handed to the
/// writer once ([`AppendedFile`]), so that a run of thousands of frames writes each row once
/// instead of the whole table after every frame. The text is what [`write_csv`] writes for
/// the same table.
#[derive(Clone, Debug, Default)]
pub struct GrowingCsv {
    file: AppendedFile,
    columns: usize,
}

impl GrowingCsv {
    /// The table of `columns` without rows: its header is the first text appended.
    pub fn new(columns: &[String]) -> Self {
        let header = CsvTable::<f64> {
            columns: columns.to_vec(),
            rows: Vec::new(),
        };
        let mut file = AppendedFile::default();
        // Writing a header into memory cannot fail.
        file.push(&csv_text(&header).unwrap_or_default());
        Self {
            file,
            columns: columns.len(),
        }
    }

    /// Continues the table after the text that `mark` describes (a resumed run's), dropping
    /// what was not handed over.
    pub fn continue_from(&mut self, mark: FileMark) {
        self.file = AppendedFile::continued(mark);
    }

    /// Appends `row`, refusing one of the wrong length or with a value that is not finite
    /// (the error names `path`, the file the table is written to).
    pub fn push<C: CsvCell>(&mut self, path: &Path, row: &[C]) -> Result<()> {
        if row.len() != self.columns {
            let message = format!(
                "a row has {} values but the table has {} columns",
                row.len(),
                self.columns
            );
            return Err(invalid_data(path, message));
        }
        let bad = row
            .iter()
            .enumerate()
            .find_map(|(c, v)| v.number().filter(|v| !v.is_finite()).map(|v| (c, v)));
        if let Some((c, v)) = bad {
            return Err(invalid_data(
                path,
                format!("column {c}: value {v} is not finite"),
            ));
        }
        let mut line = String::with_capacity(24 * row.len());
        let mut cell = String::new();
        for (c, v) in row.iter().enumerate() {
            if c > 0 {
                line.push(',');
            }
            cell.clear();
            v.push_to(&mut cell);
            push_field(&mut line, &cell, row.len() == 1);
        }
        line.push('\n');
        self.file.push(line.as_bytes());
        Ok(())
    }

    /// The file the rows go to.
    pub fn file(&mut self) -> &mut AppendedFile {
        &mut self.file
    }

    /// The length and checksum of the text so far.
    pub fn mark(&self) -> FileMark {
        self.file.mark()
    }
}

/// Appends a field as the csv crate writes it (RFC 4180: quoted, with its quotes doubled,
/// when it holds a comma, quote or line break; an empty field quoted when it is `alone` on
/// its line).
fn push_field(line: &mut String, field: &str, alone: bool) {
    if field.contains([',', '"', '\n', '\r']) || (field.is_empty() && alone) {
        line.push('"');
        line.push_str(&field.replace('"', "\"\""));
        line.push('"');
    } else {
        line.push_str(field);
    }
}

/// The CSV text of a checked table.
fn csv_text<C: CsvCell>(table: &CsvTable<C>) -> std::result::Result<Vec<u8>, String> {
    let capacity = 16 * (table.columns.len() + 1) * (table.rows.len() + 1);
    let mut writer = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::with_capacity(capacity));
    let mut cell = String::new();
    let error = |e: csv::Error| e.to_string();
    writer.write_record(&table.columns).map_err(error)?;
    for row in &table.rows {
        for v in row {
            cell.clear();
            v.push_to(&mut cell);
            writer.write_field(&cell).map_err(error)?;
        }
        writer.write_record(None::<&[u8]>).map_err(error)?;
    }
    writer.into_inner().map_err(|e| e.to_string())
}

/// Appends `v` in a form that parses back to exactly `v` (Rust's `Display` and `LowerExp`
/// both print the shortest round-trip digits). `Display` never uses an exponent, which
/// would turn 1e-300 into 300 zeros, so values far from 1 use `{:e}` instead.
pub(crate) fn push_f64(out: &mut String, v: f64) {
    use std::fmt::Write as _;
    let a = v.abs();
    if a == 0.0 || (1e-5..1e16).contains(&a) {
        let _ = write!(out, "{v}");
    } else {
        let _ = write!(out, "{v:e}");
    }
}

/// [`push_f64`] into a new string.
pub(crate) fn format_f64(v: f64) -> String {
    let mut s = String::new();
    push_f64(&mut s, v);
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_growing_table_is_the_text_write_csv_writes() {
        let columns: Vec<String> = ["step", "a,b", "value"].map(String::from).to_vec();
        let rows = vec![vec![0.0, -0.0, 1e-300], vec![1.0, 1.0 / 3.0, -2.5e20]];
        let mut growing = GrowingCsv::new(&columns);
        for row in &rows {
            growing.push(Path::new("t.csv"), row).unwrap();
        }
        let table = CsvTable { columns, rows };
        let whole = csv_text(&table).unwrap();
        assert_eq!(growing.file().pending(), whole.as_slice());
        let nan = growing.push(Path::new("t.csv"), &[1.0, f64::NAN, 0.0]);
        assert!(nan.unwrap_err().to_string().contains("t.csv"));
        assert!(growing.push(Path::new("t.csv"), &[1.0]).is_err());
        // Rows are handed over once; the mark counts them all.
        let first = growing.file().take().unwrap();
        assert_eq!(first.bytes, whole);
        growing.push(Path::new("t.csv"), &[2.0, 0.5, 0.25]).unwrap();
        let next = growing.file().take().unwrap();
        assert_eq!(
            (next.offset, next.bytes.as_slice()),
            (whole.len() as u64, &b"2,0.5,0.25\n"[..])
        );
        assert_eq!(
            growing.mark().length,
            (whole.len() + next.bytes.len()) as u64
        );
    }

    #[test]
    fn text_cells_are_quoted_as_the_csv_crate_quotes_them() {
        let columns: Vec<String> = ["name", "value"].map(String::from).to_vec();
        let rows = vec![
            vec![Cell::Text("a, \"b\"".into()), Cell::Number(0.5)],
            vec![Cell::Text("line\nbreak".into()), Cell::Empty],
            vec![Cell::Empty, Cell::Text("plain".into())],
        ];
        let mut growing = GrowingCsv::new(&columns);
        for row in &rows {
            growing.push(Path::new("t.csv"), row).unwrap();
        }
        let whole = csv_text(&CsvTable { columns, rows }).unwrap();
        assert_eq!(growing.file().pending(), whole.as_slice());
        let mut alone = GrowingCsv::new(&["x".to_string()]);
        alone.push(Path::new("t.csv"), &[Cell::Empty]).unwrap();
        let whole = csv_text(&CsvTable {
            columns: vec!["x".to_string()],
            rows: vec![vec![Cell::Empty]],
        });
        assert_eq!(alone.file().pending(), whole.unwrap().as_slice());
    }

    #[test]
    fn numbers_round_trip_and_stay_short() {
        for v in [
            0.0,
            -0.0,
            1.0,
            -2.5,
            0.1,
            1.0 / 3.0,
            1e-300,
            6.02e23,
            123456.789,
            1e-5,
            9.99e15,
        ] {
            let s = format_f64(v);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{s}");
            assert!(s.len() <= 24, "{s}");
        }
        assert_eq!(format_f64(0.25), "0.25");
        assert_eq!(format_f64(1e-300), "1e-300");
    }

    #[test]
    fn mixed_cells_are_written_and_checked() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        let mut table = CsvTable::new(["name", "value", "order"]);
        table
            .rows
            .push(vec!["a, b".into(), 0.5.into(), Cell::from(None)]);
        table
            .rows
            .push(vec!["c".into(), 1e-300.into(), Some(2.0).into()]);
        write_csv(&path, &table).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, "name,value,order\n\"a, b\",0.5,\nc,1e-300,2\n");
        table.rows[1][1] = f64::NAN.into();
        let err = write_csv(&path, &table).unwrap_err().to_string();
        assert!(err.contains("column `value`, row 1"), "{err}");
    }

    #[test]
    fn names_with_commas_and_quotes_are_quoted() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("q.csv");
        let mut table = CsvTable::new(["p_N, MPa", "a\"b", "u_y"]);
        table.rows.push(vec![1.0, 2.0, 3.0]);
        write_csv(&path, &table).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, "\"p_N, MPa\",\"a\"\"b\",u_y\n1,2,3\n");
    }
}
