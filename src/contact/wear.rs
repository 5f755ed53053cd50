//! Wear of the surfaces of a contact pair: the local wear laws and a pair's wear model, which
//! the pair's interface elements apply next to its interface law
//! ([`crate::element::set::ContactPair`]).
//!
//! Wear depth h ≥ 0 (mm) removes material from a surface and so opens the gap: the interface
//! law of a worn point sees u_N + h_A + h_B (the committed depths; explicit in time, see
//! [`PointHistory::advanced`](super::PointHistory::advanced)). Two laws of the depth
//! increment over a slip increment Δu_T^p:
//! - Archard (Archard, J. Appl. Phys. 24 (1953) 981, in the local form of Põdra & Andersson,
//!   Tribol. Int. 32 (1999) 71): dh = k |p_N| |Δu_T^p|, k the dimensional wear coefficient
//!   in mm²/N = 1/MPa;
//! - dissipated energy (Fouvry, Kapsa & Vincent, Wear 200 (1996) 186: wear volume
//!   proportional to the accumulated dissipated energy, here per point):
//!   dh = α |p_T Δu_T^p|, α in 1/MPa.
//!
//! Each surface has its own coefficient (0: that surface does not wear).

use super::{NORMAL, dot, length, tangential};

/// Default stability limit of a wear jump: the depth a jump adds at a point may be at most
/// this fraction of the point's elastic closure |p_N| (1/k_N + ℓ/(π E*)), the interface and
/// the bodies' surfaces in series (see [`crate::solver::cycles`]).
pub const DEFAULT_JUMP_LIMIT: f64 = 0.5;

/// The local wear law.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WearLaw {
    /// dh = k |p_N| |Δu_T^p|.
    Archard,
    /// dh = α |p_T Δu_T^p|.
    Energy,
}

/// The wear of one contact pair (parameters checked by the case validation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WearModel {
    pub law: WearLaw,
    /// Coefficient of the surface of body A and of body B, 1/MPa (0: unworn).
    pub coefficients: [f64; 2],
    /// Largest total depth h_A + h_B (mm) before the interface counts as worn through.
    pub max_depth: Option<f64>,
    /// Fraction of the elastic closure |p_N| (1/k_N + ℓ/(π E*)) a wear jump may add at a
    /// point (0 < `jump_limit` ≤ 1, checked with the case).
    pub jump_limit: f64,
}

impl WearModel {
    /// Depth increments (h_A, h_B) of a closed point with stress (p_T, p_N, p_θ) that slipped
    /// by `slip` = Δu_τ^p = (Δu_T^p, Δu_θ^p).
    #[inline]
    pub fn increment(&self, stress: [f64; 3], slip: [f64; 2]) -> [f64; 2] {
        let intensity = match self.law {
            WearLaw::Archard => stress[NORMAL].abs() * length(slip),
            WearLaw::Energy => dot(tangential(stress), slip).abs(),
        };
        [
            self.coefficients[0] * intensity,
            self.coefficients[1] * intensity,
        ]
    }

    /// Short description for logs.
    pub fn describe(&self) -> String {
        let law = match self.law {
            WearLaw::Archard => "Archard dh = k |p_N| |du_slip|",
            WearLaw::Energy => "energy dh = alpha |p_T du_slip|",
        };
        format!(
            "{law}, coefficients A {} and B {} 1/MPa",
            self.coefficients[0], self.coefficients[1]
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn archard_uses_pressure_and_energy_uses_shear_work() {
        let model = |law| WearModel {
            law,
            coefficients: [2e-8, 0.0],
            max_depth: None,
            jump_limit: DEFAULT_JUMP_LIMIT,
        };
        // p_T = -30 MPa, p_N = -100 MPa, backward slip 1e-3 mm.
        let stress = [-30.0, -100.0, 0.0];
        let a = model(WearLaw::Archard).increment(stress, [-1e-3, 0.0]);
        assert_eq!(a, [2e-8 * 100.0 * 1e-3, 0.0]);
        let e = model(WearLaw::Energy).increment(stress, [-1e-3, 0.0]);
        assert_eq!(e, [2e-8 * 30.0 * 1e-3, 0.0]);
    }

    #[test]
    fn wear_follows_the_slip_vector() {
        let model = |law| WearModel {
            law,
            coefficients: [1e-8, 3e-8],
            max_depth: None,
            jump_limit: DEFAULT_JUMP_LIMIT,
        };
        // Slip (3, 4) µm, length 5 µm, at p_N = −100 MPa with the shear (24, 32) MPa along it
        // (|p_τ| = 40 MPa): Archard |p_N| · 5e-3, energy p_τ·Δu = 40 · 5e-3.
        let (stress, slip) = ([24.0, -100.0, 32.0], [3e-3, 4e-3]);
        let a = model(WearLaw::Archard).increment(stress, slip);
        let e = model(WearLaw::Energy).increment(stress, slip);
        for (got, intensity) in [(a, 100.0 * 5e-3), (e, 40.0 * 5e-3)] {
            for (g, k) in got.iter().zip([1e-8, 3e-8]) {
                assert!(
                    (g - k * intensity).abs() <= 1e-15 * k * intensity,
                    "{got:?}"
                );
            }
        }
    }
}
