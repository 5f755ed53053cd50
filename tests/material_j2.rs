//! Material-point tests of J2 plasticity with linear isotropic hardening
//! (docs/theory.md, closed forms): uniaxial stress and simple shear against the exact curves,
//! step-size independence along radial paths, the consistent tangent against finite
//! differences, return to the yield surface, plastic incompressibility and parameter checks.

use asperity::material::elastic::LinearElastic;
use asperity::material::j2::J2Plasticity;
use asperity::material::{Material, OutOfPlane, PointState, Tangent, Voigt, ZZ, voigt, von_mises};

const E: f64 = 200_000.0;
const NU: f64 = 0.3;
const SY: f64 = 250.0;
/// Plastic hardening modulus H of the hardening cases (E_t = E H/(E + H) ≈ 9524 MPa).
const H: f64 = 10_000.0;
const MODES: [OutOfPlane; 2] = [OutOfPlane::StrainGiven, OutOfPlane::StressFree];

fn material(h: f64) -> J2Plasticity {
    J2Plasticity::new(LinearElastic::new(E, NU).unwrap(), SY, h).unwrap()
}

fn shear_modulus() -> f64 {
    E / (2.0 * (1.0 + NU))
}

/// Uniaxial stress σ_xx with all other stresses zero at axial strain `exx`: a local Newton
/// iteration on the lateral strains (ε_yy in plane stress; ε_yy and ε_zz with given ε_zz)
/// using the material's own tangent, starting from the committed lateral strains.
fn uniaxial(m: &J2Plasticity, committed: &PointState, exx: f64, mode: OutOfPlane) -> PointState {
    let mut eps = committed.strain;
    eps[0] = exx;
    eps[2] = 0.0;
    for _ in 0..50 {
        let (s, d) = m.update(&eps, committed, mode);
        match mode {
            OutOfPlane::StressFree => {
                if s.stress[1].abs() <= 1e-11 {
                    return s;
                }
                eps[1] -= s.stress[1] / d[(1, 1)];
            }
            OutOfPlane::StrainGiven => {
                if s.stress[1].abs().max(s.stress[ZZ].abs()) <= 1e-11 {
                    return s;
                }
                let (a, b, c, dd) = (d[(1, 1)], d[(1, ZZ)], d[(ZZ, 1)], d[(ZZ, ZZ)]);
                let det = a * dd - b * c;
                let (r1, r2) = (s.stress[1], s.stress[ZZ]);
                eps[1] -= (dd * r1 - b * r2) / det;
                eps[ZZ] -= (a * r2 - c * r1) / det;
            }
        }
    }
    panic!("lateral Newton iteration did not converge at exx = {exx}");
}

/// Pure shear strain γ_xy (all other strain components zero).
fn shear(m: &J2Plasticity, committed: &PointState, gamma: f64, mode: OutOfPlane) -> PointState {
    m.update(&voigt(0.0, 0.0, gamma, 0.0), committed, mode).0
}

fn assert_close(actual: f64, expected: f64, tol: f64, what: &str) {
    assert!(
        (actual - expected).abs() <= tol,
        "{what}: got {actual}, expected {expected} (diff {:e} > tol {tol:e})",
        (actual - expected).abs()
    );
}

/// Evenly spaced points from `a` (exclusive) to `b` (inclusive).
fn steps(a: f64, b: f64, n: usize) -> impl Iterator<Item = f64> {
    (1..=n).map(move |k| a + (b - a) * k as f64 / n as f64)
}

