//! Reissner–Sagoci: a rigid circular punch of radius a bonded to an elastic half-space and
//! turned by φ about its axis (Reissner & Sagoci, J. Appl. Phys. 15, 1944; Johnson, *Contact
//! Mechanics*, 1985, §3.10). The torque is T = 16 G a³ φ / 3 and the shear traction under the
//! punch τ_zθ(r) = (4 G φ / π) r / √(a² − r²), singular at the edge r = a.
//!
//! The half-space is the cylinder 0 ≤ r ≤ R, −H ≤ z ≤ 0 with R = H = 20 a, its bottom held
//! (u_z = u_θ = 0) and its side free; the punch is `rotation = φ` on the face r ≤ a, z = 0
//! (u_θ = φ r: bonded, turning rigidly). The mesh is graded geometrically towards the edge of
//! the punch in r and towards the surface in z.
//!
//! Why the tolerances: holding the bottom at depth H stiffens the half-space by a relative
//! O((a/H)³) ≈ 1e-4; the edge singularity τ ∝ (a − r)^(−1/2) is what limits the torque's
//! accuracy, to the order of the smallest elements at the edge relative to a (measured
//! +0.51 % on this mesh): 1 % is allowed. The traction is compared at 0.1 a ≤ r ≤ 0.7 a,
//! away from the edge, where the nodal values recovered from the Gauss points are within
//! 0.35 % (measured): 1 % is allowed.

use crate::common;

use asperity::material::Z_THETA;
use asperity::post::{BodyPoints, nodal_values, reaction_torques};
use asperity::solver::stepping::run_steps;
use common::*;

const A: f64 = 1.0;
const R: f64 = 20.0 * A;
const H: f64 = 20.0 * A;
const E: f64 = 1000.0;
const NU: f64 = 0.3;
const PHI: f64 = 0.01;

/// Points from `from` to `to` with `n` intervals shrinking geometrically (by `ratio` each)
/// towards `to`.
fn towards(from: f64, to: f64, n: usize, ratio: f64) -> Vec<f64> {
    let mut v: Vec<f64> = graded(0.0, to - from, n, 1.0 / ratio)
        .iter()
        .map(|s| from + s)
        .collect();
    v[n] = to;
    v
}

#[test]
fn a_bonded_punch_turned_by_phi_carries_reissner_sagoci_torque_and_shear() {
    let g = E / (2.0 * (1.0 + NU));
    // r: graded towards the punch's edge from both sides; z: towards the surface.
    let mut xs = towards(0.0, A, 14, 1.3);
    let outside = towards(R, A, 18, 1.35);
    xs.extend(outside.iter().rev().skip(1));
    let ys = towards(-H, 0.0, 22, 1.35);
    let mut mesh = tensor(&xs, &ys, "half_space");
    add_curve_group(&mut mesh, "punch", |x| {
        x[1].abs() < 1e-12 && x[0] <= A + 1e-12
    });
    add_curve_group(&mut mesh, "bottom", |x| (x[1] + H).abs() < 1e-12);
    let case = CaseBuilder::axisymmetric()
        .set("analysis", "twist", true)
        .body("half_space", elastic(E, NU))
        .support("punch", &[("rotation", PHI)])
        .support("bottom", &[("uz", 0.0), ("utheta", 0.0)])
        .case();
    let model = model(mesh, &case).expect("the half-space's model builds");
    let mut torque = 0.0;
    let (solution, _) = run_steps(&model, &settings(&case), |step| {
        torque = reaction_torques(&model, step.internal_force, step.external_force)[0];
        Ok(0.0)
    })
    .expect("the punch turns");

    let exact = 16.0 * g * A.powi(3) * PHI / 3.0;
    assert!(
        (torque - exact).abs() <= 0.01 * exact,
        "T = {torque:.6e} against 16 G a³ φ / 3 = {exact:.6e} ({:+.3} %)",
        100.0 * (torque / exact - 1.0)
    );

    let points = BodyPoints::new(&model);
    let nodal = nodal_values(&model, &points, solution.point_states());
    let scale = 4.0 * g * PHI / std::f64::consts::PI;
    let mut checked = 0;
    for (&(_, n), v) in points.points.iter().zip(&nodal) {
        let [r, z] = model.mesh.nodes[n as usize];
        if z.abs() > 1e-12 || !(0.1 * A..=0.7 * A).contains(&r) {
            continue;
        }
        let expected = scale * r / (A * A - r * r).sqrt();
        let tau = v.stress[Z_THETA];
        assert!(
            (tau - expected).abs() <= 0.01 * expected,
            "τ_zθ at r = {r:.4}: {tau:.5e} against {expected:.5e} ({:+.2} %)",
            100.0 * (tau / expected - 1.0)
        );
        checked += 1;
    }
    assert!(
        checked >= 5,
        "{checked} surface nodes under the punch checked"
    );
}
