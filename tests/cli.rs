//! The command line as a user meets it: `mesh-info` on a real gmsh fixture, and clear errors
//! (naming the file, the entity and the problem, with a non-zero exit status) for bad cases.
use crate::common;

use std::path::Path;
use std::process::Command;

use common::{CaseBuilder, block_material, elastic, fixture, held_block, two_blocks, with_keys};

fn asperity(args: &[&str]) -> (bool, String) {
    let (code, text) = asperity_code(args);
    (code == Some(0), text)
}

/// The exit code (`None` if killed) and the output of a run.
fn asperity_code(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("runs");
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out.status.code(), text)
}

/// The path of `tests/fixtures/<name>` as an argument.
fn fixture_arg(name: &str) -> String {
    fixture(name).display().to_string()
}

/// Runs `case` (a plane-strain case on the two-body fixture) in a temporary folder.
fn run_case(case: CaseBuilder) -> (bool, String) {
    let dir = tempfile::tempdir().unwrap();
    let case = case
        .mesh_file(&fixture("two_bodies_ascii.msh"))
        .write(&dir.path().join("case.toml"));
    let (code, text) = run_into(&case, &dir.path().join("out"));
    (code == Some(0), text)
}

/// `asperity run <case> --out <out>`: the exit code and the output.
fn run_into(case: &Path, out: &Path) -> (Option<i32>, String) {
    asperity_code(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ])
}

#[test]
fn mesh_info_lists_groups_and_element_counts() {
    let (ok, text) = asperity(&["mesh-info", &fixture_arg("two_bodies_ascii.msh")]);
    assert!(ok, "{text}");
    for expected in [
        "body_a",
        "body_b",
        "contact",
        "corner",
        "quad8: 22",
        "problems: none",
    ] {
        assert!(text.contains(expected), "missing '{expected}' in:\n{text}");
    }
}

#[test]
fn mesh_info_on_a_linear_mesh_explains_the_fix() {
    let (ok, text) = asperity(&["mesh-info", &fixture_arg("linear.msh")]);
    assert!(!ok);
    assert!(
        text.contains("linear.msh") && text.to_lowercase().contains("order"),
        "{text}"
    );
}

#[test]
fn bad_mesh_files_are_explained_with_the_fix() {
    for (name, words) in [
        (
            "msh22.msh",
            &[
                "MSH 2.2 is not supported",
                "-format msh41",
                "MshFileVersion",
            ][..],
        ),
        (
            "linear.msh",
            &["first order", "-order 2", "SecondOrderIncomplete = 1"][..],
        ),
        (
            "quad9.msh",
            &["9-node", "type 10", "SecondOrderIncomplete = 1"][..],
        ),
        ("truncated.msh", &["truncated"][..]),
        ("two_bodies.geo", &["not a gmsh MSH file"][..]),
        (
            "parametric.msh",
            &["parametric", "Mesh.SaveParametric = 0"][..],
        ),
    ] {
        let (ok, text) = asperity(&["mesh-info", &fixture_arg(name)]);
        assert!(!ok, "{name}: {text}");
        for w in words.iter().chain(&[name]) {
            assert!(text.contains(w), "{name}: message lacks `{w}`: {text}");
        }
    }
}

#[test]
fn a_body_that_is_not_in_the_mesh_is_named_with_the_alternatives() {
    let (ok, text) = run_case(CaseBuilder::plane_strain().body("shaft", block_material()));
    assert!(!ok);
    assert!(
        text.contains("'shaft'")
            && text.contains("body_a")
            && text.contains("two_bodies_ascii.msh"),
        "{text}"
    );
}

#[test]
fn a_support_group_that_does_not_exist_is_named() {
    let (ok, text) = run_case(
        CaseBuilder::plane_strain()
            .body("body_a", block_material())
            .support("base", &[("ux", 0.0)]),
    );
    assert!(!ok);
    assert!(text.contains("'base'") && text.contains("bottom"), "{text}");
}

#[test]
fn an_unsupported_body_is_reported_before_solving() {
    // body_b shares no node with body_a and has no support of its own.
    let (ok, text) = run_case(
        CaseBuilder::plane_strain()
            .body("body_a", block_material())
            .body("body_b", block_material())
            .support("bottom", &[("ux", 0.0), ("uy", 0.0)])
            .pressure("top", 1.0),
    );
    assert!(!ok);
    // Named with its free motions and the support to add, before any solve.
    assert!(
        text.contains("body 'body_b' is free to move in x and y and to rotate")
            && text.contains("hold ux and uy on a curve of 'body_b'"),
        "{text}"
    );
    assert!(
        !text.contains("'body_a' is free") && !text.contains("cut-backs"),
        "{text}"
    );
}

