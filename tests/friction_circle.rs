//! Friction in two tangential directions (axisymmetry with twist, issue 25): the radial
//! return on the friction circle |p_τ| ≤ μ|p_N| of the linear Coulomb law against hand
//! values, the consistent tangents of both laws against central differences, slip along a
//! combined meridional and circumferential path, the rough law's slip hardening driven by the
//! length of the slip path whatever its direction, the slip-path extent of the cycle
//! trackers, and the torque a pair transmits.
use crate::common;

use asperity::contact::linear::LinearCoulomb;
use asperity::contact::rough::RoughJoint;
use asperity::contact::{
    ContactStatus, InterfaceLaw, InterfaceState, PointHistory, extend_slip_ends, length, tangential,
};
use asperity::post::interface::torques;
use common::linear_coulomb;
use common::shrink_fit::{B, L, case, mesh};

fn coulomb() -> LinearCoulomb {
    LinearCoulomb::new(1e5, 1e4, 0.3).unwrap()
}

/// The paper's law with slip hardening (μ_F from 0.15 to 0.3 over ~1/n of slip).
fn rough() -> RoughJoint {
    RoughJoint::new(RoughJoint {
        c_n: 2e-5,
        m: 0.8,
        unloading: None,
        r: 2e-3,
        s: 0.5,
        mu_m: 0.3,
        beta: 0.5,
        n: 200.0,
        starting_pressure: 0.1,
    })
    .unwrap()
}

fn close(a: f64, b: f64, tolerance: f64) -> bool {
    (a - b).abs() <= tolerance * b.abs().max(1.0)
}

/// Hand values: k_N = 1e5, k_T = 1e4 MPa/mm, μ = 0.3, closure 1e-3 mm (p_N = −100 MPa, limit
/// 30 MPa); the slide (3, 4)e-3 mm from no plastic slip makes the trial shear (30, 40) MPa,
/// |p^tr| = 50, F = 20 MPa, Δλ = F/k_T = 2e-3 mm along n = (0.6, 0.8): p_τ = (18, 24) MPa,
/// u^p = (1.2, 1.6)e-3 mm, ū = 2e-3 mm.
#[test]
fn radial_return_on_the_circle_matches_hand_values() {
    let (s, _) = coulomb().update([3e-3, -1e-3, 4e-3], &InterfaceState::default());
    assert_eq!(s.status, ContactStatus::Slip);
    let expected = [
        (s.stress[0], 18.0),
        (s.stress[1], -100.0),
        (s.stress[2], 24.0),
        (s.plastic_slip[0], 1.2e-3),
        (s.plastic_slip[1], 1.6e-3),
        (s.accumulated_slip, 2e-3),
    ];
    for (got, want) in expected {
        // A handful of roundings of numbers of order one.
        assert!((got - want).abs() <= 1e-14 * want.abs(), "{got} vs {want}");
    }
    // Inside the circle it sticks: the slide (1, 2)e-3 mm gives (10, 20) MPa, |p| = 22.4 < 30.
    let (s, k) = coulomb().update([1e-3, -1e-3, 2e-3], &InterfaceState::default());
    assert_eq!(s.status, ContactStatus::Stick);
    assert_eq!([s.stress[0], s.stress[2]], [10.0, 20.0]);
    assert_eq!((k[(0, 0)], k[(2, 2)], k[(0, 2)]), (1e4, 1e4, 0.0));
}

/// Central differences of `law`'s stresses at `u` from `committed` against its tangent, for
/// every entry of the 3×3 (T, N, θ) block; `scale` is the size of its entries.
fn check_tangent(law: &dyn InterfaceLaw, u: [f64; 3], committed: &InterfaceState, scale: f64) {
    let (state, k) = law.update(u, committed);
    let h = 1e-9;
    for j in 0..3 {
        let (mut up, mut um) = (u, u);
        up[j] += h;
        um[j] -= h;
        let (sp, _) = law.update(up, committed);
        let (sm, _) = law.update(um, committed);
        assert_eq!(
            (sp.status, sm.status),
            (state.status, state.status),
            "{u:?}"
        );
        for i in 0..3 {
            let fd = (sp.stress[i] - sm.stress[i]) / (2.0 * h);
            // Central differences of smooth functions with entries ~scale: truncation h² and
            // round-off ε·|p|/h ≈ 1e-5 of the scale.
            assert!(
                (fd - k[(i, j)]).abs() <= 1e-5 * scale,
                "{:?} at {u:?}: K[{i},{j}] = {} vs fd {fd}",
                state.status,
                k[(i, j)]
            );
        }
    }
}

