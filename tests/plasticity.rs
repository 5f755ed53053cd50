//! J2 plasticity of the bodies in whole models (Hill 1950; docs/theory.md, closed forms): a thick
//! cylinder under internal pressure in plane strain, elastic-perfectly plastic, driven by the
//! bore displacement: onset of yield at the closed-form pressure, the pressure-displacement
//! curve flattening at the collapse pressure p_L = (2/√3) σ_Y ln(c/b), and Newton's
//! convergence on plastic steps.
use crate::common;

use asperity::Error;
use asperity::model::ModelSpec;
use asperity::post::reactions;
use asperity::solver::stepping::run_steps;
use common::*;

const B: f64 = 10.0;
const C: f64 = 20.0;
const H: f64 = 1.0;
const E: f64 = 200_000.0;
const NU: f64 = 0.3;
const SY: f64 = 240.0;

/// Von Mises stress at the bore per unit internal pressure (Lamé, plane strain).
fn bore_von_mises_per_pressure() -> f64 {
    let (sr, st) = (-1.0, (C * C + B * B) / (C * C - B * B));
    let sz = NU * (sr + st);
    (0.5 * ((sr - st).powi(2) + (st - sz).powi(2) + (sz - sr).powi(2))).sqrt()
}

#[test]
fn thick_cylinder_yields_at_the_closed_form_pressure_and_collapses_at_p_l() {
    let p_e = SY / bore_von_mises_per_pressure();
    let p_l = 2.0 / 3f64.sqrt() * SY * (C / B).ln();
    // Elastic bore displacement at p_e (plane-strain Lamé) sets the scale of the drive.
    let u_e = p_e * B * B * (1.0 + NU) * ((1.0 - 2.0 * NU) * B + C * C / B) / (E * (C * C - B * B));
    // Fine steps through the onset, then on to 25 u_e.
    let mut factors: Vec<f64> = (1..=24).map(|i| 0.9 + 0.2 * i as f64 / 24.0).collect();
    factors.extend((1..=24).map(|i| 1.1 + 23.9 * (i as f64 / 24.0).powi(2)));
    let mut xs = graded(B, C - B, 32, 1.05);
    *xs.last_mut().unwrap() = C;
    let mut mesh = tensor(&xs, &uniform(0.0, H, 1), "wall");
    add_curve_group(&mut mesh, "bore", |x| (x[0] - B).abs() < 1e-12);
    add_curve_group(&mut mesh, "ends", |x| x[1] == 0.0 || x[1] == H);
    let mut material = elastic(E, NU);
    material.insert("yield_stress".into(), SY.into());
    let case = CaseBuilder::axisymmetric()
        .body("wall", material)
        .support("ends", &[("uz", 0.0)])
        .support("bore", &[("ur", u_e)])
        .step_factors(&factors)
        // From the converged state, not extrapolated: an extrapolated start converges the
        // plastic steps before three iterations can measure the order.
        .set("solver", "extrapolate", false)
        .case();
    let model = model(mesh, &case).unwrap();
    let mut curve = Vec::new();
    let mut orders = Vec::new();
    let mut external = vec![0.0; model.dofs.dof_count()];
    model.external_force(0.0, &mut external);
    run_steps(&model, &settings(&case), |step| {
        let r = reactions(&model, step.internal_force, &external)[1];
        let p = r[0] / (2.0 * std::f64::consts::PI * B * H);
        let yielding = step.solution.point_states().iter().any(|s| s.yielding);
        curve.push((step.load_factor, p, yielding));
        let res = &step.newton.residuals;
        // Order of the last iteration that is still above the round-off floor (a relative
        // residual of ~1e-13 is as far as double precision gets on this system).
        let above: Vec<f64> = res.iter().copied().filter(|&r| r > 1e-11).collect();
        if yielding && above.len() >= 3 && above.len() < res.len() {
            let k = above.len() - 1;
            orders.push((res.clone(), above[k].ln() / above[k - 1].ln()));
        }
        Ok(0.0)
    })
    .unwrap();
    // Onset: the last elastic and first plastic step bracket p_e (the first integration
    // point lies 0.11 h inside the bore, where the stress is lower by ~1 %).
    let first = curve.iter().position(|c| c.2).expect("the cylinder yields");
    let (before, after) = (curve[first - 1].1, curve[first].1);
    println!(
        "onset of yield between p = {before:.2} and {after:.2} MPa; closed form p_e = {p_e:.2} MPa"
    );
    assert!(
        before <= p_e * 1.02 && after >= p_e * 0.98,
        "onset bracket [{before}, {after}] vs {p_e}"
    );
    // Collapse: the maximum pressure reached approaches p_L.
    let p_max = curve.iter().map(|c| c.1).fold(0.0, f64::max);
    let last = curve.last().unwrap();
    println!(
        "collapse: max p = {p_max:.2} MPa at u_a up to {:.1} u_e (last {:.2}); p_L = {p_l:.2} MPa ({:+.2} %)",
        last.0,
        last.1,
        100.0 * (p_max - p_l) / p_l
    );
    assert!(
        (p_max - p_l).abs() < 0.02 * p_l,
        "limit pressure {p_max} vs {p_l}"
    );
    // The curve has flattened: the last quarter of the drive adds less than 0.5 % pressure.
    let q = curve[curve.len() * 3 / 4].1;
    assert!((last.1 - q) / q < 0.005, "not flattened: {q} → {}", last.1);
    // Quadratic convergence on plastic steps.
    for (res, order) in orders.iter().take(3) {
        println!("plastic step residuals {res:?}: last order {order:.2}");
    }
    let worst = orders.iter().map(|(_, o)| *o).fold(f64::INFINITY, f64::min);
    println!(
        "{} plastic steps, worst observed order {worst:.2}",
        orders.len()
    );
    assert!(
        orders.len() > 10 && worst > 1.6,
        "plastic Newton steps should converge quadratically (worst order {worst})"
    );
}

#[test]
fn bad_plastic_parameters_are_rejected_with_their_names() {
    for (parameters, key) in [
        (
            &[("yield_stress", -5.0)][..],
            "body[0].material.yield_stress",
        ),
        (
            &[("yield_stress", 5.0), ("hardening", -2000.0)][..],
            "body[0].material.hardening",
        ),
        (&[("hardening", 10.0)][..], "body[0].material.hardening"),
    ] {
        let mut material = elastic(1000.0, 0.3);
        for (k, v) in parameters {
            material.insert(k.to_string(), (*v).into());
        }
        let case = CaseBuilder::plane_strain().body("b", material);
        let e = case
            .try_case()
            .and_then(|case| ModelSpec::new(&case))
            .unwrap_err();
        let Error::InvalidParameter {
            path,
            key: named,
            reason,
            ..
        } = e
        else {
            panic!("{parameters:?}: expected an invalid parameter, got {e}")
        };
        assert_eq!(
            (path.as_path(), named.as_str()),
            (std::path::Path::new("test.toml"), key)
        );
        assert!(reason.contains("'b'"), "{reason}");
    }
}
