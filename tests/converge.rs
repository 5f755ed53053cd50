//! Mesh-convergence studies (`asperity converge`): the order / Richardson arithmetic on
//! synthetic sequences of known order, the quantities of interest evaluated on a solved
//! shrink fit against its closed form, the `--quantity` syntax, and the command's exit status
//! for a converged study (thick cylinder against Lamé), a deliberately non-converged quantity
//! (the singular edge pressure of a flat punch) and a case that cannot be refined.
use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use asperity::Error;
use asperity::config::{Case, QuantitySpec, parse_quantity};
use asperity::model::Model;
use asperity::post::interface::resultants;
use asperity::post::quantities::evaluate;
use asperity::solver::stepping::run_steps;
use asperity::study::{Criteria, analyse};
use common::*;

fn criteria(reference: Option<f64>, tolerance: f64, min_order: Option<f64>) -> Criteria {
    Criteria {
        reference,
        tolerance,
        min_order,
        noise: asperity::study::ROUND_OFF,
    }
}

/// q(h) = q∞ + c h^p at h = 1, 1/r, 1/r², ...
fn sequence(levels: usize, ratio: f64, limit: f64, c: f64, p: f64) -> (Vec<f64>, Vec<f64>) {
    let h: Vec<f64> = (0..levels).map(|k| ratio.powi(-(k as i32))).collect();
    (h.iter().map(|h| limit + c * h.powf(p)).collect(), h)
}

#[test]
fn richardson_recovers_order_and_limit_of_a_smooth_sequence() {
    for (ratio, p) in [(2.0, 3.0), (2.0, 4.0), (1.5, 2.0), (3.0, 1.0)] {
        let (q, h) = sequence(4, ratio, 2.5, 0.3, p);
        let c = analyse(&q, &h, ratio, &criteria(Some(2.5), 0.1, Some(p - 0.1)));
        let order = c.order.unwrap();
        let limit = c.extrapolated.unwrap();
        println!(
            "r = {ratio}, p = {p}: observed {order:.6}, fitted {:.6}, extrapolated {limit:.12}",
            c.reference_order.unwrap()
        );
        assert!((order - p).abs() < 1e-6, "order {order} vs {p}");
        assert!((c.reference_order.unwrap() - p).abs() < 1e-6);
        assert!((limit - 2.5).abs() < 1e-10, "extrapolated {limit}");
        // The estimate is the true error of the finest level.
        let true_error = (q[3] - 2.5).abs();
        assert!((c.error_estimate.unwrap() - true_error).abs() < 1e-9 * true_error.max(1e-12));
        assert!(c.converged && c.passed(), "{:?}", c.failures);
    }
}

#[test]
fn a_sequence_whose_differences_grow_is_not_converged() {
    // A singular value: q = h^(-1/2) grows without bound.
    let (q, h) = sequence(3, 2.0, 0.0, 1.0, -0.5);
    let c = analyse(&q, &h, 2.0, &criteria(None, 1.0, None));
    assert!(!c.converged && !c.passed());
    assert!(
        c.failures[0].starts_with("not converged"),
        "{:?}",
        c.failures
    );
    assert!(c.extrapolated.is_none());
    // Differences that grow and then shrink a little (a logarithmic divergence with noise):
    // still not converged, although the three finest levels alone give a positive order.
    let q = [10.0, 13.4, 17.4, 21.2];
    let c = analyse(
        &q,
        &[1.0, 0.5, 0.25, 0.125],
        2.0,
        &criteria(None, 1.0, None),
    );
    assert!(c.order.unwrap() > 0.0);
    assert!(!c.converged, "{:?}", c);
    assert!(c.failures[0].contains("grow"), "{:?}", c.failures);
}

#[test]
fn a_value_that_does_not_change_is_exact_not_unconverged() {
    let q = [4.0, 4.0 + 1e-14, 4.0 - 1e-14];
    let c = analyse(
        &q,
        &[1.0, 0.5, 0.25],
        2.0,
        &criteria(Some(4.0), 1e-9, Some(2.0)),
    );
    assert!(c.converged && c.passed(), "{:?}", c.failures);
    assert!(c.order.is_none());
    assert_eq!(c.extrapolated, Some(q[2]));
    assert!(c.notes[0].contains("round-off"), "{:?}", c.notes);
}