/// Uniaxial stress, loading → elastic unloading → reverse loading, in both out-of-plane
/// modes, against the exact bilinear curve:
/// - loading past ε_y = σ_Y/E: σ = σ_Y + E_t (ε − ε_y), E_t = E H/(E + H), ε̄ᵖ = ε − σ/E;
/// - unloading from (ε₁, σ₁): σ = σ₁ + E (ε − ε₁);
/// - isotropic hardening: reverse yielding at σ = −σ₁ = −(σ_Y + H ε̄ᵖ₁), i.e. at
///   ε_ry = ε₁ − 2σ₁/E, then σ = −σ₁ + E_t (ε − ε_ry).
#[test]
fn uniaxial_stress_follows_the_bilinear_curve_with_isotropic_reversal() {
    for h in [H, 0.0] {
        let m = material(h);
        let et = m.tangent_modulus();
        let ey = SY / E;
        for mode in MODES {
            let tol = 1e-9 * SY;
            let ctx = format!("{mode:?}, H = {h}");
            // Loading.
            let mut st = PointState::default();
            let e1 = 6.0 * ey;
            for eps in steps(0.0, e1, 30) {
                st = uniaxial(&m, &st, eps, mode);
                let exact = if eps <= ey {
                    E * eps
                } else {
                    SY + et * (eps - ey)
                };
                assert_close(st.stress[0], exact, tol, &format!("loading σ_xx, {ctx}"));
                assert_eq!(st.yielding, eps > ey, "{ctx} at ε = {eps}");
                let ep = st.plastic_strain;
                assert_close(ep[0], eps - exact / E, 1e-12, &format!("εᵖ_xx, {ctx}"));
                assert_close(ep[1], -0.5 * ep[0], 1e-15, &format!("εᵖ_yy, {ctx}"));
                assert_close(ep[ZZ], -0.5 * ep[0], 1e-15, &format!("εᵖ_zz, {ctx}"));
                assert_close(
                    st.equivalent_plastic_strain,
                    ep[0],
                    1e-12,
                    &format!("ε̄ᵖ, {ctx}"),
                );
            }
            let s1 = SY + et * (e1 - ey);
            let ep1 = e1 - s1 / E;
            assert_close(m.flow_stress(ep1), s1, 1e-9, "σ₁ = σ_Y + H ε̄ᵖ₁");
            let peak = st;

            // Elastic unloading down to just before the reverse yield point.
            let e_ry = e1 - 2.0 * s1 / E;
            for eps in steps(e1, e_ry + 1e-6 * ey, 20) {
                st = uniaxial(&m, &st, eps, mode);
                assert_close(
                    st.stress[0],
                    s1 + E * (eps - e1),
                    tol,
                    &format!("unloading, {ctx}"),
                );
                assert!(!st.yielding, "{ctx}: unloading must be elastic");
                assert_eq!(st.equivalent_plastic_strain, peak.equivalent_plastic_strain);
            }
            // Still elastic at −σ₁ + 0.2 MPa, yielding just beyond: the reverse yield stress
            // equals the current forward one.
            assert!(!uniaxial(&m, &peak, e_ry + 1e-6, mode).yielding, "{ctx}");
            let beyond = uniaxial(&m, &peak, e_ry - 1e-6, mode);
            assert!(beyond.yielding, "{ctx}");
            assert_close(
                beyond.stress[0],
                -s1 - et * 1e-6,
                tol,
                &format!("reverse yield, {ctx}"),
            );

            // Reverse loading.
            for eps in steps(st.strain[0], e_ry - 6.0 * ey, 30) {
                st = uniaxial(&m, &st, eps, mode);
                let exact = if eps >= e_ry {
                    s1 + E * (eps - e1)
                } else {
                    -s1 + et * (eps - e_ry)
                };
                assert_close(st.stress[0], exact, tol, &format!("reverse σ_xx, {ctx}"));
                // Reverse plastic strain magnitude Δ = E (ε_ry − ε)/(E + H).
                let d = (E * (e_ry - eps) / (E + h)).max(0.0);
                assert_close(
                    st.equivalent_plastic_strain,
                    ep1 + d,
                    1e-12,
                    &format!("reverse ε̄ᵖ, {ctx}"),
                );
                assert_close(
                    st.plastic_strain[0],
                    ep1 - d,
                    1e-12,
                    &format!("reverse εᵖ, {ctx}"),
                );
            }
        }
    }
}

