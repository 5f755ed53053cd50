//! The job files of a planned study: `jobs.txt` (one command per line, for GNU parallel) and
//! `array.sbatch` (a Slurm job array), and the checks that keep them what they look like.
//!
//! Both files are read line by line (GNU parallel runs every line as a command, Slurm reads
//! `#SBATCH` lines up to the first command), so a value that reaches them must never start a
//! line: every `[slurm]` value is checked against the syntax Slurm accepts for it, and the
//! paths written into them (the study folder, the executable) may hold no control character.
//! Paths are then single-quoted for the POSIX shell that runs the commands; in the `#SBATCH
//! --output` line, which Slurm parses itself, the study folder is quoted for Slurm's parser.

use std::path::Path;

use serde::Deserialize;

use super::invalid;
use crate::Result;
use crate::error::shell_quote;
use crate::output::atomic::write_atomically;

/// The resource lines of `array.sbatch`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Slurm {
    /// `--time`: "minutes", "minutes:seconds", "hours:minutes:seconds", "days-hours",
    /// "days-hours:minutes" or "days-hours:minutes:seconds".
    #[serde(default = "default_time")]
    pub time: String,
    /// `--mem`: a positive integer with an optional K, M, G or T suffix (megabytes without).
    #[serde(default = "default_memory")]
    pub memory: String,
    /// CPUs of one run, at least 1: `--cpus-per-task` of `array.sbatch` and the solver
    /// threads (`RAYON_NUM_THREADS`) of every `jobs.txt` line, so that GNU parallel, which
    /// starts one job per core, runs `cores` threads in all rather than `cores × cores`.
    #[serde(default = "one")]
    pub cpus: usize,
    /// `--partition`: a partition name (letters, digits, `_`, `-`, `.`) or a comma-separated
    /// list of them.
    pub partition: Option<String>,
}

fn default_time() -> String {
    "01:00:00".into()
}
fn default_memory() -> String {
    "4G".into()
}
fn one() -> usize {
    1
}

impl Default for Slurm {
    fn default() -> Self {
        Self {
            time: default_time(),
            memory: default_memory(),
            cpus: 1,
            partition: None,
        }
    }
}

/// Whether `s` is one or more ASCII digits.
fn digits(s: &str) -> bool {
    !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit())
}

/// Whether `time` is in one of the formats of Slurm's `--time` (see [`Slurm::time`]): an
/// optional `days-` followed by one to three `:`-separated numbers; with days, the numbers
/// are hours[:minutes[:seconds]], without, minutes[:seconds] or hours:minutes:seconds.
fn slurm_time(time: &str) -> bool {
    let clock = match time.split_once('-') {
        Some((days, clock)) if digits(days) => clock,
        Some(_) => return false,
        None => time,
    };
    let parts: Vec<&str> = clock.split(':').collect();
    parts.len() <= 3 && parts.iter().all(|p| digits(p))
}

/// Whether `memory` is a positive integer with an optional K, M, G or T suffix (either case,
/// as Slurm's `--mem` takes it).
fn slurm_memory(memory: &str) -> bool {
    let number = memory
        .strip_suffix(['K', 'M', 'G', 'T', 'k', 'm', 'g', 't'])
        .unwrap_or(memory);
    digits(number) && number.parse::<u64>().is_ok_and(|n| n > 0)
}

/// Whether `partition` is a comma-separated list of partition names (letters, digits, `_`,
/// `-`, `.`).
fn slurm_partition(partition: &str) -> bool {
    partition.split(',').all(|name| {
        !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c))
    })
}

