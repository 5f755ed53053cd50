//! `asperity sweep`: planning (case files, manifest, jobs.txt, array.sbatch), key errors, the
//! local pool with restart, and collection with a failed run reported.

use std::path::{Path, PathBuf};
use std::process::Command;

use asperity::Error;
use asperity::config::Case;
use asperity::sweep;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn exe() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_asperity"))
}

/// The shipped example with its base path made absolute, written into `dir` with `edit`.
fn sweep_file(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(root().join("pipelines/sweep/specimen.toml")).unwrap();
    let base = root().join("pipelines/fit/specimen/specimen.toml");
    let text = text.replace(
        "\"../fit/specimen/specimen.toml\"",
        &format!("{:?}", base.display().to_string()),
    );
    let path = dir.join("sweep.toml");
    std::fs::write(&path, edit(text)).unwrap();
    path
}

fn law_of(case: &Path) -> (f64, f64) {
    let case = Case::from_file(case).unwrap();
    let law = &case.contacts[0].law;
    assert_eq!(law.law.name, "rough_joint");
    (law.get("c_n").unwrap(), law.get("m").unwrap())
}

#[test]
fn plan_writes_one_checked_case_per_grid_point_and_the_job_files() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study");
    let m = sweep::plan(&sweep_file(dir.path(), |t| t), &study, &exe()).unwrap();
    assert_eq!(m.runs.len(), 6);
    let mut seen = Vec::new();
    for r in &m.runs {
        let (c_n, m_) = law_of(&study.join(&r.dir).join("case.toml"));
        assert_eq!(
            (r.values[0].as_float(), r.values[1].as_float()),
            (Some(c_n), Some(m_))
        );
        seen.push((c_n, m_));
    }
    // Grid: every combination of the geometric range 1e-3..4e-3 (3 values) and [0.4, 0.6].
    for c in [1e-3, 2e-3, 4e-3] {
        for e in [0.4, 0.6] {
            assert!(
                seen.iter().any(|(a, b)| (a - c).abs() < 1e-15 && *b == e),
                "{c}, {e}: {seen:?}"
            );
        }
    }
    let study = study.canonicalize().unwrap();
    let jobs = std::fs::read_to_string(study.join("jobs.txt")).unwrap();
    let lines: Vec<&str> = jobs.lines().collect();
    assert_eq!(lines.len(), 6);
    for (k, line) in lines.iter().enumerate() {
        assert_eq!(
            *line,
            format!(
                "'{}' sweep run '{}' --task {k}",
                exe().display(),
                study.display()
            )
        );
    }
    let sbatch = std::fs::read_to_string(study.join("array.sbatch")).unwrap();
    for line in [
        "#SBATCH --array=0-5",
        "#SBATCH --ntasks=1",
        "#SBATCH --cpus-per-task=1",
        "#SBATCH --mem=1G",
        "#SBATCH --time=00:10:00",
    ] {
        assert!(
            sbatch.lines().any(|l| l == line),
            "{line} missing:\n{sbatch}"
        );
    }
    let command = format!(
        "exec '{}' sweep run '{}' --task \"$SLURM_ARRAY_TASK_ID\"",
        exe().display(),
        study.display()
    );
    assert_eq!(sbatch.lines().last(), Some(command.as_str()));
    // Slurm reads #SBATCH lines only before the first command.
    let first_command = sbatch.lines().position(|l| !l.starts_with('#')).unwrap();
    assert!(
        sbatch
            .lines()
            .skip(first_command)
            .all(|l| !l.starts_with("#SBATCH"))
    );
    assert!(
        Command::new("bash")
            .arg("-n")
            .arg(study.join("array.sbatch"))
            .status()
            .unwrap()
            .success()
    );
}

#[test]
fn latin_hypercube_plan_stays_in_its_ranges() {
    let dir = tempfile::tempdir().unwrap();
    let path = sweep_file(dir.path(), |t| {
        t.replace(
            "method = \"grid\"",
            "method = \"latin_hypercube\"\nsamples = 5\nseed = 3",
        )
        .replace("values = [0.4, 0.6]", "range = { from = 0.4, to = 0.6 }")
    });
    let m = sweep::plan(&path, &dir.path().join("study"), &exe()).unwrap();
    assert_eq!(m.runs.len(), 5);
    let mut strata: Vec<usize> = m
        .runs
        .iter()
        .map(|r| {
            let v = r.values[1].as_float().unwrap();
            assert!((0.4..0.6).contains(&v));
            ((v - 0.4) / 0.2 * 5.0) as usize
        })
        .collect();
    strata.sort();
    assert_eq!(strata, vec![0, 1, 2, 3, 4]);
}

