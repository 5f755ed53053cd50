//! Cyclic plasticity at a material point against closed forms (issue 27): Armstrong–Frederick
//! and Chaboche kinematic hardening with Voce isotropic hardening in uniaxial stress.
//!
//! The reference is the uniaxial model integrated in closed form branch by branch: on a
//! plastic branch of direction s = ±1 starting from backstresses X_k0 and accumulated plastic
//! strain p0, after Δp of plastic flow X_k = s C_k/γ_k + (X_k0 − s C_k/γ_k) e^(−γ_k Δp)
//! (X_k0 + s C_k Δp for γ_k = 0), σ = Σ X_k + s σ_y(p0 + Δp) and ε = εᵖ0 + s Δp + σ/E; the
//! only numerics is the scalar root of ε(Δp) = target (bisection to round-off). The material
//! point is driven in plane stress with σ_yy = 0 enforced by Newton's method on ε_yy, so it
//! is in uniaxial stress. The return integrates the backstresses exactly along a fixed flow
//! direction, so the finite-element point must agree with the closed form to round-off at any
//! increment size: the tolerances (1e-9 relative, and the 1e-6 the issue asks for) leave
//! room only for the iterations' stopping tolerances.

use asperity::material::cyclic::{CyclicPlasticity, KinematicTerm, Voce};
use asperity::material::elastic::LinearElastic;
use asperity::material::{Material, OutOfPlane, PointState, voigt};

const E: f64 = 200_000.0;
const SIGMA_Y: f64 = 200.0;

fn material(h: f64, voce: Voce, kinematic: &[KinematicTerm]) -> CyclicPlasticity {
    let elastic = LinearElastic::new(E, 0.3).unwrap();
    CyclicPlasticity::new(elastic, SIGMA_Y, h, voce, kinematic).unwrap()
}

fn term(c: f64, gamma: f64) -> KinematicTerm {
    KinematicTerm { c, gamma }
}

/// A material point in uniaxial stress σ_xx (plane stress with σ_yy = 0).
struct Point {
    m: CyclicPlasticity,
    state: PointState,
    internal: Vec<f64>,
}

impl Point {
    fn new(m: CyclicPlasticity) -> Self {
        let internal = vec![0.0; m.internal_variables()];
        Self {
            m,
            state: PointState::default(),
            internal,
        }
    }

    /// Updates from the committed state to (ε_xx, ε_yy); returns the new state, the new
    /// internal variables and the (plane-stress) tangent.
    fn trial(&self, exx: f64, eyy: f64) -> (PointState, Vec<f64>, asperity::material::Tangent) {
        let mut internal = vec![0.0; self.internal.len()];
        let (s, d) = self.m.update_with_history(
            &voigt(exx, eyy, 0.0, 0.0),
            &self.state,
            &self.internal,
            &mut internal,
            OutOfPlane::StressFree,
        );
        (s, internal, d)
    }

    /// Strain control: ε_xx = `exx` with σ_yy = 0; commits and returns σ_xx.
    fn strain_to(&mut self, exx: f64) -> f64 {
        let mut eyy = self.state.strain[1];
        for _ in 0..50 {
            let (s, internal, d) = self.trial(exx, eyy);
            if s.stress[1].abs() <= 1e-10 {
                self.state = s;
                self.internal = internal;
                return self.state.stress[0];
            }
            eyy -= s.stress[1] / d[(1, 1)];
        }
        panic!("uniaxial strain control did not converge at {exx}");
    }