impl Slurm {
    /// Checks every value against Slurm's syntax for it; the error names `slurm.<key>` of
    /// sweep file `path`.
    pub(super) fn check(&self, path: &Path) -> Result<()> {
        let refuse = |key: &str, value: &str, reason: &str| {
            Err(invalid(
                path,
                format!("slurm.{key}"),
                format!("{value:?}"),
                reason,
            ))
        };
        if self.cpus < 1 {
            return refuse("cpus", "0", "at least one CPU per task");
        }
        if !slurm_time(&self.time) {
            return refuse(
                "time",
                &self.time,
                "not a Slurm time limit: use \"minutes\", \"minutes:seconds\", \
                 \"hours:minutes:seconds\", \"days-hours\", \"days-hours:minutes\" or \
                 \"days-hours:minutes:seconds\" (digits only)",
            );
        }
        if !slurm_memory(&self.memory) {
            return refuse(
                "memory",
                &self.memory,
                "not a Slurm memory size: a positive integer with an optional K, M, G or T \
                 suffix (\"4G\", \"512M\", \"4096\")",
            );
        }
        match &self.partition {
            Some(p) if !slurm_partition(p) => refuse(
                "partition",
                p,
                "not a Slurm partition name: letters, digits, '_', '-' and '.', several \
                 separated by commas (\"debug\", \"gpu,short\")",
            ),
            _ => Ok(()),
        }
    }
}

/// `path` as text fit for a job file: valid UTF-8 (else the file would name another path)
/// without control characters (C0, DEL and the C1 range: a line break would start a new
/// command); the error names sweep file `sweep` and `what` the path is.
pub(super) fn job_path<'p>(sweep: &Path, what: &str, path: &'p Path) -> Result<&'p str> {
    let refuse = |reason: &str| Err(invalid(sweep, what.into(), format!("{path:?}"), reason));
    match path.to_str() {
        None => refuse("the path is not valid UTF-8; job files could not name it"),
        Some(text) if text.chars().any(char::is_control) => refuse(
            "the path contains a control character (line break, tab, ...), which would break \
             the command lines of jobs.txt and array.sbatch; choose another name",
        ),
        Some(text) => Ok(text),
    }
}

/// The study folder as text fit for the job files ([`job_path`]), without a backslash: in
/// the `#SBATCH --output` file name a backslash stops Slurm from expanding `%A_%a`, so every
/// task would write the same log.
pub(super) fn study_path<'p>(sweep: &Path, study: &'p Path) -> Result<&'p str> {
    let text = job_path(sweep, "study folder", study)?;
    if text.contains('\\') {
        return Err(invalid(
            sweep,
            "study folder".into(),
            format!("{study:?}"),
            "the path contains a backslash, with which Slurm would not expand %A_%a in the log \
             file names of array.sbatch; choose another name",
        ));
    }
    Ok(text)
}

/// Quotes `s` for the argument parser of `#SBATCH` lines (sbatch's `_get_argument`): in
/// double quotes, with `\`, `"` and `#` escaped by a backslash (older Slurm versions end the
/// line at a `#` even inside quotes).
fn slurm_quote(s: &str) -> String {
    let mut quoted = String::with_capacity(s.len() + 2);
    quoted.push('"');
    for c in s.chars() {
        if matches!(c, '\\' | '"' | '#') {
            quoted.push('\\');
        }
        quoted.push(c);
    }
    quoted.push('"');
    quoted
}

/// The lines of `jobs.txt`: one command per run, each with the solver threads of one run
/// (`slurm.cpus`), as `array.sbatch` gives each task its `--cpus-per-task`; without it every
/// run would start one thread per core while GNU parallel runs one job per core.
fn jobs_lines(dir: &str, n: usize, exe: &str, slurm: &Slurm) -> String {
    (0..n)
        .map(|k| {
            format!(
                "RAYON_NUM_THREADS={} {exe} sweep run {dir} --task {k}\n",
                slurm.cpus
            )
        })
        .collect()
}

/// Writes `jobs.txt` (GNU parallel) and `array.sbatch` (Slurm) of a study with `n` runs;
/// `study` and `exe` are the texts of [`study_path`] and [`job_path`], `slurm` is checked.
/// The job files a plan writes into its study folder: one command per run, and the Slurm
/// job array.
pub(super) const JOBS: &str = "jobs.txt";
pub(super) const ARRAY: &str = "array.sbatch";

