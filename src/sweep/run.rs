//! Running the runs of a planned study (one task, or all of them on a local pool of child
//! processes) and collecting their results.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use super::{Manifest, keys};
use crate::config::Case;
use crate::output::csv::{Cell, CsvTable, write_csv};
use crate::output::summary::Summary;
use crate::run::folder::{OutputFolder, OutputMode, RunFile};
use crate::{Error, Result};
use crate::{python, run};

/// Whether run `dir` is done: its `summary.json` exists (converged, or failed and not
/// `retry_failed`) and was made from the run's present `case.toml` ([`made_from_its_case`]).
fn done(dir: &Path, retry_failed: bool) -> bool {
    match read_summary(dir) {
        // A summary without a status is no run's (damaged): the run is not done.
        Ok(s) if made_from_its_case(dir) => match s.get("status").and_then(|v| v.as_str()) {
            Some(status) => !(retry_failed && status != "converged"),
            None => false,
        },
        _ => false,
    }
}

/// Whether the results in run folder `dir` are of its present `case.toml`: they are unless its
/// `run.json` holds another case text. A study planned again into the same folder rewrites
/// the case files of the runs it changes; their earlier results are then stale (not done,
/// not collected, and replaced rather than resumed). A run refused before it started (a
/// case file that does not parse) has no `run.json`: its summary stands.
fn made_from_its_case(dir: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(dir.join(RunFile::Info.name())) else {
        return true;
    };
    let info = serde_json::from_str::<serde_json::Value>(&text).ok();
    let recorded = info
        .as_ref()
        .and_then(|i| i.get("case"))
        .and_then(|c| c.as_str());
    let present = std::fs::read_to_string(dir.join("case.toml")).ok();
    recorded.is_some() && recorded == present.as_deref()
}

fn read_summary(dir: &Path) -> Result<serde_json::Value> {
    let path = dir.join(RunFile::Summary.name());
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    serde_json::from_str(&text).map_err(|e| Error::Case {
        path,
        message: format!("not a summary: {e}"),
    })
}

/// A run's folder `dir` of `study` that is a symbolic link is an error: a sweep never writes
/// through one.
fn refuse_linked_run(study: &Path, dir: &Path) -> Result<()> {
    crate::run::folder::refuse_linked_folder(
        study,
        dir,
        "a run's folder is a symbolic link, and a sweep never writes through one: remove it \
         and plan the study again",
    )
}

/// Runs task `k` of `study` unless it is done; returns whether it ran. A run that fails still
/// leaves its `summary.json` (with the error) and returns the error.
pub fn run_task(study: &Path, k: usize, retry_failed: bool) -> Result<bool> {
    let manifest = Manifest::read(study)?;
    let entry = manifest
        .runs
        .get(k)
        .ok_or_else(|| Error::InvalidParameter {
            path: study.join(super::MANIFEST),
            key: "--task".into(),
            value: k.to_string(),
            reason: format!(
                "the study has runs 0 to {}",
                manifest.runs.len().saturating_sub(1)
            ),
        })?;
    let dir = study.join(&entry.dir);
    refuse_linked_run(study, &dir)?;
    if done(&dir, retry_failed) {
        return Ok(false);
    }
    let case_path = dir.join("case.toml");
    // A retried run, or one whose results are of an earlier plan, starts over; otherwise a
    // run stopped part-way (a killed or pre-empted job) continues from its restart record, or
    // starts over without one. Either way only the files the run folder's manifest lists are
    // removed.
    let options = run::RunOptions {
        progress: false,
        mode: if retry_failed || !made_from_its_case(&dir) {
            OutputMode::Force
        } else {
            OutputMode::Resume
        },
        command_line: std::env::args().collect(),
    };
    let result = Case::from_file(&case_path)
        .and_then(|case| run::run_with(&case, &dir, &options, |_| Ok(())));
    if let Err(e) = result {
        // Errors before the model exists leave no summary: record them, so that `collect`
        // reports the run with its error.
        if read_summary(&dir).is_err() {
            let mut summary = Summary::new(&case_path);
            summary.fail(&e);
            summary.write(&OutputFolder::scratch(&dir)?.path(RunFile::Summary)?)?;
        }
        return Err(e);
    }
    Ok(true)
}

