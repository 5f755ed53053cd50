//! The condensed path keeps a plastic bulk's factor while the tangent changes little (a chord
//! step, the condensed solver's reuse threshold τ = 0.01), and stops keeping it for the rest of an increment
//! once a chord step fails to contract: the change measure, relative to the diagonal, can
//! understate the chord rate by orders of magnitude.

use crate::common;

use common::*;

#[test]
fn a_chord_step_that_does_not_contract_ends_the_reuse_of_the_factor() {
    let (condensed, stats) = solve_two_blocks(incompressible_plastic_blocks("condensed"));
    let (krylov, krylov_stats) = solve_two_blocks(incompressible_plastic_blocks("krylov"));
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
    let (difference, scale) = largest_difference(&condensed.u, &krylov.u);
    assert!(difference < 1e-6 * scale, "{difference:e} of {scale:e}");
    // The factor was still kept where a chord step contracted.
    let work = &stats.work.solver;
    assert!(work.kept_factorisations.calls > 0, "{work:?}");
}
