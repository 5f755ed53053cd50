//! `run.json`: what made the results in an output folder.

use std::path::PathBuf;

use super::RunOptions;
use super::folder::{OutputFolder, OutputMode, RunFile};
use crate::config::Case;
use crate::model::PenaltyDefault;
use crate::output::atomic::write_text;
use crate::{Error, Result};

/// The contents of `run.json`: what made the results in the folder.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RunInfo {
    /// `asperity`.
    pub program: &'static str,
    pub version: &'static str,
    pub command_line: Vec<String>,
    /// The case file (absolute where it can be made so) and its text.
    pub case_file: PathBuf,
    pub case: String,
    /// The folder the command ran in.
    pub working_directory: Option<PathBuf>,
    /// UTC, RFC 3339.
    pub start: String,
    /// `null` while the run goes on (or if it was killed).
    pub end: Option<String>,
    pub host: String,
    /// Threads of the parallel assembly and solves.
    pub threads: usize,
    /// Whether the run continued from a restart record.
    pub resumed: bool,
    /// `running`, `converged`, `failed` or `interrupted`.
    pub status: &'static str,
    pub error: Option<String>,
    /// The penalty stiffnesses the model building set for laws that leave them out, pair by
    /// pair (empty until the model is built).
    pub penalty_defaults: Vec<PenaltyDefault>,
}

impl RunInfo {
    pub(super) fn new(case: &Case, case_text: &str, options: &RunOptions) -> Self {
        Self {
            program: "asperity",
            version: env!("CARGO_PKG_VERSION"),
            command_line: options.command_line.clone(),
            case_file: std::path::absolute(&case.path).unwrap_or_else(|_| case.path.clone()),
            case: case_text.to_string(),
            working_directory: std::env::current_dir().ok(),
            start: utc_now(),
            end: None,
            host: host_name(),
            threads: rayon::current_num_threads(),
            resumed: options.mode == OutputMode::Resume,
            status: "running",
            error: None,
            penalty_defaults: Vec::new(),
        }
    }

    pub(super) fn finish<T>(&mut self, result: &Result<T>) {
        self.end = Some(utc_now());
        self.status = match result {
            Ok(_) => "converged",
            Err(Error::Interrupted { .. }) => "interrupted",
            Err(_) => "failed",
        };
        self.error = result.as_ref().err().map(crate::Error::readable);
    }

    pub(super) fn write(&self, folder: &OutputFolder) -> Result<()> {
        let path = folder.path(RunFile::Info)?;
        let text = serde_json::to_string_pretty(self)
            .map_err(|e| Error::io(&path, std::io::Error::other(e)))?;
        write_text(&path, &text)
    }
}

/// The machine's name (Linux; `unknown` elsewhere).
fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .ok()
        .filter(|h| !h.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "unknown".into())
}

/// The current time as RFC 3339 UTC with seconds (`2026-11-23T12:45:48Z`).
fn utc_now() -> String {
    humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string()
}