    /// Stress control: σ_xx = `sxx`, σ_yy = 0 by Newton's method on (ε_xx, ε_yy).
    fn stress_to(&mut self, sxx: f64) {
        let (mut exx, mut eyy) = (self.state.strain[0], self.state.strain[1]);
        for _ in 0..50 {
            let (s, internal, d) = self.trial(exx, eyy);
            let r = nalgebra::Vector2::new(s.stress[0] - sxx, s.stress[1]);
            if r.norm() <= 1e-10 {
                self.state = s;
                self.internal = internal;
                return;
            }
            let k = nalgebra::Matrix2::new(d[(0, 0)], d[(0, 1)], d[(1, 0)], d[(1, 1)]);
            let du = k.lu().solve(&r).unwrap();
            exx -= du[0];
            eyy -= du[1];
        }
        panic!("uniaxial stress control did not converge at {sxx}");
    }

    fn plastic_strain(&self) -> f64 {
        self.state.plastic_strain[0]
    }
}

/// The closed-form uniaxial model (module docs).
#[derive(Clone)]
struct Uniaxial {
    h: f64,
    voce: Voce,
    terms: Vec<KinematicTerm>,
    /// Plastic strain, accumulated plastic strain, backstresses, total strain.
    ep: f64,
    p: f64,
    x: Vec<f64>,
    eps: f64,
}

impl Uniaxial {
    fn new(h: f64, voce: Voce, terms: &[KinematicTerm]) -> Self {
        Self {
            h,
            voce,
            terms: terms.to_vec(),
            ep: 0.0,
            p: 0.0,
            x: vec![0.0; terms.len()],
            eps: 0.0,
        }
    }

    fn flow_stress(&self, p: f64) -> f64 {
        SIGMA_Y + self.h * p + self.voce.q * (1.0 - (-self.voce.b * p).exp())
    }

    /// Backstresses after Δp of flow in direction s.
    fn backstresses(&self, s: f64, dp: f64) -> Vec<f64> {
        self.terms
            .iter()
            .zip(&self.x)
            .map(|(t, &x0)| {
                if t.gamma == 0.0 {
                    x0 + s * t.c * dp
                } else {
                    let sat = s * t.c / t.gamma;
                    sat + (x0 - sat) * (-t.gamma * dp).exp()
                }
            })
            .collect()
    }

    fn stress_after(&self, s: f64, dp: f64) -> f64 {
        self.backstresses(s, dp).iter().sum::<f64>() + s * self.flow_stress(self.p + dp)
    }

    /// Strain control to `target`; returns the stress.
    fn strain_to(&mut self, target: f64) -> f64 {
        let s = (target - self.eps).signum();
        let elastic = E * (target - self.ep);
        let centre: f64 = self.x.iter().sum();
        self.eps = target;
        if s * (elastic - centre) <= self.flow_stress(self.p) {
            return elastic;
        }
        let strain = |dp: f64| self.ep + s * dp + self.stress_after(s, dp) / E;
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if s * (strain(mid) - target) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        self.commit(s, 0.5 * (lo + hi))
    }

    /// Stress control to `target` (reachable: the flow stress stays below it).
    fn stress_to(&mut self, target: f64) {
        let s = (target - E * (self.eps - self.ep)).signum();
        let centre: f64 = self.x.iter().sum();
        if s * (target - centre) <= self.flow_stress(self.p) {
            self.eps = self.ep + target / E;
            return;
        }
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if s * (self.stress_after(s, mid) - target) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let sigma = self.commit(s, 0.5 * (lo + hi));
        self.eps = self.ep + sigma / E;
    }

    fn commit(&mut self, s: f64, dp: f64) -> f64 {
        let sigma = self.stress_after(s, dp);
        self.x = self.backstresses(s, dp);
        self.p += dp;
        self.ep += s * dp;
        self.eps = self.ep + sigma / E;
        sigma
    }
}

/// Strain-controlled cycles between ±`amplitude` in `increments` per half cycle; returns the
/// peak (tensile) stress of every cycle.
fn peaks(point: &mut Point, amplitude: f64, cycles: usize, increments: usize) -> Vec<f64> {
    let mut peaks = Vec::new();
    let mut at = 0.0;
    for cycle in 0..cycles {
        let targets: &[f64] = if cycle == 0 {
            &[amplitude]
        } else {
            &[-amplitude, amplitude]
        };
        let mut sigma = 0.0;
        for &target in targets {
            for i in 1..=increments {
                sigma = point.strain_to(at + (target - at) * i as f64 / increments as f64);
            }
            at = target;
        }
        peaks.push(sigma);
    }
    peaks
}

