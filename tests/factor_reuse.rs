//! The condensed path keeps a plastic bulk's factor while the tangent changes little (a chord
//! step, the condensed solver's reuse threshold τ = 0.01), and stops keeping it for the rest of an increment
//! once a chord step fails to contract: the change measure, relative to the diagonal, can
//! understate the chord rate by orders of magnitude.

use crate::common;

use asperity::mesh::msh::read_msh;
use asperity::solver::state::{RunStatistics, Solution};
use asperity::solver::stepping::run_steps;
use common::*;

/// [`incompressible_plastic_blocks`] solved on `linear_solver`'s path.
fn run(linear_solver: &str) -> (Solution, RunStatistics) {
    let case = incompressible_plastic_blocks(linear_solver).case();
    let mesh = read_msh(&fixture("contact_pair.msh")).unwrap();
    let built = model(mesh, &case).unwrap();
    run_steps(&built, &settings(&case), |_| Ok(0.0)).expect("solves")
}

#[test]
fn a_chord_step_that_does_not_contract_ends_the_reuse_of_the_factor() {
    let (condensed, stats) = run("condensed");
    let (krylov, krylov_stats) = run("krylov");
    // Without the contraction check the condensed run kept its factor through 42 of 48
    // iterations, cut its last step back after 25 of them stagnating at a relative residual
    // of 2e-3, and ended 5e-4 away from the Krylov path's answer (its residual just under
    // the tolerance); with it, it needs the Krylov path's 14 iterations.
    assert_eq!(stats.cutbacks, 0, "{stats:?}");
    assert!(
        stats.iterations <= krylov_stats.iterations + 2,
        "condensed {} iterations, Krylov {}",
        stats.iterations,
        krylov_stats.iterations
    );
    let largest = |v: &mut dyn Iterator<Item = f64>| v.fold(0.0_f64, |m, x| m.max(x.abs()));
    let scale = largest(&mut krylov.u.iter().copied());
    let difference = largest(&mut condensed.u.iter().zip(&krylov.u).map(|(a, b)| a - b));
    assert!(difference < 1e-6 * scale, "{difference:e} of {scale:e}");
    // The factor was still kept where a chord step contracted.
    let work = &stats.work.solver;
    assert!(work.kept_factorisations.calls > 0, "{work:?}");
}
