//! Robust stick–slip: a near-rigid flat punch (1000 times stiffer than its foundation) pressed
//! onto an elastic base through a stiff frictional interface (k_N = k_T = 1e8 MPa/mm, μ = 0.1)
//! in ten increments, the hard case for stick–slip iterations. It must run without a single
//! cut-back, with and without the predictor, and its answer must be the physical one: the
//! contact force balances the load, the Coulomb cone holds at every point, the shear is
//! antisymmetric about the punch's centre line (no net tangential force), the base's lateral
//! (Poisson) expansion under the stiff punch is resisted by friction with a stick zone in the
//! middle and slip towards the edges (Spence's partial slip under a rigid flat punch), and the
//! answer does not depend on how tightly Newton converged.

use crate::common;

use asperity::config::Case;
use asperity::contact::ContactStatus;
use asperity::element::interface6::interface_point;
use asperity::element::set::INTERFACE_POINTS;
use asperity::model::Model;
use asperity::post::interface::resultants;
use asperity::solver::newton::NewtonSettings;
use asperity::solver::state::{RunStatistics, Solution};
use asperity::solver::stepping::run_steps;
use common::{
    CaseBuilder, add_curve_group, elastic, linear_coulomb, merge, settings, tensor, uniform,
};

const PRESSURE: f64 = 100.0;
const MU: f64 = 0.1;
/// Half-width of the punch (mm).
const HALF: f64 = 1.0;

/// The punch [−1, 1] × [4, 4.5] (E = 2e8 MPa) on the base [−4, 4] × [0, 4] (E = 2e5 MPa,
/// deep enough to act as a half-space), plane strain, pressed by 100 MPa in ten equal
/// steps; the base held on the ground. The base's surface, squeezed by the punch, tends to
/// expand sideways (ν = 0.3) and the near-rigid punch resists through friction: the middle
/// sticks, the edges slip over a zone that shrinks as μ grows (Spence 1968; Johnson 1985,
/// §5.7); μ = 0.1 makes it wide enough for this mesh.
fn punch() -> (Model, Case) {
    let mut base = tensor(&uniform(-4.0, 4.0, 32), &uniform(0.0, 4.0, 8), "base");
    add_curve_group(&mut base, "ground", |x| x[1] == 0.0);
    add_curve_group(&mut base, "base_top", |x| x[1] == 4.0 && x[0].abs() <= HALF);
    let mut punch = tensor(&uniform(-HALF, HALF, 8), &uniform(4.0, 4.5, 2), "punch");
    add_curve_group(&mut punch, "punch_bottom", |x| x[1] == 4.0);
    add_curve_group(&mut punch, "punch_top", |x| x[1] == 4.5);
    let case = CaseBuilder::plane_strain()
        .body("base", elastic(2e5, 0.3))
        .body("punch", elastic(2e8, 0.3))
        .support("ground", &[("ux", 0.0), ("uy", 0.0)])
        .contact(
            &[
                ("name", "contact".into()),
                ("side_a", "base_top".into()),
                ("side_b", "punch_bottom".into()),
            ],
            linear_coulomb(1e8, 1e8, MU),
        )
        .pressure("punch_top", PRESSURE)
        .steps(10)
        .case();
    let model = common::model(merge(base, punch, false), &case).expect("model builds");
    (model, case)
}

fn solve(model: &Model, settings: &NewtonSettings) -> (Solution, RunStatistics) {
    run_steps(model, settings, |_| Ok(0.0)).expect("the punch solves")
}

#[test]
fn near_rigid_punch_needs_no_cutback_with_or_without_the_predictor() {
    let (model, case) = punch();
    for extrapolate in [true, false] {
        let settings = NewtonSettings {
            extrapolate,
            ..settings(&case)
        };
        let (_, stats) = solve(&model, &settings);
        assert_eq!(
            stats.cutbacks, 0,
            "extrapolate = {extrapolate}: {} cut-backs, {} iterations",
            stats.cutbacks, stats.iterations
        );
    }
}