fn closed_form_peaks(model: &mut Uniaxial, amplitude: f64, cycles: usize) -> Vec<f64> {
    (0..cycles)
        .map(|cycle| {
            if cycle > 0 {
                model.strain_to(-amplitude);
            }
            model.strain_to(amplitude)
        })
        .collect()
}

/// One Armstrong–Frederick backstress, monotonic: σ = σ_Y + (C/γ)(1 − e^(−γ εᵖ)).
#[test]
fn armstrong_frederick_monotonic_curve() {
    let (c, gamma) = (50_000.0, 250.0);
    let mut point = Point::new(material(0.0, Voce::default(), &[term(c, gamma)]));
    for i in 1..=60 {
        // Large increments on purpose: the return is exact along a fixed direction.
        let sigma = point.strain_to(5e-4 * i as f64);
        let ep = point.plastic_strain();
        let expected = if ep == 0.0 {
            E * 5e-4 * i as f64
        } else {
            SIGMA_Y + c / gamma * (1.0 - (-gamma * ep).exp())
        };
        assert!(
            (sigma - expected).abs() <= 1e-9 * expected,
            "ε = {}: σ = {sigma}, closed form {expected}",
            5e-4 * i as f64
        );
    }
    assert!(point.plastic_strain() > 0.02);
}

