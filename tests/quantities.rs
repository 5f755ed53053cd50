//! The quantities a run reports without being asked (issue 28): the default penalty
//! stiffness of a law that leaves it out (10 E*/h, in `run.json`, overlapping the faces by
//! p/k; fixed and reported by a model fit), the prescribed displacement of every driven
//! support, the stick, slip and open extent and the dissipation of every contact pair in
//! `history.csv` and `summary.json`, all named by the user's names, and the parts of the
//! model by name in `results.pvd`.

use crate::common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::{CaseBuilder, list, run_cli, table, two_blocks};
use toml::Table;

/// The rows of `history.csv` by column name.
fn history(out: &Path) -> Vec<HashMap<String, f64>> {
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            let values = l.split(',').map(|v| v.parse().unwrap());
            header.iter().map(|h| h.to_string()).zip(values).collect()
        })
        .collect()
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// [`two_blocks`] (E = 1000 MPa, ν = 0.3, joint 2 mm long) with a linear Coulomb joint of
/// friction 0.3 whose stiffnesses are `stiffness` (`None`: left to their default).
fn blocks(stiffness: Option<f64>) -> CaseBuilder {
    let mut law = table(&[("type", "linear_coulomb".into()), ("friction", 0.3.into())]);
    if let Some(k) = stiffness {
        law.insert("normal_stiffness".into(), k.into());
        law.insert("tangential_stiffness".into(), k.into());
    }
    two_blocks(0.3).set_last("contact", "law", law)
}

fn relative_gap() -> Table {
    table(&[
        ("name", "gap".into()),
        ("kind", "relative_displacement".into()),
        ("pair", "joint".into()),
        ("component", "y".into()),
    ])
}

/// The default is 10 E*/h with E* the surface moduli in series and h the mean element
/// length, recorded in run.json; under the lid's pressure p the faces overlap by p/k on
/// average (exactly: the mean normal gap is −(∫ p dl)/(k L) and ∫ p dl = p L).
#[test]
fn a_defaulted_penalty_is_ten_surface_moduli_over_the_element_length_and_overlaps_by_p_over_k() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let p = 3.0;
    let case = blocks(None)
        .pressure("lid", p)
        .push("history", relative_gap())
        .write(&dir.path().join("case.toml"));
    run_cli(&case, &out, &[]);
    let info = json(&out.join("run.json"));
    let default = &info["penalty_defaults"][0];
    assert_eq!(default["contact"], "joint");
    assert_eq!(
        default["parameters"],
        serde_json::json!(["normal_stiffness", "tangential_stiffness"])
    );
    let elements = json(&out.join("summary.json"))["model"]["interface_elements"]
        .as_f64()
        .unwrap();
    let surface = 1000.0 / (1.0 - 0.3 * 0.3);
    let (e_star, h) = (surface / 2.0, 2.0 / elements);
    let k = default["stiffness"].as_f64().unwrap();
    assert!((default["surface_modulus"].as_f64().unwrap() - e_star).abs() < 1e-9 * e_star);
    assert!((default["element_length"].as_f64().unwrap() - h).abs() < 1e-12);
    assert!((k - 10.0 * e_star / h).abs() < 1e-9 * k, "{k}");
    let log = std::fs::read_to_string(out.join("log.txt")).unwrap();
    assert!(log.contains("contact 'joint': normal_stiffness and tangential_stiffness not given"));
    let last = history(&out).pop().unwrap();
    let overlap = -last["gap"];
    assert!(
        (overlap - p / k).abs() < 1e-6 * p / k,
        "{overlap} vs p/k = {}",
        p / k
    );

    // A case that gives the stiffnesses gets no default.
    let given = dir.path().join("given");
    run_cli(
        &blocks(Some(k))
            .pressure("lid", p)
            .write(&dir.path().join("given.toml")),
        &given,
        &[],
    );
    assert_eq!(
        json(&given.join("run.json"))["penalty_defaults"],
        serde_json::json!([])
    );
}

