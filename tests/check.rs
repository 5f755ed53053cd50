//! `asperity check` (validate a case and its mesh, build the model, solve nothing) and
//! `asperity init` (a template case that runs as it is).

use std::path::Path;
use std::process::{Command, Output};

fn asperity(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("asperity runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// `asperity init DIR`.
fn init(dir: &Path) -> Output {
    asperity(&["init".as_ref(), dir.as_os_str()])
}

/// The number after `label` in `text`, e.g. `448` for "448 elements" and label " elements".
fn count_before(text: &str, label: &str) -> usize {
    let end = text
        .find(label)
        .unwrap_or_else(|| panic!("no `{label}` in {text}"));
    let start = text[..end].rfind(' ').map_or(0, |i| i + 1);
    text[start..end].parse().unwrap()
}

#[test]
fn check_reports_the_model_of_a_valid_case_and_writes_no_results() {
    let dir = tempfile::tempdir().unwrap();
    assert!(init(dir.path()).status.success());
    let case = dir.path().join("case.toml");
    let out = asperity(&["check".as_ref(), case.as_os_str()]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    // The template's script: n = 8 elements along the contact, (W − w)/w · n = 16 beside it,
    // H/w · n = 16 through the foundation and h/w · n = 8 through the block, so
    // (8 + 16) · 16 = 384 foundation and 8 · 8 = 64 block quads, 8 interface elements.
    let line = |prefix: &str| {
        stdout
            .lines()
            .find(|l| l.starts_with(prefix))
            .unwrap_or_else(|| panic!("no `{prefix}` line in {stdout}"))
            .to_string()
    };
    assert_eq!(count_before(&line("body 'foundation'"), " elements"), 384);
    assert_eq!(count_before(&line("body 'block'"), " elements"), 64);
    assert_eq!(
        count_before(&line("contact 'contact'"), " interface elements"),
        8
    );
    let model = line("model:");
    assert!(model.contains("plane strain"), "{model}");
    assert_eq!(count_before(&model, " elements,"), 448);
    // Quad8 nodes of an nx × ny grid: corners (nx + 1)(ny + 1), mid-sides of the horizontal
    // edges nx (ny + 1) and of the vertical ones (nx + 1) ny; the block's bottom row is its
    // own (two coincident curves), so the two grids add up.
    let foundation = 25 * 17 + 24 * 17 + 25 * 16;
    let block = 9 * 9 + 8 * 9 + 9 * 8;
    assert_eq!(count_before(&model, " nodes"), foundation + block);
    assert!(stdout.contains("ok"), "{stdout}");
    // Nothing solved, nothing written beside the case (the mesh went to a temporary folder).
    let mut files: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    files.sort();
    assert_eq!(files, ["block_on_foundation.geo", "case.toml"]);
}

#[test]
fn check_names_what_is_wrong_in_an_invalid_case() {
    let dir = tempfile::tempdir().unwrap();
    assert!(init(dir.path()).status.success());
    let case = dir.path().join("case.toml");
    let template = std::fs::read_to_string(&case).unwrap();
    for (from, to, expect) in [
        // A misspelt key: named by the reader.
        ("pressure = 50.0", "presure = 50.0", "presure"),
        // A group the mesh does not have: named once the mesh is read.
        ("group = \"top\"", "group = \"lid\"", "lid"),
        // A value out of range: named with its key path.
        ("nu = 0.3 }", "nu = 0.7 }", "nu"),
    ] {
        std::fs::write(&case, template.replacen(from, to, 1)).unwrap();
        let out = asperity(&["check".as_ref(), case.as_os_str()]);
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "`{to}` passed the check");
        assert!(
            stderr.contains("error:") && stderr.contains(expect),
            "{stderr}"
        );
        assert!(!text(&out.stdout).contains("ok"));
    }
}

#[test]
fn the_init_template_runs_and_balances_the_load() {
    let dir = tempfile::tempdir().unwrap();
    let out = init(dir.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
    let case = dir.path().join("case.toml");
    let out = asperity(&["run".as_ref(), case.as_os_str()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // [output] dir = "out" is relative to the case file.
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("out/summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["status"], "converged");
    assert_eq!(summary["totals"]["steps"], 4);
    // Equilibrium: the base carries the pressure on the block's top, 50 MPa × w = 10 mm ×
    // 1 mm thickness = 500 N; the friction force on the foundation is held by the base and
    // the symmetry plane together, so their x reactions cancel.
    let r = &summary["reactions"];
    let base_y = r["base"]["y"].as_f64().unwrap();
    assert!((base_y - 500.0).abs() < 1e-8 * 500.0, "{base_y}");
    let x = r["base"]["x"].as_f64().unwrap() + r["symmetry"]["x"].as_f64().unwrap();
    assert!(x.abs() < 1e-8 * 500.0, "{x}");
}

#[test]
fn init_never_overwrites() {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("case.toml");
    std::fs::write(&case, "# mine\n").unwrap();
    let out = init(dir.path());
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("case.toml"),
        "{}",
        text(&out.stderr)
    );
    assert_eq!(std::fs::read_to_string(&case).unwrap(), "# mine\n");
    // All or nothing: the script was not written either.
    assert!(!dir.path().join("block_on_foundation.geo").exists());
    // A link to nothing under a template's name counts as a file: nothing is written.
    #[cfg(unix)]
    {
        let dir = tempfile::tempdir().unwrap();
        let geo = dir.path().join("block_on_foundation.geo");
        std::os::unix::fs::symlink(dir.path().join("nothing"), &geo).unwrap();
        let out = init(dir.path());
        assert!(!out.status.success());
        assert!(!dir.path().join("case.toml").exists(), "half a template");
        assert!(!dir.path().join("nothing").exists());
    }
}

/// A model free to move as a rigid body is an error of `check` and `run` alike, before
/// anything is solved (exit code 3): the template with its x supports taken away (the base
/// held in y only, the symmetry plane gone) leaves both bodies free to slide in x together
/// (the contact's friction joins them), while y and the rotation stay held by the base.
#[test]
fn check_and_run_refuse_a_model_free_to_move() {
    let dir = tempfile::tempdir().unwrap();
    assert!(init(dir.path()).status.success());
    let case = dir.path().join("case.toml");
    let template = std::fs::read_to_string(&case).unwrap();
    let base = "ux = 0.0\nuy = 0.0";
    let symmetry = "group = \"symmetry\"";
    assert!(template.contains(base) && template.contains(symmetry));
    // The symmetry support holds the base's y instead of the plane's x.
    let at = template.find(symmetry).unwrap();
    let (head, tail) = template.split_at(at);
    let tail = tail
        .replacen(symmetry, "group = \"base\"", 1)
        .replacen("ux = 0.0", "uy = 0.0", 1);
    let free = head.replacen(base, "uy = 0.0", 1) + &tail;
    std::fs::write(&case, free).unwrap();
    for command in ["check", "run"] {
        let out = asperity(&[command.as_ref(), case.as_os_str()]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{command}: {stderr}");
        for expected in [
            "body 'foundation' is free to move in x",
            "body 'block' is free to move in x",
            "hold ux on a curve or point of 'foundation'",
        ] {
            assert!(stderr.contains(expected), "{command}: {stderr}");
        }
        assert!(
            !stderr.contains("rotate") && !stderr.contains("Newton"),
            "{command}: {stderr}"
        );
    }
}
