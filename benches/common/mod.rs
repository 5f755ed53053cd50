//! Shared by the benches: the case builder of the tests (`tests/common/case.rs`), a run's
//! ratio to its floor, and appending a result table, with the machine and date, to
//! BENCHMARKS.md.

use std::io::Write;

#[path = "../../tests/common/case.rs"]
mod case;

pub use case::*;

use asperity::solver::floor::Floor;
use asperity::solver::state::RunStatistics;

/// The ratio of a run to its floor (`summary.json` `floor.ratio`, docs/guide/outputs.md): the
/// run read its mesh in `mesh_seconds` and took `run_seconds` in all (reading the mesh,
/// building the model and solving; the benches' runs write no files).
pub fn floor_ratio(stats: &RunStatistics, mesh_seconds: f64, run_seconds: f64) -> f64 {
    let floor = Floor::new(&stats.work, mesh_seconds, run_seconds);
    floor.ratio.unwrap_or(f64::NAN)
}

/// The machine: CPU model and number of cores.
fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    format!("{cpu}, {cores} cores")
}

/// The current UTC date and time.
fn now() -> String {
    std::process::Command::new("date")
        .args(["-u", "+%Y-%m-%d %H:%M UTC"])
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default()
}

/// Appends `### title, date, machine` and a markdown table with `header` and `rows` (rows are
/// already formatted `| a | b |` lines) to BENCHMARKS.md.
pub fn append_table(title: &str, header: &[&str], rows: &[String]) {
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open("BENCHMARKS.md")
        .expect("BENCHMARKS.md");
    writeln!(file, "\n### {title}, {}, {}\n", now(), machine()).unwrap();
    writeln!(file, "| {} |", header.join(" | ")).unwrap();
    writeln!(file, "|{}", "---|".repeat(header.len())).unwrap();
    for r in rows {
        writeln!(file, "{r}").unwrap();
    }
}
