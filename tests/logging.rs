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
    // -q with -v is a usage error, as is a pool without threads or with more than four
    // per core.
    for args in [
        &["-q", "-v", "check", "x.toml"][..],
        &["--threads", "0", "check", "x.toml"],
        &["--threads", "65535", "check", "x.toml"],
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

/// `-v` prints the Newton iterations (DEBUG); each carries the step it belongs to as the
/// `step{step=N}` span, and the steps run 1, 2, 3, 4 in order (the template has four steps).
#[test]
fn newton_lines_name_their_step() {
    let (_dir, case) = template();
    let (_, stderr) = run(&case, &["-v"]);
    let newton: Vec<&str> = lines_at(&stderr, "DEBUG")
        .into_iter()
        .filter(|l| l.contains(" newton "))
        .collect();
    assert!(!newton.is_empty(), "no Newton lines with -v:\n{stderr}");
    let steps: Vec<usize> = newton
        .iter()
        .map(|l| {
            let rest = l
                .strip_prefix("step{step=")
                .unwrap_or_else(|| panic!("Newton line without its step: {l}"));
            rest[..rest.find('}').unwrap()].parse().unwrap()
        })
        .collect();
    assert!(steps.windows(2).all(|w| w[0] <= w[1]), "{steps:?}");
    let mut seen = steps.clone();
    seen.dedup();
    assert_eq!(seen, [1, 2, 3, 4], "{stderr}");
}

/// On a terminal a log line is written with the progress bar cleared first and redrawn
/// after it, so the two never share a line; without a bar the line is written as it is.
#[test]
fn log_lines_go_through_the_progress_bar() {
    use asperity::run::progress::write_log_line;
    use indicatif::{ProgressBar, ProgressDrawTarget, TermLike};
    use std::io::Write;
    use std::sync::{Arc, Mutex};

    /// What reaches the terminal, in order: bar drawing and log lines alike.
    #[derive(Clone, Debug, Default)]
    struct Screen(Arc<Mutex<Vec<String>>>);
    impl Screen {
        fn push(&self, event: String) -> std::io::Result<()> {
            self.0.lock().unwrap().push(event);
            Ok(())
        }
    }
    impl TermLike for Screen {
        fn width(&self) -> u16 {
            80
        }
        fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn write_line(&self, s: &str) -> std::io::Result<()> {
            self.push(format!("bar {s}"))
        }
        fn write_str(&self, s: &str) -> std::io::Result<()> {
            self.push(format!("bar {s}"))
        }
        fn clear_line(&self) -> std::io::Result<()> {
            self.push("clear".into())
        }
        fn flush(&self) -> std::io::Result<()> {
            Ok(())
        }
    }
    impl Write for Screen {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            self.push(format!("log {}", String::from_utf8_lossy(b)))?;
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    let mut screen = Screen::default();
    let bar = ProgressBar::with_draw_target(
        Some(4),
        ProgressDrawTarget::term_like(Box::new(screen.clone())),
    );
    bar.inc(1);
    write_log_line(Some(&bar), &mut screen, b"INFO increment 1\n").unwrap();
    let events = screen.0.lock().unwrap().clone();
    let log = events
        .iter()
        .position(|e| e == "log INFO increment 1\n")
        .unwrap_or_else(|| panic!("{events:?}"));
    let drawn_before = events[..log].iter().rposition(|e| e.starts_with("bar "));
    let cleared = events[..log].iter().rposition(|e| e == "clear");
    assert!(drawn_before.is_some(), "the bar was drawn: {events:?}");
    assert!(
        cleared > drawn_before,
        "bar cleared before the line: {events:?}"
    );
    assert!(
        events[log + 1..].iter().any(|e| e.starts_with("bar ")),
        "bar redrawn after the line: {events:?}"
    );

    let mut plain = Screen::default();
    write_log_line(None, &mut plain, b"INFO x\n").unwrap();
    assert_eq!(*plain.0.lock().unwrap(), ["log INFO x\n"]);
}
