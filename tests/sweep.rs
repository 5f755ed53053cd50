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
    let text = std::fs::read_to_string(root().join("examples/sweep/specimen.toml")).unwrap();
    let base = root().join("examples/fit/specimen/specimen.toml");
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
                "RAYON_NUM_THREADS=1 '{}' sweep run '{}' --task {k}",
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
        "RAYON_NUM_THREADS=\"${{SLURM_CPUS_PER_TASK:-1}}\" exec '{}' sweep run '{}' --task \"$SLURM_ARRAY_TASK_ID\"",
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
    // Repaired, the failed run is retried over its own files (its summary, log and manifest).
    std::fs::copy(
        study.join("runs/0003/case.toml"),
        study.join("runs/0004/case.toml"),
    )
    .unwrap();
    let (ok, text) = run_cli(&["sweep", "run", s, "--jobs", "2", "--retry-failed"]);
    assert!(ok && text.contains("ran 1 runs (0 failed"), "{text}");
    let c = sweep::collect(&study, false).unwrap();
    assert!(c.failures.is_empty(), "{:?}", c.failures);
    // A damaged summary (cut short, or no run's) is reported as such, not as 'not run', and
    // the run is not done: the next `sweep run` runs it again.
    std::fs::write(study.join("runs/0001/summary.json"), "{").unwrap();
    std::fs::write(study.join("runs/0002/summary.json"), "[]").unwrap();
    let c = sweep::collect(&study, false).unwrap();
    let damaged: Vec<(usize, &str)> = c.failures.iter().map(|f| (f.0, f.1.as_str())).collect();
    assert_eq!(
        damaged,
        [(1, "damaged"), (2, "damaged")],
        "{:?}",
        c.failures
    );
    assert!(c.failures[0].2.contains("summary.json"), "{:?}", c.failures);
    let (ok, text) = run_cli(&["sweep", "run", s, "--jobs", "2"]);
    assert!(ok && text.contains("ran 2 runs (0 failed"), "{text}");
}

/// A study planned again into its folder with other values: the runs whose case changed are
/// stale — reported as such by collect, never as the new values' results — and run again
/// (over their own files); the unchanged ones stay done.
#[test]
fn a_study_planned_again_runs_the_runs_whose_case_changed() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study");
    let s = study.to_str().unwrap();
    let with_c_n = |values: &str| {
        let values = values.to_string();
        sweep_file(dir.path(), move |t| {
            t.replace(
                "range = { from = 1e-3, to = 4e-3, count = 3, log = true }",
                &format!("values = {values}"),
            )
            .replace("values = [0.4, 0.6]", "values = [0.4]")
        })
    };
    let path = with_c_n("[1e-3, 2e-3]");
    assert!(run_cli(&["sweep", "plan", path.to_str().unwrap(), "--out", s]).0);
    let (ok, text) = run_cli(&["sweep", "run", s, "--jobs", "2"]);
    assert!(ok && text.contains("ran 2 runs"), "{text}");
    // Columns: run, c_n, m, status, force, ...
    let force = |study: &Path| -> Vec<String> {
        let c = sweep::collect(study, false).unwrap();
        let csv = std::fs::read_to_string(&c.csv).unwrap();
        csv.lines()
            .skip(1)
            .map(|l| l.split(',').nth(4).unwrap().to_string())
            .collect()
    };
    let first = force(&study);
    let path = with_c_n("[1e-3, 4e-3]");
    assert!(run_cli(&["sweep", "plan", path.to_str().unwrap(), "--out", s]).0);
    let c = sweep::collect(&study, false).unwrap();
    assert_eq!(c.failures.len(), 1, "{:?}", c.failures);
    assert_eq!((c.failures[0].0, c.failures[0].1.as_str()), (1, "stale"));
    let (ok, text) = run_cli(&["sweep", "run", s, "--jobs", "2"]);
    assert!(ok && text.contains("ran 1 runs"), "{text}");
    let second = force(&study);
    assert_eq!(second[0], first[0]);
    let (old, new): (f64, f64) = (first[1].parse().unwrap(), second[1].parse().unwrap());
    // c_n = 4e-3 is a softer joint than 2e-3: a smaller compressive reaction.
    assert!(new < 0.0 && new > old, "{old} → {new}");
}