#[test]
fn coulomb_tangent_matches_finite_differences_on_and_inside_the_circle() {
    let committed = InterfaceState {
        plastic_slip: [2e-4, -1e-4],
        ..Default::default()
    };
    // Stick; slip in T and θ together; slip mostly in θ; slip against the committed slip.
    for u in [
        [3e-4, -1e-3, 0.0],
        [4e-3, -1e-3, 3e-3],
        [1e-4, -2e-3, -6e-3],
        [-5e-3, -1e-3, 1e-3],
    ] {
        check_tangent(&coulomb(), u, &committed, 1e5);
    }
    // The slip tangent is unsymmetric (∂p_τ/∂u_N = −μ k_N n, ∂p_N/∂u_τ = 0) and turns the
    // direction only: along n it is zero, across n it is μ|p_N| k_T / |p^tr|.
    let (s, k) = coulomb().update([3e-3, -1e-3, 4e-3], &InterfaceState::default());
    let n = [s.stress[0] / 30.0, s.stress[2] / 30.0];
    let along = k[(0, 0)] * n[0] * n[0] + 2.0 * k[(0, 2)] * n[0] * n[1] + k[(2, 2)] * n[1] * n[1];
    let across = k[(0, 0)] * n[1] * n[1] - 2.0 * k[(0, 2)] * n[0] * n[1] + k[(2, 2)] * n[0] * n[0];
    assert!(along.abs() < 1e-9, "{along}");
    assert!(close(across, 30.0 * 1e4 / 50.0, 1e-14), "{across}");
    assert!(close(k[(2, 1)], -0.3 * 1e5 * 0.8, 1e-14) && k[(1, 2)] == 0.0);
}

#[test]
fn rough_tangent_matches_finite_differences_with_hardening_and_pressure_change() {
    let law = rough();
    // A committed slipping state: p = 50 MPa, shear on the circle in a skew direction.
    let (mu, _) = law.friction(2e-3);
    let closure = 2e-5 * 50f64.powf(0.8);
    let committed = InterfaceState {
        relative: [1e-2, -closure, -4e-3],
        stress: [0.6 * mu * 50.0, -50.0, -0.8 * mu * 50.0],
        plastic_slip: [3e-3, -1e-3],
        accumulated_slip: 2e-3,
        max_closure: closure,
        friction: mu,
        status: ContactStatus::Slip,
        ..Default::default()
    };
    // Loading on: slip in a turned direction at higher pressure; unloading to stick; slip
    // at lower pressure; a pure circumferential increment.
    for (du, dp) in [
        ([2e-4, 3e-4], 0.1),
        ([-2e-4, 1e-4], 0.0),
        ([1e-4, -3e-4], -0.2),
        ([0.0, -4e-4], 0.05),
    ] {
        let c = 2e-5 * (50.0f64 * (1.0 + dp)).powf(0.8);
        let u = [1e-2 + du[0], -c, -4e-3 + du[1]];
        let (_, k) = law.update(u, &committed);
        check_tangent(&law, u, &committed, k.amax());
    }
}