fn key_error(e: Error) -> (PathBuf, String, String) {
    match e {
        Error::InvalidParameter {
            path, key, reason, ..
        } => (path, key, reason),
        other => panic!("expected an invalid-parameter error, got {other}"),
    }
}

#[test]
fn keys_that_are_not_in_the_case_are_errors_naming_the_sweep_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study");
    let path = sweep_file(dir.path(), |t| {
        t.replace("contact.0.law.m", "contact.3.law.m")
    });
    let (p, key, reason) = key_error(sweep::plan(&path, &study, &exe()).unwrap_err());
    assert_eq!((p, key.as_str()), (path.clone(), "vary[1].key"));
    assert!(
        reason.contains("contact.3") && reason.contains("out of range"),
        "{reason}"
    );
    // A misspelt last segment: the case refuses the unknown key.
    let path = sweep_file(dir.path(), |t| {
        t.replace("contact.0.law.m", "contact.0.law.mm")
    });
    let (p, _, reason) = key_error(sweep::plan(&path, &study, &exe()).unwrap_err());
    assert_eq!(p, path);
    assert!(reason.contains("mm"), "{reason}");
    // A value out of the law's range fails at planning, not in the middle of the sweep.
    let path = sweep_file(dir.path(), |t| {
        t.replace("values = [0.4, 0.6]", "values = [0.4, -0.6]")
    });
    let (_, key, reason) = key_error(sweep::plan(&path, &study, &exe()).unwrap_err());
    assert!(
        key.contains("contact.0.law.m = -0.6") && reason.contains("contact[0].law.m"),
        "{key}: {reason}"
    );
}

fn run_cli(args: &[&str]) -> (bool, String) {
    let out = Command::new(exe()).args(args).output().unwrap();
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out.status.success(), text)
}

/// The reaction of the specimen grows as the joint stiffens: smaller c_n, for the same m,
/// gives a larger force (the bodies and the joint in series).
#[test]
fn local_pool_runs_restarts_and_collect_reports_a_failed_run() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study");
    let path = sweep_file(dir.path(), |t| t);
    let s = study.to_str().unwrap();
    assert!(run_cli(&["sweep", "plan", path.to_str().unwrap(), "--out", s]).0);
    // Break run 4's case file: it must fail, leave its error in summary.json, and be reported.
    std::fs::write(study.join("runs/0004/case.toml"), "[mesh]\nfile = 3\n").unwrap();
    let (ok, text) = run_cli(&["sweep", "run", s, "--jobs", "2"]);
    assert!(!ok && text.contains("ran 6 runs (1 failed: [4])"), "{text}");
    let (ok, text) = run_cli(&["sweep", "run", s, "--jobs", "2"]);
    assert!(
        ok && text.contains("ran 0 runs"),
        "restart must skip finished runs: {text}"
    );
    let c = sweep::collect(&study, false).unwrap();
    assert_eq!(c.failures.len(), 1);
    assert_eq!((c.failures[0].0, c.failures[0].1.as_str()), (4, "failed"));
    assert!(c.failures[0].2.contains("case.toml"), "{:?}", c.failures);
    let csv = std::fs::read_to_string(&c.csv).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 6);
    let force = |k: usize| -> f64 { rows[k][5].parse().unwrap() };
    // Runs 0, 2 (c_n = 1e-3, 2e-3 at m = 0.4): compressive, stiffer joint → larger |force|.
    assert!(force(0) < force(2) && force(2) < 0.0, "{csv}");
    assert_eq!(rows[4][3], "failed");
    assert!(rows[4][5].is_empty());
    let (ok, text) = run_cli(&["sweep", "collect", s, "--no-plot"]);
    assert!(!ok && text.contains("run 4: failed"), "{text}");
}