fn assert_states_agree(a: &PointState, b: &PointState, rel: f64, what: &str) {
    let ds = (a.stress - b.stress).norm() / a.stress.norm();
    let dp = (a.plastic_strain - b.plastic_strain).norm() / a.plastic_strain.norm();
    let de = (a.equivalent_plastic_strain - b.equivalent_plastic_strain).abs()
        / a.equivalent_plastic_strain;
    let dstrain = (a.strain - b.strain).norm() / a.strain.norm();
    eprintln!("{what}: rel. diff stress {ds:.1e}, plastic strain {dp:.1e}, ε̄ᵖ {de:.1e}");
    assert!(
        ds <= rel && dp <= rel && de <= rel && dstrain <= rel,
        "{what}: {ds:e} {dp:e} {de:e} {dstrain:e}"
    );
}

/// Radial return with linear hardening is exact along paths of constant stress direction, so
/// 1 and 100 increments must agree to round-off.
#[test]
fn monotonic_segments_do_not_depend_on_the_number_of_increments() {
    for h in [H, 0.0, -20_000.0] {
        let m = material(h);
        let ey = SY / E;
        for mode in MODES {
            let ctx = format!("{mode:?}, H = {h}");
            // With softening the lateral-strain problem of the uniaxial driver has several
            // solutions (e.g. the fully softened σ = 0), so its local Newton iteration may
            // pick another branch in one big step; drive uniaxial stress only when H ≥ 0.
            if h >= 0.0 {
                // Uniaxial stress, loading 0 → 5ε_y.
                let one = uniaxial(&m, &PointState::default(), 5.0 * ey, mode);
                let mut many = PointState::default();
                for eps in steps(0.0, 5.0 * ey, 100) {
                    many = uniaxial(&m, &many, eps, mode);
                }
                assert_states_agree(&one, &many, 1e-10, &format!("uniaxial loading, {ctx}"));
                // ... then straight to reverse plastic loading (unloading + reverse yield in the
                // same increments): the stress stays uniaxial, so this is exact as well.
                let target = 5.0 * ey - 2.0 * von_mises(&one.stress) / E - 3.0 * ey;
                let one_r = uniaxial(&m, &one, target, mode);
                let mut many_r = one;
                for eps in steps(5.0 * ey, target, 100) {
                    many_r = uniaxial(&m, &many_r, eps, mode);
                }
                assert!(one_r.yielding && one_r.stress[0] < 0.0);
                assert_states_agree(&one_r, &many_r, 1e-10, &format!("uniaxial reversal, {ctx}"));
            }

            // Pure shear γ_xy (σ_zz = 0 by symmetry, so it is also a plane-stress path).
            let g_end = 5.0 * SY / (3f64.sqrt() * shear_modulus());
            let one = shear(&m, &PointState::default(), g_end, mode);
            let mut many = PointState::default();
            for g in steps(0.0, g_end, 100) {
                many = shear(&m, &many, g, mode);
            }
            assert_states_agree(&one, &many, 1e-10, &format!("pure shear, {ctx}"));
        }
        // A general radial strain path with given ε_zz (volumetric part included): the trial
        // deviator always points the same way, so the path is radial in stress space too.
        let dir = voigt(1.0, -0.4, 0.7, 0.25) * 1e-2;
        let (one, _) = m.update(&dir, &PointState::default(), OutOfPlane::StrainGiven);
        let mut many = PointState::default();
        for t in steps(0.0, 1.0, 100) {
            many = m.update(&(dir * t), &many, OutOfPlane::StrainGiven).0;
        }
        assert_states_agree(&one, &many, 1e-10, &format!("radial strain path, H = {h}"));
    }
}

