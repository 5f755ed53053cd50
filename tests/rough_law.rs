//! The rough-joint law of Buczkowski & Kleiber (1994), §2, at one integration point: the
//! friction curve (Eq. 4, Fig. 4), a cyclic tangential history at constant pressure against
//! the closed form of docs/theory.md (Lambert W), the normal power law, and property tests
//! of the return map and its consistent tangent.
use asperity::contact::rough::RoughJoint;
use asperity::contact::{ContactStatus, InterfaceLaw, InterfaceState};
use proptest::prelude::*;

fn law(mu_m: f64, beta: f64, n: f64) -> RoughJoint {
    RoughJoint::new(RoughJoint {
        c_n: 1e-4,
        m: 0.5,
        unloading: None,
        r: 1e-3,
        s: 0.5,
        mu_m,
        beta,
        n,
        starting_pressure: 0.1,
    })
    .unwrap()
}

#[test]
fn friction_curve_is_eq_4_pointwise() {
    for (mu_m, beta) in [(0.1, 0.1), (0.2, 0.2), (0.3, 0.3)] {
        let l = law(mu_m, beta, 275.0);
        for slip in [0.0f64, 1e-3, 5e-3, 1e-2, 2e-2, 1.0] {
            let exact = mu_m * (1.0 - (1.0 - beta) * (-275.0 * slip).exp());
            let (mu, dmu) = l.friction(slip);
            assert!(
                (mu - exact).abs() < 1e-15,
                "({mu_m}, {beta}) at {slip}: {mu} vs {exact}"
            );
            // Slope (Eq. 14) against a forward difference (ū ≥ 0 has a one-sided start).
            let h = 1e-9;
            let fd = (l.friction(slip + h).0 - mu) / h;
            assert!(
                (fd - dmu).abs() < 1e-4 * dmu.max(1e-12),
                "slope at {slip}: {fd} vs {dmu}"
            );
        }
        assert!(
            (l.friction(0.0).0 - beta * mu_m).abs() < 1e-15,
            "initial friction β μ_m"
        );
    }
}

/// Principal branch of the Lambert W function (Halley iteration), for x ≥ 0.
fn lambert_w0(x: f64) -> f64 {
    let mut w = if x < 1.0 {
        x
    } else {
        x.ln() - x.ln().ln().max(0.0)
    };
    for _ in 0..100 {
        let e = w.exp();
        let f = w * e - x;
        let step = f / (e * (w + 1.0) - (w + 2.0) * f / (2.0 * w + 2.0));
        w -= step;
        if step.abs() < 1e-16 * w.abs().max(1e-300) {
            break;
        }
    }
    w
}

/// Exact constant-pressure response (docs/theory.md, Lambert W) of a point driven along `path`
/// (u_T values, monotonic between them), tracked event by event.
struct Exact {
    kt: f64,
    p: f64,
    mu_m: f64,
    beta: f64,
    n: f64,
    up: f64,
    slip: f64,
}

impl Exact {
    fn mu(&self, slip: f64) -> f64 {
        self.mu_m * (1.0 - (1.0 - self.beta) * (-self.n * slip).exp())
    }

    /// Moves u_T monotonically to `u` from the current state; returns τ.
    fn go_to(&mut self, u: f64) -> f64 {
        let tau = self.kt * (u - self.up);
        if tau.abs() <= self.mu(self.slip) * self.p {
            return tau;
        }
        let s = tau.signum();
        let a = self.mu_m * self.p / self.kt;
        let b = (1.0 - self.beta) * a;
        let d = s * (u - self.up) + self.slip;
        let slip = (d - a) + lambert_w0(self.n * b * (-self.n * (d - a)).exp()) / self.n;
        self.up += s * (slip - self.slip);
        self.slip = slip;
        s * self.mu(slip) * self.p
    }
}

#[test]
fn cyclic_history_at_constant_pressure_matches_the_closed_form_at_any_step_size() {
    let l = law(0.2, 0.2, 275.0);
    // Closure for p = 50 MPa: c = c_N p^m.
    let p: f64 = 50.0;
    let u_n = -1e-4 * p.powf(0.5);
    // k_T is constant at constant pressure (the law's smooth floor changes it by ~1e-6 here).
    let kt = l.tangential_stiffness(p).0;
    // Load, reverse, reload (mm): each beyond the elastic range (β μ_m p / k_T ≈ 2.8e-4 at
    // first) but with n ū ≈ 1..2, inside the hardening range of Eq. (4).
    let path = [0.004, -0.001, 0.005];
    let mut exact = Exact {
        kt,
        p,
        mu_m: 0.2,
        beta: 0.2,
        n: 275.0,
        up: 0.0,
        slip: 0.0,
    };
    let reference: Vec<(f64, f64, f64)> = path
        .iter()
        .map(|&u| {
            let tau = exact.go_to(u);
            (tau, exact.up, exact.slip)
        })
        .collect();
    for steps in [1usize, 50] {
        let mut state = InterfaceState::default();
        // Close the contact first (no tangential motion).
        state = l.update([0.0, u_n, 0.0], &state).0;
        let mut from = 0.0;
        for (k, &to) in path.iter().enumerate() {
            for i in 1..=steps {
                let u = from + (to - from) * i as f64 / steps as f64;
                state = l.update([u, u_n, 0.0], &state).0;
            }
            from = to;
            let (tau, up, slip) = reference[k];
            let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-12);
            println!(
                "{steps:>2} steps/segment, u_T = {to:+.3}: p_T = {:+.9} (exact {tau:+.9}), u_T^p = {:+.9} ({up:+.9}), ū = {:.9} ({slip:.9})",
                state.stress[0], state.plastic_slip[0], state.accumulated_slip
            );
            assert!(rel(state.stress[0], tau) < 1e-8, "stress");
            assert!(rel(state.plastic_slip[0], up) < 1e-8, "plastic slip");
            assert!(rel(state.accumulated_slip, slip) < 1e-8, "accumulated slip");
            assert!(
                (state.stress[1] + p).abs() < 1e-9 * p,
                "pressure from the total law"
            );
        }
    }
}

