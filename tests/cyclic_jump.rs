//! Cycle jumping over plastic bodies (issue 27): a jump carries the bodies' plastic strains
//! and backstresses through the jumped cycles unchanged, which is right for a body whose
//! simulated cycle closed its loop and wrong for one still ratcheting. On the press fit of
//! `make cyclic_press_fit` (whose kinematic hub reads "ratcheting" over its first four
//! cycles, then "plastic shakedown"; its isotropic hub stays elastic while cycled):
//! - a jump after a cycle in which the kinematic hub ratcheted is refused, naming
//!   `step[1].cycles_per_jump` and the body, exit code 1;
//! - the isotropic hub (elastic shakedown) and the kinematic hub after eight cycles of a
//!   step of their own (plastic shakedown) jump, and the jumps leave their state exactly as
//!   the simulated cycles left it: the run ends bit for bit where a run of the same simulated
//!   cycles without jumps ends.

use std::path::Path;
use std::process::Command;

/// The shipped case `hardening` (without VTU output) with its cyclic step replaced by
/// `steps` (TOML `[[step]]` tables).
fn case(hardening: &str, steps: &str) -> String {
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("pipelines/cyclic_press_fit");
    let text = std::fs::read_to_string(source.join(format!("{hardening}.toml")))
        .unwrap()
        .replace("vtu = true", "vtu = false")
        .replace("\"../../", &format!("\"{}/", env!("CARGO_MANIFEST_DIR")));
    let cycling = text.find("[[step]]\nname = \"cycling\"").unwrap();
    let output = text.find("[output]").unwrap();
    format!("{}{steps}\n{}", &text[..cycling], &text[output..])
}

/// A cyclic step of the shipped pressure cycle.
fn step(name: &str, cycles: usize, per_jump: usize) -> String {
    format!(
        "[[step]]\nname = \"{name}\"\ncycles = {cycles}\ncycles_per_jump = {per_jump}\n\
         increments = 16\n\
         loads = {{ hub_outer = {{ time = [0.0, 0.5, 1.0], value = [0.0, 1.0, 0.0] }} }}\n"
    )
}

struct Run {
    code: Option<i32>,
    stderr: String,
    summary: serde_json::Value,
    last_row: String,
}

fn run(text: &str) -> Run {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("case.toml");
    std::fs::write(&path, text).unwrap();
    let out = dir.path().join("out");
    let run = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .arg("run")
        .arg(&path)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    Run {
        code: run.status.code(),
        stderr: String::from_utf8_lossy(&run.stderr).into_owned(),
        summary: serde_json::from_str(&summary).unwrap(),
        last_row: history.lines().last().unwrap().to_string(),
    }
}

/// The hub's verdict of step `step` and its last cycle's values.
fn hub(run: &Run, step: &str) -> (String, serde_json::Value) {
    let verdicts = run.summary["shakedown"].as_array().unwrap();
    let v = verdicts
        .iter()
        .find(|v| v["step"] == step && v["body"] == "hub")
        .unwrap_or_else(|| panic!("no verdict for the hub in {step}: {verdicts:?}"));
    (
        v["shakedown"].as_str().unwrap().to_string(),
        v["last_cycle"].clone(),
    )
}

/// A history row without its `cycles` column (the load cycles a frame stands for, which a
/// jump changes by design; column 20: step, time, ..., analysis_step, cycle, cycles, ...).
fn state_columns(row: &str) -> Vec<&str> {
    let mut columns: Vec<&str> = row.split(',').collect();
    columns.remove(20);
    columns
}

#[test]
fn a_jump_over_a_ratcheting_body_is_refused() {
    let refused = run(&case("kinematic", &step("cycling", 10, 3)));
    assert_eq!(refused.code, Some(1), "{}", refused.stderr);
    for words in [
        "body 'hub' is still ratcheting",
        "step[1].cycles_per_jump = 1",
        "a jump over 3 cycles",
    ] {
        assert!(
            refused.stderr.contains(words),
            "{words}: {}",
            refused.stderr
        );
    }
    assert_eq!(refused.summary["status"], "failed");
}

#[test]
fn stabilised_bodies_jump_with_their_state_unchanged() {
    // Isotropic: elastic shakedown from the first cycle. 10 cycles in jumps of 3 are 4
    // simulated cycles.
    let jumped = run(&case("isotropic", &step("cycling", 10, 3)));
    assert_eq!(jumped.code, Some(0), "{}", jumped.stderr);
    let simulated = run(&case("isotropic", &step("cycling", 4, 1)));
    assert_eq!(hub(&jumped, "cycling").0, "elastic shakedown");
    assert_eq!(
        state_columns(&jumped.last_row),
        state_columns(&simulated.last_row)
    );

    // Kinematic: eight cycles to settle into alternating plasticity, then 21 cycles in jumps
    // of 5 (5 simulated), against the same 5 cycles simulated without jumps.
    let settled = |cycles, per_jump| {
        case(
            "kinematic",
            &format!(
                "{}\n{}",
                step("settling", 8, 1),
                step("service", cycles, per_jump)
            ),
        )
    };
    let jumped = run(&settled(21, 5));
    assert_eq!(jumped.code, Some(0), "{}", jumped.stderr);
    let simulated = run(&settled(5, 1));
    let (verdict, last) = hub(&jumped, "service");
    assert_eq!(verdict, "plastic shakedown");
    assert!(last["plastic_strain_increment"].as_f64().unwrap() > 1e-4);
    // Bit for bit: the values print the same.
    assert_eq!(last, hub(&simulated, "service").1);
    assert_eq!(
        state_columns(&jumped.last_row),
        state_columns(&simulated.last_row)
    );
}