/// The upper block rests on a frictional joint (μ = 0.3) and is pushed sideways by half its
/// normal load: no equilibrium exists at any load level. The message names the physical
/// cause and the pair, and the exit code is 5 (a limit load: the joint cannot carry it).
#[test]
fn friction_capacity_exceeded_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let case = two_blocks(0.3)
        .traction("lid", [5.0, -10.0])
        .write(&dir.path().join("case.toml"));
    let out = dir.path().join("out");
    let (code, text) = run_into(&case, &out);
    assert_eq!(code, Some(5), "{text}");
    assert!(
        text.contains("friction capacity exceeded") && text.contains("contact 'joint'"),
        "{text}"
    );
    assert!(text.contains("body 'upper' is free to move in x"), "{text}");
    // The report itself (from "error:" on; INFO lines of the run come before it).
    let report = &text[text.find("error:").expect("an error report")..];
    assert!(report.lines().count() < 20, "{text}");
}

#[test]
fn an_unknown_key_is_named() {
    let material = with_keys(block_material(), &[("G", 1.0)]);
    let (ok, text) = run_case(CaseBuilder::plane_strain().body("body_a", material));
    assert!(!ok);
    assert!(text.contains("`G`") && text.contains("case.toml"), "{text}");
}

#[test]
fn a_load_on_a_curve_of_no_body_is_reported() {
    let (ok, text) = run_case(
        CaseBuilder::plane_strain()
            .body("body_a", block_material())
            .support("bottom", &[("ux", 0.0), ("uy", 0.0)])
            .pressure("top", 1.0),
    );
    assert!(!ok);
    assert!(
        text.contains("load 'top'") && text.contains("not an edge of any body"),
        "{text}"
    );
}

#[test]
fn a_successful_run_writes_the_series_and_history() {
    let dir = tempfile::tempdir().unwrap();
    let case = held_block()
        .step_factors(&[0.5, 1.0])
        .write(&dir.path().join("case.toml"));
    let out = dir.path().join("out");
    let (code, text) = run_into(&case, &out);
    assert_eq!(code, Some(0), "{text}");
    for f in [
        "bodies_0001.vtu",
        "bodies_0002.vtu",
        "results.pvd",
        "history.csv",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    assert!(
        text.contains("unknowns") && text.contains("reaction 'bottom'"),
        "{text}"
    );
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    // Header, the unloaded state (step 0) and the two steps.
    assert_eq!(history.lines().count(), 4, "{history}");
    assert!(
        history.lines().nth(1).unwrap().starts_with("0,0,0,"),
        "{history}"
    );
}

/// A block pressed (step 1, linear) then dragged into sliding (step 2, needs several Newton
/// iterations): with one iteration allowed and no cut-backs step 2 fails. The run must stop
/// with an error naming the step, and the files of step 1 must be complete on disk.
#[test]
fn a_step_that_cannot_converge_is_named_and_earlier_results_stay_on_disk() {
    let dir = tempfile::tempdir().unwrap();
    let case = two_blocks(0.3)
        .support_history("lid", &[("ux", 0.5)], &[0.0, 1.0])
        .pressure_history("lid", 10.0, &[1.0, 1.0])
        .steps(2)
        .set("solver", "max_iterations", 1)
        .set("solver", "max_cutbacks", 0)
        .write(&dir.path().join("case.toml"));
    let out = dir.path().join("out");
    let (code, text) = run_into(&case, &out);
    assert_ne!(code, Some(0), "{text}");
    assert!(
        text.contains("step 2") && text.contains("did not converge") && text.contains("residuals"),
        "{text}"
    );
    for f in [
        "frame_0001.vtm",
        "bodies_0001_1.vtu",
        "bodies_0001_2.vtu",
        "interface_0001.vtu",
        "contact_joint_0001.csv",
        "results.pvd",
        "history.csv",
    ] {
        assert!(out.join(f).is_file(), "{f} missing after the failed step");
    }
    assert!(!out.join("frame_0002.vtm").exists() && !out.join("bodies_0002_1.vtu").exists());
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left behind");
}

/// A perfectly plastic block in plane strain, clamped at its base and pulled at its top by
/// twice its plane-strain limit traction (2/√3) σ_Y: no equilibrium exists above a load factor
/// of about one half. The run must stop with "plastic collapse", exit code 5 (README "Exit
/// codes"), the converged steps on disk and summary.json saying "failed".
#[test]
fn plastic_collapse_exits_with_code_5_and_keeps_the_converged_steps() {
    let dir = tempfile::tempdir().unwrap();
    let traction = 2.0 * 2.0 / 3f64.sqrt() * 100.0;
    let case = CaseBuilder::plane_strain()
        .mesh_file(&fixture("contact_pair.msh"))
        .body(
            "lower",
            with_keys(elastic(70000.0, 0.3), &[("yield_stress", 100.0)]),
        )
        .support("base", &[("ux", 0.0), ("uy", 0.0)])
        .traction("lower_top", [0.0, traction])
        .steps(4)
        .write(&dir.path().join("case.toml"));
    let out = dir.path().join("out");
    let (code, text) = run_into(&case, &out);
    assert_eq!(code, Some(5), "{text}");
    assert!(
        text.contains("plastic collapse") && text.contains("the load cannot exceed ≈ load factor"),
        "{text}"
    );
    assert!(out.join("bodies_0001.vtu").is_file(), "step 1 is on disk");
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.contains("\"failed\""), "{summary}");
}

