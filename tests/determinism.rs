//! Determinism: the same case gives bitwise-identical result files run after run and with 1, 2
//! or 4 worker threads. Parallel assembly must therefore never let the thread count change
//! the order of a floating-point sum.
//!
//! Each case is run by the built binary in a child process with `RAYON_NUM_THREADS` set (the
//! pool size is fixed at start-up), on a mesh of `tests/fixtures/contact_pair.geo` fine
//! enough (a few hundred cells) that assembly is split into several parallel chunks. Every
//! result file of the output folder is compared byte for byte; of the run's own records,
//! `summary.json` is compared as JSON without its wall-clock `seconds` and case path, and
//! `run.json`, `log.txt` and `restart.bin` (times, host, timestamps) are left out.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{CaseBuilder, block_material, file_names, fixture, two_blocks, with_keys};

/// A frictional pair that slips: two bodies pressed together (lid moved down) and sheared
/// (lid moved sideways) until the tangential force reaches μ times the normal force.
fn frictional() -> CaseBuilder {
    two_blocks(0.2)
        .support("lid", &[("ux", 0.03), ("uy", -0.01)])
        .steps(3)
}

/// An axisymmetric elasto-plastic body compressed past yield and partly unloaded.
fn plastic() -> CaseBuilder {
    let material = with_keys(
        block_material(),
        &[("yield_stress", 1.0), ("hardening", 10.0)],
    );
    CaseBuilder::axisymmetric()
        .body("lower", material)
        .support("base", &[("uy", 0.0)])
        .support("lower_top", &[("uy", -0.03)])
        .step_factors(&[0.5, 1.0, 0.5])
}

/// Runs `case` on a mesh of `contact_pair.geo` (size 0.3) with `threads` worker threads into
/// `dir/out_<threads>`.
fn run(dir: &Path, case: &CaseBuilder, threads: usize) -> PathBuf {
    let case_path = case
        .clone()
        .mesh_geo(&fixture("contact_pair.geo"), 0.3)
        .write(&dir.join("case.toml"));
    let out = dir.join(format!("out_{threads}"));
    let status = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(["run", case_path.to_str().unwrap(), "--out"])
        .arg(&out)
        .env("RAYON_NUM_THREADS", threads.to_string())
        .output()
        .expect("runs");
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    out
}

/// `summary.json` without its timings (the floor's counts kept) and the path of the case
/// file (each run has its own).
fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    let object = value.as_object_mut().unwrap();
    object.remove("seconds").unwrap();
    object.remove("case").unwrap();
    let floor = object["floor"].as_object_mut().unwrap();
    for timing in ["seconds", "ratio", "parts", "work_seconds"] {
        floor.remove(timing).unwrap();
    }
    value
}

/// Newton iterations of every step (column `iterations` of `history.csv`).
fn iterations(dir: &Path) -> Vec<u32> {
    let history = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let mut lines = history.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = header.iter().position(|&c| c == "iterations").unwrap();
    lines
        .map(|l| l.split(',').nth(column).unwrap().parse().unwrap())
        .collect()
}

fn check_identical(case: &CaseBuilder) {
    let dir = tempfile::tempdir().unwrap();
    let reference = run(dir.path(), case, 1);
    // The case must be nonlinear (a step that takes several Newton iterations, or interface
    // iterations within one), or it would test little. history.csv's first row is the
    // unloaded start (step 0).
    let steps = iterations(&reference);
    let interface_iterations = summary(&reference)["floor"]["counts"]["interface_iterations"]
        .as_u64()
        .unwrap();
    assert!(
        steps[1..].iter().any(|&n| n > 1) || interface_iterations > 0,
        "{steps:?}"
    );
    let files = file_names(&reference);
    assert!(files.iter().any(|f| f.ends_with(".vtu")), "{files:?}");
    // Threads 1 again (run after run), then 2 and 4.
    for (k, threads) in [1, 2, 4].into_iter().enumerate() {
        let other_dir = dir.path().join(format!("run_{k}"));
        std::fs::create_dir(&other_dir).unwrap();
        let other = run(&other_dir, case, threads);
        assert_eq!(file_names(&other), files, "{threads} threads");
        // Records of the run itself (times, host, timestamped log lines; the restart record
        // holds the run's timings) are not results; summary.json is compared without its
        // timings below.
        let records = ["summary.json", "run.json", "log.txt", "restart.bin"];
        for f in files.iter().filter(|f| !records.contains(&f.as_str())) {
            let (a, b) = (
                std::fs::read(reference.join(f)).unwrap(),
                std::fs::read(other.join(f)).unwrap(),
            );
            assert!(a == b, "{f} differs with {threads} threads");
        }
        assert_eq!(summary(&other), summary(&reference), "{threads} threads");
    }
}

#[test]
fn a_frictional_case_is_bitwise_identical_with_1_2_and_4_threads() {
    check_identical(&frictional());
}

#[test]
fn a_plastic_case_is_bitwise_identical_with_1_2_and_4_threads() {
    check_identical(&plastic());
}