/// Pressed by a prescribed displacement d, the reaction with the default stiffness is within
/// a few per cent of the one with a 1000 times stiffer joint, and the difference is the
/// default's compliance in series: d/F = C + 1/(k L t) with the bodies' compliance C from
/// the stiff run (uniform to a good approximation: the blocks are equal).
#[test]
fn a_defaulted_penalty_answer_is_close_to_a_stiff_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = 0.01;
    let pressed = |stiffness: Option<f64>, name: &str| {
        let out = dir.path().join(name);
        let case = blocks(stiffness)
            .support("lid", &[("ux", 0.0), ("uy", -d)])
            .write(&dir.path().join(format!("{name}.toml")));
        run_cli(&case, &out, &[]);
        let k = json(&out.join("run.json"))["penalty_defaults"][0]["stiffness"].as_f64();
        (history(&out).pop().unwrap()["reaction_base_y"], k)
    };
    let (default, k) = pressed(None, "default");
    let k = k.unwrap();
    let (stiff, _) = pressed(Some(1000.0 * k), "stiff");
    let length = 2.0;
    let bodies = d / stiff - 1.0 / (1000.0 * k * length);
    let predicted = d / (bodies + 1.0 / (k * length));
    let relative = (default - stiff).abs() / stiff;
    println!("reaction: default {default}, stiff {stiff}, predicted {predicted}");
    assert!(relative < 0.05, "{relative}");
    assert!((default - predicted).abs() < 0.1 * (default - stiff).abs());
}

/// Two supports of one group ("lid") by their names: "press" pushes the upper block down in
/// a first step, "shear" drags it back and forth in a cyclic step of `cycles` cycles of four
/// frames each.
fn fretting(cycles: i64) -> CaseBuilder {
    let step = |name: &str, keys: &[(&str, i64)], supports: Table| {
        let mut step = table(&[("name", name.into()), ("supports", supports.into())]);
        for (k, v) in keys {
            step.insert(k.to_string(), (*v).into());
        }
        step
    };
    let lid = |name: &str, component: &str, value: f64| {
        table(&[
            ("name", name.into()),
            ("group", "lid".into()),
            (component, value.into()),
        ])
    };
    let shear = table(&[
        ("time", list(&[0.0, 0.25, 0.75, 1.0])),
        ("value", list(&[0.0, 1.0, -1.0, 0.0])),
    ]);
    blocks(Some(1e4))
        .push("support", lid("press", "uy", -0.01))
        .push("support", lid("shear", "ux", 0.03))
        .push(
            "step",
            step(
                "press",
                &[("increments", 2)],
                table(&[("press", 1.0.into())]),
            ),
        )
        .push(
            "step",
            step(
                "fret",
                &[("cycles", cycles), ("increments", 4)],
                table(&[("shear", shear.into())]),
            ),
        )
}