/// Peak resident memory (VmHWM) of process `pid` in bytes, from `/proc` (Linux).
fn peak_memory(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Runs every run of `study` that is not done, at most `jobs` at once, each as a child
/// process `exe sweep run STUDY --task K` (so a crash stays in its run; output in the run's
/// `log.txt`). Memory: another run starts only while the memory available
/// ([`crate::memory`]) exceeds twice the largest peak seen so far of a run (the runs of a
/// sweep are of similar size), so runs whose memory is large wait instead of swapping. Returns (ran, failed) task ids.
pub fn run_local(
    study: &Path,
    jobs: usize,
    exe: &Path,
    retry_failed: bool,
) -> Result<(Vec<usize>, Vec<usize>)> {
    let manifest = Manifest::read(study)?;
    let mut pending: Vec<usize> = manifest
        .runs
        .iter()
        .filter(|r| !done(&study.join(&r.dir), retry_failed))
        .map(|r| r.id)
        .rev()
        .collect();
    let threads =
        (std::thread::available_parallelism().map_or(1, |n| n.get()) / jobs.max(1)).max(1);
    let mut running: Vec<(usize, Child)> = Vec::new();
    let (mut ran, mut failed) = (Vec::new(), Vec::new());
    let mut peak = 0u64;
    while !pending.is_empty() || !running.is_empty() {
        let fits = running.is_empty() || crate::memory::available().is_none_or(|m| m > 2 * peak);
        if running.len() < jobs.max(1)
            && fits
            && let Some(k) = pending.pop()
        {
            let dir = study.join(&manifest.runs[k].dir);
            refuse_linked_run(study, &dir)?;
            // The run's log, listed in the run folder's manifest like the run's own files
            // (never opened through a link of that name).
            let log_path = OutputFolder::scratch(&dir)?.path(RunFile::Log)?;
            let log = {
                use std::os::unix::fs::OpenOptionsExt;
                std::fs::OpenOptions::new()
                    .write(true)
                    .create(true)
                    .truncate(true)
                    .custom_flags(libc::O_NOFOLLOW)
                    .open(&log_path)
                    .map_err(|e| Error::io(&log_path, e))?
            };
            let err = log.try_clone().map_err(|e| Error::io(&log_path, e))?;
            let mut command = Command::new(exe);
            command
                .args(["sweep", "run"])
                .arg(study)
                .args(["--task", &k.to_string()]);
            if retry_failed {
                command.arg("--retry-failed");
            }
            let child = command
                .env("RAYON_NUM_THREADS", threads.to_string())
                .stdin(Stdio::null())
                .stdout(log)
                .stderr(err)
                .spawn()
                .map_err(|e| Error::io(exe, e))?;
            running.push((k, child));
            continue;
        }
        std::thread::sleep(Duration::from_millis(20));
        let mut i = 0;
        while i < running.len() {
            peak = peak.max(peak_memory(running[i].1.id()).unwrap_or(0));
            match running[i].1.try_wait().map_err(|e| Error::io(exe, e))? {
                Some(status) => {
                    let (k, _) = running.swap_remove(i);
                    ran.push(k);
                    if !status.success() {
                        failed.push(k);
                    }
                }
                None => i += 1,
            }
        }
    }
    ran.sort();
    failed.sort();
    Ok((ran, failed))
}

/// What `collect` found.
#[derive(Clone, Debug)]
pub struct Collected {
    pub csv: PathBuf,
    pub runs: usize,
    /// (run id, status, error) of every run that did not converge.
    pub failures: Vec<(usize, String, String)>,
    /// What happened to the plots.
    pub plots: String,
}

/// Gathers every run's status and quantities into `study/sweep.csv` (columns: run, the keys,
/// status, the quantities, error) and plots each quantity against each key.
pub fn collect(study: &Path, plot: bool) -> Result<Collected> {
    let manifest = Manifest::read(study)?;
    let mut columns = vec!["run".to_string()];
    columns.extend(manifest.keys.iter().cloned());
    columns.push("status".into());
    columns.extend(manifest.quantities.keys().cloned());
    columns.push("error".into());
    let mut table = CsvTable::new(columns);
    let mut failures = Vec::new();
    for run in &manifest.runs {
        let mut row: Vec<Cell> = vec![Cell::Number(run.id as f64)];
        row.extend(run.values.iter().map(|v| match v {
            toml::Value::Float(x) => Cell::Number(*x),
            toml::Value::Integer(i) => Cell::Number(*i as f64),
            other => Cell::Text(other.to_string().trim_matches('"').to_string()),
        }));
        let dir = study.join(&run.dir);
        let (status, mut error, summary) = match read_summary(&dir) {
            Ok(_) if !made_from_its_case(&dir) => (
                "stale".to_string(),
                format!(
                    "the results in {} are of an earlier plan of this run (its run.json holds \
                     another case than case.toml): run the sweep again",
                    dir.display()
                ),
                None,
            ),
            Ok(s) => match s.get("status").and_then(|v| v.as_str()) {
                Some(status) => {
                    let error = s
                        .get("error")
                        .and_then(|v| v.as_str())
                        .unwrap_or_default()
                        .to_string();
                    (status.to_string(), error, Some(s))
                }
                None => (
                    "damaged".to_string(),
                    format!(
                        "{}: no run's summary (no \"status\"): run the sweep again",
                        dir.join(RunFile::Summary.name()).display()
                    ),
                    None,
                ),
            },
            Err(_) if dir.join(RunFile::Summary.name()).exists() => (
                "damaged".to_string(),
                format!(
                    "{}: not readable as a run's summary (damaged, or cut short): run the sweep \
                     again",
                    dir.join(RunFile::Summary.name()).display()
                ),
                None,
            ),
            Err(_) => (
                "not_run".to_string(),
                format!(
                    "no summary.json in {} (not run yet, or stopped)",
                    dir.display()
                ),
                None,
            ),
        };
        row.push(Cell::Text(status.clone()));
        for (name, path) in &manifest.quantities {
            let value = summary
                .as_ref()
                .filter(|_| status == "converged")
                .and_then(|s| keys::get_json(s, path))
                .and_then(|v| v.as_f64());
            if value.is_none() && status == "converged" {
                error = format!("quantity '{name}': summary.json has no number at `{path}`");
            }
            row.push(value.map_or(Cell::Empty, Cell::Number));
        }
        // One line per run, so that `grep failed sweep.csv` shows whole errors (the full
        // text stays in the run's summary.json).
        let one_line = error.lines().map(str::trim).collect::<Vec<_>>().join("; ");
        row.push(if error.is_empty() {
            Cell::Empty
        } else {
            Cell::Text(one_line)
        });
        if status != "converged" || !error.is_empty() {
            failures.push((run.id, status, error));
        }
        table.rows.push(row);
    }
    let csv = study.join("sweep.csv");
    write_csv(&csv, &table)?;
    let plots = if plot {
        python::run_script("sweep/plot_sweep.py", study, "one PNG per quantity").map_or_else(
            |skipped| skipped,
            |()| format!("one PNG per quantity in {}", study.display()),
        )
    } else {
        "not made (--no-plot)".into()
    };
    Ok(Collected {
        csv,
        runs: manifest.runs.len(),
        failures,
        plots,
    })
}