/// The held block (`common::held_block`) with `steps` equal steps.
fn block_case(dir: &Path, steps: i64) -> std::path::PathBuf {
    held_block().steps(steps).write(&dir.join("case.toml"))
}

/// A second run into a results folder refuses (exit 2) and changes nothing; `--force`
/// replaces the earlier run's files — a run with fewer steps leaves none of the old step files
/// — and never touches a file of the user's.
#[test]
fn an_existing_results_folder_is_refused_unless_forced() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out_s = out.to_str().unwrap();
    let case = block_case(dir.path(), 3);
    let case_s = case.to_str().unwrap();
    let (code, text) = asperity_code(&["run", case_s, "--out", out_s]);
    assert_eq!(code, Some(0), "{text}");
    assert!(out.join("bodies_0003.vtu").is_file());
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let before = std::fs::read(out.join("history.csv")).unwrap();

    let case = block_case(dir.path(), 2);
    let (code, text) = asperity_code(&["run", case_s, "--out", out_s]);
    assert_eq!(code, Some(2), "{text}");
    assert!(
        text.contains("--force") && text.contains("earlier run"),
        "{text}"
    );
    assert_eq!(std::fs::read(out.join("history.csv")).unwrap(), before);

    let (code, text) = asperity_code(&["run", case.to_str().unwrap(), "--out", out_s, "--force"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(out.join("bodies_0002.vtu").is_file());
    assert!(
        !out.join("bodies_0003.vtu").exists(),
        "a stale step file survived --force"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
    let pvd = std::fs::read_to_string(out.join("results.pvd")).unwrap();
    assert!(!pvd.contains("0003"), "{pvd}");
}

/// `run.json` records what made the results, and the default folder is next to the case
/// file (README "Output"), not in the working directory.
#[test]
fn run_json_describes_the_run_and_the_default_folder_follows_the_case() {
    let dir = tempfile::tempdir().unwrap();
    let case = block_case(dir.path(), 1);
    let cwd = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(["run", case.to_str().unwrap()])
        .current_dir(cwd.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let folder = dir.path().join("out/case");
    assert!(folder.join("results.pvd").is_file());
    assert!(std::fs::read_dir(cwd.path()).unwrap().next().is_none());
    let info: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("run.json")).unwrap()).unwrap();
    assert_eq!(info["program"], "asperity");
    assert_eq!(info["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(info["status"], "converged");
    assert_eq!(info["case"], std::fs::read_to_string(&case).unwrap());
    assert_eq!(info["command_line"][1], "run");
    assert!(info["threads"].as_u64().unwrap() >= 1);
    for key in ["start", "end"] {
        let t = info[key].as_str().unwrap();
        assert!(
            t.len() == 20 && t.ends_with('Z') && t.starts_with("20"),
            "{key} = {t}"
        );
    }
    assert!(info["start"].as_str() <= info["end"].as_str());
}

/// README "Exit codes": 2 usage, 3 bad input, 4 a file that cannot be read.
#[test]
fn exit_codes_tell_usage_input_and_io_errors_apart() {
    let (code, text) = asperity_code(&["run"]);
    assert_eq!(code, Some(2), "{text}");
    let (code, text) = asperity_code(&["run", "x.toml", "--force", "--resume"]);
    assert_eq!(code, Some(2), "{text}");
    let (code, text) = asperity_code(&["run", "/nonexistent/case.toml"]);
    assert_eq!(code, Some(4), "{text}");
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("case.toml");
    std::fs::write(&case, "[mesh]\nfile = \"m.msh\"\n").unwrap();
    let (code, text) = asperity_code(&["run", case.to_str().unwrap()]);
    assert_eq!(code, Some(3), "{text}");
    assert!(!dir.path().join("out").exists(), "bad input wrote output");
}
