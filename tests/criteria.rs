//! The engineering convergence criteria (`[solver]`, docs/convergence_criteria.md): small
//! cases of every kind the program solves — linear elastic, frictional sliding with stick and
//! slip, J2 plasticity, a load that goes to zero and comes back — give the same answer with
//! the default criteria as with a tight relative-norm tolerance (1e-10), to 1e-4 relative;
//! a linear problem takes one solve; steps with nothing loaded and steps unloaded to a
//! stress-free state converge; the old keys still work and bad values are named.

use crate::common;

use asperity::Error;
use asperity::config::Case;
use asperity::solver::newton::{Criteria, NewtonSettings};
use asperity::solver::state::{RunStatistics, Solution};
use asperity::solver::stepping::run_steps;
use common::{
    CaseBuilder, block_on_base, elastic, linear_coulomb, rectangle, settings, sliding_block_mesh,
};

/// The defaults and the tight reference settings of `case`.
fn default_and_tight(case: &Case) -> (NewtonSettings, NewtonSettings) {
    let default = settings(case);
    let tight = NewtonSettings {
        force_tolerance: 1e-10,
        displacement_tolerance: 1e-10,
        criteria: Criteria {
            relative_norms: true,
            ..default.criteria
        },
        ..default
    };
    (default, tight)
}

/// Every step's displacements (a copy after each converged step) and the run's statistics.
fn history(
    mesh: asperity::mesh::Mesh,
    case: &Case,
    s: &NewtonSettings,
) -> (Vec<Vec<f64>>, RunStatistics, Solution) {
    let model = common::model(mesh, case).expect("model builds");
    let mut steps = Vec::new();
    let (solution, stats) = run_steps(&model, s, |step| {
        steps.push(step.solution.u.clone());
        Ok(0.0)
    })
    .expect("solves");
    (steps, stats, solution)
}

/// The largest difference between the two runs' displacements over all steps, relative to
/// the largest displacement of the tight run.
fn relative_difference(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    let scale = b.iter().flatten().fold(0.0_f64, |m, x| m.max(x.abs()));
    let d = a
        .iter()
        .flatten()
        .zip(b.iter().flatten())
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
    d / scale
}

/// Solves `case` on `mesh()` with the defaults and tightly; checks the 1e-4 agreement and
/// returns the iterations (default, tight).
fn agrees(mesh: impl Fn() -> asperity::mesh::Mesh, case: &Case) -> (usize, usize) {
    let (default, tight) = default_and_tight(case);
    let (a, sa, _) = history(mesh(), case, &default);
    let (b, sb, _) = history(mesh(), case, &tight);
    let d = relative_difference(&a, &b);
    assert!(d <= 1e-4, "relative difference {d:.3e}");
    assert_eq!(sa.cutbacks, 0, "the defaults cut back");
    (sa.iterations, sb.iterations)
}

#[test]
fn frictional_sliding_with_stick_and_slip_agrees_with_a_tight_run() {
    // Pressed, pushed past the friction limit (slip), back a little (stick), on again.
    let case = block_on_base(70000.0, 0.33, &[], linear_coulomb(1e4, 1e3, 0.25))
        .pressed_and_pushed(8.0, 0.01, &[0.5, 1.0, 0.9, 1.5, 2.0, 1.9, 2.5])
        .case();
    let (default, tight) = agrees(sliding_block_mesh, &case);
    assert!(
        default <= tight,
        "iterations: default {default}, tight {tight}"
    );
}

/// Interface iterations (`[solver] interface_iterations`, 12 by default) settle the
/// stick–slip statuses within a Newton iteration: the frictional block reaches the tight
/// run's answer as plain Newton iterations do (1e-4), in fewer Newton iterations; without
/// them (0) the iterations are plain Newton's.
#[test]
fn interface_iterations_reach_the_tight_answer_in_fewer_newton_iterations() {
    let case = block_on_base(70000.0, 0.33, &[], linear_coulomb(1e4, 1e3, 0.25))
        .pressed_and_pushed(8.0, 0.01, &[0.5, 1.0, 0.9, 1.5, 2.0, 1.9, 2.5])
        .case();
    let (default, tight) = default_and_tight(&case);
    assert_eq!(default.interface_iterations, 12);
    let plain = NewtonSettings {
        interface_iterations: 0,
        ..default
    };
    let (reference, _, _) = history(sliding_block_mesh(), &case, &tight);
    let mut iterations = Vec::new();
    for s in [&default, &plain] {
        let (u, stats, _) = history(sliding_block_mesh(), &case, s);
        let d = relative_difference(&u, &reference);
        assert!(d <= 1e-4, "relative difference {d:.3e}");
        assert_eq!(stats.cutbacks, 0);
        iterations.push(stats.iterations);
    }
    println!("Newton iterations with and without interface iterations: {iterations:?}");
    assert!(iterations[0] < iterations[1], "{iterations:?}");
}

/// A plane-strain strip [0, 4] × [0, 1] (slightly distorted elements) held on its bottom
/// (t0) and left (s0) edges, its top edge (t1) pulled and pushed: `material` decides whether it yields.
fn strip(material: toml::Table, top: &[f64]) -> (impl Fn() -> asperity::mesh::Mesh, Case) {
    let mesh = || rectangle(4.0, 1.0, 8, 3, 0.1, false);
    let case = CaseBuilder::plane_strain()
        .body("body", material)
        .support("t0", &[("uy", 0.0)])
        .support("s0", &[("ux", 0.0)])
        .support_history("t1", &[("uy", 0.01)], top)
        .step_factors(top)
        .case();
    (mesh, case)
}