/// A plan refuses, before it writes anything, a study folder whose files of a plan's names are
/// not a sweep's (a jobs.txt of the user's, a manifest.json that is no sweep's), and a sweep
/// that varies one key twice; a refused plan leaves no folder behind.
#[test]
fn a_plan_never_overwrites_what_no_sweep_wrote() {
    let dir = tempfile::tempdir().unwrap();
    let path = sweep_file(dir.path(), |t| t);
    for name in ["jobs.txt", "manifest.json"] {
        let study = dir.path().join(format!("mine_{name}"));
        std::fs::create_dir(&study).unwrap();
        std::fs::write(study.join(name), "mine").unwrap();
        match sweep::plan(&path, &study, &exe()) {
            Err(Error::OutputForeign { file, .. }) => assert_eq!(file, study.join(name)),
            other => panic!("{name}: expected a refusal, got {other:?}"),
        }
        assert_eq!(std::fs::read_to_string(study.join(name)).unwrap(), "mine");
        assert_eq!(
            std::fs::read_dir(&study).unwrap().count(),
            1,
            "{name}: wrote files"
        );
    }
    let twice = sweep_file(dir.path(), |t| {
        t.replace("key = \"contact.0.law.m\"", "key = \"contact.0.law.c_n\"")
    });
    let study = dir.path().join("twice");
    let (p, key, reason) = key_error(sweep::plan(&twice, &study, &exe()).unwrap_err());
    assert_eq!((p, key.as_str()), (twice, "vary[1].key"));
    assert!(reason.contains("vary[0]"), "{reason}");
    let bad = sweep_file(dir.path(), |t| {
        t.replace("values = [0.4, 0.6]", "values = [0.4, -0.6]")
    });
    assert!(sweep::plan(&bad, &study, &exe()).is_err());
    assert!(!study.exists(), "a refused plan made its folder");
    // A run's folder linked elsewhere is refused when the study is planned again, and what
    // the link points to is left as it was.
    #[cfg(unix)]
    {
        let path = sweep_file(dir.path(), |t| t);
        let study = dir.path().join("linked");
        sweep::plan(&path, &study, &exe()).unwrap();
        let other = dir.path().join("other");
        std::fs::create_dir(&other).unwrap();
        std::fs::write(other.join("case.toml"), "mine").unwrap();
        std::fs::remove_dir_all(study.join("runs/0001")).unwrap();
        std::os::unix::fs::symlink(&other, study.join("runs/0001")).unwrap();
        match sweep::plan(&path, &study, &exe()) {
            Err(Error::OutputForeign { file, .. }) => assert_eq!(file, study.join("runs/0001")),
            other => panic!("expected a refusal, got {other:?}"),
        }
        assert_eq!(
            std::fs::read_to_string(other.join("case.toml")).unwrap(),
            "mine"
        );
        // Nor does a run write through it.
        match sweep::run_task(&study, 1, false) {
            Err(Error::OutputForeign { file, .. }) => assert_eq!(file, study.join("runs/0001")),
            other => panic!("expected a refusal, got {other:?}"),
        }
        assert_eq!(std::fs::read_dir(&other).unwrap().count(), 1);
    }
}

// ---- Hostile inputs: values and paths that reach generated job files and file names ----

/// The shipped sweep file with its `[slurm]` section replaced by `slurm` (TOML lines).
fn with_slurm(dir: &Path, slurm: &str) -> PathBuf {
    sweep_file(dir, |t| {
        format!("{}[slurm]\n{slurm}\n", t.split("[slurm]").next().unwrap())
    })
}

