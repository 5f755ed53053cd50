//! Bending in plane stress: a cantilever under a uniform shear end load against
//! Timoshenko beam theory, δ = PL³/(3EI) + PL/(κGA), κ = 5/6.
use crate::common;

use common::*;

#[test]
fn cantilever_tip_deflection_matches_beam_theory() {
    let (l, h, t, e, nu, tau): (f64, f64, f64, f64, f64, f64) =
        (100.0, 10.0, 5.0, 210_000.0, 0.3, 2.0);
    let case = CaseBuilder::plane_stress(t)
        .body("body", elastic(e, nu))
        .support("s0", &[("ux", 0.0), ("uy", 0.0)])
        .traction("s1", [0.0, -tau])
        .case();
    let p = tau * h * t;
    let i = t * h.powi(3) / 12.0;
    let g = e / (2.0 * (1.0 + nu));
    let beam = p * l.powi(3) / (3.0 * e * i) + p * l / (5.0 / 6.0 * g * h * t);
    let (model, solution) = solve(rectangle(l, h, 20, 4, 0.0, false), &case);
    let tip: Vec<f64> = (0..model.mesh.nodes.len())
        .filter(|&n| (model.mesh.nodes[n][0] - l).abs() < 1e-9)
        .map(|n| displacement(&solution, n)[1])
        .collect();
    let mean = tip.iter().sum::<f64>() / tip.len() as f64;
    let rel = (-mean - beam).abs() / beam;
    println!(
        "tip deflection {:.6} mm, Timoshenko beam {beam:.6} mm, relative difference {rel:.2e}",
        -mean
    );
    // The clamp also restrains the Poisson contraction at x = 0 and the end load is uniform
    // rather than parabolic: both are O((h/L)²) ≈ 1 % effects on the deflection.
    assert!(rel < 0.015, "tip deflection off beam theory by {rel}");
    // Equilibrium: the support reaction balances the end load exactly.
    let r = asperity::post::reactions(
        &model,
        &internal_force(&model, &solution),
        &external_force(&model),
    );
    assert!(
        (r[0][1] - p).abs() < 1e-9 * p,
        "reaction {:?} vs load {p}",
        r[0]
    );
}

/// Internal forces of the converged solution (reassembled).
fn internal_force(
    model: &asperity::model::Model,
    solution: &asperity::solver::state::Solution,
) -> Vec<f64> {
    let mut system =
        asperity::assembly::GlobalSystem::new(model.pattern.clone(), model.dofs.dof_count());
    let mut trial = solution.trial.clone();
    let input = asperity::assembly::AssemblyInput {
        dofs: &model.dofs,
        u: &solution.u,
        tangent: false,
        algorithm: Default::default(),
    };
    let (set, coloring) = (&model.continuum, &model.continuum_coloring);
    system.assemble(&input, set, coloring, &solution.committed, &mut trial);
    system.internal_force
}

/// External forces at the end of the single step.
fn external_force(model: &asperity::model::Model) -> Vec<f64> {
    let mut f = vec![0.0; model.dofs.dof_count()];
    model.external_force(1.0, &mut f);
    f
}
