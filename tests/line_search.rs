//! Newton line-searches its corrections while the relative residual is above 1e-3, and, once
//! the residual has risen at an iteration of an increment, every later correction of that
//! increment: a full step that would rise again is shortened. Plain Newton iterations on a
//! frictional joint otherwise fall into cycles, the friction statuses flipping back and forth
//! between two iterates whose residuals straddle 1e-3.

use crate::common;

use common::*;

/// The two blocks pressed and sheared ([`plastic_blocks_pressed_and_sheared`]), the lower one
/// yielding almost at once (σ_Y = 1e-3 MPa, H = 100 MPa), solved on `linear_solver`'s path.
fn blocks_yielding_at_once(linear_solver: &str) -> CaseBuilder {
    let lower = with_keys(
        block_material(),
        &[("yield_stress", 1e-3), ("hardening", 100.0)],
    );
    two_blocks_on(lower, 0.2)
        .support("lid", &[("ux", 0.01), ("uy", -0.006)])
        .step_factors(&[0.25, 0.5, 0.75, 1.0])
        .set("solver", "linear_solver", linear_solver)
}

#[test]
fn a_newton_cycle_on_a_frictional_joint_is_broken_by_the_line_search() {
    // The Krylov path makes plain Newton iterations (no interface iterations). Full steps
    // below a residual of 1e-3 took it through 229 iterations and 8 cut-backs here (at
    // σ_Y = 1e-9 the cycle never ended and the run failed); now 16, as few as the condensed
    // path's interface iterations need within a factor of three.
    let (krylov, stats) = solve_two_blocks(blocks_yielding_at_once("krylov"));
    let (condensed, condensed_stats) = solve_two_blocks(blocks_yielding_at_once("condensed"));
    assert_eq!(stats.cutbacks, 0, "{stats:?}");
    assert!(
        stats.iterations <= 3 * condensed_stats.iterations,
        "Krylov {} iterations, condensed {}",
        stats.iterations,
        condensed_stats.iterations
    );
    let (difference, scale) = largest_difference(&krylov.u, &condensed.u);
    assert!(difference < 1e-6 * scale, "{difference:e} of {scale:e}");
}
