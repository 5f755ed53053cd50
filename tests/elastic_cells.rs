//! A plastic body's cells that provably stay elastic are left out of the Newton iterations
//! (`solver::elastic_cells`): the answer is that of evaluating every cell at every iteration
//! (the Krylov path, which evaluates all of them), the committed point states are those of
//! the converged displacements (the left-out cells' states are made once per increment).

use crate::common;

use common::*;

fn largest(values: impl Iterator<Item = f64>) -> f64 {
    values.fold(0.0, |m, v| m.max(v.abs()))
}

#[test]
fn elastic_cells_left_out_of_the_iterations_give_the_answer_of_evaluating_them() {
    let (condensed, stats) = solve_two_blocks(plastic_blocks_pressed_and_sheared("condensed"));
    let (krylov, krylov_stats) = solve_two_blocks(plastic_blocks_pressed_and_sheared("krylov"));
    // Cells were left out: a plastic bulk's converged increment then makes their states
    // (one state evaluation per increment that left any out); the Krylov path evaluates
    // every cell at every iteration and needs none.
    let work = &stats.work.solver;
    assert!(
        work.state_evaluations.calls >= 2,
        "no cells left out: {work:?}"
    );
    assert_eq!(krylov_stats.work.solver.state_evaluations.calls, 0);
    // Part of the lower block yielded, and most of its points did not.
    let plastic = condensed
        .committed
        .iter()
        .filter(|p| p.equivalent_plastic_strain > 0.0)
        .count();
    assert!(plastic > 0, "nothing yielded");
    // Both converge to the Newton tolerance; the plastic increments end at relative
    // residuals up to 4e-7, and the two paths' answers differ by 3.3e-7 of the largest
    // displacement with every cell evaluated too (the binary before this change).
    let scale = largest(krylov.u.iter().copied());
    let difference = largest(condensed.u.iter().zip(&krylov.u).map(|(a, b)| a - b));
    assert!(difference < 1e-6 * scale, "{difference:e} of {scale:e}");
    // The committed states of every point, left out or not, are those at the converged
    // displacements: a stale state (an iteration's) would differ by far more.
    assert_eq!(condensed.committed.len(), krylov.committed.len());
    let stress_scale = largest(krylov.committed.iter().map(|p| p.stress.amax()));
    let stress_difference = largest(
        (condensed.committed.iter())
            .zip(&krylov.committed)
            .map(|(a, b)| (a.stress - b.stress).amax()),
    );
    assert!(
        stress_difference < 1e-5 * stress_scale,
        "stresses {stress_difference:e} of {stress_scale:e}"
    );
    let plastic_scale = largest(krylov.committed.iter().map(|p| p.equivalent_plastic_strain));
    let plastic_difference = largest(
        (condensed.committed.iter())
            .zip(&krylov.committed)
            .map(|(a, b)| a.equivalent_plastic_strain - b.equivalent_plastic_strain),
    );
    assert!(
        plastic_difference < 1e-5 * plastic_scale,
        "plastic strains {plastic_difference:e} of {plastic_scale:e}"
    );
}
