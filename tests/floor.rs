//! `summary.json` `floor` (issue 29): the floor of a run is made of calls the run made, so it
//! never exceeds the run, and its counts are those of the run's own log. No timings are
//! asserted, only relations that hold whatever the machine's speed.

use crate::common;

use common::{CaseBuilder, run_cli, two_blocks};
use serde_json::Value;

/// The upper block of [`two_blocks`] (μ = 0.3) pressed onto the lower one and pulled sideways
/// by less than the friction capacity, in three steps, solved with `linear_solver`.
fn pressed_and_pulled(linear_solver: &str) -> CaseBuilder {
    two_blocks(0.3)
        .traction("lid", [2.0, -10.0])
        .step_factors(&[0.25, 0.5, 1.0])
        .set("solver", "linear_solver", linear_solver)
        // Each increment from the last converged state, not extrapolated: several iterations
        // per increment, so that kept interface LUs appear in the counts.
        .set("solver", "extrapolate", false)
}

/// Runs `case` with the command line and returns its `summary.json`.
fn summary(case: CaseBuilder) -> Value {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    run_cli(&case.write(&dir.path().join("case.toml")), &out, &[]);
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

pub(crate) fn count(summary: &Value, key: &str) -> u64 {
    summary["floor"]["counts"][key]
        .as_u64()
        .unwrap_or_else(|| panic!("floor.counts.{key} in {}", summary["floor"]))
}

pub(crate) fn seconds(value: &Value) -> f64 {
    value.as_f64().unwrap_or_else(|| panic!("seconds: {value}"))
}

/// What holds for every floor: its parts add up to it, each is at most the phase it is
/// taken from (the assembly: with the analysis it may run beside), and the floor is at most
/// the run (gmsh left out of both), its ratio the quotient and at least 1. The counts of
/// increments, frames and solves are the totals'.
pub(crate) fn check_floor(summary: &Value) {
    let floor = &summary["floor"];
    let time = &summary["seconds"];
    let parts = &floor["parts"];
    let sum: f64 = [
        "mesh",
        "assembly",
        "factorisation",
        "solves",
        "output",
        "conduction",
    ]
    .iter()
    .map(|k| seconds(&parts[k]))
    .sum();
    let total = seconds(&floor["seconds"]);
    // The same six numbers summed in the same order.
    assert_eq!(total, sum, "{floor}");
    let gmsh = time["gmsh"].as_f64().unwrap_or(0.0);
    assert!(
        seconds(&parts["mesh"]) <= seconds(&time["mesh"]) - gmsh,
        "{floor}"
    );
    // With elastic bodies on the condensed path their one assembly runs beside the ordering
    // and symbolic analysis, whose time the factorisation phase takes: the assembly is within
    // its phase and the analysis.
    let symbolic = time["symbolic"].as_f64().unwrap_or(0.0);
    assert!(
        seconds(&parts["assembly"]) <= seconds(&time["assembly"]) + symbolic,
        "{floor} {time}"
    );
    for (part, phase) in [
        ("factorisation", "factorisation"),
        ("solves", "solve"),
        ("conduction", "conduction"),
    ] {
        assert!(
            seconds(&parts[part]) <= seconds(&time[phase]),
            "{part}: {floor} {time}"
        );
    }
    // A fresh run's output is all its output.
    assert_eq!(parts["output"], time["output"], "{floor} {time}");
    // The seconds of each kind of call counted (the floor's mean solves a part of the
    // solves').
    let work = floor["work_seconds"].as_object().unwrap();
    for (kind, value) in work {
        assert!(seconds(value) >= 0.0, "{kind}: {floor}");
        let calls = if kind == "frames" {
            1
        } else {
            count(summary, kind)
        };
        assert!(calls > 0 || seconds(value) == 0.0, "{kind}: {floor}");
    }
    assert_eq!(work["frames"], time["output"], "{floor} {time}");
    assert!(
        seconds(&parts["solves"]) <= seconds(&work["solves"]),
        "{floor}"
    );
    let run = seconds(&time["total"]) - gmsh;
    assert!(total > 0.0 && total <= run, "{floor} {time}");
    let ratio = seconds(&floor["ratio"]);
    assert!(ratio >= 1.0, "{floor}");
    assert_eq!(ratio, run / total);
    let totals = &summary["totals"];
    assert_eq!(totals["cutbacks"], 0, "the counts below assume no cut-back");
    assert_eq!(count(summary, "increments"), totals["increments"]);
    assert_eq!(
        count(summary, "frames"),
        summary["steps"].as_array().unwrap().len() as u64
    );
    // Load control: one linear solve per Newton iteration.
    assert_eq!(count(summary, "solves"), totals["iterations"]);
}

/// On the condensed path the elastic bulk is assembled with its tangent once (over all dofs:
/// the free equations' matrix is its restriction, and K·u uses both) and factored once; its
/// force is K·u throughout, and its elements are evaluated again only for point states: a
/// frame's, and the two ends of an increment whose strain-increment bound exceeds the
/// plausibility limit; every Newton iteration factors the interface
/// system by LU or keeps the last LU (an unchanged interface tangent), and every interface
/// iteration within one factors it again.
#[test]
fn the_condensed_floor_counts_what_its_log_says() {
    let summary = summary(pressed_and_pulled("condensed"));
    check_floor(&summary);
    let iterations = summary["totals"]["iterations"].as_u64().unwrap();
    assert!(iterations >= 3, "{summary}");
    assert_eq!(count(&summary, "assemblies"), 1);
    assert_eq!(count(&summary, "factorisations"), 1);
    assert_eq!(count(&summary, "kept_factorisations"), 0);
    // A linear bulk without a temperature field: its force is K·u throughout, and every
    // increment here is a frame with fields, whose point states the frame makes
    // (`frame_states`); the exact check of the strain increment where the bound exceeded
    // the limit evaluates the states at the increment's start and end (two loops, storing
    // nothing).
    let increments = summary["totals"]["increments"].as_u64().unwrap();
    let exact = count(&summary, "state_evaluations");
    assert_eq!(exact % 2, 0, "{summary}");
    assert!(exact / 2 <= increments, "{summary}");
    assert_eq!(count(&summary, "frame_states"), increments, "{summary}");
    assert_eq!(count(&summary, "force_assemblies"), 0, "{summary}");
    let interface_lus = count(&summary, "interface_factorisations");
    let kept = count(&summary, "kept_interface_factorisations");
    // One LU (or a kept one) per Newton iteration, and one per interface iteration.
    let interface_iterations = count(&summary, "interface_iterations");
    assert_eq!(interface_lus + kept, iterations + interface_iterations);
    // Sticking throughout: after the first iterations the interface tangent repeats.
    assert!(kept > 0 && interface_lus > 0, "{summary}");
    // Every evaluation after the first takes the bulk's force from K·u or its elements,
    // and the interface's from its elements.
    assert!(count(&summary, "products") > 0);
    assert!(count(&summary, "interface_assemblies") > iterations);
}

/// Off the condensed path every pass of the Newton loop assembles the whole model with its
/// tangent (one per iteration and the last one that finds the increment converged, plus one
/// per rejected full step of a line search), and every iteration factors it; there is no
/// interface system and no K·u.
#[test]
fn the_cholesky_floor_counts_what_its_log_says() {
    let summary = summary(pressed_and_pulled("krylov"));
    check_floor(&summary);
    let totals = &summary["totals"];
    let iterations = totals["iterations"].as_u64().unwrap();
    let increments = totals["increments"].as_u64().unwrap();
    assert_eq!(count(&summary, "assemblies"), iterations + increments);
    let bicgstab = totals["unsymmetric_solves"].as_u64().unwrap();
    assert_eq!(count(&summary, "factorisations"), iterations - bicgstab);
    for key in [
        "interface_assemblies",
        "interface_force_assemblies",
        "interface_factorisations",
        "products",
        "kept_factorisations",
    ] {
        assert_eq!(count(&summary, key), 0, "{key}");
    }
    // A line search assembles its full step with the tangent (accepted, that is the next
    // iteration's assembly, counted above: no full step is rejected here), and only shorter
    // steps without it.
    assert!(count(&summary, "line_search_evaluations") > 0, "{summary}");
    assert_eq!(count(&summary, "force_assemblies"), 0);
}
