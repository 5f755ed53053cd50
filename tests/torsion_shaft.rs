//! Elastic torsion of a hollow shaft a ≤ r ≤ b, length L, base held, twisted at the top by a
//! torque T (`[[load]] torque`) or by a prescribed rotation φ (`[[support]] rotation`), in an
//! axisymmetric analysis with twist. The exact solution (Saint-Venant torsion of a circular
//! tube; Timoshenko & Goodier, *Theory of Elasticity*, §104) is u_θ = T z r / (G J),
//! τ_zθ = T r / J with J = π (b⁴ − a⁴) / 2, and the twist of the top φ = T L / (G J); all
//! other stresses vanish. u_θ is bilinear in (r, z) and τ_zθ linear in r, both inside the
//! quadratic elements' space, and the torque load's traction t_θ ∝ r is the exact one, so
//! the finite-element solution is exact up to round-off: the tolerances below (1e-8 relative)
//! only leave room for the linear solve and the nodal recovery's arithmetic.

use crate::common;

use asperity::material::Z_THETA;
use asperity::model::Model;
use asperity::post::{BodyPoints, nodal_values, reaction_torques, reactions};
use asperity::solver::stepping::run_steps;
use common::*;
use toml::Value;

const A: f64 = 5.0;
const B: f64 = 10.0;
const L: f64 = 20.0;
const E: f64 = 200_000.0;
const NU: f64 = 0.3;
/// N·mm: τ_zθ at the outside T b / J ≈ 68 MPa.
const T: f64 = 1.0e5;

fn shear_modulus() -> f64 {
    E / (2.0 * (1.0 + NU))
}

fn polar_moment() -> f64 {
    std::f64::consts::PI * (B.powi(4) - A.powi(4)) / 2.0
}

/// The tube's mesh: 4 × 8 quad8 (groups "tube", "base" at z = 0, "top" at z = L).
fn tube() -> asperity::mesh::Mesh {
    let mut mesh = tensor(&uniform(A, B, 4), &uniform(0.0, L, 8), "tube");
    add_curve_group(&mut mesh, "base", |x| x[1].abs() < 1e-9);
    add_curve_group(&mut mesh, "top", |x| (x[1] - L).abs() < 1e-9);
    mesh
}

fn twisted() -> CaseBuilder {
    CaseBuilder::axisymmetric()
        .set("analysis", "twist", true)
        .body("tube", elastic(E, NU))
        .support("base", &[("uz", 0.0), ("utheta", 0.0)])
}

/// What the tests read of the last step: the nodal u_θ, the reaction torques and forces of
/// the supports, and the nodal τ_zθ with each output point's mesh node.
struct Result {
    model: Model,
    u: Vec<f64>,
    torques: Vec<f64>,
    forces: Vec<[f64; 2]>,
    shear: Vec<(u32, f64)>,
}

fn solve_twisted(case: CaseBuilder) -> Result {
    let case = case.case();
    let model = model(tube(), &case).expect("the tube's model builds");
    let mut reactions_last = (Vec::new(), Vec::new());
    let (solution, _) = run_steps(&model, &settings(&case), |step| {
        reactions_last = (
            reaction_torques(&model, step.internal_force, step.external_force),
            reactions(&model, step.internal_force, step.external_force),
        );
        Ok(0.0)
    })
    .expect("the tube solves");
    let points = BodyPoints::new(&model);
    let nodal = nodal_values(&model, &points, solution.point_states());
    let shear = points
        .points
        .iter()
        .zip(&nodal)
        .map(|(&(_, n), v)| (n, v.stress[Z_THETA]))
        .collect();
    Result {
        u: solution.u.clone(),
        torques: reactions_last.0,
        forces: reactions_last.1,
        shear,
        model,
    }
}

/// Checks the exact torsion field of torque `torque` in `r`.
fn assert_exact_torsion(r: &Result, torque: f64) {
    let (g, j) = (shear_modulus(), polar_moment());
    let scale_u = torque * L * B / (g * j);
    for (n, x) in r.model.mesh.nodes.iter().enumerate() {
        let expected = torque * x[1] * x[0] / (g * j);
        let [ur, uz, ut] = [0, 1, 2].map(|c| r.u[3 * n + c]);
        assert!(
            (ut - expected).abs() <= 1e-8 * scale_u,
            "u_θ at {x:?}: {ut} against {expected}"
        );
        assert!(
            ur.abs().max(uz.abs()) <= 1e-12 * scale_u,
            "u_r, u_z at {x:?}"
        );
    }
    let scale_tau = torque * B / j;
    for &(n, tau) in &r.shear {
        let radius = r.model.mesh.nodes[n as usize][0];
        let expected = torque * radius / j;
        assert!(
            (tau - expected).abs() <= 1e-8 * scale_tau,
            "τ_zθ at r = {radius}: {tau} against {expected}"
        );
    }
}

#[test]
fn a_torque_twists_the_tube_as_saint_venant_torsion_and_the_base_reacts_with_minus_t() {
    let r = solve_twisted(twisted().push(
        "load",
        table(&[("group", "top".into()), ("torque", T.into())]),
    ));
    assert_exact_torsion(&r, T);
    // Supports: "base", then the automatic axis support (no node on the axis here).
    let base = 0;
    assert!(
        (r.torques[base] + T).abs() <= 1e-9 * T,
        "reaction torque of the base {} against −T = {}",
        r.torques[base],
        -T
    );
    // Pure torsion carries no axial force.
    assert!(
        r.forces[base][1].abs() <= 1e-9 * T / B,
        "{:?}",
        r.forces[base]
    );
}