#[test]
fn tolerances_and_min_order_fail_with_a_reason() {
    let (q, h) = sequence(3, 2.0, 1.0, 0.1, 1.0);
    // Change between the finest levels 0.025 / 1.025.
    let c = analyse(&q, &h, 2.0, &criteria(None, 1e-3, None));
    assert_eq!(c.failures.len(), 1);
    assert!(
        c.failures[0].contains("relative change"),
        "{:?}",
        c.failures
    );
    // Wrong reference.
    let c = analyse(&q, &h, 2.0, &criteria(Some(1.2), 0.1, None));
    assert!(
        c.failures.iter().any(|f| f.contains("reference")),
        "{:?}",
        c.failures
    );
    // First order where at least second was demanded.
    let c = analyse(&q, &h, 2.0, &criteria(None, 0.1, Some(2.0)));
    assert!(c.converged);
    assert!(c.failures[0].contains("min_order"), "{:?}", c.failures);
}

#[test]
fn alternating_differences_are_noted() {
    let q = [1.0 + 0.1, 1.0 - 0.025, 1.0 + 0.00625];
    let c = analyse(&q, &[1.0, 0.5, 0.25], 2.0, &criteria(Some(1.0), 0.1, None));
    assert!(c.passed(), "{:?}", c.failures);
    assert!((c.order.unwrap() - 2.0).abs() < 1e-9);
    assert!(c.notes.iter().any(|n| n.contains("alternate")));
    // The error against the reference changes sign too: no order is fitted to it.
    assert!(c.reference_order.is_none());
}

#[test]
fn command_line_quantities_are_parsed_and_unknown_keys_named() {
    let q = parse_quantity("p:contact_pressure:pair=fit,statistic=at,y=5,reference=46.4").unwrap();
    assert_eq!(q.name, "p");
    assert_eq!(q.y, Some(5.0));
    assert_eq!(q.reference, Some(46.4));
    assert_eq!(q.tolerance, 1e-3);
    let e = parse_quantity("p:contact_pressure:pair=fit,statistc=peak").unwrap_err();
    assert!(e.contains("statistc") && e.contains("syntax"), "{e}");
    let e = parse_quantity("p:pressure:pair=fit").unwrap_err();
    assert!(e.contains("pressure"), "{e}");
    let e = parse_quantity("p:displacement:point=a,component=x,x=left").unwrap_err();
    assert!(e.contains("not a number"), "{e}");
    let e = parse_quantity("p").unwrap_err();
    assert!(e.contains("no kind"), "{e}");
}

#[test]
fn quantity_sections_are_checked_against_the_case() {
    let base = r#"
        [mesh]
        geo = "x.geo"
        [analysis]
        type = "axisymmetric"
        [[body]]
        group = "b"
        material = { E = 1.0, nu = 0.3 }
        [[support]]
        group = "bottom"
        uz = 0.0
    "#;
    let parse =
        |q: &str| Case::from_toml(&format!("{base}\n[[quantity]]\n{q}"), Path::new("c.toml"));
    assert!(
        parse("name = \"r\"\nkind = \"reaction\"\nsupport = \"axis\"\ncomponent = \"r\"").is_ok()
    );
    // A quantity that does not fit the case is a case error naming the quantity and the key.
    let message = |q: &str| match parse(q) {
        Err(Error::Case { path, message }) if path == Path::new("c.toml") => message,
        other => panic!("expected a case error, got {other:?}"),
    };
    let e = message("name = \"r\"\nkind = \"reaction\"\nsupport = \"top\"\ncomponent = \"z\"");
    assert!(e.contains("'top'") && e.contains("bottom, axis"), "{e}");
    let e = message("name = \"r\"\nkind = \"reaction\"\nsupport = \"bottom\"");
    assert!(e.contains("give `component`"), "{e}");
    let e = message("name = \"r\"\nkind = \"stick_zone\"\npair = \"p\"\nx = 1.0");
    assert!(e.contains("`x` does not apply"), "{e}");
    let e = message(
        "name = \"r\"\nkind = \"reaction\"\nsupport = \"bottom\"\ncomponent = \"z\"\nrefrence = 1.0",
    );
    assert!(e.contains("refrence"), "{e}");
}

