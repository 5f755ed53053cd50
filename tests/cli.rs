//! The command line as a user meets it: `mesh-info` on a real gmsh fixture, and clear errors
//! (naming the file, the entity and the problem, with a non-zero exit status) for bad cases.
use std::path::Path;
use std::process::Command;

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

fn fixture(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
        .display()
        .to_string()
}

/// Writes a case next to a temporary copy-free reference to the two-body fixture.
fn run_case(body: &str) -> (bool, String) {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("case.toml");
    std::fs::write(
        &case,
        format!(
            "[mesh]\nfile = \"{}\"\n{body}",
            fixture("two_bodies_ascii.msh")
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    asperity(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ])
}

#[test]
fn mesh_info_lists_groups_and_element_counts() {
    let (ok, text) = asperity(&["mesh-info", &fixture("two_bodies_ascii.msh")]);
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
    let (ok, text) = asperity(&["mesh-info", &fixture("linear.msh")]);
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
        let (ok, text) = asperity(&["mesh-info", &fixture(name)]);
        assert!(!ok, "{name}: {text}");
        for w in words.iter().chain(&[name]) {
            assert!(text.contains(w), "{name}: message lacks `{w}`: {text}");
        }
    }
}

const ANALYSIS: &str = "[analysis]\ntype = \"plane_strain\"\n";

#[test]
fn a_body_that_is_not_in_the_mesh_is_named_with_the_alternatives() {
    let (ok, text) = run_case(&format!(
        "{ANALYSIS}[[body]]\ngroup = \"shaft\"\nmaterial = {{ E = 1000.0, nu = 0.3 }}\n"
    ));
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
    let (ok, text) = run_case(&format!(
        "{ANALYSIS}[[body]]\ngroup = \"body_a\"\nmaterial = {{ E = 1000.0, nu = 0.3 }}\n[[support]]\ngroup = \"base\"\nux = 0.0\n"
    ));
    assert!(!ok);
    assert!(text.contains("'base'") && text.contains("bottom"), "{text}");
}

#[test]
fn an_unsupported_body_is_reported_as_such() {
    // body_b shares no node with body_a and has no support of its own.
    let (ok, text) = run_case(&format!(
        "{ANALYSIS}[[body]]\ngroup = \"body_a\"\nmaterial = {{ E = 1000.0, nu = 0.3 }}\n[[body]]\ngroup = \"body_b\"\n\
         material = {{ E = 1000.0, nu = 0.3 }}\n[[support]]\ngroup = \"bottom\"\nux = 0.0\nuy = 0.0\n[[load]]\n\
         group = \"top\"\npressure = 1.0\n"
    ));
    assert!(!ok);
    assert!(
        text.contains("not positive definite") && text.contains("supports"),
        "{text}"
    );
}

#[test]
fn an_unknown_key_is_named() {
    let (ok, text) = run_case(&format!(
        "{ANALYSIS}[[body]]\ngroup = \"body_a\"\nmaterial = {{ E = 1000.0, nu = 0.3, G = 1.0 }}\n"
    ));
    assert!(!ok);
    assert!(text.contains("`G`") && text.contains("case.toml"), "{text}");
}

#[test]
fn a_load_on_a_curve_of_no_body_is_reported() {
    let (ok, text) = run_case(&format!(
        "{ANALYSIS}[[body]]\ngroup = \"body_a\"\nmaterial = {{ E = 1000.0, nu = 0.3 }}\n[[support]]\ngroup = \"bottom\"\n\
         ux = 0.0\nuy = 0.0\n[[load]]\ngroup = \"top\"\npressure = 1.0\n"
    ));
    assert!(!ok);
    assert!(
        text.contains("load 'top'") && text.contains("not an edge of any body"),
        "{text}"
    );
}

#[test]
fn a_successful_run_writes_the_series_and_history() {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("case.toml");
    std::fs::write(
        &case,
        format!(
            "[mesh]\nfile = \"{}\"\n{ANALYSIS}[[body]]\ngroup = \"body_a\"\nmaterial = {{ E = 1000.0, nu = 0.3 }}\n\
             [[support]]\ngroup = \"bottom\"\nux = 0.0\nuy = 0.0\n[[support]]\ngroup = \"corner\"\nux = 0.0\n\
             [steps]\nfactors = [0.5, 1.0]\n",
            fixture("two_bodies_ascii.msh")
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let (ok, text) = asperity(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{text}");
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
    let case = dir.path().join("case.toml");
    std::fs::write(
        &case,
        format!(
            r#"[mesh]
file = "{}"
[analysis]
type = "plane_strain"
[[body]]
group = "lower"
material = {{ E = 1000.0, nu = 0.3 }}
[[body]]
group = "upper"
material = {{ E = 1000.0, nu = 0.3 }}
[[support]]
group = "base"
ux = 0.0
uy = 0.0
[[support]]
group = "lid"
ux = 0.5
factors = [0.0, 1.0]
[[load]]
group = "lid"
pressure = 10.0
factors = [1.0, 1.0]
[[contact]]
name = "joint"
side_a = "lower_top"
side_b = "upper_bottom"
law = {{ type = "linear_coulomb", normal_stiffness = 1e4, tangential_stiffness = 1e4, friction = 0.3 }}
[steps]
count = 2
[solver]
max_iterations = 1
max_cutbacks = 0
"#,
            fixture("contact_pair.msh")
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let (ok, text) = asperity(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok, "{text}");
    assert!(
        text.contains("step 2") && text.contains("did not converge") && text.contains("residuals"),
        "{text}"
    );
    for f in [
        "bodies_0001.vtu",
        "interface_0001.vtu",
        "contact_joint_0001.csv",
        "results.pvd",
        "history.csv",
    ] {
        assert!(out.join(f).is_file(), "{f} missing after the failed step");
    }
    assert!(!out.join("bodies_0002.vtu").exists());
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
    let case = dir.path().join("case.toml");
    let traction = 2.0 * 2.0 / 3f64.sqrt() * 100.0;
    std::fs::write(
        &case,
        format!(
            r#"[mesh]
file = "{}"
[analysis]
type = "plane_strain"
[[body]]
group = "lower"
material = {{ E = 70000.0, nu = 0.3, yield_stress = 100.0 }}
[[support]]
group = "base"
ux = 0.0
uy = 0.0
[[load]]
group = "lower_top"
traction = [0.0, {traction}]
[steps]
count = 4
"#,
            fixture("contact_pair.msh")
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let (code, text) = asperity_code(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(5), "{text}");
    assert!(
        text.contains("plastic collapse") && text.contains("last converged load factor"),
        "{text}"
    );
    assert!(out.join("bodies_0001.vtu").is_file(), "step 1 is on disk");
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.contains("\"failed\""), "{summary}");
}