#[test]
fn near_rigid_punch_answer_is_physical() {
    let (model, case) = punch();
    let (solution, _) = solve(&model, &settings(&case));
    let states = &solution.interface_committed;
    let [normal, tangential, _, _] = resultants(&model, states)[0];
    // Equilibrium of the punch: the contact force carries the load (per mm of thickness). The
    // criteria leave at most R_n q̃ per node out of balance; the exact solves leave ~1e-10.
    let load = PRESSURE * 2.0 * HALF;
    assert!(
        (normal + load).abs() <= 1e-6 * load,
        "normal force {normal} against the load {load}"
    );
    // Symmetry: no net shear.
    assert!(
        tangential.abs() <= 1e-6 * MU * load,
        "net tangential force {tangential}"
    );
    let (mut stick, mut slip) = (0, 0);
    let (mut shear_right, mut normal_right) = (0.0, 0.0);
    for (e, element) in model.interface.elements.iter().enumerate() {
        for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
            let s = &states[e * INTERFACE_POINTS + g];
            let [pt, pn, _] = s.stress;
            // The Coulomb cone (the return map is exact up to round-off).
            assert!(
                pt.abs() <= MU * pn.abs() * (1.0 + 1e-9) + 1e-9,
                "point ({e}, {g}): |p_T| = {} above μ|p_N| = {}",
                pt.abs(),
                MU * pn.abs()
            );
            let p = interface_point(&model.analysis, &element.b_coords, xi, w);
            if p.x[0] > 0.0 {
                shear_right += pt * p.da;
                normal_right += pn * p.da;
            }
            match s.status {
                ContactStatus::Stick => stick += 1,
                ContactStatus::Slip => slip += 1,
                ContactStatus::Open => panic!("point ({e}, {g}) opened under the punch"),
            }
        }
    }
    assert!(stick > 0 && slip > 0, "stick {stick}, slip {slip}");
    // Each half carries shear, bounded by friction, and the halves cancel.
    assert!(shear_right.abs() > 1e-3 * MU * normal_right.abs());
    assert!(shear_right.abs() <= MU * normal_right.abs());
}

#[test]
fn near_rigid_punch_answer_does_not_depend_on_the_tolerance() {
    let (model, case) = punch();
    let (default, _) = solve(&model, &settings(&case));
    let tight = NewtonSettings {
        force_tolerance: 1e-10,
        displacement_tolerance: 1e-10,
        criteria: asperity::solver::newton::Criteria {
            relative_norms: true,
            ..settings(&case).criteria
        },
        ..settings(&case)
    };
    let (reference, _) = solve(&model, &tight);
    assert_displacements_agree(&default, &reference, 1e-4);
}

/// The largest difference of `a`'s displacements from `reference`'s is at most `tolerance`
/// of the largest displacement of `reference`.
fn assert_displacements_agree(a: &Solution, reference: &Solution, tolerance: f64) {
    let scale = reference.u.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let difference = (a.u.iter().zip(&reference.u)).fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(
        difference <= tolerance * scale,
        "displacements differ by {difference:.3e} of {scale:.3e}"
    );
}

/// With elastic bodies the interface iterations solve an increment's contact problem within
/// one Newton iteration: the punch's ten increments take at most one Newton iteration each
/// (plain Newton iterations: more, the stick–slip front moving a few points per iteration),
/// and the answers agree within the convergence criteria.
#[test]
fn near_rigid_punch_takes_one_newton_iteration_per_increment_with_interface_iterations() {
    let (model, case) = punch();
    let default = settings(&case);
    let plain = NewtonSettings {
        interface_iterations: 0,
        ..default
    };
    let (with, with_stats) = solve(&model, &default);
    let (without, without_stats) = solve(&model, &plain);
    println!(
        "Newton iterations: {} with interface iterations, {} without",
        with_stats.iterations, without_stats.iterations
    );
    assert!(with_stats.iterations <= with_stats.increments);
    assert!(with_stats.iterations < without_stats.iterations);
    assert_displacements_agree(&with, &without, 1e-4);
}
