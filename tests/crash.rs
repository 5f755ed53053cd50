//! A run killed with SIGKILL at random moments leaves only complete files, and `--resume`
//! reaches the same results as a run that was never stopped — byte for byte.
//!
//! The case (a plastic block pressed and dragged under a frictional contact, then unloaded)
//! cuts several steps back, so kills land inside steps as well as between them. The run is
//! deterministic (README "Output"), which makes the strongest check possible: every step file
//! a killed run left must be byte-identical to the uninterrupted run's file of that name,
//! `history.csv` and `results.pvd` must be prefixes of the uninterrupted ones (the tables that
//! grow by appended rows may end in a partial line, which `--resume` cuts off), and after
//! `--resume` every result file must be identical.

use crate::common;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::Stdio;

use common::{
    CaseBuilder, asperity, block_material, file_names, run_cli, two_blocks_on, with_keys,
};

/// Dragged plastic contact with unloading: 8 steps, about 30 increments.
fn case() -> CaseBuilder {
    two_blocks_on(with_keys(block_material(), &[("yield_stress", 12.0)]), 0.3)
        .support_history(
            "lid",
            &[("ux", 0.2)],
            &[0.0, 0.25, 0.5, 0.75, 1.0, 1.0, 0.5, 0.0],
        )
        .pressure_history("lid", 10.0, &[1.0, 1.0, 1.0, 1.0, 1.0, 1.5, 1.5, 1.0])
        .steps(8)
        .set("solver", "max_iterations", 8)
        .set("solver", "max_cutbacks", 12)
}

/// A small deterministic generator (xorshift64*), so that each seed kills at the same place
/// in the log every time the test runs.
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: u64) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) % n
    }
}

/// Starts a run into `out` and kills it (SIGKILL) `delay` µs after its `k`-th converged
/// increment was logged.
fn kill_run(case: &Path, out: &Path, k: u64, delay: u64) {
    let mut child = asperity()
        .args(["-v", "run"])
        .arg(case)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let mut seen = 0;
    for line in BufReader::new(stderr).lines() {
        if line.unwrap().contains("increment converged") {
            seen += 1;
            if seen == k {
                break;
            }
        }
    }
    std::thread::sleep(std::time::Duration::from_micros(delay));
    child.kill().unwrap(); // SIGKILL on Unix
    child.wait().unwrap();
}