/// A point pressed at constant pressure, then slid along the fixed direction d in the (T, θ)
/// plane: once it slips, |p_τ| = μ|p_N| and p_τ is parallel to d (and to each slip
/// increment); then turned by a right angle, every slip increment stays parallel to the
/// returned shear (radial return) and the shear turns towards the new direction.
#[test]
fn combined_slip_lies_on_the_circle_along_the_slip_increment() {
    let law = coulomb();
    let u_n = -1e-3;
    let limit = 0.3 * 100.0;
    for angle in [0.3f64, 1.2, 2.5, -2.0] {
        let d = [angle.cos(), angle.sin()];
        let mut state = law.update([0.0, u_n, 0.0], &InterfaceState::default()).0;
        let step = 2e-4; // twice the elastic slide μ|p|/k_T = 3e-3 over 15 increments
        for i in 1..=30 {
            let a = step * i as f64;
            let before = state.plastic_slip;
            state = law.update([a * d[0], u_n, a * d[1]], &state).0;
            if state.status == ContactStatus::Slip {
                let shear = tangential(state.stress);
                assert!(close(length(shear), limit, 1e-14), "{shear:?}");
                let cross = shear[0] * d[1] - shear[1] * d[0];
                assert!(cross.abs() <= 1e-12 * limit, "p_τ not along d: {shear:?}");
                assert!(shear[0] * d[0] + shear[1] * d[1] > 0.0);
                let slip = [
                    state.plastic_slip[0] - before[0],
                    state.plastic_slip[1] - before[1],
                ];
                assert!((slip[0] * d[1] - slip[1] * d[0]).abs() <= 1e-15);
            }
        }
        assert_eq!(state.status, ContactStatus::Slip);
        // Turn by a right angle: slide along e = d rotated by +90° from the end of the first
        // path.
        let end = state.relative;
        let e = [-d[1], d[0]];
        for i in 1..=100 {
            let before = state.plastic_slip;
            let a = step * i as f64;
            let u = [end[0] + a * e[0], u_n, end[2] + a * e[1]];
            state = law.update(u, &state).0;
            let shear = tangential(state.stress);
            assert!(close(length(shear), limit, 1e-14), "{i}: {shear:?}");
            let slip = [
                state.plastic_slip[0] - before[0],
                state.plastic_slip[1] - before[1],
            ];
            assert!((slip[0] * shear[1] - slip[1] * shear[0]).abs() <= 1e-15 * limit);
            assert!(
                slip[0] * shear[0] + slip[1] * shear[1] >= 0.0,
                "dissipation ≥ 0"
            );
        }
        // Each increment adds k_T·2e-4 = 2 MPa along e to a shear of 30 MPa, so the part
        // along d decays by about 30/32 per increment: after 100 to below 0.2 % of the limit.
        let shear = tangential(state.stress);
        assert!(
            (shear[0] * e[0] + shear[1] * e[1]) / limit > 0.999,
            "{shear:?}"
        );
    }
}

/// The rough law's friction hardens with the slip length ū = ∫|du^p| whatever its direction:
/// the same slide length along T, along θ or along a skew line leaves the same ū, μ_F and
/// |p_τ|; a slide that turns by a right angle halfway hardens as much as a straight one of
/// the same length of slip.
#[test]
fn rough_law_hardens_with_the_length_of_the_slip_path_in_any_direction() {
    let law = rough();
    let p: f64 = 40.0;
    let closure = 2e-5 * p.powf(0.8);
    let pressed = law
        .update([0.0, -closure, 0.0], &InterfaceState::default())
        .0;
    // The state after sliding along `path` (t from 0 to 1) and the length of its plastic
    // slip path, Σ|Δu^p|.
    let slide_along = |path: &dyn Fn(f64) -> [f64; 2]| {
        let (mut s, mut travelled) = (pressed, 0.0);
        for i in 1..=400 {
            let x = path(i as f64 / 400.0);
            let before = s.plastic_slip;
            s = law.update([x[0], -closure, x[1]], &s).0;
            travelled += length([s.plastic_slip[0] - before[0], s.plastic_slip[1] - before[1]]);
        }
        (s, travelled)
    };
    let slide = |path: &dyn Fn(f64) -> [f64; 2]| slide_along(path).0;
    let total = 0.02;
    let straight = slide(&|t| [total * t, 0.0]);
    assert!(
        straight.accumulated_slip > 0.015,
        "{}",
        straight.accumulated_slip
    );
    for angle in [std::f64::consts::FRAC_PI_2, 0.7, -2.4] {
        let d = [f64::cos(angle), f64::sin(angle)];
        let s = slide(&|t| [total * t * d[0], total * t * d[1]]);
        // The same sequence of scalar returns on a rotated line: equal to round-off.
        assert!(close(s.accumulated_slip, straight.accumulated_slip, 1e-12));
        assert!(close(s.friction, straight.friction, 1e-12));
        let shear = length(tangential(s.stress));
        assert!(close(shear, s.friction * p, 1e-12), "on the circle");
        assert!(close(shear, length(tangential(straight.stress)), 1e-10));
    }
    // A right-angle turn halfway: the plastic slip path is longer than the distance from
    // its start, and ū counts the path (μ_F by ū, not by |u^p|).
    let (turned, travelled) = slide_along(&|t| {
        let half = 0.5 * total;
        if t <= 0.5 {
            [total * t, 0.0]
        } else {
            [half, total * (t - 0.5)]
        }
    });
    assert!(close(turned.accumulated_slip, travelled, 1e-12));
    assert!(turned.accumulated_slip > length(turned.plastic_slip) * 1.05);
    let (mu, _) = law.friction(turned.accumulated_slip);
    assert!(close(turned.friction, mu, 1e-14));
    assert!(close(length(tangential(turned.stress)), mu * p, 1e-12));
}