pub(super) fn write_jobs(study: &str, n: usize, exe: &str, slurm: &Slurm) -> Result<()> {
    let folder = Path::new(study);
    let (exe, dir) = (shell_quote(exe), shell_quote(study));
    let jobs = jobs_lines(&dir, n, &exe, slurm);
    write_atomically(&folder.join(JOBS), |w| w.write_all(jobs.as_bytes()))?;
    let partition = slurm
        .partition
        .as_ref()
        .map(|p| format!("#SBATCH --partition={p}\n"))
        .unwrap_or_default();
    // `%` starts Slurm's file-name patterns (`%A`, `%a`); `%%` is a literal one.
    let log = slurm_quote(&format!(
        "{}/runs/slurm-%A_%a.out",
        study.replace('%', "%%")
    ));
    let script = format!(
        "#!/bin/bash\n\
         # Slurm job array of the sweep in {dir}: one task per run, the task id selecting the run.\n\
         # Submit with `sbatch {sbatch}`; finished runs are skipped, so resubmitting\n\
         # completes an interrupted sweep. Then `asperity sweep collect {dir}`.\n\
         #SBATCH --job-name=asperity-sweep\n\
         #SBATCH --array=0-{last}\n\
         #SBATCH --ntasks=1\n\
         #SBATCH --cpus-per-task={cpus}\n\
         #SBATCH --mem={mem}\n\
         #SBATCH --time={time}\n\
         {partition}\
         #SBATCH --output={log}\n\
         RAYON_NUM_THREADS=\"${{SLURM_CPUS_PER_TASK:-1}}\" exec {exe} sweep run {dir} --task \"$SLURM_ARRAY_TASK_ID\"\n",
        sbatch = shell_quote(&format!("{study}/array.sbatch")),
        last = n - 1,
        cpus = slurm.cpus,
        mem = slurm.memory,
        time = slurm.time,
    );
    write_atomically(&folder.join(ARRAY), |w| w.write_all(script.as_bytes()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slurm_times_in_every_accepted_format_and_nothing_else() {
        for ok in [
            "30",
            "30:00",
            "1:00:00",
            "2-0",
            "2-12:00",
            "2-12:00:00",
            "0",
        ] {
            assert!(slurm_time(ok), "{ok}");
        }
        for bad in [
            "",
            "1::0",
            "1-2-3",
            "1:2:3:4",
            "1-2:3:4:5",
            "-1",
            "1-",
            "1h",
            " 1",
            "1\n",
            "１",
        ] {
            assert!(!slurm_time(bad), "{bad:?}");
        }
    }

    #[test]
    fn slurm_memory_is_a_positive_integer_with_a_unit() {
        for ok in ["1", "4096", "4G", "512m", "1T", "100K"] {
            assert!(slurm_memory(ok), "{ok}");
        }
        for bad in ["", "0", "0G", "G", "4X", "-4G", "4 G", "4GB", "1e3", "4G\n"] {
            assert!(!slurm_memory(bad), "{bad:?}");
        }
    }

    /// GNU parallel starts one job per core: each line must ask for the CPUs of one run (the
    /// `cpus` of `[slurm]`, 1 by default), not let the solver take every core.
    #[test]
    fn every_jobs_line_sets_the_threads_of_one_run() {
        for (cpus, want) in [(1, "RAYON_NUM_THREADS=1 "), (4, "RAYON_NUM_THREADS=4 ")] {
            let slurm = Slurm {
                cpus,
                ..Slurm::default()
            };
            let text = jobs_lines("'s'", 3, "'a'", &slurm);
            let lines: Vec<&str> = text.lines().collect();
            assert_eq!(lines.len(), 3);
            for (k, line) in lines.iter().enumerate() {
                assert_eq!(*line, format!("{want}'a' sweep run 's' --task {k}"));
            }
        }
    }

    #[test]
    fn quoting_keeps_every_character_literal() {
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
        assert_eq!(slurm_quote(r#"a"b#c\d e"#), r#""a\"b\#c\\d e""#);
    }
}