fn read(path: PathBuf) -> String {
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The steps a history lists (integer pseudo-times only: a partial step has none here), in
/// its complete lines.
fn history_steps(history: &str) -> Vec<usize> {
    history
        .split_inclusive('\n')
        .filter(|l| l.ends_with('\n'))
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .filter(|&s| s > 0)
        .collect()
}

/// The steps whose `frame_NNNN.vtm` a series lists, each file present in `dir`.
fn series_steps(pvd: &str, dir: &Path) -> Vec<usize> {
    let mut steps = Vec::new();
    for line in pvd.lines().filter(|l| l.contains("<DataSet")) {
        let file = line
            .split("file=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        assert!(dir.join(file).is_file(), "the series lists missing {file}");
        if let Some(n) = file.strip_prefix("frame_") {
            steps.push(n.trim_end_matches(".vtm").parse().unwrap());
        }
    }
    steps
}

/// The per-contact fretting tables, which like `history.csv` grow by a row per frame
/// (`hysteresis_<pair>.csv`, `point_loops_<pair>.csv`) or per cycle (`cycles.csv`,
/// `wear_<pair>.csv`), and the run's manifest, a line per file.
fn is_growing_table(name: &str) -> bool {
    name == "cycles.csv"
        || name == "run_files.txt"
        || name == "restart_energy.bin"
        || (name.ends_with(".csv")
            && ["hysteresis_", "point_loops_", "wear_"]
                .iter()
                .any(|prefix| name.starts_with(prefix)))
}

/// What a killed run must have left in `dir`, against the uninterrupted run in `reference`.
/// Returns the number of steps the killed run had completed.
fn check_killed(dir: &Path, reference: &Path) -> usize {
    let mut listed = Vec::new();
    for name in file_names(dir) {
        let path = dir.join(&name);
        let reference_text = || read(reference.join(&name));
        if name.ends_with(".tmp") {
            continue; // removed by the next run, checked after the resume
        }
        match name.as_str() {
            "history.csv" => {
                let text = read(path);
                assert!(
                    reference_text().starts_with(&text),
                    "history.csv is not a prefix of the full run's:\n{text}"
                );
                listed = history_steps(&text);
            }
            "results.pvd" => {
                let text = read(path);
                let reference = reference_text();
                let entries = text.lines().filter(|l| l.contains("<DataSet"));
                let all: Vec<&str> = reference
                    .lines()
                    .filter(|l| l.contains("<DataSet"))
                    .collect();
                for (i, line) in entries.enumerate() {
                    assert_eq!(line, all[i], "results.pvd entry {i}");
                }
                assert!(text.ends_with("</VTKFile>\n"), "results.pvd incomplete");
            }
            // Tables growing by a row per frame or cycle: prefixes, like history.csv.
            table if is_growing_table(table) => {
                let bytes = std::fs::read(&path).unwrap();
                assert!(
                    std::fs::read(reference.join(&name))
                        .unwrap()
                        .starts_with(&bytes),
                    "{name} is not a prefix of the full run's:\n{}",
                    String::from_utf8_lossy(&bytes)
                );
            }
            // Records of the run itself (times, log lines with timestamps), not results.
            "run.json" | "summary.json" | "restart.bin" | "log.txt" => {}
            _ => assert_eq!(
                std::fs::read(&path).unwrap(),
                std::fs::read(reference.join(&name)).unwrap(),
                "{name} differs from the uninterrupted run's"
            ),
        }
    }
    if let Ok(pvd) = std::fs::read_to_string(dir.join("results.pvd")) {
        let series = series_steps(&pvd, dir);
        // The series is written last: it lists the history's steps, or all but the newest
        // when the kill fell between the two renames.
        assert!(
            series == listed || series[..] == listed[..listed.len().saturating_sub(1)],
            "series {series:?} and history {listed:?} disagree"
        );
    }
    listed.len()
}

/// After `--resume`: the same files as the uninterrupted run, byte for byte (except the
/// records of the run itself: run.json, summary.json's timings, the restart record's
/// timings), and no temporary file.
fn check_resumed(dir: &Path, reference: &Path) {
    let own = ["run.json", "summary.json", "restart.bin", "log.txt"];
    assert_eq!(
        file_names(dir),
        file_names(reference),
        "file sets differ after --resume"
    );
    for name in file_names(reference)
        .iter()
        .filter(|n| !own.contains(&n.as_str()))
    {
        assert!(
            std::fs::read(dir.join(name)).unwrap() == std::fs::read(reference.join(name)).unwrap(),
            "{name} differs after --resume"
        );
    }
    let summary = read(dir.join("summary.json"));
    assert!(summary.contains("\"converged\""), "{summary}");
    // The step records and the energy balance, read back from the files the record continues.
    let json = |text: &str| serde_json::from_str::<serde_json::Value>(text).unwrap();
    let (resumed, full) = (json(&summary), json(&read(reference.join("summary.json"))));
    for key in ["steps", "energy", "reactions"] {
        assert_eq!(resumed[key], full[key], "summary.json {key} after --resume");
    }
}

#[test]
fn killed_runs_leave_complete_files_and_resume_to_identical_results() {
    let root = tempfile::tempdir().unwrap();
    let case = case().write(&root.path().join("case.toml"));
    let reference = root.path().join("reference");
    run_cli(&case, &reference, &[]);
    let steps = history_steps(&read(reference.join("history.csv")));
    assert_eq!(steps, (1..=8).collect::<Vec<_>>());
    let mut interrupted = 0;
    for seed in 1..=6u64 {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ seed);
        let dir = root.path().join(format!("killed_{seed}"));
        // About 30 increments in all: kill anywhere from the first to the last ones.
        let k = 1 + rng.below(30);
        let delay = rng.below(20_000);
        kill_run(&case, &dir, k, delay);
        let done = check_killed(&dir, &reference);
        println!("seed {seed}: killed {delay} µs after increment {k}: {done} of 8 steps on disk");
        interrupted += usize::from(done < 8);
        run_cli(&case, &dir, &["--resume"]);
        check_resumed(&dir, &reference);
    }
    // Otherwise the kills all came too late to test anything.
    assert!(interrupted >= 3, "only {interrupted} runs were interrupted");
}