#[test]
fn a_prescribed_rotation_of_the_top_gives_the_same_tube_and_opposite_reactions() {
    let phi = T * L / (shear_modulus() * polar_moment());
    let r = solve_twisted(twisted().support("top", &[("rotation", phi)]));
    assert_exact_torsion(&r, T);
    let (base, top) = (0, 1);
    assert!((r.torques[top] - T).abs() <= 1e-8 * T, "{:?}", r.torques);
    assert!((r.torques[base] + T).abs() <= 1e-8 * T, "{:?}", r.torques);
}

#[test]
fn a_circumferential_traction_is_a_torque_of_its_moment() {
    // A uniform t_θ on the top ring has the moment ∫ t_θ r dA = t_θ 2π (b³ − a³) / 3; the
    // reaction of the base balances it exactly (the consistent nodal forces' moment is the
    // traction's, integrated exactly by the 3-point rule).
    let t_theta = 10.0;
    let moment = t_theta * 2.0 * std::f64::consts::PI * (B.powi(3) - A.powi(3)) / 3.0;
    let mut load = table(&[("group", "top".into())]);
    load.insert("traction".into(), list(&[0.0, 0.0, t_theta]));
    let r = solve_twisted(twisted().push("load", load));
    assert!(
        (r.torques[0] + moment).abs() <= 1e-9 * moment,
        "{} against {}",
        r.torques[0],
        -moment
    );
}

#[test]
fn a_circumferential_ring_force_on_a_point_is_a_torque_of_f_theta_times_r() {
    // A ring force F_θ (N, total over the circle) at the top's outer corner r = b: its
    // moment about the axis is F_θ b, which the base reacts exactly.
    let f_theta = 2.0e3;
    let mut mesh = tube();
    add_point_group(&mut mesh, "corner", [B, L]);
    let mut load = table(&[("group", "corner".into())]);
    load.insert("force".into(), list(&[0.0, 0.0, f_theta]));
    let case = twisted().push("load", load).case();
    let model = model(mesh, &case).expect("the tube's model builds");
    let mut torques = Vec::new();
    run_steps(&model, &settings(&case), |step| {
        torques = reaction_torques(&model, step.internal_force, step.external_force);
        Ok(0.0)
    })
    .expect("the tube solves");
    let moment = f_theta * B;
    assert!(
        (torques[0] + moment).abs() <= 1e-9 * moment,
        "{} against {}",
        torques[0],
        -moment
    );
}

#[test]
fn twist_keys_are_refused_without_twist_and_twist_without_an_axis() {
    let message = |builder: CaseBuilder| builder.try_case().unwrap_err().to_string();
    let plain = CaseBuilder::axisymmetric().body("tube", elastic(E, NU));
    for (key, value) in [("utheta", 0.1), ("rotation", 0.01)] {
        let e = message(plain.clone().support("top", &[(key, value)]));
        assert!(
            e.contains(&format!("support[0].{key}")) && e.contains("twist"),
            "{e}"
        );
    }
    let e = message(plain.clone().push(
        "load",
        table(&[("group", "top".into()), ("torque", T.into())]),
    ));
    assert!(e.contains("load[0].torque") && e.contains("twist"), "{e}");
    let mut load = table(&[("group", "top".into())]);
    load.insert("traction".into(), list(&[0.0, 0.0, 1.0]));
    let e = message(plain.clone().push("load", load));
    assert!(e.contains("load[0].traction") && e.contains("twist"), "{e}");
    let e = message(
        CaseBuilder::plane_strain()
            .set("analysis", "twist", true)
            .body("tube", elastic(E, NU)),
    );
    assert!(
        e.contains("analysis.twist") && e.contains("axisymmetric"),
        "{e}"
    );
    let e = message(twisted().support("top", &[("utheta", 0.1), ("rotation", 0.01)]));
    assert!(
        e.contains("support[1].rotation") && e.contains("utheta"),
        "{e}"
    );
}

#[test]
fn a_tube_that_nothing_holds_in_twist_is_refused_as_free_to_turn() {
    let case = CaseBuilder::axisymmetric()
        .set("analysis", "twist", true)
        .body("tube", elastic(E, NU))
        .support("base", &[("uz", 0.0)])
        .push(
            "load",
            table(&[("group", "top".into()), ("torque", Value::from(T))]),
        )
        .case();
    let e = model(tube(), &case).unwrap_err().to_string();
    assert!(
        e.contains("body 'tube' is free to turn about the axis") && e.contains("rotation"),
        "{e}"
    );
}

#[test]
fn an_implausible_twist_names_the_node_that_turned_most() {
    // A rotation φ of the top moves the node at (b, L) by u_θ = φ b = 0.5 mm, and nothing
    // else as far: above 1 % of the model's size, so the increment is implausible, and
    // without cut-backs the step fails naming that node (a node's u_θ is part of its
    // displacement increment; the check once paired a twist model's dofs two by two).
    let phi = 0.05;
    let case = twisted()
        .support("top", &[("rotation", phi)])
        .set("solver", "max_displacement_increment", 0.01)
        .set("solver", "max_cutbacks", 0)
        .case();
    let model = model(tube(), &case).expect("the tube's model builds");
    let error = run_steps(&model, &settings(&case), |_| Ok(0.0))
        .expect_err("the increment is implausible")
        .to_string();
    let corner = (0..model.mesh.nodes.len())
        .find(|&n| {
            let [r, z] = model.mesh.nodes[n];
            (r - B).abs() < 1e-9 && (z - L).abs() < 1e-9
        })
        .expect("the tube has a node at (b, L)");
    let expected = format!(
        "node {} moves by {:.3e} mm",
        model.mesh.node_tags[corner],
        phi * B
    );
    assert!(error.contains(&expected), "{expected} not in: {error}");
}