#[test]
fn history_and_summary_report_displacements_extents_and_dissipation_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    run_cli(&fretting(2).write(&dir.path().join("case.toml")), &out, &[]);
    let rows = history(&out);
    assert_eq!(rows.len(), 1 + 2 + 8, "step 0, press, two cycles of four");
    // The prescribed displacements are the step histories' values: the press ramps to
    // -0.01 over its two frames and holds, the shear follows its table at quarter cycles.
    let shear_table = [1.0, 0.0, -1.0, 0.0];
    for (j, row) in rows.iter().enumerate().skip(1) {
        let press = if j == 1 { -0.005 } else { -0.01 };
        let shear = if j <= 2 {
            0.0
        } else {
            0.03 * shear_table[(j - 3) % 4]
        };
        assert!((row["displacement_press_y"] - press).abs() < 1e-15, "{j}");
        assert!((row["displacement_shear_x"] - shear).abs() < 1e-15, "{j}");
        // The extents add up to the joint's length (2 mm).
        let total = row["joint_stick_length"] + row["joint_slip_length"] + row["joint_open_length"];
        assert!((total - 2.0).abs() < 1e-12, "{j}: {total}");
        // Reactions by support name, not by their shared group.
        assert!(row.contains_key("reaction_press_y") && row.contains_key("reaction_shear_x"));
    }
    assert!(!rows[0].contains_key("reaction_lid_x"));
    assert!(
        rows.iter().any(|r| r["joint_slip_length"] > 0.0),
        "the joint slips"
    );
    // The dissipation increments of a cycle's frames add up to cycles.csv's dissipation of
    // that cycle, and the running total to their sum.
    let mut reader = csv::Reader::from_path(out.join("cycles.csv")).unwrap();
    let header = reader.headers().unwrap().clone();
    let column = |name: &str| header.iter().position(|h| h == name).unwrap();
    let mut cycles = 0;
    for record in reader.records() {
        let record = record.unwrap();
        let value = |name: &str| record[column(name)].parse::<f64>().unwrap();
        let (step, cycle) = (value("analysis_step"), value("cycle"));
        let increments: f64 = rows
            .iter()
            .filter(|r| r["analysis_step"] == step && r["cycle"] == cycle)
            .map(|r| r["joint_dissipation_increment"])
            .sum();
        let dissipation = value("dissipation");
        assert!(
            (increments - dissipation).abs() <= 1e-9 * dissipation.abs(),
            "step {step} cycle {cycle}: {increments} vs {dissipation}"
        );
        cycles += usize::from(step == 2.0);
    }
    assert_eq!(cycles, 2);
    let total: f64 = rows.iter().map(|r| r["joint_dissipation_increment"]).sum();
    let last = rows.last().unwrap()["joint_dissipation"];
    assert!(last > 0.0 && (total - last).abs() <= 1e-12 * last);

    // summary.json: the same names and values per step, and per analysis step its work and
    // dissipation, the fretting step's friction dissipation that of the pair.
    let summary = json(&out.join("summary.json"));
    let step = &summary["steps"][3];
    assert_eq!(
        step["displacements"]["shear"]["x"],
        rows[4]["displacement_shear_x"]
    );
    assert!(step["displacements"]["shear"]["y"].is_null());
    assert_eq!(
        step["contact"]["joint"]["stick"],
        rows[4]["joint_stick_length"]
    );
    assert!(step["reactions"]["press"].is_object());
    let fret = &summary["analysis_steps"][1];
    assert_eq!(fret["name"], "fret");
    let in_step: f64 = rows[3..]
        .iter()
        .map(|r| r["joint_dissipation_increment"])
        .sum();
    let pair = fret["contact_dissipation"]["joint"].as_f64().unwrap();
    assert!(
        (pair - in_step).abs() <= 1e-12 * in_step,
        "{pair} vs {in_step}"
    );
    // The energy ledger counts the same friction work (both p_T Δu_Tᵖ at the end of each
    // increment), and the only dissipation of this elastic model.
    let ledger = fret["dissipation"].as_f64().unwrap();
    assert!((ledger - pair).abs() <= 1e-9 * pair, "{ledger} vs {pair}");
    let energy = &summary["energy"]["steps"][1];
    assert_eq!(fret["external_work"], energy["external_work"]);
    assert_eq!(ledger, energy["friction_dissipation"].as_f64().unwrap());
}

/// `pyvista.read("results.pvd")` names the bodies and the pair (pipelines/check_output.py's
/// check, run with the repository's venv; skipped, saying so, where it is not installed).
#[test]
fn pyvista_shows_the_parts_by_name() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let python = std::env::var_os("ASPERITY_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join(".venv/bin/python"));
    if !python.is_file() {
        eprintln!("skipped: no {} (make venv)", python.display());
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    run_cli(&fretting(1).write(&dir.path().join("case.toml")), &out, &[]);
    let vtm = std::fs::read_to_string(out.join("frame_0001.vtm")).unwrap();
    assert!(
        vtm.contains("name=\"lower\" file=\"bodies_0001_1.vtu\""),
        "{vtm}"
    );
    let output = Command::new(&python)
        .arg(root.join("pipelines/check_output.py"))
        .arg(&out)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        text.contains("bodies ['lower', 'upper'], contacts ['joint']"),
        "{text}"
    );
}

/// `asperity fit` of a law whose penalty stiffness is left out: a material-point test has no
/// mesh to default it from, so the fit file is refused, naming the key; given, it fits.
#[test]
fn a_fit_at_a_material_point_needs_the_penalty_stiffness() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("shear.csv");
    std::fs::write(
        &data,
        "# units: displacement = mm, shear = MPa\ndisplacement,shear\n0.001,3\n0.002,6\n0.004,9\n0.008,9\n",
    )
    .unwrap();
    let fit = |stiffness: &str| {
        let path = dir.path().join("fit.toml");
        let text = format!(
            "law = \"linear_coulomb\"\n[parameters]\nfriction = {{ initial = 0.5, min = 0.0, max = 2.0 }}\n\
             {stiffness}\n[[test]]\nkind = \"tangential\"\ndata = \"shear.csv\"\npressure = 30.0\n"
        );
        std::fs::write(&path, text).unwrap();
        asperity::fit::Fit::from_file(&path)
    };
    let message = fit("").unwrap_err().to_string();
    assert!(
        message.contains("parameters.normal_stiffness") && message.contains("no mesh"),
        "{message}"
    );
    let given = "normal_stiffness = { value = 1e4 }\ntangential_stiffness = { value = 3e3 }";
    assert!(fit(given).is_ok());
}