/// The shared shrink fit (`common::shrink_fit`) with k_N = 1e4: p = δ / (C + 1/k_N).
mod shrink_fit {
    use super::*;
    pub use crate::common::shrink_fit::*;

    pub const K_N: f64 = 1e4;

    pub fn pressure() -> f64 {
        DELTA / (compliance() + 1.0 / K_N)
    }

    /// Plane-strain Lamé displacement of the hub's outside under the bore pressure p.
    pub fn hub_outside(p: f64) -> f64 {
        p * B * B * (1.0 + NU) * 2.0 * (1.0 - NU) * C / (E * (C * C - B * B))
    }

    pub fn model_and_case() -> (Model, Case) {
        let case = case(false, linear_coulomb(K_N, K_N, 0.2));
        let model = model(mesh(false), &case).expect("model builds");
        (model, case)
    }
}

#[test]
fn quantities_are_evaluated_on_the_solved_model() {
    let (model, case) = shrink_fit::model_and_case();
    let quantities: Vec<_> = [
        "mean:contact_pressure:pair=fit,statistic=mean",
        "peak:contact_pressure:pair=fit,statistic=peak",
        "mid:contact_pressure:pair=fit,statistic=at,y=5",
        "between:contact_pressure:pair=fit,statistic=at,y=3.3",
        "stick:stick_zone:pair=fit",
        "opening:relative_displacement:pair=fit,component=x",
        "stiffness:stiffness:pair=fit,component=r",
        "corner:displacement:point=hub_corner,component=x",
        "reaction:reaction:support=hub_ends,component=y",
    ]
    .iter()
    .map(|t| {
        let q = parse_quantity(t).unwrap();
        q.check(&case).unwrap();
        q
    })
    .collect();
    let mut values = Vec::new();
    let mut resultant = [0.0; 4];
    run_steps(&model, &settings(&case), |step| {
        values = evaluate(&quantities, &model, step)?;
        resultant = resultants(&model, &step.solution.interface_committed)[0];
        Ok(0.0)
    })
    .unwrap();
    let p = shrink_fit::pressure();
    for (q, v) in quantities.iter().zip(&values) {
        println!("{}: {v:.8e}", q.name);
    }
    let close = |v: f64, expected: f64, tol: f64| (v - expected).abs() <= tol * expected.abs();
    for (i, name) in ["mean", "peak", "mid", "between"].iter().enumerate() {
        assert!(close(values[i], p, 1e-4), "{name}: {} vs {p}", values[i]);
    }
    assert!(
        close(values[4], shrink_fit::L, 1e-12),
        "stick zone {}",
        values[4]
    );
    // The faces overlap by δ; the interface closes by p / k_N of it: B − A = δ − p / k_N.
    let opening = shrink_fit::DELTA - p / shrink_fit::K_N;
    assert!(
        close(values[5], opening, 1e-4),
        "{} vs {opening}",
        values[5]
    );
    // The shaft pushes the hub outwards: F_x = 2π b L p, and k = −F_x / ū_x.
    assert!(close(
        resultant[2],
        2.0 * std::f64::consts::PI * shrink_fit::B * shrink_fit::L * p,
        1e-4
    ));
    assert!(close(values[6], -resultant[2] / values[5], 1e-12));
    let u = shrink_fit::hub_outside(p);
    assert!(close(values[7], u, 1e-4), "{} vs {u}", values[7]);
    // The hub's end planes carry equal and opposite axial forces.
    assert!(values[8].abs() < 1e-9 * resultant[2], "{}", values[8]);

    // A coordinate outside the pair, and a point group that does not exist, are named.
    let mut bad = vec![parse_quantity("far:contact_pressure:pair=fit,statistic=at,y=20").unwrap()];
    let evaluation_error = |bad: &[QuantitySpec]| {
        let e = run_steps(&model, &settings(&case), |step| {
            evaluate(bad, &model, step)?;
            Ok(0.0)
        })
        .unwrap_err();
        match e {
            Error::Quantity { name, reason } => (name, reason),
            other => panic!("expected a quantity error, got {other}"),
        }
    };
    let (name, e) = evaluation_error(&bad);
    assert_eq!(name, "far");
    assert!(e.contains("outside pair 'fit'"), "{e}");
    bad[0] = parse_quantity("nowhere:displacement:point=tip,component=x").unwrap();
    let (name, e) = evaluation_error(&bad);
    assert_eq!(name, "nowhere");
    assert!(e.contains("'tip'") && e.contains("hub_corner"), "{e}");
}

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// Runs `asperity converge` on a copy of a study file with the `.geo` path made absolute and
/// `edit` applied; returns (exit code, stdout + stderr, output folder). `ASPERITY_PIPELINES`
/// names a folder without the plot script, so the plot is skipped (and says how to make it).
fn converge(
    study: &str,
    edit: impl Fn(String) -> String,
    args: &[&str],
) -> (i32, String, tempfile::TempDir) {
    converge_into(study, edit, args, |_| {})
}

