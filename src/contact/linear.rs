//! The first interface law: linear normal stiffness in compression with a tension cut-off,
//! linear tangential stiffness, and ideal Coulomb slip |p_T| ≤ μ|p_N| by radial return
//! (paper Box 1, corrected as in docs/theory.md, "Known misprints in the paper", 1–2: the trial stress starts from the converged
//! p_T,n, and the returned stress is p_T = μ|p_N| sign(p_T^tr)).

use super::laws::{Bound, LawDescriptor, ParameterDefault, ParameterDescriptor, check};
use super::{
    ContactStatus, InterfaceLaw, InterfaceState, InterfaceTangent, OPEN_TANGENT_FRACTION, sticks,
};
use crate::error::ParameterError;

/// Linear penalty-type interface with Coulomb friction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearCoulomb {
    /// Normal stiffness k_N in MPa/mm (compression only).
    pub normal_stiffness: f64,
    /// Tangential stiffness k_T in MPa/mm.
    pub tangential_stiffness: f64,
    /// Coulomb coefficient μ (0: frictionless).
    pub friction: f64,
}

/// The law in the table of interface laws: `law = { type = "linear_coulomb", ... }`.
pub const LAW: LawDescriptor = LawDescriptor {
    name: "linear_coulomb",
    doc: "Linear normal stiffness (compression only), linear tangential stiffness and ideal\n\
          Coulomb friction.",
    parameters: &[
        ParameterDescriptor {
            key: "normal_stiffness",
            unit: "MPa/mm",
            default: ParameterDefault::Penalty,
            bound: Bound::Positive,
            doc: "k_N in MPa/mm. Default: 10 E*/h, E* the surface modulus of the two bodies\n\
                  (1/E* = (1 − ν_A²)/E_A + (1 − ν_B²)/E_B; E in plane stress) and h the pair's\n\
                  mean interface element length, written to the log and run.json. The faces\n\
                  then overlap by about p/k_N under contact pressure p (docs/guide/contact-defaults.md).",
        },
        ParameterDescriptor {
            key: "tangential_stiffness",
            unit: "MPa/mm",
            default: ParameterDefault::Penalty,
            bound: Bound::Positive,
            doc: "k_T in MPa/mm. Default: the same 10 E*/h as `normal_stiffness`'s default; a\n\
                  sticking point then slips elastically by p_T/k_T ≤ μ p/k_N.",
        },
        ParameterDescriptor {
            key: "friction",
            unit: "",
            default: ParameterDefault::Value(0.0),
            bound: Bound::NonNegative,
            doc: "Coulomb coefficient μ (default 0: frictionless).",
        },
    ],
    build: |x| Ok(Box::new(LinearCoulomb::new(x[0], x[1], x[2])?)),
    unused: |_| None,
};

impl LinearCoulomb {
    /// Checks k_N > 0, k_T > 0, μ ≥ 0 (the bounds of [`LAW`]).
    pub fn new(
        normal_stiffness: f64,
        tangential_stiffness: f64,
        friction: f64,
    ) -> Result<Self, ParameterError> {
        check(
            LAW.parameters,
            &[normal_stiffness, tangential_stiffness, friction],
        )?;
        Ok(Self {
            normal_stiffness,
            tangential_stiffness,
            friction,
        })
    }
}

