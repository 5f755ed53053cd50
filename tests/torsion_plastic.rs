//! Plastic torsion of a solid shaft 0 ≤ r ≤ b (elastic–perfectly plastic J2, yield stress
//! σ_Y in tension, k = σ_Y / √3 in shear), base held, top turned by a prescribed rotation
//! (`[[support]] rotation`) in steps up to 20 times the twist of first yield. The closed form
//! (Hill, *The Mathematical Theory of Plasticity*, 1950, ch. IV; Lubliner, *Plasticity
//! Theory*, §4.2): with the twist per length θ, the elastic core r < r_y = k / (G θ) and
//! plastic annulus τ_zθ = k outside, the torque is T = G J θ while r_y ≥ b, then
//! T = T_p (1 − (r_y / b)³ / 4), approaching the fully plastic T_p = 2π k b³ / 3 from below.
//!
//! Why the tolerance: the displacement of the exact solution u_θ = θ z r lies in the
//! elements' space, and its stress depends on r alone, so it is in equilibrium at every free
//! node; the finite-element torque differs from the closed form only by the Gauss quadrature
//! of ∫ τ(r) 2π r² dr, whose τ(r) has a kink at r_y inside an element (8 elements over the
//! radius): at most 1.8e-4 measured (θ = 1.5 θ_y), exact where r_y falls on an element
//! boundary; 1e-3 is allowed. Above T_p it cannot go: every Gauss point's shear
//! stress is at most k after the return mapping.

use crate::common;

use asperity::post::reaction_torques;
use asperity::solver::stepping::run_steps;
use common::*;

const B: f64 = 10.0;
const L: f64 = 5.0;
const E: f64 = 200_000.0;
const NU: f64 = 0.3;
const YIELD: f64 = 300.0;

#[test]
fn the_torque_of_a_twisted_solid_shaft_follows_the_elastic_plastic_closed_form_up_to_t_p() {
    let g = E / (2.0 * (1.0 + NU));
    let k = YIELD / 3f64.sqrt();
    let j = std::f64::consts::PI * B.powi(4) / 2.0;
    let t_p = 2.0 * std::f64::consts::PI * k * B.powi(3) / 3.0;
    let first_yield = k / (g * B);
    let theta_max = 20.0 * first_yield;
    let factors = [0.025, 0.05, 0.075, 0.1, 0.2, 0.4, 0.7, 1.0];

    let mut mesh = tensor(&uniform(0.0, B, 8), &uniform(0.0, L, 2), "shaft");
    add_curve_group(&mut mesh, "base", |x| x[1].abs() < 1e-9);
    add_curve_group(&mut mesh, "top", |x| (x[1] - L).abs() < 1e-9);
    let material = with_keys(elastic(E, NU), &[("yield_stress", YIELD)]);
    let case = CaseBuilder::axisymmetric()
        .set("analysis", "twist", true)
        .body("shaft", material)
        .support("base", &[("uz", 0.0), ("utheta", 0.0)])
        .support("top", &[("rotation", theta_max * L)])
        .step_factors(&factors)
        .case();
    let model = model(mesh, &case).expect("the shaft's model builds");
    let top = 1;
    let mut torques = Vec::new();
    run_steps(&model, &settings(&case), |step| {
        torques.push(reaction_torques(&model, step.internal_force, step.external_force)[top]);
        Ok(0.0)
    })
    .expect("the shaft twists");

    assert_eq!(torques.len(), factors.len());
    let mut last = 0.0;
    for (&factor, &torque) in factors.iter().zip(&torques) {
        let theta = factor * theta_max;
        let r_y = k / (g * theta);
        let exact = if r_y >= B {
            g * j * theta
        } else {
            t_p * (1.0 - (r_y / B).powi(3) / 4.0)
        };
        assert!(
            (torque - exact).abs() <= 1e-3 * exact,
            "θ = {theta:.3e}: T = {torque:.6e} against {exact:.6e}"
        );
        assert!(
            torque <= t_p * (1.0 + 1e-9),
            "T = {torque} above T_p = {t_p}"
        );
        assert!(torque > last, "the torque rises with the twist");
        last = torque;
    }
    assert!(
        last >= 0.995 * t_p,
        "at 20 × the first-yield twist T = {last:.6e} is near T_p = {t_p:.6e}"
    );
}