/// Simple shear (only γ_xy), loading → unloading → reverse loading.
///
/// Exact solution: τ = G(γ − γᵖ), q = √3|τ|, and the flow rule
/// Δεᵖ = Δε̄ᵖ (3/2) s/q gives Δγᵖ = 2Δεᵖ_xy = √3 Δε̄ᵖ sign τ. Yield: √3 τ = σ_Y + H ε̄ᵖ, so
/// τ_y = σ_Y/√3 at γ_y = τ_y/G. While yielding √3 dτ = H dε̄ᵖ and dτ = G(dγ − √3 dε̄ᵖ)
/// = G dγ − 3G dτ/H, hence dτ/dγ = G_t = G H/(3G + H) (= 0 for perfect plasticity), i.e.
/// τ = τ_y + G_t (γ − γ_y) and ε̄ᵖ = γᵖ/√3 = (γ − τ/G)/√3. After loading to (γ₁, τ₁) the
/// unloading slope is G and reverse yielding starts at τ = −τ₁ (γ_ry = γ₁ − 2τ₁/G), then
/// τ = −τ₁ + G_t (γ − γ_ry).
#[test]
fn simple_shear_follows_the_exact_curve() {
    let g = shear_modulus();
    let ty = SY / 3f64.sqrt();
    let gy = ty / g;
    for h in [H, 0.0] {
        let m = material(h);
        let gt = g * h / (3.0 * g + h);
        for mode in MODES {
            let ctx = format!("{mode:?}, H = {h}");
            let tol = 1e-9 * ty;
            let check_state = |st: &PointState, tau: f64, what: &str| {
                assert_close(st.stress[2], tau, tol, &format!("{what} τ, {ctx}"));
                for i in [0, 1, ZZ] {
                    assert!(
                        st.stress[i].abs() <= tol,
                        "{what}: σ[{i}] = {}",
                        st.stress[i]
                    );
                }
                let gp = st.strain[2] - tau / g;
                assert_close(
                    st.plastic_strain[2],
                    gp,
                    1e-12,
                    &format!("{what} γᵖ, {ctx}"),
                );
                for i in [0, 1, ZZ] {
                    assert!(st.plastic_strain[i].abs() <= 1e-15);
                }
            };
            let mut st = PointState::default();
            let g1 = 6.0 * gy;
            for gam in steps(0.0, g1, 30) {
                st = shear(&m, &st, gam, mode);
                let tau = if gam <= gy {
                    g * gam
                } else {
                    ty + gt * (gam - gy)
                };
                check_state(&st, tau, "loading");
                assert_eq!(st.yielding, gam > gy, "{ctx}");
                let ebar = (gam - tau / g) / 3f64.sqrt();
                assert_close(st.equivalent_plastic_strain, ebar, 1e-12, "loading ε̄ᵖ");
                if st.yielding {
                    let sy = m.flow_stress(st.equivalent_plastic_strain);
                    assert_close(3f64.sqrt() * st.stress[2], sy, tol, "on the yield surface");
                }
            }
            let t1 = ty + gt * (g1 - gy);
            let ebar1 = st.equivalent_plastic_strain;
            let g_ry = g1 - 2.0 * t1 / g;
            for gam in steps(g1, g_ry + 1e-6 * gy, 20) {
                st = shear(&m, &st, gam, mode);
                check_state(&st, t1 + g * (gam - g1), "unloading");
                assert!(!st.yielding);
                assert_eq!(st.equivalent_plastic_strain, ebar1);
            }
            for gam in steps(st.strain[2], g_ry - 6.0 * gy, 30) {
                st = shear(&m, &st, gam, mode);
                let tau = if gam >= g_ry {
                    t1 + g * (gam - g1)
                } else {
                    -t1 + gt * (gam - g_ry)
                };
                check_state(&st, tau, "reverse");
                assert_eq!(st.yielding, gam < g_ry, "{ctx}");
                // ε̄ᵖ keeps growing: ε̄ᵖ₁ + |Δγᵖ|/√3.
                let gp1 = g1 - t1 / g;
                let ebar = ebar1 + (gp1 - (gam - tau / g)) / 3f64.sqrt();
                assert_close(st.equivalent_plastic_strain, ebar, 1e-12, "reverse ε̄ᵖ");
            }
        }
    }
}

/// Central finite differences of the stress update with respect to each strain component.
/// The strain components a mode's tangent acts on: all six (with the twist shears rθ, zθ)
/// at given out-of-plane strain, the in-plane four in plane stress (which has no twist).
fn components(mode: OutOfPlane) -> usize {
    match mode {
        OutOfPlane::StrainGiven => 6,
        OutOfPlane::StressFree => 4,
    }
}

