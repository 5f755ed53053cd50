//! The first interface law: linear normal stiffness in compression with a tension cut-off,
//! linear tangential stiffness, and ideal Coulomb slip |p_T| ≤ μ|p_N| by radial return
//! (paper Box 1, corrected as in docs/theory.md, "Known misprints in the paper", 1–2: the trial stress starts from the converged
//! p_T,n, and the returned stress is p_T = μ|p_N| sign(p_T^tr)).
//!
//! With twist the tangential stress is the vector p_τ = (p_T, p_θ) and friction is
//! isotropic: p_τ^tr = k_T (u_τ − u_τ,n^p), F = |p_τ^tr| + μ p_N (Eq. 11 on the circle
//! |p_τ| ≤ μ|p_N|), and in slip the radial return p_τ = μ|p_N| n, n = p_τ^tr/|p_τ^tr|,
//! Δu_τ^p = (F/k_T) n. Its consistent tangent (unsymmetric):
//! ∂p_τ/∂u_τ = μ|p_N| k_T/|p_τ^tr| (I − n nᵀ) (only the direction turns),
//! ∂p_τ/∂u_N = −μ k_N n, ∂p_N/∂u_N = k_N. Without twist n = sign(p_T^tr) and the first
//! vanishes: the scalar law.

use super::laws::{Bound, LawDescriptor, ParameterDefault, ParameterDescriptor, check};
use super::{
    ContactStatus, InterfaceLaw, InterfaceState, InterfaceTangent, NORMAL, OPEN_TANGENT_FRACTION,
    diagonal_tangent, direction, length, slip_tangent, sticks, tangential,
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
        relative: [f64; 3],
        committed: &InterfaceState,
    ) -> (InterfaceState, InterfaceTangent) {
        let (kt, kn, mu) = (
            self.tangential_stiffness,
            self.normal_stiffness,
            self.friction,
        );
        let u_n = relative[NORMAL];
        let u_t = tangential(relative);
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
            let tangent = diagonal_tangent([kt, kn]) * OPEN_TANGENT_FRACTION;
            return (s, tangent);
        }
        let p_n = kn * u_n;
        let up = committed.plastic_slip;
        let trial = [kt * (u_t[0] - up[0]), kt * (u_t[1] - up[1])];
        let norm = length(trial);
        let f = norm + mu * p_n;
        if sticks(f, mu * p_n.abs(), committed) {
            s.stress = [trial[0], p_n, trial[1]];
            s.plastic_slip = up;
            s.status = ContactStatus::Stick;
            return (s, diagonal_tangent([kt, kn]));
        }
        // Radial return: Δλ = F / k_T brings the trial stress back onto |p_τ| = μ|p_N|.
        let n = direction(trial, norm);
        // f may be a round-off below 0 on the cone (see `sticks`): no backward slip.
        let dlambda = f.max(0.0) / kt;
        let limit = mu * p_n.abs();
        s.stress = [limit * n[0], p_n, limit * n[1]];
        s.plastic_slip = [up[0] + dlambda * n[0], up[1] + dlambda * n[1]];
        s.accumulated_slip += dlambda;
        s.status = ContactStatus::Slip;
        // Along n ideal plasticity (0); across it the direction turns with the trial stress
        // (none at a zero trial stress, frictionless); ∂p_τ/∂u_N = −μ k_N n: unsymmetric.
        let across = if norm > 0.0 { limit * kt / norm } else { 0.0 };
        let coupling = [-mu * kn * n[0], -mu * kn * n[1]];
        (s, slip_tangent(n, 0.0, across, coupling, kn))
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
        let (s, _) = law().update([0.01, 0.002, 0.0], &InterfaceState::default());
        assert_eq!(s.stress, [0.0; 3]);
        assert_eq!(s.status, ContactStatus::Open);
    }

    #[test]
    fn stick_then_slip_at_mu_times_pressure() {
        let l = law();
        let (s, _) = l.update([1e-4, -1e-3, 0.0], &InterfaceState::default());
        assert_eq!(s.status, ContactStatus::Stick);
        assert!((s.stress[0] - 4.0).abs() < 1e-12 && (s.stress[1] + 100.0).abs() < 1e-12);
        let (s, _) = l.update([1e-2, -1e-3, 0.0], &InterfaceState::default());
        assert_eq!(s.status, ContactStatus::Slip);
        assert!((s.stress[0] - 30.0).abs() < 1e-12);
        // The elastic part left is exactly μ|p_N| / k_T.
        assert!((1e-2 - s.plastic_slip[0] - 30.0 / 4e4).abs() < 1e-15);
    }

    #[test]
    fn tangent_matches_finite_differences_in_all_states() {
        let l = law();
        let committed = InterfaceState {
            plastic_slip: [2e-4, -1e-4],
            ..Default::default()
        };
        let cases = [
            [3e-4, -1e-3, 0.0],
            [5e-3, -1e-3, -1e-4],
            [-5e-3, -2e-3, -1e-4],
            [1e-3, -1e-3, 4e-3],
        ];
        for u in cases {
            let (_, k) = l.update(u, &committed);
            let h = 1e-9;
            for j in 0..3 {
                let (mut up, mut um) = (u, u);
                up[j] += h;
                um[j] -= h;
                let (sp, _) = l.update(up, &committed);
                let (sm, _) = l.update(um, &committed);
                for i in 0..3 {
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