/// `#SBATCH` lines, then exactly one command: what Slurm and bash must both see in
/// `array.sbatch`. Returns the command line. Slurm reads options only up to the first line
/// that is neither blank nor a comment, so every option must come before it.
fn the_one_command(sbatch: &str) -> &str {
    let commands: Vec<&str> = sbatch
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .collect();
    assert_eq!(commands.len(), 1, "exactly one command expected:\n{sbatch}");
    let first = sbatch.lines().position(|l| l == commands[0]).unwrap();
    assert!(
        sbatch
            .lines()
            .skip(first)
            .all(|l| !l.starts_with("#SBATCH")),
        "#SBATCH after the command:\n{sbatch}"
    );
    assert!(
        Command::new("bash")
            .arg("-n")
            .arg("-c")
            .arg(sbatch)
            .status()
            .unwrap()
            .success(),
        "bash -n fails:\n{sbatch}"
    );
    commands[0]
}

/// The argument of `#SBATCH <option>` as Slurm's batch-script parser reads it (sbatch
/// `_get_argument`: a backslash escapes the next character, '…' and "…" quote, an unquoted
/// `#` starts a comment, blanks separate arguments); `None` if the option is absent. Older
/// Slurm versions (before 17.11) quote with "…" only and end the line at any unescaped `#`:
/// both readings must agree.
fn sbatch_option(sbatch: &str, option: &str) -> Option<String> {
    let rest = sbatch
        .lines()
        .filter_map(|l| l.strip_prefix("#SBATCH "))
        .find_map(|l| l.strip_prefix(option))?;
    let read = |legacy: bool| {
        let (mut out, mut quote, mut escape) = (String::new(), None, false);
        for c in rest.chars() {
            match (escape, quote, c) {
                (true, ..) => {
                    escape = false;
                    out.push(c);
                }
                (false, _, '\\') => escape = true,
                (false, _, '#') if legacy => break,
                (false, Some(q), c) if c == q => quote = None,
                (false, Some(_), c) => out.push(c),
                (false, None, '"') => quote = Some(c),
                (false, None, '\'') if !legacy => quote = Some(c),
                (false, None, '#') => break,
                (false, None, c) if c.is_whitespace() => break,
                (false, None, c) => out.push(c),
            }
        }
        assert!(quote.is_none(), "unmatched quote in #SBATCH {option}{rest}");
        out
    };
    let argument = read(false);
    assert_eq!(argument, read(true), "#SBATCH {option}{rest}");
    Some(argument)
}