/// The slip amplitude of a cycle is half the extent of its slip path: for a reciprocating
/// stroke along any fixed direction half the stroke, for a circle its radius, and without
/// twist exactly half the range of u_T^p.
#[test]
fn slip_amplitude_is_half_the_extent_of_the_slip_path() {
    let amplitude = |path: &[[f64; 2]]| {
        let mut h = PointHistory::default();
        for &x in path {
            h.cycle_slip = x;
            h.cycle_slip_ends = extend_slip_ends(h.cycle_slip_ends, x);
        }
        h.cycle_slip_amplitude()
    };
    // Sinusoidal stroke ±a along a skew direction from the middle.
    let (a, d) = (3e-3, [0.6, -0.8]);
    let stroke: Vec<[f64; 2]> = (0..=100)
        .map(|i| {
            let s = a * (2.0 * std::f64::consts::PI * i as f64 / 100.0).sin();
            [s * d[0], s * d[1]]
        })
        .collect();
    assert!(close(amplitude(&stroke), a, 1e-12));
    // A circle of radius r through the start.
    let r = 2e-3;
    let circle: Vec<[f64; 2]> = (0..=64)
        .map(|i| {
            let t = 2.0 * std::f64::consts::PI * i as f64 / 64.0;
            [r * (1.0 - t.cos()), r * t.sin()]
        })
        .collect();
    assert!(close(amplitude(&circle), r, 1e-12));
    // One direction: half the range, bit for bit.
    let line = [0.0, 1e-3, -2e-3, 5e-4, 4e-3, -1e-3];
    let path: Vec<[f64; 2]> = line.iter().map(|&x| [x, 0.0]).collect();
    assert_eq!(amplitude(&path), 0.5 * (4e-3 - -2e-3));
}

/// The torque of a pair is −∫ p_θ r dA with the 2πr of the circle in dA: a uniform
/// circumferential shear τ on the shrink fit's cylindrical interface (radius b, length L)
/// transmits 2π b² L τ.
#[test]
fn pair_torque_integrates_the_circumferential_shear_over_the_surface_of_revolution() {
    let law = linear_coulomb(1e6, 1e6, 0.2);
    let (model, solution) = common::solve(mesh(false), &case(false, law));
    let tau = 7.0;
    let mut states = solution.interface_committed.clone();
    for s in &mut states {
        s.stress[2] = tau;
    }
    let torque = torques(&model, &states);
    let expected = -2.0 * std::f64::consts::PI * B * B * L * tau;
    assert!(
        close(torque[0], expected, 1e-12),
        "{torque:?} vs {expected}"
    );
    // Without circumferential shear (no twist) no torque.
    assert_eq!(torques(&model, &solution.interface_committed), vec![0.0]);
}
