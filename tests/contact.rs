//! Interface elements and the linear Coulomb law against closed-form references
//! (../shared/REFERENCES.md §1, §3): shrink fit (both mesh recipes), frictionless flat
//! punch (Sneddon), Newton-Cotes against Gauss, a block sticking and sliding, opening, and
//! Newton's convergence.
mod common;

use asperity::mesh::Mesh;
use asperity::model::Model;
use asperity::post::interface::{InterfaceOutput, resultants};
use asperity::solver::stepping::Solution;
use common::*;

const E: f64 = 200_000.0;
const NU: f64 = 0.3;

/// Nodal contact pressure (−p_N) along the first pair.
fn pressures(model: &Model, solution: &Solution) -> Vec<f64> {
    let out = InterfaceOutput::new(model);
    out.nodal(model, &solution.interface_committed)[0]
        .iter()
        .map(|n| n.values[1])
        .collect()
}

mod shrink_fit {
    use super::*;

    const B: f64 = 10.0;
    const C: f64 = 20.0;
    const L: f64 = 10.0;
    const DELTA: f64 = 0.01;

    /// Plane-strain compliance C = b (C_s + C_h) of a solid shaft in a hub (REFERENCES §1).
    fn compliance() -> f64 {
        let (e, nu) = (E / (1.0 - NU * NU), NU / (1.0 - NU));
        let cs = (1.0 - nu) / e;
        let ch = ((C * C + B * B) / (C * C - B * B) + nu) / e;
        B * (cs + ch)
    }

    fn bodies(conforming: bool) -> Mesh {
        let zs = uniform(0.0, L, 4);
        let mut shaft = tensor(&uniform(0.0, B, 6), &zs, "shaft");
        add_curve_group(&mut shaft, "shaft_ends", |x| x[1] == 0.0 || x[1] == L);
        let mut hub = tensor(&uniform(B, C, 6), &zs, "hub");
        add_curve_group(&mut hub, "hub_ends", |x| x[1] == 0.0 || x[1] == L);
        if conforming {
            add_curve_group(&mut shaft, "fit", |x| (x[0] - B).abs() < 1e-12);
        } else {
            add_curve_group(&mut shaft, "shaft_outer", |x| (x[0] - B).abs() < 1e-12);
            add_curve_group(&mut hub, "hub_bore", |x| (x[0] - B).abs() < 1e-12);
        }
        merge(shaft, hub, conforming)
    }

    fn text(pairing: &str, k_n: f64) -> String {
        format!(
            r#"[analysis]
            type = "axisymmetric"
            [[body]]
            group = "shaft"
            material = {{ E = {E}, nu = {NU} }}
            [[body]]
            group = "hub"
            material = {{ E = {E}, nu = {NU} }}
            [[support]]
            group = "shaft_ends"
            uz = 0.0
            [[support]]
            group = "hub_ends"
            uz = 0.0
            [[contact]]
            {pairing}
            interference = {DELTA}
            law = {{ type = "linear_coulomb", normal_stiffness = {k_n}, tangential_stiffness = {k_n}, friction = 0.2 }}
            "#
        )
    }

    fn check(conforming: bool, k_n: f64) {
        let pairing = if conforming {
            "curve = \"fit\"\nbody_a = \"shaft\"\nbody_b = \"hub\""
        } else {
            "side_a = \"shaft_outer\"\nside_b = \"hub_bore\""
        };
        let (model, solution) = solve(bodies(conforming), &case(&text(pairing, k_n)));
        let lame = DELTA / compliance();
        let expected = DELTA / (compliance() + 1.0 / k_n);
        let p = pressures(&model, &solution);
        let worst = p
            .iter()
            .map(|v| (v - expected).abs() / expected)
            .fold(0.0, f64::max);
        println!(
            "recipe {}, k_N = {k_n:e}: Lamé p = {lame:.5}, spring-modified {expected:.5}, FE {:.5}..{:.5} (max rel. error {worst:.2e})",
            if conforming {
                "(b) split"
            } else {
                "(a) coincident"
            },
            p.iter().cloned().fold(f64::INFINITY, f64::min),
            p.iter().cloned().fold(0.0, f64::max)
        );
        // Mesh: 6 quad8 through each wall; the Lamé displacement error at that density is
        // ~2e-5 (tests/lame.rs), so 1e-3 bounds real defects only.
        assert!(worst < 1e-3, "contact pressure off by {worst}");
        // Radial interface forces sum to 2π b L p (the resultant of p_N over the interface).
        let r = resultants(&model, &solution.interface_committed)[0];
        let total = 2.0 * std::f64::consts::PI * B * L * expected;
        assert!(
            (r[0] + total).abs() < 1e-3 * total,
            "normal resultant {} vs −{total}",
            r[0]
        );
        assert!(r[1].abs() < 1e-6 * total, "no shear expected: {}", r[1]);
    }

    #[test]
    fn coincident_recipe_matches_lame_for_a_stiff_interface() {
        check(false, 1e9);
    }

    #[test]
    fn split_recipe_matches_lame_for_a_stiff_interface() {
        check(true, 1e9);
    }

    #[test]
    fn finite_normal_stiffness_matches_the_spring_modified_formula() {
        check(false, 1e4);
        check(true, 2e3);
    }
}