#[test]
fn slurm_values_outside_slurm_syntax_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study");
    for (key, value) in [
        ("partition", r#""debug\necho INJECTED""#),
        ("partition", r#""debug; touch CANARY""#),
        ("partition", r#""$(touch CANARY)""#),
        ("partition", r#""`touch CANARY`""#),
        ("partition", r#""a b""#),
        ("partition", r#""'a'""#),
        ("partition", r#""""#),
        ("partition", r#""a,,b""#),
        ("time", r#""01:00:00\ntouch CANARY""#),
        ("time", r#""01:00:00\r""#),
        ("time", r#""1:00:00; touch CANARY""#),
        ("time", r#""""#),
        ("time", r#""1::00""#),
        ("time", r#""1-2-3""#),
        ("time", r#""1:2:3:4""#),
        ("time", r#""1-2:3:4:5""#),
        ("time", r#""one hour""#),
        ("time", r#""1-""#),
        ("time", r#""-1""#),
        ("time", r#""1h""#),
        ("memory", r#""4G\ntouch CANARY""#),
        ("memory", r#""4G\u0000""#),
        ("memory", r#""0""#),
        ("memory", r#""0G""#),
        ("memory", r#""4X""#),
        ("memory", r#""-4G""#),
        ("memory", r#""G""#),
        ("memory", r#""4 G""#),
        ("memory", r#""4GB""#),
        ("memory", r#""99999999999999999999999G""#),
        ("cpus", "0"),
    ] {
        let path = with_slurm(dir.path(), &format!("{key} = {value}"));
        let (p, k, reason) = key_error(sweep::plan(&path, &study, &exe()).unwrap_err());
        assert_eq!((p, k), (path, format!("slurm.{key}")), "{key} = {value}");
        assert!(!reason.is_empty());
        assert!(!study.exists(), "{key} = {value}: the study was created");
    }
}

#[test]
fn slurm_values_in_slurm_syntax_become_resource_lines() {
    let dir = tempfile::tempdir().unwrap();
    for (time, memory, partition, cpus) in [
        ("30", "4096", "debug", 1),
        ("30:00", "4G", "gpu,short", 2),
        ("1:00:00", "512M", "a_b-c.d", 16),
        ("2-0", "1T", "x1", 1),
        ("2-12:00", "100K", "P", 1),
        ("2-12:00:00", "2g", "long.q", 1),
    ] {
        let study = dir.path().join(format!("study-{cpus}-{memory}"));
        let path = with_slurm(
            dir.path(),
            &format!(
                "time = {time:?}\nmemory = {memory:?}\npartition = {partition:?}\ncpus = {cpus}"
            ),
        );
        sweep::plan(&path, &study, &exe()).unwrap();
        let sbatch = std::fs::read_to_string(study.join("array.sbatch")).unwrap();
        the_one_command(&sbatch);
        assert_eq!(sbatch_option(&sbatch, "--time=").unwrap(), time);
        assert_eq!(sbatch_option(&sbatch, "--mem=").unwrap(), memory);
        assert_eq!(sbatch_option(&sbatch, "--partition=").unwrap(), partition);
        assert_eq!(
            sbatch_option(&sbatch, "--cpus-per-task=").unwrap(),
            cpus.to_string()
        );
    }
}

/// Every file named `name` below `dir`.
fn find(dir: &Path, name: &str) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.file_name().is_some_and(|n| n == name) {
            found.push(path.clone());
        }
        if path.is_dir() && !path.is_symlink() {
            found.extend(find(&path, name));
        }
    }
    found
}

/// A stand-in for asperity at `path` that appends its arguments (each followed by a NUL)
/// and then `RAYON_NUM_THREADS=…` and an empty record end to `$ARGV_LOG`.
fn stub_asperity(path: &Path) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(
        path,
        "#!/bin/sh\nprintf '%s\\0' \"$@\" \"RAYON_NUM_THREADS=$RAYON_NUM_THREADS\" '' >> \"$ARGV_LOG\"\n",
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).unwrap();
}

/// The calls recorded by [`stub_asperity`]: each call's arguments.
fn recorded_calls(log: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(log).unwrap_or_default();
    let mut calls = Vec::new();
    let mut call = Vec::new();
    for field in text.split('\0') {
        if field.is_empty() {
            if !call.is_empty() {
                calls.push(std::mem::take(&mut call));
            }
        } else {
            call.push(field.to_string());
        }
    }
    calls
}

/// Study folders and executables whose names are shell syntax: planned, `jobs.txt` (read line
/// by line as GNU parallel does, each line run by `sh -c`) and `array.sbatch` (run by bash
/// with a task id) call the executable with the study as one argument, and nothing else runs.
#[test]
fn study_and_executable_paths_with_shell_syntax_stay_single_arguments() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path().canonicalize().unwrap();
    let path = sweep_file(&dir, |t| t);
    let exe = dir
        .join("bin it's $(touch CANARY) `touch CANARY`; touch CANARY")
        .join("asperity");
    stub_asperity(&exe);
    let work = dir.join("work");
    std::fs::create_dir(&work).unwrap();
    let log = dir.join("argv.log");
    for name in [
        "it's",
        "$(touch CANARY)",
        "`touch CANARY`",
        "a; touch CANARY",
        "a\" && touch CANARY && \"b",
        "sp ace | touch CANARY > x < y & {} !x $HOME ~ * ?",
        "%A %a %j %%",
        "#x # touch CANARY",
        "é ' \" '",
    ] {
        let study = dir.join(name).join("study");
        sweep::plan(&path, &study, &exe).unwrap();
        let study_arg = study.to_str().unwrap().to_string();
        let expected = |task: &str, threads: &str| {
            vec![
                "sweep".to_string(),
                "run".into(),
                study_arg.clone(),
                "--task".into(),
                task.into(),
                format!("RAYON_NUM_THREADS={threads}"),
            ]
        };
        let jobs = std::fs::read_to_string(study.join("jobs.txt")).unwrap();
        assert_eq!(jobs.lines().count(), 6, "{name}: {jobs}");
        let _ = std::fs::remove_file(&log);
        for line in jobs.lines() {
            let status = Command::new("sh")
                .args(["-c", line])
                .current_dir(&work)
                .env("ARGV_LOG", &log)
                .env_remove("RAYON_NUM_THREADS")
                .status()
                .unwrap();
            assert!(status.success(), "{name}: {line}");
        }
        let calls = recorded_calls(&log);
        let want: Vec<_> = (0..6).map(|k| expected(&k.to_string(), "1")).collect();
        assert_eq!(calls, want, "{name}: jobs.txt");

        let sbatch = std::fs::read_to_string(study.join("array.sbatch")).unwrap();
        the_one_command(&sbatch);
        assert_eq!(
            sbatch_option(&sbatch, "--output=").unwrap(),
            format!("{}/runs/slurm-%A_%a.out", study_arg.replace('%', "%%")),
            "{name}"
        );
        let _ = std::fs::remove_file(&log);
        let status = Command::new("bash")
            .arg(study.join("array.sbatch"))
            .current_dir(&work)
            .env("ARGV_LOG", &log)
            .env("SLURM_ARRAY_TASK_ID", "3")
            .env("SLURM_CPUS_PER_TASK", "2")
            .status()
            .unwrap();
        assert!(status.success(), "{name}: array.sbatch");
        assert_eq!(
            recorded_calls(&log),
            vec![expected("3", "2")],
            "{name}: array.sbatch"
        );
        assert_eq!(find(&dir, "CANARY"), Vec::<PathBuf>::new(), "{name}");
    }
}

/// Control characters in a path written into a job file (the study folder, the executable,
/// the sweep file named in every case file) and backslashes in the study folder (Slurm then
/// expands no `%A_%a` in the log file name) are refused, naming the path, before anything is
/// written; so are control characters in a varied key (written into every case file's header).
#[test]
fn control_characters_in_paths_and_keys_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let path = sweep_file(dir.path(), |t| t);
    for bad in [
        "a\nb", "a\rb", "a\tb", "a\u{7f}b", "a\u{1b}b", "a\0b", "a\\b",
    ] {
        let study = dir.path().join(bad).join("study");
        let (p, key, _) = key_error(sweep::plan(&path, &study, &exe()).unwrap_err());
        assert_eq!((&p, key.as_str()), (&path, "study folder"), "{bad:?}");
        assert!(!dir.path().join(bad).exists(), "{bad:?}");
    }
    let study = dir.path().join("study");
    let hostile_exe = dir.path().join("bin\ntouch CANARY").join("asperity");
    let (_, key, _) = key_error(sweep::plan(&path, &study, &hostile_exe).unwrap_err());
    assert_eq!(key, "asperity executable");
    // A sweep file whose name has a newline (its default study folder would have one too).
    let named = dir.path().join("sweep\ntouch CANARY.toml");
    std::fs::copy(&path, &named).unwrap();
    let (p, key, _) = key_error(sweep::plan(&named, &study, &exe()).unwrap_err());
    assert_eq!((p, key.as_str()), (named, "sweep file"));
    let keyed = sweep_file(dir.path(), |t| {
        t.replace("\"contact.0.law.m\"", r#""contact.0.law.m\n""#)
    });
    let (_, key, _) = key_error(sweep::plan(&keyed, &study, &exe()).unwrap_err());
    assert_eq!(key, "vary[1].key");
    assert!(!study.exists());
}

/// Quantity names become plot file names (`<name>.png`) and CSV columns: the rules of
/// contact pair names apply, at planning and when a manifest is read.
#[test]
fn quantity_names_that_are_not_safe_file_names_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study");
    for name in [
        "../escape",
        "/tmp/absolute",
        "a/b",
        "",
        "x,y",
        "line\nbreak",
        "..",
        "CON",
    ] {
        let path = sweep_file(dir.path(), |t| {
            t.replace(
                "iterations = \"totals.iterations\"",
                &format!("{name:?} = \"totals.iterations\""),
            )
        });
        let (p, key, reason) = key_error(sweep::plan(&path, &study, &exe()).unwrap_err());
        assert_eq!((p, key), (path, format!("quantities.{name:?}")), "{name:?}");
        assert!(reason.contains("name"), "{reason}");
        assert!(!study.exists(), "{name:?}");
    }
    // A manifest edited by hand after planning.
    sweep::plan(&sweep_file(dir.path(), |t| t), &study, &exe()).unwrap();
    let manifest = study.join("manifest.json");
    let text = std::fs::read_to_string(&manifest).unwrap();
    std::fs::write(
        &manifest,
        text.replace("\"iterations\":", "\"../iterations\":"),
    )
    .unwrap();
    let (p, key, _) = key_error(sweep::collect(&study, false).unwrap_err());
    assert_eq!(
        (p, key.as_str()),
        (
            study.canonicalize().unwrap().join("manifest.json"),
            "quantities.\"../iterations\""
        )
    );
}

/// Astronomical plans are counted before anything is allocated and refused above
/// `sweep::MAX_RUNS`, naming the key and the count.
#[test]
fn plans_with_more_runs_than_the_limit_are_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study");
    let base = sweep_file(dir.path(), |t| t);
    let base = std::fs::read_to_string(base).unwrap();
    let head = base.split("[[vary]]").next().unwrap().to_string();
    let ranges = |counts: &[&str]| -> String {
        counts
            .iter()
            .enumerate()
            .map(|(i, n)| {
                format!("[[vary]]\nkey = \"mesh.parameters.p{i}\"\nrange = {{ from = 1, to = 2, count = {n} }}\n")
            })
            .collect()
    };
    let lhs = head.replace(
        "method = \"grid\"",
        "method = \"latin_hypercube\"\nsamples = 1000000000000",
    ) + &ranges(&["1"]);
    let zip = head.replace("method = \"grid\"", "method = \"zip\"") + &ranges(&["100000000"; 2]);
    for (text, key, count) in [
        (
            head.clone() + &ranges(&["100000000"]),
            "vary[0].range.count",
            "100000000",
        ),
        (zip, "vary[0].range.count", "100000000"),
        (lhs, "samples", "1000000000000"),
        (head.clone() + &ranges(&["100"; 6]), "vary", "1000000000000"),
        (
            head.clone() + &ranges(&["100000"; 5]),
            "vary",
            "18446744073709551615",
        ),
        (head.clone() + &ranges(&["1000", "101"]), "vary", "101000"),
    ] {
        let path = dir.path().join("huge.toml");
        std::fs::write(&path, &text).unwrap();
        let e = sweep::plan(&path, &study, &exe()).unwrap_err();
        let message = e.to_string();
        let (p, k, _) = key_error(e);
        assert_eq!((p, k.as_str()), (path, key), "{message}");
        assert!(
            message.contains(count) && message.contains(&sweep::MAX_RUNS.to_string()),
            "{message}"
        );
        assert!(!study.exists());
    }
    assert_eq!(sweep::MAX_RUNS, 100_000);
}

/// `collect` plots through the one Python runner (`asperity::python`): the script found in
/// `$ASPERITY_PIPELINES`, run with the `.venv/bin/python` beside that folder; when the script,
/// matplotlib or the script's success is missing, the `plots:` line says why and how to make
/// the plots by hand. The Python here is a stand-in that runs the "script" with `sh`.
#[test]
fn collect_plots_with_the_pipelines_script_or_says_how_to_make_them() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path().canonicalize().unwrap();
    let study = dir.join("study");
    sweep::plan(&sweep_file(&dir, |t| t), &study, &exe()).unwrap();
    let pipelines = dir.join("repo/pipelines");
    std::fs::create_dir_all(pipelines.join("sweep")).unwrap();
    let collect = |matplotlib: bool| {
        let out = Command::new(exe())
            .args(["sweep", "collect", study.to_str().unwrap()])
            .env("ASPERITY_PIPELINES", &pipelines)
            .env("STUB_MATPLOTLIB", if matplotlib { "0" } else { "1" })
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        text.lines()
            .find_map(|l| l.split_once("; plots: ").map(|(_, p)| p.to_string()))
            .unwrap_or_else(|| panic!("no plots: in {text}"))
    };
    let manual = |python: &str, script: &str| {
        format!(
            "to make it, run `{python} {script} {}` in the repository (after `make venv`)",
            study.display()
        )
    };
    assert_eq!(
        collect(true),
        format!(
            "skipped one PNG per quantity: ASPERITY_PIPELINES={} has no sweep/plot_sweep.py; {}",
            pipelines.display(),
            manual(".venv/bin/python", "pipelines/sweep/plot_sweep.py")
        )
    );
    let script = pipelines.join("sweep/plot_sweep.py");
    let python = dir.join("repo/.venv/bin/python");
    std::fs::create_dir_all(python.parent().unwrap()).unwrap();
    std::fs::write(
        &python,
        "#!/bin/sh\nif [ \"$1\" = -c ]; then exit \"$STUB_MATPLOTLIB\"; fi\nexec sh \"$@\"\n",
    )
    .unwrap();
    std::fs::set_permissions(&python, std::fs::Permissions::from_mode(0o755)).unwrap();
    let by_hand = manual(&python.display().to_string(), &script.display().to_string());
    std::fs::write(&script, "touch \"$1/stub.png\"\n").unwrap();
    assert_eq!(
        collect(false),
        format!(
            "skipped one PNG per quantity: {} has no matplotlib; {by_hand}",
            python.display()
        )
    );
    assert!(!study.join("stub.png").exists());
    assert_eq!(
        collect(true),
        format!("one PNG per quantity in {}", study.display())
    );
    assert!(study.join("stub.png").exists());
    std::fs::write(
        &script,
        "echo first >&2\necho 'the last line' >&2\nexit 1\n",
    )
    .unwrap();
    assert_eq!(
        collect(true),
        format!(
            "skipped one PNG per quantity: {} failed: the last line; {by_hand}",
            script.display()
        )
    );
}

/// A varied string value with a line break (TOML writes it as a multi-line string) stays a
/// value: the header comment of every run's case file cannot turn its lines into keys.
#[test]
fn a_value_with_line_breaks_stays_inside_the_case_header_comment() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study");
    let path = sweep_file(dir.path(), |t| {
        let head = t.split("[[vary]]").next().unwrap().to_string();
        head + "[[vary]]\nkey = \"mesh.geo\"\nvalues = [\"a\\nb = 1\\r\\n[injected]\"]\n"
    });
    sweep::plan(&path, &study, &exe()).unwrap();
    let text = std::fs::read_to_string(study.join("runs/0000/case.toml")).unwrap();
    let tree: toml::Value = toml::from_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert_eq!(tree["mesh"]["geo"].as_str(), Some("a\nb = 1\r\n[injected]"));
    assert!(
        tree.get("b").is_none() && tree.get("injected").is_none(),
        "{text}"
    );
}