#[test]
fn plastic_loading_and_unloading_agrees_with_a_tight_run() {
    let mut material = elastic(200_000.0, 0.3);
    material.insert("yield_stress".into(), 250.0.into());
    material.insert("hardening".into(), 2000.0.into());
    let factors = [0.1, 0.2, 0.3, 0.4, 0.6, 0.8, 1.0, 0.5, 0.0];
    let (mesh, case) = strip(material, &factors);
    let (default, tight) = agrees(mesh, &case);
    assert!(
        default <= tight,
        "iterations: default {default}, tight {tight}"
    );
}

#[test]
fn linear_steps_take_one_solve_each_and_none_when_extrapolated() {
    let (mesh, case) = strip(elastic(200_000.0, 0.3), &[0.5, 1.0, -1.0]);
    let (default, _) = default_and_tight(&case);
    let plain = NewtonSettings {
        extrapolate: false,
        ..default
    };
    let (_, stats, _) = history(mesh(), &case, &plain);
    assert_eq!(stats.iterations, 3);
    // Step 2 continues step 1 in proportion: for a linear problem the extrapolation is the
    // answer (R_l test before any solve). Step 3 reverses and is solved.
    let extrapolated = NewtonSettings {
        extrapolate: true,
        ..default
    };
    let (_, stats, _) = history(mesh(), &case, &extrapolated);
    assert_eq!(stats.iterations, 2);
}

#[test]
fn nothing_loaded_and_unloaded_to_zero_converge() {
    // Step 1 loads nothing (u = 0 exactly, no flux at all), step 2 loads, step 3 returns to
    // zero: a stress-free state, judged by the zero-flux criteria against the run's average
    // force; the displacements must return to zero.
    let (mesh, case) = strip(elastic(200_000.0, 0.3), &[0.0, 1.0, 0.0]);
    let (default, _) = default_and_tight(&case);
    let (steps, stats, _) = history(mesh(), &case, &default);
    assert_eq!(stats.cutbacks, 0);
    assert!(
        steps[0].iter().all(|&x| x == 0.0),
        "step 1 must stay at rest"
    );
    let peak = steps[1].iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let rest = steps[2].iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    assert!(
        peak > 1e-3 && rest <= 1e-10 * peak,
        "peak {peak}, rest {rest}"
    );
}

#[test]
fn pressure_on_a_frictional_contact_unloaded_to_zero_converges() {
    // The block pressed and released: the interface ends stress-free (zero flux).
    let case = block_on_base(70000.0, 0.33, &[], linear_coulomb(1e4, 1e3, 0.25))
        .pressure_history("block_top", 8.0, &[0.5, 1.0, 0.0])
        .support("block_top", &[("ux", 0.0)])
        .steps(3)
        .case();
    let (default, _) = default_and_tight(&case);
    let (steps, stats, _) = history(sliding_block_mesh(), &case, &default);
    assert_eq!(stats.cutbacks, 0);
    let peak = steps[1].iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let rest = steps[2].iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    assert!(rest <= 1e-6 * peak, "peak {peak}, rest {rest}");
}

fn solver_table(entries: &[(&str, toml::Value)]) -> asperity::Result<Case> {
    let mut builder = CaseBuilder::plane_strain()
        .body("body", elastic(200_000.0, 0.3))
        .support("t0", &[("uy", 0.0)]);
    for (k, v) in entries {
        builder = builder.set("solver", k, v.clone());
    }
    builder.try_case()
}

#[test]
fn defaults_and_old_keys() {
    let case = solver_table(&[]).expect("valid");
    let s = &case.solver;
    assert_eq!(
        (
            s.residual_tolerance,
            s.correction_tolerance,
            s.linear_residual_tolerance
        ),
        (5e-4, 1e-3, 1e-8)
    );
    assert!(!s.relative_norms);
    let old = solver_table(&[("force_tolerance", 1e-10.into())]).expect("valid");
    assert!(old.solver.relative_norms);
    assert_eq!(old.solver.force_tolerance, 1e-10);
    let c = settings(&old).criteria;
    assert!(c.relative_norms && c.residual == 5e-4);
}

#[test]
fn bad_thresholds_are_named() {
    for (key, value) in [
        ("residual_tolerance", toml::Value::from(0.0)),
        ("correction_tolerance", (-1.0).into()),
        ("zero_flux", f64::NAN.into()),
        ("average_force", 0.0.into()),
    ] {
        let e = solver_table(&[(key, value)]).expect_err("invalid");
        assert_eq!(invalid_key(e), format!("solver.{key}"));
    }
    let e = solver_table(&[("linear_residual_tolerance", 1e-2.into())]).expect_err("invalid");
    assert_eq!(invalid_key(e), "solver.linear_residual_tolerance");
    let e = solver_table(&[("interface_iterations", 101.into())]).expect_err("invalid");
    assert_eq!(invalid_key(e), "solver.interface_iterations");
    // An unknown key is a case error whose message names it.
    let e = solver_table(&[("residual_tolerence", 1e-3.into())]).expect_err("unknown key");
    assert!(
        matches!(&e, Error::Case { message, .. } if message.contains("residual_tolerence")),
        "{e}"
    );
}

/// The case-file key of an [`Error::InvalidParameter`].
fn invalid_key(e: Error) -> String {
    match e {
        Error::InvalidParameter { key, .. } => key,
        other => panic!("expected an invalid parameter, got {other:?}"),
    }
}
