//! Newton's convergence with the algorithmically consistent tangent of Armstrong–Frederick
//! kinematic hardening under non-proportional flow (issue 27): a square block (plane strain,
//! base held) whose top is pulled and then sheared 90° out of phase, so that the strain path
//! is a circle and the flow direction turns continuously against the backstress. With
//! γ > 0 the exact tangent is unsymmetric there; the bodies' solver factors it by LU
//! (src/solver/linear.rs), so Newton converges quadratically. Measured with the symmetric
//! part of the tangent (before the LU path): median terminal order 1.02, i.e. linear.
use crate::common;

use asperity::solver::stepping::run_steps;
use common::*;
use toml::Value;

/// Increments of the ramp and of the circle.
const RAMP: usize = 4;
const CIRCLE: usize = 24;

/// The terminal order log(r₃/r₂)/log(r₂/r₁) of a residual sequence over its last three
/// residuals above `floor` (the relative residual double precision reaches on this model is
/// ~1e-15), when they still fall.
fn terminal_order(residuals: &[f64], floor: f64) -> Option<f64> {
    let above: Vec<f64> = residuals.iter().copied().filter(|&r| r > floor).collect();
    let [a, b, c] = above.get(above.len().checked_sub(3)?..)?.try_into().ok()?;
    (a > b && b > c).then(|| (c / b).ln() / (b / a).ln())
}

#[test]
fn newton_is_quadratic_under_non_proportional_armstrong_frederick_flow() {
    let mut mesh = tensor(&uniform(0.0, 1.0, 4), &uniform(0.0, 1.0, 4), "block");
    add_curve_group(&mut mesh, "bottom", |x| x[1] == 0.0);
    add_curve_group(&mut mesh, "top", |x| x[1] == 1.0);
    let mut material = with_keys(elastic(200_000.0, 0.3), &[("yield_stress", 250.0)]);
    let term = table(&[("C", 60_000.0.into()), ("gamma", 300.0.into())]);
    material.insert("kinematic".into(), Value::Array(vec![Value::Table(term)]));
    let angle = |k: usize| 2.0 * std::f64::consts::PI * k as f64 / CIRCLE as f64;
    let ramp = (1..=RAMP).map(|k| k as f64 / RAMP as f64);
    let pull: Vec<f64> = ramp.chain((1..=CIRCLE).map(|k| angle(k).cos())).collect();
    let shear: Vec<f64> = (0..RAMP)
        .map(|_| 0.0)
        .chain((1..=CIRCLE).map(|k| angle(k).sin()))
        .collect();
    let case = CaseBuilder::plane_strain()
        .body("block", material)
        .support("bottom", &[("ux", 0.0), ("uy", 0.0)])
        .support_history("top", &[("ux", 0.006)], &shear)
        .support_history("top", &[("uy", 0.004)], &pull)
        .steps((RAMP + CIRCLE) as i64)
        .set("solver", "residual_tolerance", 1e-14)
        .set("solver", "correction_tolerance", 1e-14)
        .set("solver", "linear_residual_tolerance", 1e-14)
        .set("solver", "max_iterations", 40)
        .case();
    let model = model(mesh, &case).unwrap();
    let mut orders = Vec::new();
    let mut circle_steps = 0;
    run_steps(&model, &settings(&case), |step| {
        circle_steps += usize::from(step.step > RAMP);
        let yielding = step.solution.point_states().iter().any(|s| s.yielding);
        let residuals = &step.newton.residuals;
        if step.step > RAMP
            && yielding
            && let Some(order) = terminal_order(residuals, 1e-12)
        {
            let shown: Vec<String> = residuals.iter().map(|r| format!("{r:.1e}")).collect();
            println!("{}: terminal order {order:.2}", shown.join(" "));
            orders.push(order);
        }
        Ok(0.0)
    })
    .unwrap();
    orders.sort_by(f64::total_cmp);
    let median = orders[orders.len() / 2];
    println!(
        "{} of {circle_steps} circle increments measured: median order {median:.2}, lowest {:.2}",
        orders.len(),
        orders[0]
    );
    // Quadratic convergence has order 2 (rounding near the floor scatters single values);
    // the symmetric part of the tangent gave 1.02 on this path.
    assert!(
        orders.len() >= CIRCLE / 2,
        "too few plastic increments measured"
    );
    assert!(median >= 1.8, "median terminal order {median:.2}");
}
