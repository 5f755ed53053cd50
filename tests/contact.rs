//! Interface elements and the linear Coulomb law against closed-form references
//! (docs/theory.md, closed forms): shrink fit (both mesh recipes), frictionless flat
//! punch (Sneddon), Newton-Cotes against Gauss, a block sticking and sliding, opening, and
//! Newton's convergence.
use crate::common;

use asperity::config::Case;
use asperity::mesh::Mesh;
use asperity::model::Model;
use asperity::post::interface::{InterfaceOutput, resultants};
use asperity::solver::newton::NewtonSettings;
use asperity::solver::state::Solution;
use common::shrink_fit::{E, NU};
use common::*;

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
    pub use crate::common::shrink_fit::*;

    fn check(conforming: bool, k_n: f64) {
        let law = linear_coulomb(k_n, k_n, 0.2);
        let (model, solution) = solve(mesh(conforming), &case(conforming, law));
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

mod flat_punch {
    use super::*;

    const A: f64 = 10.0;

    /// A stiff cylindrical punch of radius a on a foundation 20a wide and deep, loaded by a
    /// uniform pressure on its top (axisymmetric, frictionless).
    pub fn model(rule: &str, k_n: f64, n_punch: usize) -> (Model, Solution) {
        let (r_out, depth, h) = (20.0 * A, 20.0 * A, A);
        let mut xs = uniform(0.0, A, n_punch);
        xs.extend(graded(A, r_out - A, 12, 1.35).into_iter().skip(1));
        // Cells shrink towards the contact surface.
        let mut ys = graded(0.0, depth, 14, 0.72);
        *ys.last_mut().unwrap() = depth;
        let mut foundation = tensor(&xs, &ys, "foundation");
        add_curve_group(&mut foundation, "base", |x| x[1] == 0.0);
        add_curve_group(&mut foundation, "surface", |x| {
            (x[1] - depth).abs() < 1e-9 && x[0] <= A + 1e-9
        });
        let mut punch = tensor(
            &uniform(0.0, A, n_punch),
            &uniform(depth, depth + h, 4),
            "punch",
        );
        add_curve_group(&mut punch, "face", |x| (x[1] - depth).abs() < 1e-9);
        add_curve_group(&mut punch, "top", |x| (x[1] - depth - h).abs() < 1e-9);
        let case = CaseBuilder::axisymmetric()
            .body("foundation", elastic(E, NU))
            .body("punch", elastic(1000.0 * E, NU))
            .support("base", &[("uz", 0.0)])
            .pressure("top", 1.0)
            .contact(
                &[
                    ("side_a", "surface".into()),
                    ("side_b", "face".into()),
                    ("integration", rule.into()),
                ],
                linear_coulomb(k_n, 1.0, 0.0),
            )
            .case();
        solve(merge(foundation, punch, false), &case)
    }

    #[test]
    fn pressure_follows_sneddon_inside_r_over_a_0_8() {
        let (model, solution) = model("newton_cotes", 1e3 * E / A, 16);
        let out = InterfaceOutput::new(&model);
        let nodal = &out.nodal(&model, &solution.interface_committed)[0];
        let table = &out.tables(&model, &solution.interface_committed)[0];
        // p_m = P / (π a²) = the applied top pressure (1 MPa).
        let mut checked = 0;
        for (row, n) in table.rows.iter().zip(nodal) {
            let r = row[1] / A;
            if r <= 0.8 + 1e-9 {
                let sneddon = 0.5 / (1.0 - r * r).sqrt();
                let fe = n.values[1];
                println!("r/a = {r:.4}: p/p_m = {fe:.4}, Sneddon {sneddon:.4}");
                assert!(
                    (fe - sneddon).abs() < 0.05 * sneddon,
                    "r/a = {r}: {fe} vs {sneddon}"
                );
                checked += 1;
            }
        }
        assert!(checked >= 20, "too few points checked: {checked}");
        // Equilibrium: the contact carries the whole punch load πa²·1.
        let r = resultants(&model, &solution.interface_committed)[0];
        let load = std::f64::consts::PI * A * A;
        assert!(
            (r[0] + load).abs() < 1e-6 * load,
            "normal resultant {} vs {load}",
            r[0]
        );
    }
}

/// Oscillation of a nodal pressure profile under the punch: the number of local extrema
/// (sign changes of the first difference). The exact profile (Sneddon) increases
/// monotonically from the axis to the edge, so every extremum is a spurious zig-zag, the
/// known defect of fully integrated interface elements (Buczkowski & Kleiber (1994), §3.3.1).
fn extrema(model: &Model, solution: &Solution) -> usize {
    let out = InterfaceOutput::new(model);
    let p: Vec<f64> = out.tables(model, &solution.interface_committed)[0]
        .rows
        .iter()
        .map(|r| r[4])
        .collect();
    let d: Vec<f64> = p.windows(2).map(|w| w[1] - w[0]).collect();
    d.windows(2).filter(|w| w[0] * w[1] < 0.0).count()
}

#[test]
fn newton_cotes_contact_stress_is_smoother_than_gauss() {
    for k_n in [1e3 * E / 10.0, 1e6 * E / 10.0] {
        let (m_nc, s_nc) = flat_punch::model("newton_cotes", k_n, 16);
        let (m_g, s_g) = flat_punch::model("gauss", k_n, 16);
        let (nc, g) = (extrema(&m_nc, &s_nc), extrema(&m_g, &s_g));
        println!(
            "k_N = {k_n:e}: spurious extrema of the pressure profile: Newton-Cotes {nc}, Gauss {g}"
        );
        assert_eq!(nc, 0, "the lumped rule must give a monotone profile");
        assert!(
            g >= 3,
            "Gauss was expected to oscillate near the punch edge ({g} extrema)"
        );
    }
}

mod block {
    use super::*;
    use asperity::contact::ContactStatus;
    use asperity::solver::stepping::run_steps;

    /// A block [1, 3] × [1, 2] on a base [0, 4] × [0, 1] (plane strain), coincident nodes on
    /// the contact. The block's top edge is the loaded/driven one.
    pub fn mesh() -> Mesh {
        block_on_base_mesh(4.0, [1.0, 3.0], 2.0, [8, 4], 2)
    }

    /// The block on the base with a named linear Coulomb joint.
    fn case() -> CaseBuilder {
        let name = [("name", "joint".into())];
        block_on_base(E, NU, &name, linear_coulomb(1e4, 1e3, 0.3))
    }

    /// Steps: 1 press (p = 10 MPa), 2 small push (stick), 3 and 4 push beyond the limit
    /// (slide), 5 push back a little (elastic unloading).
    #[test]
    fn sticks_below_mu_n_slides_at_mu_n_and_keeps_its_slip_on_unloading() {
        let case = case()
            .pressed_and_pushed(10.0, 0.01, &[0.0, 0.1, 1.0, 2.0, 1.9])
            .case();
        let model = model(mesh(), &case).unwrap();
        let mut seen = Vec::new();
        run_steps(&model, &settings(&case), |step| {
            let r = resultants(&model, &step.solution.interface_committed)[0];
            let states = &step.solution.interface_committed;
            let statuses: Vec<ContactStatus> = states.iter().map(|s| s.status).collect();
            let slip: Vec<f64> = states.iter().map(|s| s.plastic_slip[0]).collect();
            println!(
                "step {}: N = {:.6}, T = {:.6}, statuses {:?}",
                step.step, -r[0], r[1], statuses
            );
            seen.push((r, statuses, slip));
            Ok(0.0)
        })
        .unwrap();
        let n = 10.0 * 2.0;
        for (r, _, _) in &seen {
            assert!(
                (-r[0] - n).abs() < 1e-9 * n,
                "normal force {} vs {n}",
                -r[0]
            );
        }
        // Step 2: every point sticks and T < μN.
        assert!(
            seen[1].1.iter().all(|s| *s == ContactStatus::Stick),
            "{:?}",
            seen[1].1
        );
        assert!(seen[1].0[1].abs() < 0.3 * n);
        // Steps 3, 4: every point slides and T = μN.
        for k in [2, 3] {
            assert!(
                seen[k].1.iter().all(|s| *s == ContactStatus::Slip),
                "step {}: {:?}",
                k + 1,
                seen[k].1
            );
            assert!(
                (seen[k].0[1].abs() - 0.3 * n).abs() < 1e-9 * n,
                "sliding force {} vs μN {}",
                seen[k].0[1],
                0.3 * n
            );
        }
        // Step 5: unloading is elastic, the slip stays where it was.
        assert!(
            seen[4].1.iter().all(|s| *s == ContactStatus::Stick),
            "{:?}",
            seen[4].1
        );
        assert!(seen[4].0[1].abs() < 0.3 * n * 0.99);
        for (a, b) in seen[3].2.iter().zip(&seen[4].2) {
            assert!(
                (a - b).abs() < 1e-15 && a.abs() > 1e-3,
                "plastic slip changed on unloading: {a} → {b}"
            );
        }
    }

    #[test]
    fn a_pulled_block_opens_and_carries_no_stress() {
        let case = case()
            .support("block_top", &[("ux", 0.0), ("uy", 0.05)])
            .case();
        let (model, solution) = solve(mesh(), &case);
        for s in &solution.interface_committed {
            assert_eq!(s.status, ContactStatus::Open);
            assert_eq!(s.stress, [0.0; 3]);
            assert!(s.relative[1] > 0.0);
        }
        // The block moves up rigidly by 0.05 and the base stays unloaded.
        for (n, p) in model.mesh.nodes.iter().enumerate() {
            let u = displacement(&solution, n);
            let in_block = model
                .continuum
                .cells
                .iter()
                .any(|c| c.body == 1 && c.nodes.contains(&(n as u32)));
            let expected = if in_block { 0.05 } else { 0.0 };
            assert!(
                (u[1] - expected).abs() < 1e-9,
                "node at {p:?}: u_y = {}",
                u[1]
            );
        }
    }
}

mod hertz {
    use super::*;

    /// Half of a block with a parabolic face y = 1 + x²/(2R) pressed onto a flat base
    /// (plane strain, frictionless): the faces have equal node counts and an initial gap
    /// (pairing "ordered"), and contact spreads from the symmetry plane as the load grows.
    /// Plain Newton iterations (no interface iterations, which would find the contact zone
    /// within the first iteration: the default solves each step in one), whose convergence
    /// order is the point.
    #[test]
    fn newton_converges_quadratically_on_a_frictionless_contact_with_a_growing_zone() {
        let r = 20.0;
        let mut base = tensor(&uniform(0.0, 4.0, 16), &uniform(0.0, 1.0, 4), "base");
        add_curve_group(&mut base, "ground", |x| x[1] == 0.0);
        add_curve_group(&mut base, "base_sym", |x| x[0] == 0.0);
        add_curve_group(&mut base, "base_top", |x| x[1] == 1.0);
        let mut block = structured(16, 4, 0.0, false, move |s, t| {
            let x = 4.0 * s;
            [x, 1.0 + x * x / (2.0 * r) + t * 1.0]
        });
        block.groups[0].name = "block".into();
        for (g, name) in [("s0", "block_sym"), ("t0", "face"), ("t1", "block_top")] {
            block.groups.iter_mut().find(|x| x.name == g).unwrap().name = name.into();
        }
        let case = CaseBuilder::plane_strain()
            .body("base", elastic(E, NU))
            .body("block", elastic(E, NU))
            .support("ground", &[("uy", 0.0)])
            .support("base_sym", &[("ux", 0.0)])
            .support("block_sym", &[("ux", 0.0)])
            .pressure("block_top", 20.0)
            .steps(2)
            .contact(
                &[
                    ("side_a", "base_top".into()),
                    ("side_b", "face".into()),
                    ("pairing", "ordered".into()),
                ],
                linear_coulomb(1e7, 1.0, 0.0),
            )
            .case();
        let model = model(merge(base, block, false), &case).unwrap();
        let mut logs = Vec::new();
        let plain = NewtonSettings {
            interface_iterations: 0,
            ..settings(&case)
        };
        asperity::solver::stepping::run_steps(&model, &plain, |step| {
            logs.push(step.newton.residuals.clone());
            Ok(0.0)
        })
        .unwrap();
        for (k, residuals) in logs.iter().enumerate() {
            println!("step {}: relative residuals {residuals:?}", k + 1);
            let last = residuals.len() - 1;
            // Quadratic convergence: log r_{k+1} / log r_k → 2. The law is piecewise linear,
            // so once the contact zone is found Newton would be exact, were it not for the
            // 1e-9 k regularising stiffness of open points (OPEN_TANGENT_FRACTION), which
            // makes the last step slightly inexact: measured order 1.7.
            let (prev, next) = (residuals[last - 1], residuals[last]);
            let order = next.ln() / prev.ln();
            println!("  observed order of the last iteration: {order:.2}");
            assert!(
                next < 1e-8 && (order >= 1.5 || next < 1e-14),
                "{residuals:?}"
            );
        }
    }
}

mod bad_input {
    use super::*;
    use asperity::Error;
    use asperity::error::TopologyProblem;
    use asperity::model::ModelSpec;

    /// The problem and node coordinates of the topology error of pair "j".
    fn topology(case: &Case, mesh: Mesh) -> (TopologyProblem, Option<[f64; 2]>) {
        let e = model(mesh, case).unwrap_err();
        let Error::Topology {
            pair,
            problem,
            node,
            ..
        } = e
        else {
            panic!("expected a topology error, got {e}")
        };
        assert_eq!(pair, "j");
        let m = two_blocks(3);
        let at = node.map(|t| m.nodes[m.node_tags.iter().position(|&x| x == t).unwrap()]);
        (problem, at)
    }

    fn two_blocks(n_upper: usize) -> Mesh {
        let mut lower = tensor(&uniform(0.0, 2.0, 4), &uniform(0.0, 1.0, 2), "lower");
        add_curve_group(&mut lower, "lower_top", |x| x[1] == 1.0);
        let mut upper = tensor(&uniform(0.0, 2.0, n_upper), &uniform(1.0, 2.0, 2), "upper");
        add_curve_group(&mut upper, "upper_bottom", |x| x[1] == 1.0);
        let mut free = tensor(&uniform(5.0, 6.0, 1), &uniform(0.0, 1.0, 1), "loose");
        add_curve_group(&mut free, "loose_side", |x| x[0] == 5.0);
        merge(merge(lower, upper, false), free, false)
    }

    /// Two bodies joined by pair "j" between the curves `a` and `b`.
    fn pair(a: &str, b: &str, normal_stiffness: f64) -> Case {
        let faces = [
            ("name", "j".into()),
            ("side_a", a.into()),
            ("side_b", b.into()),
        ];
        CaseBuilder::plane_strain()
            .body("lower", elastic(1000.0, 0.3))
            .body("upper", elastic(1000.0, 0.3))
            .contact(&faces, linear_coulomb(normal_stiffness, 1e4, 0.0))
            .case()
    }

    #[test]
    fn curves_that_do_not_match_are_reported_with_coordinates() {
        let case = pair("lower_top", "upper_bottom", 1e4);
        let (problem, at) = topology(&case, two_blocks(3));
        assert_eq!(problem, TopologyProblem::Unpaired);
        assert!((at.unwrap()[0] - 1.0 / 3.0).abs() < 1e-12, "{at:?}");
    }

    #[test]
    fn a_curve_of_no_body_is_reported() {
        let case = pair("loose_side", "upper_bottom", 1e4);
        let e = model(two_blocks(4), &case).unwrap_err();
        assert!(
            matches!(e, Error::Topology { ref pair, problem: TopologyProblem::NoOwner, element: Some(_), .. } if pair == "j"),
            "{e}"
        );
        assert!(e.to_string().contains("loose_side"), "{e}");
    }

    /// A second `[[contact]]` on the same curves (or any pair joining a face another pair
    /// joins) would add its stiffness to the same surface: refused, naming both pairs.
    #[test]
    fn two_pairs_on_one_surface_are_refused() {
        let faces = |name: &str| {
            [
                ("name", name.into()),
                ("side_a", "lower_top".into()),
                ("side_b", "upper_bottom".into()),
            ]
        };
        let case = CaseBuilder::plane_strain()
            .body("lower", elastic(1000.0, 0.3))
            .body("upper", elastic(1000.0, 0.3))
            .contact(&faces("j0"), linear_coulomb(1e4, 1e4, 0.0))
            .contact(&faces("j"), linear_coulomb(1e4, 1e4, 0.0))
            .case();
        let (problem, at) = topology(&case, two_blocks(4));
        assert_eq!(problem, TopologyProblem::SharedFace);
        assert_eq!(at.unwrap()[1], 1.0);
        let e = model(two_blocks(4), &case).unwrap_err();
        assert!(e.to_string().contains("contact 'j0'"), "{e}");
    }

    #[test]
    fn a_negative_stiffness_is_rejected_with_its_name() {
        let e = ModelSpec::new(&pair("lower_top", "upper_bottom", -1e4)).unwrap_err();
        let Error::InvalidParameter {
            path, key, value, ..
        } = e
        else {
            panic!("expected an invalid parameter, got {e}")
        };
        assert_eq!(path, std::path::Path::new("test.toml"));
        assert_eq!(
            (key.as_str(), value.as_str()),
            ("contact[0].law.normal_stiffness", "-10000")
        );
    }
}

/// The rough-joint law of Buczkowski & Kleiber (1994), Eqs. 1–5 (power-law compliance and
/// slip-hardening friction), in whole models.
mod rough_joint {
    use super::*;
    use asperity::contact::ContactStatus;
    use asperity::solver::stepping::run_steps;

    /// Shrink fit with u_N = c_N p^m: the pressure is the root of C p + c_N p^m = δ.
    #[test]
    fn shrink_fit_pressure_is_the_root_of_the_compliance_equation() {
        use shrink_fit::*;
        for (c_n, m) in [(5e-4, 0.5), (1e-3, 1.0 / 3.0)] {
            let law = rough_joint(&[
                ("c_n", c_n),
                ("m", m),
                ("R", 1e-3),
                ("S", 0.5),
                ("mu_m", 0.2),
            ]);
            let (model, solution) = solve(mesh(false), &case(false, law));
            // Root of C p + c_N p^m − δ by bisection on (0, δ/C).
            let c = compliance();
            let (mut lo, mut hi) = (0.0, DELTA / c);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if c * mid + c_n * f64::powf(mid, m) > DELTA {
                    hi = mid
                } else {
                    lo = mid
                }
            }
            let expected = 0.5 * (lo + hi);
            let p = pressures(&model, &solution);
            let worst = p
                .iter()
                .map(|v| (v - expected).abs() / expected)
                .fold(0.0, f64::max);
            println!(
                "c_N = {c_n}, m = {m:.4}: root p = {expected:.5}, FE {:.5} (max rel. error {worst:.2e})",
                p[0]
            );
            assert!(worst < 1e-3, "pressure off by {worst}");
        }
    }

    fn sliding_case(algorithm: &str) -> Case {
        block_on_base(E, NU, &[], sliding_rough_joint())
            .pressed_and_pushed(10.0, 0.004, &[0.0, 0.5, 1.0])
            .set("solver", "contact_algorithm", algorithm)
            .set("solver", "max_iterations", 200)
            .set("solver", "force_tolerance", 1e-10)
            .set("solver", "displacement_tolerance", 1e-10)
            .case()
    }

    #[test]
    fn the_three_global_algorithms_reach_the_same_solution() {
        let mut solutions = Vec::new();
        for algorithm in ["newton", "two_step", "elastic_contact"] {
            let case = sliding_case(algorithm);
            let model = model(block::mesh(), &case).unwrap();
            let mut residuals = Vec::new();
            let t = std::time::Instant::now();
            let (solution, stats) = run_steps(&model, &settings(&case), |step| {
                residuals.push(step.newton.residuals.clone());
                Ok(0.0)
            })
            .unwrap();
            let slipping = solution
                .interface_committed
                .iter()
                .filter(|s| s.status == ContactStatus::Slip)
                .count();
            println!(
                "{algorithm:>15}: {} iterations, {} unsymmetric solves, {:.3} s, {slipping} slipping points; last step residuals {:?}",
                stats.iterations,
                stats.unsymmetric_solves,
                t.elapsed().as_secs_f64(),
                residuals.last().unwrap()
            );
            assert!(slipping > 0, "the case must slip");
            if algorithm == "newton" {
                let r = residuals.last().unwrap();
                let k = r.len() - 1;
                let order = r[k].ln() / r[k - 1].ln();
                println!("  observed order of the last Newton iteration: {order:.2}");
                assert!(
                    order > 1.7 || r[k] < 1e-15,
                    "Newton should converge quadratically: {r:?}"
                );
            }
            solutions.push(solution.u);
        }
        let scale = solutions[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for other in &solutions[1..] {
            let diff = solutions[0]
                .iter()
                .zip(other)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            println!(
                "max displacement difference to Newton: {:.2e} (scale {scale:.3e})",
                diff
            );
            assert!(diff < 1e-7 * scale, "algorithms disagree by {diff}");
        }
    }
}