impl InterfaceLaw for LinearCoulomb {
    fn update(
        &self,
        relative: [f64; 2],
        committed: &InterfaceState,
    ) -> (InterfaceState, InterfaceTangent) {
        let (kt, kn, mu) = (
            self.tangential_stiffness,
            self.normal_stiffness,
            self.friction,
        );
        let [u_t, u_n] = relative;
        let mut s = InterfaceState {
            relative,
            accumulated_slip: committed.accumulated_slip,
            max_closure: committed.max_closure.max(-u_n),
            friction: mu,
            stiffness: [kt, kn],
            ..InterfaceState::default()
        };
        if u_n > 0.0 {
            // Open: no stress. (Faces exactly touching, u_N = 0, count as closed with zero
            // stress, so bodies resting on each other start with the contact stiffness.) The tangential reference follows the face, so a point that
            // closes again starts without tangential stress.
            s.plastic_slip = u_t;
            s.status = ContactStatus::Open;
            let tangent = InterfaceTangent::new(kt, 0.0, 0.0, kn) * OPEN_TANGENT_FRACTION;
            return (s, tangent);
        }
        let p_n = kn * u_n;
        let trial = kt * (u_t - committed.plastic_slip);
        let f = trial.abs() + mu * p_n;
        if sticks(f, mu * p_n.abs(), committed) {
            s.stress = [trial, p_n];
            s.plastic_slip = committed.plastic_slip;
            s.status = ContactStatus::Stick;
            return (s, InterfaceTangent::new(kt, 0.0, 0.0, kn));
        }
        // Return map: Δλ = F / k_T brings the trial stress back onto |p_T| = μ|p_N|.
        let sign = trial.signum();
        // f may be a round-off below 0 on the cone (see `sticks`): no backward slip.
        let dlambda = f.max(0.0) / kt;
        s.stress = [mu * p_n.abs() * sign, p_n];
        s.plastic_slip = committed.plastic_slip + dlambda * sign;
        s.accumulated_slip += dlambda;
        s.status = ContactStatus::Slip;
        // ∂p_T/∂u_T = 0 (ideal plasticity), ∂p_T/∂u_N = −μ k_N sign: unsymmetric.
        (s, InterfaceTangent::new(0.0, -mu * kn * sign, 0.0, kn))
    }

    fn carries_shear(&self) -> bool {
        self.friction > 0.0 && self.tangential_stiffness > 0.0
    }

    fn describe(&self) -> String {
        format!(
            "linear Coulomb, k_N = {} MPa/mm, k_T = {} MPa/mm, mu = {}",
            self.normal_stiffness, self.tangential_stiffness, self.friction
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> LinearCoulomb {
        LinearCoulomb::new(1e5, 4e4, 0.3).unwrap()
    }

    #[test]
    fn open_carries_no_stress() {
        let (s, _) = law().update([0.01, 0.002], &InterfaceState::default());
        assert_eq!(s.stress, [0.0, 0.0]);
        assert_eq!(s.status, ContactStatus::Open);
    }

    #[test]
    fn stick_then_slip_at_mu_times_pressure() {
        let l = law();
        let (s, _) = l.update([1e-4, -1e-3], &InterfaceState::default());
        assert_eq!(s.status, ContactStatus::Stick);
        assert!((s.stress[0] - 4.0).abs() < 1e-12 && (s.stress[1] + 100.0).abs() < 1e-12);
        let (s, _) = l.update([1e-2, -1e-3], &InterfaceState::default());
        assert_eq!(s.status, ContactStatus::Slip);
        assert!((s.stress[0] - 30.0).abs() < 1e-12);
        // The elastic part left is exactly μ|p_N| / k_T.
        assert!((1e-2 - s.plastic_slip - 30.0 / 4e4).abs() < 1e-15);
    }

    #[test]
    fn tangent_matches_finite_differences_in_all_states() {
        let l = law();
        let committed = InterfaceState {
            plastic_slip: 2e-4,
            ..Default::default()
        };
        for u in [[3e-4, -1e-3], [5e-3, -1e-3], [-5e-3, -2e-3]] {
            let (_, k) = l.update(u, &committed);
            let h = 1e-9;
            for j in 0..2 {
                let (mut up, mut um) = (u, u);
                up[j] += h;
                um[j] -= h;
                let (sp, _) = l.update(up, &committed);
                let (sm, _) = l.update(um, &committed);
                for i in 0..2 {
                    let fd = (sp.stress[i] - sm.stress[i]) / (2.0 * h);
                    assert!(
                        (fd - k[(i, j)]).abs() < 1e-6 * 1e5,
                        "u {u:?} ({i},{j}): fd {fd} vs {}",
                        k[(i, j)]
                    );
                }
            }
        }
    }
}