#[test]
fn normal_law_is_the_total_power_law_with_an_optional_unloading_curve() {
    let mut l = law(0.2, 1.0, 0.0);
    for p in [0.5, 5.0, 50.0] {
        let c = 1e-4 * f64::powf(p, 0.5);
        let (pressure, k) = l.normal(c, c);
        assert!((pressure - p).abs() < 1e-12 * p);
        assert!((k - p.powf(0.5) / (1e-4 * 0.5)).abs() < 1e-9 * k, "Eq. 2");
    }
    // Unloading from p_max = 50 along c − c_perm = c_Nu p^m_u.
    l.unloading = Some((2e-5, 0.8));
    let c_max = 1e-4 * 50f64.powf(0.5);
    let c_perm = c_max - 2e-5 * 50f64.powf(0.8);
    let (p_at_max, _) = l.normal(c_max * (1.0 - 1e-12), c_max);
    assert!(
        (p_at_max - 50.0).abs() < 1e-6,
        "unloading starts at p_max: {p_at_max}"
    );
    let (p_mid, _) = l.normal(0.5 * (c_max + c_perm), c_max);
    let expected = (0.5 * (c_max - c_perm) / 2e-5).powf(1.0 / 0.8);
    assert!((p_mid - expected).abs() < 1e-9 * expected);
    assert_eq!(
        l.normal(0.99 * c_perm, c_max).0,
        0.0,
        "permanent set: no stress below c_perm"
    );
}

fn tangent_fd_check(l: &RoughJoint, u: [f64; 2], committed: &InterfaceState) {
    let u = [u[0], u[1], 0.0];
    let (state, k) = l.update(u, committed);
    for j in 0..2 {
        let h = 1e-9 * (1.0 + u[j].abs() * 1e3);
        let (mut up, mut um) = (u, u);
        up[j] += h;
        um[j] -= h;
        let (sp, _) = l.update(up, committed);
        let (sm, _) = l.update(um, committed);
        if sp.status != state.status || sm.status != state.status {
            continue; // a kink between the states: the tangent is one-sided there
        }
        for i in 0..2 {
            let fd = (sp.stress[i] - sm.stress[i]) / (2.0 * h);
            let scale = k.amax().max(1.0);
            assert!(
                (fd - k[(i, j)]).abs() < 1e-5 * scale,
                "{:?} at u = {u:?}: K[{i},{j}] = {} vs fd {fd} (committed {committed:?})",
                state.status,
                k[(i, j)]
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Random committed states and increments: the returned stress lies on or inside the
    /// slip surface, the slip dissipates (p_T · Δu_T^p ≥ 0), and the tangent matches central
    /// finite differences of the return map in stick, slip and reversal.
    #[test]
    fn return_map_properties(
        mu_m in 0.05f64..0.5,
        beta in 0.05f64..1.0,
        n in 0.0f64..500.0,
        p_n in 1.0f64..100.0,
        slip_n in 0.0f64..0.02,
        tau_fraction in -1.0f64..1.0,
        du_t in -0.01f64..0.01,
        dp in -0.5f64..0.5,
    ) {
        let l = law(mu_m, beta, n);
        let (mu_committed, _) = l.friction(slip_n);
        let u_n0 = -1e-4 * p_n.powf(0.5);
        let committed = InterfaceState {
            relative: [0.003, u_n0, 0.0],
            stress: [tau_fraction * mu_committed * p_n, -p_n, 0.0],
            plastic_slip: [0.001, 0.0],
            accumulated_slip: slip_n,
            max_closure: -u_n0,
            ..InterfaceState::default()
        };
        let p_new = p_n * (1.0 + dp);
        let u = [0.003 + du_t, -1e-4 * p_new.powf(0.5)];
        let (s, _) = l.update([u[0], u[1], 0.0], &committed);
        let limit = l.friction(s.accumulated_slip).0 * -s.stress[1];
        prop_assert!(s.stress[0].abs() <= limit * (1.0 + 1e-12) + 1e-12, "outside the slip surface");
        let dup = s.plastic_slip[0] - committed.plastic_slip[0];
        prop_assert!(s.stress[0] * dup >= -1e-14 * limit, "negative dissipation");
        prop_assert!((s.accumulated_slip - slip_n - dup.abs()).abs() < 1e-15, "ū grows by |Δu^p|");
        if s.status == ContactStatus::Slip {
            prop_assert!((s.stress[0].abs() - limit).abs() <= 1e-10 * limit, "slip must lie on the surface");
        }
        tangent_fd_check(&l, u, &committed);
    }
}
