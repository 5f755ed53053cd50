//! Interface elements and the linear Coulomb law against closed-form references
//! (docs/theory.md, closed forms): shrink fit (both mesh recipes), frictionless flat
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

    pub const B: f64 = 10.0;
    const C: f64 = 20.0;
    pub const L: f64 = 10.0;
    pub const DELTA: f64 = 0.01;

    /// Plane-strain compliance C = b (C_s + C_h) of a solid shaft in a hub (docs/theory.md, "Lamé cylinders and the shrink fit").
    pub fn compliance() -> f64 {
        let (e, nu) = (E / (1.0 - NU * NU), NU / (1.0 - NU));
        let cs = (1.0 - nu) / e;
        let ch = ((C * C + B * B) / (C * C - B * B) + nu) / e;
        B * (cs + ch)
    }

    pub fn bodies(conforming: bool) -> Mesh {
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

    pub fn text(pairing: &str, k_n: f64) -> String {
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
        let text = format!(
            r#"[analysis]
            type = "axisymmetric"
            [[body]]
            group = "foundation"
            material = {{ E = {E}, nu = {NU} }}
            [[body]]
            group = "punch"
            material = {{ E = {}, nu = {NU} }}
            [[support]]
            group = "base"
            uz = 0.0
            [[load]]
            group = "top"
            pressure = 1.0
            [[contact]]
            side_a = "surface"
            side_b = "face"
            integration = "{rule}"
            law = {{ type = "linear_coulomb", normal_stiffness = {k_n}, tangential_stiffness = 1.0, friction = 0.0 }}
            "#,
            1000.0 * E
        );
        solve(merge(foundation, punch, false), &case(&text))
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
/// known defect of fully integrated interface elements (paper §3.3.1).
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
    use asperity::solver::newton::NewtonSettings;
    use asperity::solver::stepping::run_steps;

    /// A block [1, 3] × [1, 2] on a base [0, 4] × [0, 1] (plane strain), coincident nodes on
    /// the contact. The block's top edge is the loaded/driven one.
    pub fn mesh() -> Mesh {
        let mut base = tensor(&uniform(0.0, 4.0, 8), &uniform(0.0, 1.0, 2), "base");
        add_curve_group(&mut base, "ground", |x| x[1] == 0.0);
        add_curve_group(&mut base, "base_top", |x| {
            x[1] == 1.0 && (1.0..=3.0).contains(&x[0])
        });
        let mut block = tensor(&uniform(1.0, 3.0, 4), &uniform(1.0, 2.0, 2), "block");
        add_curve_group(&mut block, "block_bottom", |x| x[1] == 1.0);
        add_curve_group(&mut block, "block_top", |x| x[1] == 2.0);
        merge(base, block, false)
    }

    fn text(extra: &str) -> String {
        format!(
            r#"[analysis]
            type = "plane_strain"
            [[body]]
            group = "base"
            material = {{ E = {E}, nu = {NU} }}
            [[body]]
            group = "block"
            material = {{ E = {E}, nu = {NU} }}
            [[support]]
            group = "ground"
            ux = 0.0
            uy = 0.0
            [[contact]]
            name = "joint"
            side_a = "base_top"
            side_b = "block_bottom"
            law = {{ type = "linear_coulomb", normal_stiffness = 1e4, tangential_stiffness = 1e3, friction = 0.3 }}
            {extra}
            "#
        )
    }

    /// Steps: 1 press (p = 10 MPa), 2 small push (stick), 3 and 4 push beyond the limit
    /// (slide), 5 push back a little (elastic unloading).
    #[test]
    fn sticks_below_mu_n_slides_at_mu_n_and_keeps_its_slip_on_unloading() {
        let case = case(&text(
            r#"[[support]]
            group = "block_top"
            ux = 0.01
            factors = [0.0, 0.1, 1.0, 2.0, 1.9]
            [[load]]
            group = "block_top"
            pressure = 10.0
            factors = [1.0, 1.0, 1.0, 1.0, 1.0]
            [steps]
            count = 5"#,
        ));
        let model = Model::build(mesh(), &case).unwrap();
        let mut seen = Vec::new();
        run_steps(&model, &NewtonSettings::from(case.solver), |step| {
            let r = resultants(&model, &step.solution.interface_committed)[0];
            let states = &step.solution.interface_committed;
            let statuses: Vec<ContactStatus> = states.iter().map(|s| s.status).collect();
            let slip: Vec<f64> = states.iter().map(|s| s.plastic_slip).collect();
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
        let case = case(&text(
            r#"[[support]]
            group = "block_top"
            ux = 0.0
            uy = 0.05"#,
        ));
        let (model, solution) = solve(mesh(), &case);
        for s in &solution.interface_committed {
            assert_eq!(s.status, ContactStatus::Open);
            assert_eq!(s.stress, [0.0, 0.0]);
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
        let text = format!(
            r#"[analysis]
            type = "plane_strain"
            [[body]]
            group = "base"
            material = {{ E = {E}, nu = {NU} }}
            [[body]]
            group = "block"
            material = {{ E = {E}, nu = {NU} }}
            [[support]]
            group = "ground"
            uy = 0.0
            [[support]]
            group = "base_sym"
            ux = 0.0
            [[support]]
            group = "block_sym"
            ux = 0.0
            [[load]]
            group = "block_top"
            pressure = 20.0
            [steps]
            count = 2
            [[contact]]
            side_a = "base_top"
            side_b = "face"
            pairing = "ordered"
            law = {{ type = "linear_coulomb", normal_stiffness = 1e7, tangential_stiffness = 1.0 }}
            "#
        );
        let case = case(&text);
        let model = Model::build(merge(base, block, false), &case).unwrap();
        let mut logs = Vec::new();
        asperity::solver::stepping::run_steps(
            &model,
            &asperity::solver::newton::NewtonSettings::from(case.solver),
            |step| {
                logs.push(step.newton.residuals.clone());
                Ok(0.0)
            },
        )
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

    fn error(text: &str, mesh: Mesh) -> String {
        Model::build(mesh, &case(text)).unwrap_err().to_string()
    }

    const BODIES: &str = r#"[analysis]
        type = "plane_strain"
        [[body]]
        group = "lower"
        material = { E = 1000.0, nu = 0.3 }
        [[body]]
        group = "upper"
        material = { E = 1000.0, nu = 0.3 }
        "#;

    const LAW: &str =
        r#"law = { type = "linear_coulomb", normal_stiffness = 1e4, tangential_stiffness = 1e4 }"#;

    fn two_blocks(n_upper: usize) -> Mesh {
        let mut lower = tensor(&uniform(0.0, 2.0, 4), &uniform(0.0, 1.0, 2), "lower");
        add_curve_group(&mut lower, "lower_top", |x| x[1] == 1.0);
        let mut upper = tensor(&uniform(0.0, 2.0, n_upper), &uniform(1.0, 2.0, 2), "upper");
        add_curve_group(&mut upper, "upper_bottom", |x| x[1] == 1.0);
        let mut free = tensor(&uniform(5.0, 6.0, 1), &uniform(0.0, 1.0, 1), "loose");
        add_curve_group(&mut free, "loose_side", |x| x[0] == 5.0);
        merge(merge(lower, upper, false), free, false)
    }

    fn pair(a: &str, b: &str) -> String {
        format!("{BODIES}[[contact]]\nname = \"j\"\nside_a = \"{a}\"\nside_b = \"{b}\"\n{LAW}\n")
    }

    #[test]
    fn curves_that_do_not_match_are_reported_with_coordinates() {
        let e = error(&pair("lower_top", "upper_bottom"), two_blocks(3));
        assert!(
            e.contains("contact 'j'") && e.contains("no coincident node") && e.contains("(0.333"),
            "{e}"
        );
    }

    #[test]
    fn a_curve_of_no_body_is_reported() {
        let e = error(&pair("loose_side", "upper_bottom"), two_blocks(4));
        assert!(
            e.contains("contact 'j'") && e.contains("loose_side") && e.contains("no body"),
            "{e}"
        );
    }

    #[test]
    fn a_negative_stiffness_is_rejected_with_its_name() {
        let text = pair("lower_top", "upper_bottom")
            .replace("normal_stiffness = 1e4", "normal_stiffness = -1e4");
        let err = asperity::config::Case::from_toml(
            &format!("[mesh]\nfile = \"m.msh\"\n{text}"),
            std::path::Path::new("c.toml"),
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("normal_stiffness") && err.contains("positive") && err.contains("c.toml"),
            "{err}"
        );
    }
}

/// The paper's law (issue: power-law compliance and slip-hardening friction) in whole models.
mod rough_joint {
    use super::*;
    use asperity::contact::ContactStatus;
    use asperity::solver::newton::NewtonSettings;
    use asperity::solver::stepping::run_steps;

    /// Shrink fit with u_N = c_N p^m: the pressure is the root of C p + c_N p^m = δ.
    #[test]
    fn shrink_fit_pressure_is_the_root_of_the_compliance_equation() {
        use shrink_fit::*;
        for (c_n, m) in [(5e-4, 0.5), (1e-3, 1.0 / 3.0)] {
            let law = format!(
                r#"law = {{ type = "rough_joint", c_n = {c_n}, m = {m}, R = 1e-3, S = 0.5, mu_m = 0.2 }}"#
            );
            let text = text("side_a = \"shaft_outer\"\nside_b = \"hub_bore\"", 1.0)
                .lines()
                .map(|l| {
                    if l.trim_start().starts_with("law =") {
                        law.clone()
                    } else {
                        l.to_string()
                    }
                })
                .collect::<Vec<_>>()
                .join("\n");
            let (model, solution) = solve(bodies(false), &case(&text));
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

    fn sliding_case(algorithm: &str) -> asperity::config::Case {
        case(&format!(
            r#"[analysis]
            type = "plane_strain"
            [[body]]
            group = "base"
            material = {{ E = {E}, nu = {NU} }}
            [[body]]
            group = "block"
            material = {{ E = {E}, nu = {NU} }}
            [[support]]
            group = "ground"
            ux = 0.0
            uy = 0.0
            [[support]]
            group = "block_top"
            ux = 0.004
            factors = [0.0, 0.5, 1.0]
            [[load]]
            group = "block_top"
            pressure = 10.0
            factors = [1.0, 1.0, 1.0]
            [steps]
            count = 3
            [solver]
            contact_algorithm = "{algorithm}"
            max_iterations = 200
            force_tolerance = 1e-10
            displacement_tolerance = 1e-10
            [[contact]]
            side_a = "base_top"
            side_b = "block_bottom"
            law = {{ type = "rough_joint", c_n = 1e-4, m = 0.5, R = 1e-3, S = 0.5, mu_m = 0.3, beta = 0.3, n = 100.0 }}
            "#
        ))
    }

    #[test]
    fn the_three_global_algorithms_reach_the_same_solution() {
        let mut solutions = Vec::new();
        for algorithm in ["newton", "two_step", "elastic_contact"] {
            let case = sliding_case(algorithm);
            let model = Model::build(block::mesh(), &case).unwrap();
            let mut residuals = Vec::new();
            let t = std::time::Instant::now();
            let (solution, stats) = run_steps(&model, &NewtonSettings::from(case.solver), |step| {
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