fn finite_difference_tangent(
    m: &J2Plasticity,
    strain: &Voigt,
    committed: &PointState,
    mode: OutOfPlane,
) -> Tangent {
    let h = 1e-8 * strain.amax();
    let yielding = m.update(strain, committed, mode).0.yielding;
    let mut d = Tangent::zeros();
    for j in 0..components(mode) {
        let mut plus = *strain;
        let mut minus = *strain;
        plus[j] += h;
        minus[j] -= h;
        let (sp, _) = m.update(&plus, committed, mode);
        let (sm, _) = m.update(&minus, committed, mode);
        assert_eq!(sp.yielding, yielding, "perturbation changed the branch");
        assert_eq!(sm.yielding, yielding, "perturbation changed the branch");
        d.set_column(j, &((sp.stress - sm.stress) / (2.0 * h)));
    }
    d
}

#[test]
fn consistent_tangent_matches_finite_differences() {
    let mut worst: f64 = 0.0;
    for h in [H, 0.0, -40_000.0] {
        let m = material(h);
        for mode in MODES {
            // A committed state with nonzero plastic strain.
            let base = voigt(3e-3, -1e-3, 2.5e-3, 0.5e-3);
            let (committed, _) = m.update(&base, &PointState::default(), mode);
            assert!(committed.yielding && committed.equivalent_plastic_strain > 1e-3);

            // Elastic: halfway back to the stress-free configuration.
            let elastic =
                committed.plastic_strain + 0.5 * (committed.strain - committed.plastic_strain);
            let mut cases = vec![(elastic, false)];
            // Plastic loading in several directions (small and large increments, along and
            // across the current flow direction).
            let e_el = committed.strain - committed.plastic_strain;
            for inc in [
                e_el * 0.2,
                e_el * 0.5 + voigt(1e-3, 0.0, 0.0, 0.0),
                e_el * 0.5 + voigt(0.0, 0.0, 1.5e-3, 0.0),
                e_el * 0.3 + voigt(-1.0, 2.0, -3.0, 1.0) * 3e-5,
                voigt(1.0, 0.0, 0.0, 0.0) * 1e-3,
                voigt(5.0, -2.0, 4.0, 1.0) * 1e-3,
            ] {
                cases.push((committed.strain + inc, true));
            }
            if mode == OutOfPlane::StrainGiven {
                // Across the flow direction into the twist shears (rθ, zθ).
                let twist = Voigt::new(0.0, 0.0, 0.0, 0.0, 1.2e-3, -0.8e-3);
                cases.push((committed.strain + e_el * 0.5 + twist, true));
            }
            for (strain, plastic) in cases {
                let (state, d) = m.update(&strain, &committed, mode);
                assert_eq!(state.yielding, plastic, "{mode:?}, H = {h}, ε = {strain:?}");
                let fd = finite_difference_tangent(&m, &strain, &committed, mode);
                // A fully softened plane-stress point (σ_y = 0) has a zero tangent; measure the
                // error against the elastic stiffness there.
                let scale = d.norm().max(1e-3 * m.elastic.stiffness(mode).norm());
                let n = components(mode);
                let err = (fd - d).view((0, 0), (n, n)).norm() / scale;
                let sy = m.flow_stress(state.equivalent_plastic_strain);
                eprintln!(
                    "{mode:?} H = {h:>7} {} (σ_y = {sy:6.1}): |D_fd − D|/|D| = {err:.2e}",
                    if plastic { "plastic" } else { "elastic" }
                );
                worst = worst.max(err);
                assert!(err <= 1e-6, "{mode:?}, H = {h}, ε = {strain:?}: {err:e}");
                if mode == OutOfPlane::StressFree {
                    for i in 0..4 {
                        assert_eq!(d[(ZZ, i)], 0.0);
                        assert_eq!(d[(i, ZZ)], 0.0);
                    }
                }
            }
        }
    }
    eprintln!("worst tangent error {worst:.2e}");
}

/// A small deterministic generator of strain vectors in [−s, s]⁴.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    fn strain(&mut self, s: f64) -> Voigt {
        voigt(self.next(), self.next(), self.next(), self.next()) * s
    }
}