/// [`converge`] with `prepare` called on the temporary folder first (the study writes into
/// its `out`).
fn converge_into(
    study: &str,
    edit: impl Fn(String) -> String,
    args: &[&str],
    prepare: impl Fn(&Path),
) -> (i32, String, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    prepare(dir.path());
    let text = std::fs::read_to_string(repo(study)).unwrap();
    let text = text.replace("\"../../geo/", &format!("\"{}/", repo("geo").display()));
    let case = dir.path().join("study.toml");
    std::fs::write(&case, edit(text)).unwrap();
    let out = dir.path().join("out");
    let output = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args([
            "converge",
            case.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(args)
        .env("ASPERITY_PIPELINES", dir.path())
        .output()
        .expect("runs");
    let text = String::from_utf8_lossy(&output.stdout).to_string()
        + &String::from_utf8_lossy(&output.stderr);
    (output.status.code().unwrap_or(-1), text, dir)
}

#[test]
fn a_converged_study_exits_zero_and_writes_the_table() {
    // Thick cylinder against Lamé, 4, 8, 16 elements through the wall, and one quantity from
    // the command line (the same bore displacement with a looser tolerance).
    let (code, text, dir) = converge(
        "pipelines/convergence/thick_cylinder.toml",
        |t| t,
        &[
            "--levels",
            "3",
            "--quantity",
            "bore_cli:displacement:point=bore_point,component=x,reference=0.009533333333333333,tolerance=1e-4,min_order=3",
        ],
    );
    println!("{text}");
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("bore_displacement") && text.contains("bore_cli"));
    let skipped = format!(
        "plot: skipped convergence.png: ASPERITY_PIPELINES={} has no plot_convergence.py; to make it, run \
         `.venv/bin/python pipelines/plot_convergence.py {}`",
        dir.path().display(),
        dir.path().join("out").display()
    );
    assert!(text.contains(&skipped), "{text}");
    let csv = std::fs::read_to_string(dir.path().join("out/convergence.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert!(rows[0].starts_with("quantity,kind,level,h,unknowns"));
    assert_eq!(rows.len(), 1 + 3 * 3, "{csv}");
    assert!(rows.iter().skip(1).all(|r| r.ends_with(",ok")), "{csv}");
    // The observed order of the quad8 bore displacement is about 4 (nodal superconvergence).
    let order: f64 = rows[1].split(',').nth(13).unwrap().parse().unwrap();
    assert!(order > 3.5, "order {order}");
    for k in 0..3 {
        let level = dir.path().join(format!("out/level_{k}"));
        assert!(level.join("history.csv").is_file());
        let summary = std::fs::read_to_string(level.join("summary.json")).unwrap();
        assert!(summary.contains("\"status\": \"converged\""), "{summary}");
    }
}

#[test]
fn a_singular_quantity_is_reported_as_not_converged() {
    // The flat punch's edge pressure at 8, 16, 32 elements under the punch.
    let (code, text, _dir) = converge(
        "pipelines/convergence/flat_punch_edge.toml",
        |t| t.replace("size = 1.0", "size = 2.0"),
        &["--levels", "3"],
    );
    println!("{text}");
    assert_eq!(code, 1, "{text}");
    let failing: Vec<&str> = text.lines().filter(|l| l.starts_with("FAILED ")).collect();
    assert_eq!(failing.len(), 1, "{text}");
    assert!(
        failing[0].starts_with("FAILED edge_pressure: not converged"),
        "{text}"
    );
}

#[test]
fn a_case_with_a_fixed_mesh_cannot_be_refined() {
    let (code, text, _dir) = converge(
        "pipelines/convergence/thick_cylinder.toml",
        |t| {
            t.replace("geo = ", "file = ")
                .replace("thick_cylinder_axi.geo", "thick_cylinder.msh")
        },
        &["--levels", "3"],
    );
    assert_eq!(code, 2, "{text}");
    assert!(
        text.contains("study.toml") && text.contains(".geo"),
        "{text}"
    );
    // Too few levels for an order, and a command-line quantity naming a missing pair.
    let (code, text, _dir) = converge(
        "pipelines/convergence/thick_cylinder.toml",
        |t| t,
        &["--levels", "2"],
    );
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("at least 3 levels"), "{text}");
    let (code, text, dir) = converge(
        "pipelines/convergence/thick_cylinder.toml",
        |t| t,
        &["--levels", "1000"],
    );
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("at most 20"), "{text}");
    assert!(
        !dir.path().join("out").exists(),
        "a refused study made its folder"
    );
    let (code, text, _dir) = converge(
        "pipelines/convergence/thick_cylinder.toml",
        |t| t,
        &["--quantity", "p:contact_pressure:pair=fit,statistic=peak"],
    );
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("no contact pair 'fit'"), "{text}");
}

