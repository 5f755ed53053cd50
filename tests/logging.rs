//! Logging of a run as a batch job sees it: stderr is a pipe here (not a terminal), so it must
//! carry the INFO lines without ANSI escape codes; `log.txt` in the output folder carries the
//! same lines, also with `-q`, which silences INFO on stderr; `--threads` sizes the pool.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `asperity init` template in a temporary folder, meshed coarser (size factor 2) to be
/// quick; returns the folder and the case.
fn template() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let out = asperity(&["init", dir.path().to_str().unwrap()]);
    assert!(out.status.success());
    let case = dir.path().join("case.toml");
    let text = std::fs::read_to_string(&case).unwrap();
    std::fs::write(&case, text.replacen("size = 1.0", "size = 2.0", 1)).unwrap();
    (dir, case)
}

fn asperity(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("asperity runs")
}

/// `args` then the case; stderr must be a pipe for these tests to mean anything, which
/// `Command::output` guarantees.
fn run(case: &Path, args: &[&str]) -> (Output, String) {
    let mut all = args.to_vec();
    all.extend(["run", case.to_str().unwrap()]);
    let out = asperity(&all);
    let stderr = String::from_utf8(out.stderr.clone()).expect("UTF-8 log");
    assert!(out.status.success(), "{stderr}");
    (out, stderr)
}

/// The lines at `level`, without their timestamps (the two sinks stamp separately).
fn lines_at<'t>(log: &'t str, level: &str) -> Vec<&'t str> {
    log.lines()
        .filter_map(|l| l.split_once(&format!(" {level} ")).map(|(_, rest)| rest))
        .collect()
}

#[test]
fn piped_stderr_has_plain_info_lines_and_log_txt_the_same() {
    let (dir, case) = template();
    let (_, stderr) = run(&case, &[]);
    assert!(
        !stderr.contains('\u{1b}'),
        "ANSI escape in a piped log:\n{stderr}"
    );
    let info = lines_at(&stderr, "INFO");
    assert!(
        info.iter().any(|l| l.starts_with("model built")),
        "no INFO lines on a non-terminal stderr:\n{stderr}"
    );
    let log = std::fs::read_to_string(dir.path().join("out/log.txt")).unwrap();
    assert!(!log.contains('\u{1b}'));
    assert_eq!(lines_at(&log, "INFO"), info);
    // Every line of the file is a log line with a timestamp and a level.
    for l in log.lines() {
        let (stamp, _) = l.split_once(' ').unwrap();
        assert!(stamp.ends_with('Z') && stamp.contains('T'), "{l}");
    }
}

#[test]
fn quiet_silences_info_on_stderr_but_not_in_log_txt() {
    let (dir, case) = template();
    let (out, stderr) = run(&case, &["-q"]);
    assert!(lines_at(&stderr, "INFO").is_empty(), "{stderr}");
    // The closing summary is the command's result (stdout), not log output.
    assert!(String::from_utf8_lossy(&out.stdout).contains("results:"));
    let log = std::fs::read_to_string(dir.path().join("out/log.txt")).unwrap();
    assert!(
        lines_at(&log, "INFO")
            .iter()
            .any(|l| l.starts_with("model built")),
        "{log}"
    );
    // -q with -v is a usage error, as is a pool without threads.
    for args in [
        &["-q", "-v", "check", "x.toml"][..],
        &["--threads", "0", "check", "x.toml"],
    ] {
        let out = asperity(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
    }
}

/// One thread and the default pool solve the same problem: the reactions agree to
/// round-off (parallel assembly sums element contributions in another order).
#[test]
fn threads_option_gives_the_same_answer() {
    let reaction = |args: &[&str]| {
        let (dir, case) = template();
        run(&case, args);
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("out/summary.json")).unwrap())
                .unwrap();
        summary["reactions"]["base"]["x"].as_f64().unwrap()
    };
    let (one, default) = (reaction(&["--threads", "1"]), reaction(&[]));
    assert!(
        one != 0.0 && (one - default).abs() <= 1e-10 * one.abs(),
        "{one} vs {default}"
    );
}