/// After every plastic return the stress lies on the updated yield surface, the plastic
/// strain stays deviatoric, and the ε̄ᵖ increment is √(2/3)‖Δεᵖ‖ (one backward-Euler step
/// has a single flow direction); in plane stress σ_zz = 0 and ε_zz is consistent.
#[test]
fn returned_states_are_on_the_yield_surface_and_plastically_incompressible() {
    let mut rng = Lcg(42);
    let mut worst_q: f64 = 0.0;
    let mut count = 0;
    for h in [H, 0.0, -20_000.0] {
        let m = material(h);
        for mode in MODES {
            let mut st = PointState::default();
            for _ in 0..200 {
                let strain = st.strain + rng.strain(2e-3);
                let (new, _) = m.update(&strain, &st, mode);
                if new.yielding {
                    count += 1;
                    let sy = m.flow_stress(new.equivalent_plastic_strain);
                    let q = von_mises(&new.stress);
                    let err = (q - sy).abs() / sy;
                    worst_q = worst_q.max(err);
                    assert!(err <= 1e-10, "{mode:?}, H = {h}: q = {q}, σ_y = {sy}");
                    let ep = new.plastic_strain;
                    let trace = ep[0] + ep[1] + ep[ZZ];
                    assert!(trace.abs() <= 1e-14 * ep.norm(), "trace εᵖ = {trace:e}");
                    let dep = new.plastic_strain - st.plastic_strain;
                    let norm =
                        (dep[0].powi(2) + dep[1].powi(2) + dep[ZZ].powi(2) + 0.5 * dep[2].powi(2))
                            .sqrt();
                    let debar = new.equivalent_plastic_strain - st.equivalent_plastic_strain;
                    assert!(((2.0f64 / 3.0).sqrt() * norm - debar).abs() <= 1e-12 * debar);
                } else {
                    assert_eq!(new.plastic_strain, st.plastic_strain);
                    assert!(von_mises(&new.stress) <= m.flow_stress(st.equivalent_plastic_strain));
                }
                if mode == OutOfPlane::StressFree {
                    assert_eq!(new.stress[ZZ], 0.0);
                    let ezz = -NU / E * (new.stress[0] + new.stress[1]) + new.plastic_strain[ZZ];
                    assert_close(new.strain[ZZ], ezz, 1e-15, "plane-stress ε_zz");
                }
                // Keep the softening case away from total loss of strength.
                if m.flow_stress(new.equivalent_plastic_strain) > 0.3 * SY {
                    st = new;
                }
            }
        }
    }
    eprintln!("{count} plastic returns, worst |q − σ_y|/σ_y = {worst_q:.2e}");
    assert!(count > 300);
}

#[test]
fn perfect_plasticity_has_a_flat_plateau() {
    let m = material(0.0);
    assert_eq!(m.tangent_modulus(), 0.0);
    for mode in MODES {
        let st = uniaxial(&m, &PointState::default(), 0.05, mode);
        assert_close(st.stress[0], SY, 1e-9 * SY, "plateau");
        assert_close(st.equivalent_plastic_strain, 0.05 - SY / E, 1e-12, "ε̄ᵖ");
    }
}

#[test]
fn bad_parameters_are_rejected_with_the_parameter_named() {
    let el = LinearElastic::new(E, NU).unwrap();
    for sy in [0.0, -10.0, f64::NAN, f64::INFINITY] {
        let err = J2Plasticity::new(el, sy, H).unwrap_err();
        assert_eq!(err.name, "yield_stress", "{err}");
    }
    // H ≤ −E always; with ν = 0.3 everything down to −E/(2(1 − ν)) ≈ −142857 MPa.
    for h in [
        -E,
        -2.0 * E,
        -0.8 * E,
        -E / 1.4,
        f64::NAN,
        f64::NEG_INFINITY,
    ] {
        let err = J2Plasticity::new(el, SY, h).unwrap_err();
        assert_eq!(err.name, "hardening", "{err}");
    }
    assert!(J2Plasticity::new(el, SY, -0.7 * E).is_ok());
    assert!(J2Plasticity::new(el, SY, 0.0).is_ok());
    let bad_elastic = LinearElastic { e: -1.0, nu: 0.3 };
    assert_eq!(J2Plasticity::new(bad_elastic, SY, H).unwrap_err().name, "E");
}