/// A level's folder is taken over as a run's with `--force`: a link in place of the folder
/// (which would send the level elsewhere) or a file of the user's under a run file's name is
/// refused before anything is meshed (exit code 2), and left as it was.
#[cfg(unix)]
#[test]
fn a_study_never_writes_through_a_link_nor_over_a_users_file() {
    let (code, text, dir) = converge_into(
        "pipelines/convergence/thick_cylinder.toml",
        |t| t,
        &["--levels", "3"],
        |dir| {
            std::fs::create_dir_all(dir.join("elsewhere")).unwrap();
            std::fs::write(dir.join("elsewhere/summary.json"), "mine").unwrap();
            std::fs::create_dir_all(dir.join("out")).unwrap();
            std::os::unix::fs::symlink(dir.join("elsewhere"), dir.join("out/level_0")).unwrap();
        },
    );
    assert_eq!(code, 2, "{text}");
    assert!(
        text.contains("level_0") && text.contains("symbolic link"),
        "{text}"
    );
    assert_eq!(
        common::file_names(&dir.path().join("elsewhere")),
        ["summary.json"]
    );
    assert_eq!(read(&dir.path().join("elsewhere/summary.json")), "mine");
    let (code, text, dir) = converge_into(
        "pipelines/convergence/thick_cylinder.toml",
        |t| t,
        &["--levels", "3"],
        |dir| {
            std::fs::create_dir_all(dir.join("out/level_1")).unwrap();
            std::fs::write(dir.join("out/level_1/summary.json"), "mine").unwrap();
        },
    );
    assert_eq!(code, 2, "{text}");
    assert!(
        text.contains("summary.json") && text.contains("run_files.txt"),
        "{text}"
    );
    assert_eq!(read(&dir.path().join("out/level_1/summary.json")), "mine");
    assert!(
        !dir.path().join("out/level_2/mesh.msh").exists(),
        "a level was meshed"
    );
}

/// Two levels whose meshes are the same (the script's counts round to the same integers at a
/// small ratio) say nothing about convergence: the study is refused (exit code 2), not
/// reported converged on a difference of zero.
#[test]
fn levels_with_the_same_mesh_are_refused() {
    let (code, text, _dir) = converge(
        "pipelines/convergence/thick_cylinder.toml",
        |t| t,
        &["--levels", "3", "--ratio", "1.01"],
    );
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("the mesh did not get finer"), "{text}");
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