/// A `model` test of `asperity fit` whose law leaves the penalty stiffnesses out keeps them
/// fixed for the whole fit at the specimen's default: the result reports the value (in
/// fit.json and the printed table), which is the one a run of the specimen gets (10 E*/h),
/// and every evaluation solves with exactly that value (it equals an evaluation given it
/// explicitly, and differs from one given twice it), so the fit recovers the friction that
/// made the data.
#[test]
fn a_model_fit_keeps_a_defaulted_penalty_fixed_and_reports_it() {
    use asperity::fit::Fit;
    use std::fmt::Write as _;
    let dir = tempfile::tempdir().unwrap();
    // The upper block pressed and dragged into sliding; the measured quantity is the lid's
    // tangential reaction, μ times the normal force once it slides.
    let specimen = blocks(None)
        .support("lid", &[("ux", 0.02), ("uy", -0.01)])
        .steps(4)
        .write(&dir.path().join("specimen.toml"));
    let out = dir.path().join("specimen");
    run_cli(&specimen, &out, &[]);
    let by_run = json(&out.join("run.json"))["penalty_defaults"][0]["stiffness"]
        .as_f64()
        .unwrap();
    let elements = json(&out.join("summary.json"))["model"]["interface_elements"]
        .as_f64()
        .unwrap();
    let e_star = 1000.0 / (1.0 - 0.3 * 0.3) / 2.0;
    assert!((by_run - 10.0 * e_star / (2.0 / elements)).abs() < 1e-9 * by_run);

    let data = dir.path().join("reaction.csv");
    let write_data = |values: &[f64]| {
        let mut csv = "# units: step = 1, value = 1\nstep,value\n".to_string();
        for (k, v) in values.iter().enumerate() {
            writeln!(csv, "{},{v:e}", k + 1).unwrap();
        }
        std::fs::write(&data, csv).unwrap();
    };
    write_data(&[1.0; 4]);
    let path = dir.path().join("fit.toml");
    std::fs::write(
        &path,
        format!(
            "law = \"linear_coulomb\"\nstarts = 1\n[parameters]\n\
             friction = {{ initial = 0.5, min = 0.0, max = 2.0 }}\n\
             [[test]]\nkind = \"model\"\ncase = {specimen:?}\ndata = \"reaction.csv\"\n\
             quantity = \"reactions.lid.x\"\n"
        ),
    )
    .unwrap();
    let fit = Fit::from_file(&path).unwrap();
    let (k_n, k_t, mu) = (0, 1, 2); // linear_coulomb's parameters, in the law's order
    let mut x = fit.parameters.values.clone();
    assert!(x[k_n].is_nan() && x[k_t].is_nan(), "{x:?}");
    x[mu] = 0.3;
    let measured = fit.simulate(&x).unwrap().remove(0);
    let mut given = x.clone();
    given[k_n] = by_run;
    given[k_t] = by_run;
    assert_eq!(fit.simulate(&given).unwrap()[0], measured);
    given[k_n] = 2.0 * by_run;
    given[k_t] = 2.0 * by_run;
    assert_ne!(fit.simulate(&given).unwrap()[0], measured);
    assert!(measured.iter().all(|f| f.abs() > 0.1), "{measured:?}");

    write_data(&measured);
    let result = Fit::from_file(&path).unwrap().run().unwrap();
    assert!(
        (result.get("friction").unwrap().value - 0.3).abs() < 1e-6,
        "{result}"
    );
    assert_eq!(result.penalty_defaults.len(), 1, "{result}");
    let fixed = &result.penalty_defaults[0];
    assert_eq!(fixed.default.contact, "joint");
    assert_eq!(
        fixed.default.parameters,
        ["normal_stiffness", "tangential_stiffness"]
    );
    assert_eq!(fixed.default.stiffness, by_run);
    assert!(result.to_string().contains("fixed at test[0]"), "{result}");
    let fit_out = dir.path().join("fit");
    asperity::fit::write(&result, &fit_out, false).unwrap();
    let reported = &json(&fit_out.join("fit.json"))["penalty_defaults"][0];
    assert_eq!(reported["stiffness"].as_f64(), Some(by_run));
    assert_eq!(reported["contact"], "joint");
    assert!(reported["test"].as_str().unwrap().starts_with("test[0]"));
    // The fitted law's case line leaves the stiffnesses out: a run of it defaults them again.
    assert!(!result.snippet.contains("stiffness"), "{}", result.snippet);
}
