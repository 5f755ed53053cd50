//! `[solver] max_cutbacks` counts a step's cut-backs in all: each halves a failed (or
//! implausible) increment and retries it, a converged sub-increment lets the next one grow
//! again (doubled), and the step fails at its next failure after `max_cutbacks` of them —
//! counted over the step, so that a load the model cannot carry is not crept up to by ever
//! smaller increments that each pass the plausibility bounds (tests/locking.rs: the
//! overloaded locking cylinder).
use crate::common;

use asperity::Error;
use common::{CaseBuilder, elastic, model, rectangle, settings};

/// The plate [0, 2] × [0, 1] of one cell (plane strain, E = 1000 MPa, ν = 0.3) on rollers at
/// its left and bottom edges, its top edge moved down by 0.01 in one step: a uniform strain
/// ε_yy = −0.01, ε_xx = ν/(1 − ν) · 0.01 (σ_xx = 0), ε_zz = 0, whose equivalent strain
/// √(⅔ ε:ε) is 8.883e-3. With `max_strain_increment` at 0.3 of that, an increment of a
/// quarter of the step is plausible and one of half the step is not: 1 → ½ → ¼ converges,
/// then twice ½ → ¼, then the last quarter (½ ends on the step's end): four cut-backs.
fn pressed_plate(max_cutbacks: i64) -> CaseBuilder {
    let nu: f64 = 0.3;
    let (eyy, exx) = (0.01, nu / (1.0 - nu) * 0.01);
    let equivalent = (2.0 / 3.0 * (eyy * eyy + exx * exx)).sqrt();
    CaseBuilder::plane_strain()
        .body("body", elastic(1000.0, nu))
        .support("s0", &[("ux", 0.0)])
        .support("t0", &[("uy", 0.0)])
        .support("t1", &[("uy", -0.01)])
        .steps(1)
        .set("solver", "max_strain_increment", 0.3 * equivalent)
        .set("solver", "max_cutbacks", max_cutbacks)
}

#[test]
fn a_step_may_make_max_cutbacks_cut_backs_in_all() {
    let case = pressed_plate(4).case();
    let built = model(rectangle(2.0, 1.0, 1, 1, 0.0, false), &case).unwrap();
    let (solution, stats) =
        asperity::solver::stepping::run_steps(&built, &settings(&case), |_| Ok(0.0))
            .expect("four cut-backs are allowed");
    assert_eq!(stats.work.increments, 4);
    assert_eq!((stats.cutbacks, stats.increments), (4, 8));
    let top = (0..built.mesh.nodes.len())
        .find(|&n| built.mesh.nodes[n][1] == 1.0)
        .unwrap();
    assert!((solution.u[2 * top + 1] + 0.01).abs() < 1e-15);
}

#[test]
fn the_failure_after_max_cutbacks_cut_backs_ends_the_step() {
    // Three allowed: the fourth failure (the third half step) ends it, although each
    // quarter converged.
    let case = pressed_plate(3).case();
    let built = model(rectangle(2.0, 1.0, 1, 1, 0.0, false), &case).unwrap();
    let error = asperity::solver::stepping::run_steps(&built, &settings(&case), |_| Ok(0.0))
        .expect_err("a fourth cut-back is not allowed");
    let text = error.to_string();
    assert!(
        matches!(&error, Error::NoConvergence(n) if n.cutbacks == 3),
        "{text}"
    );
    assert!(
        text.contains("did not converge after 3 cut-backs in the step"),
        "{text}"
    );
}
