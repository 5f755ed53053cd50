//! `history.csv`: the unloaded state as step 0, the pseudo-time, the global and per-load
//! factors, and the `[[history]]` quantities of the case, every step — checked against
//! equilibrium (the base carries the lid's pressure load at every step) and the factors the
//! case gives.

use crate::common;

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use common::{table, two_blocks};

/// Two blocks on a frictional joint: the lid pressed by p = 3 MPa along its own factors and
/// dragged sideways by a prescribed displacement along others; global factors of their own.
fn case(dir: &Path) -> std::path::PathBuf {
    let reaction = |name: &str, support: &str, component: &str| {
        table(&[
            ("name", name.into()),
            ("kind", "reaction".into()),
            ("support", support.into()),
            ("component", component.into()),
        ])
    };
    two_blocks(0.5)
        .set("analysis", "thickness", 2.5)
        .support_history("lid", &[("ux", 0.01)], &[0.0, 0.5, 1.0])
        .pressure_history("lid", 3.0, &[1.0, 2.0, 0.5])
        .step_factors(&[0.2, 0.6, 1.0])
        .push("history", reaction("base_y", "base", "y"))
        .push("history", reaction("lid_x", "lid", "x"))
        .write(&dir.join("case.toml"))
}

fn read_history(path: &Path) -> Vec<HashMap<String, f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .map(|(h, v)| (h.to_string(), v.parse().unwrap()))
                .collect()
        })
        .collect()
}

#[test]
fn history_has_the_start_the_factors_and_the_requested_quantities() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let status = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .arg("run")
        .arg(case(dir.path()))
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    let rows = read_history(&out.join("history.csv"));
    assert_eq!(rows.len(), 4, "step 0 and three steps");
    // Step 0: nothing loaded, no interface point evaluated yet (all open).
    let unloaded = |(column, v): (&String, &f64)| *v == 0.0 || column.ends_with("_open_length");
    assert!(rows[0].iter().all(unloaded), "step 0: {:?}", rows[0]);
    let (width, thickness, pressure) = (2.0, 2.5, 3.0);
    for (j, row) in rows.iter().enumerate().skip(1) {
        assert_eq!(row["step"], j as f64);
        assert_eq!(row["time"], j as f64);
        assert_eq!(row["load_factor"], [0.2, 0.6, 1.0][j - 1]);
        assert_eq!(row["factor_support_lid"], [0.0, 0.5, 1.0][j - 1]);
        let f = [1.0, 2.0, 0.5][j - 1];
        assert_eq!(row["factor_load_lid"], f);
        // The requested quantities are the reactions, and equilibrium of the whole model:
        // the base carries the lid's pressure load p·w·t·f (to the solver's tolerance).
        assert_eq!(row["base_y"], row["reaction_base_y"]);
        assert_eq!(row["lid_x"], row["reaction_lid_x"]);
        let load = pressure * width * thickness * f;
        assert!(
            (row["base_y"] - load).abs() <= 1e-6 * load,
            "step {j}: {} vs {load}",
            row["base_y"]
        );
        // The shear the base takes is what the lid is dragged with.
        assert!((row["reaction_base_x"] + row["lid_x"]).abs() <= 1e-6 * load);
    }
}

/// A `[[history]]` entry named like a column history.csv already has (`time`, a support's
/// reaction) would write two columns of one name, and a CSV reader keyed by name would read
/// the wrong one: `asperity check` and `asperity run` refuse it, naming the entry, before
/// anything is written.
#[test]
fn a_history_name_that_repeats_a_column_is_refused_by_check_and_run() {
    for (name, column) in [("time", "time"), ("reaction_base_y", "reaction_base_y")] {
        let dir = tempfile::tempdir().unwrap();
        let path = two_blocks(0.5)
            .push(
                "history",
                table(&[
                    ("name", name.into()),
                    ("kind", "reaction".into()),
                    ("support", "base".into()),
                    ("component", "y".into()),
                ]),
            )
            .write(&dir.path().join("case.toml"));
        let out = dir.path().join("out");
        for args in [vec!["check"], vec!["run", "--out", out.to_str().unwrap()]] {
            let output = Command::new(env!("CARGO_BIN_EXE_asperity"))
                .args(&args[..1])
                .arg(&path)
                .args(&args[1..])
                .output()
                .unwrap();
            let stderr = String::from_utf8_lossy(&output.stderr);
            assert_eq!(output.status.code(), Some(3), "{args:?}: {stderr}");
            assert!(
                stderr.contains("case.toml")
                    && stderr.contains("history[0].name")
                    && stderr.contains(&format!("`{column}`")),
                "{args:?}: {stderr}"
            );
        }
        assert!(!out.join("history.csv").exists());
    }
}