/// The stabilised loop of a symmetric strain cycle: X_max = (C/γ) tanh(γ εᵖ_a), so the peak
/// σ_max = σ_Y + (C/γ) tanh(γ (ε_a − σ_max/E)) (root of a scalar equation).
#[test]
fn armstrong_frederick_stabilised_loop_peak() {
    let (c, gamma, amplitude) = (50_000.0, 250.0, 6e-3);
    let mut point = Point::new(material(0.0, Voce::default(), &[term(c, gamma)]));
    let simulated = peaks(&mut point, amplitude, 40, 16);
    let (mut lo, mut hi) = (SIGMA_Y, SIGMA_Y + c / gamma);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        let rhs = SIGMA_Y + c / gamma * (gamma * (amplitude - mid / E)).tanh();
        if mid < rhs {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let stabilised = 0.5 * (lo + hi);
    let last = *simulated.last().unwrap();
    // The loop converges geometrically to the symmetric one; after 40 cycles it is there to
    // round-off, and the first peak differs visibly (the test could fail).
    assert!(
        (last - stabilised).abs() <= 1e-6 * stabilised,
        "{last} vs {stabilised}"
    );
    assert!((simulated[0] - stabilised).abs() > 1e-3 * stabilised);
}

/// Linear kinematic (Prager) hardening: after loading to σ_max, reverse yield at
/// σ_max − 2σ_Y (the Bauschinger effect); isotropic hardening would reverse at −σ_max.
#[test]
fn prager_bauschinger_reverse_yield() {
    let mut point = Point::new(material(0.0, Voce::default(), &[term(20_000.0, 0.0)]));
    let sigma_max = point.strain_to(8e-3);
    assert!(sigma_max > SIGMA_Y + 50.0);
    let p = point.state.equivalent_plastic_strain;
    let reverse = sigma_max - 2.0 * SIGMA_Y;
    // Elastic unloading to 0.1 MPa above the reverse yield stress: no flow.
    point.stress_to(reverse + 0.1);
    assert_eq!(point.state.equivalent_plastic_strain, p);
    // 0.1 MPa below it: flow.
    point.stress_to(reverse - 0.1);
    assert!(point.state.equivalent_plastic_strain > p);
    // The flow is what Prager gives: dσ = C E/(C + E) dε beyond reverse yield, i.e.
    // Δεᵖ = 0.1 / C.
    let dep = point.state.equivalent_plastic_strain - p;
    assert!((dep - 0.1 / 20_000.0).abs() <= 1e-9 * dep, "{dep}");
}

/// Chaboche with two backstresses (one of them Prager) and Voce isotropic hardening: the
/// peak stress of each strain cycle against the closed-form integration, to 1e-6.
#[test]
fn chaboche_two_terms_with_voce_peak_table() {
    let terms = [term(60_000.0, 400.0), term(4_000.0, 0.0)];
    let voce = Voce { q: 60.0, b: 15.0 };
    let h = 300.0;
    let amplitude = 5e-3;
    let mut point = Point::new(material(h, voce, &terms));
    let simulated = peaks(&mut point, amplitude, 10, 12);
    let expected = closed_form_peaks(&mut Uniaxial::new(h, voce, &terms), amplitude, 10);
    println!("cycle  peak (FE)  peak (closed form)");
    for (i, (s, e)) in simulated.iter().zip(&expected).enumerate() {
        println!("{:5}  {s:.9}  {e:.9}", i + 1);
        assert!(
            (s - e).abs() <= 1e-6 * e.abs(),
            "cycle {}: {s} vs {e}",
            i + 1
        );
    }
    // Voce hardening makes the peaks grow from cycle to cycle (the table is not constant).
    assert!(expected[9] > expected[1] + 1.0);
}

/// A stress cycle with mean stress, σ between σ_min and σ_max: linear kinematic hardening
/// shakes down plastically (the plastic strain at the peaks stops changing after the first
/// cycle), Armstrong–Frederick ratchets at the closed-form rate
/// δεᵖ = (1/γ) ln[(c² − X_lo²)/(c² − X_hi²)], c = C/γ, X_hi = σ_max − σ_Y, X_lo = σ_min + σ_Y.
#[test]
fn ratcheting_with_armstrong_frederick_not_with_prager() {
    let (sigma_max, sigma_min) = (380.0, -120.0);
    let cycle_peaks = |point: &mut Point| {
        let mut at_peak = Vec::new();
        for _ in 0..6 {
            for i in 1..=10 {
                point.stress_to(sigma_max * i as f64 / 10.0);
            }
            at_peak.push(point.plastic_strain());
            for i in 1..=10 {
                point.stress_to(sigma_max + (sigma_min - sigma_max) * i as f64 / 10.0);
            }
        }
        at_peak
    };

    let prager = cycle_peaks(&mut Point::new(material(
        0.0,
        Voce::default(),
        &[term(10_000.0, 0.0)],
    )));
    assert!(prager[0] > 1e-3);
    for w in prager.windows(2) {
        assert!((w[1] - w[0]).abs() <= 1e-12, "Prager ratchets: {prager:?}");
    }

    let (c, gamma) = (30_000.0, 100.0);
    let af = cycle_peaks(&mut Point::new(material(
        0.0,
        Voce::default(),
        &[term(c, gamma)],
    )));
    let sat = c / gamma;
    let (x_hi, x_lo) = (sigma_max - SIGMA_Y, sigma_min + SIGMA_Y);
    let rate = ((sat * sat - x_lo * x_lo) / (sat * sat - x_hi * x_hi)).ln() / gamma;
    assert!(rate > 1e-4);
    for w in af.windows(2) {
        let per_cycle = w[1] - w[0];
        assert!(
            (per_cycle - rate).abs() <= 1e-8 * rate,
            "{per_cycle} vs {rate}"
        );
    }
    // The stress-controlled reference model agrees with the same rate.
    let mut reference = Uniaxial::new(0.0, Voce::default(), &[term(c, gamma)]);
    reference.stress_to(sigma_max);
    let first = reference.ep;
    reference.stress_to(sigma_min);
    reference.stress_to(sigma_max);
    assert!((reference.ep - first - rate).abs() <= 1e-9 * rate);
}
