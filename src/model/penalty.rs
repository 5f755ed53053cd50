//! The default penalty stiffness of a contact pair whose case leaves a law's
//! `normal_stiffness` or `tangential_stiffness` out ([`ParameterDefault::Penalty`]).
//!
//! In the spirit of Abaqus/Standard's default penalty (ten times a representative stiffness
//! of the underlying elements): k = 10 E*/h, with
//! - E* the surface modulus of the two bodies in series, 1/E* = 1/E'_A + 1/E'_B,
//!   E' = E/(1 − ν²) (E in plane stress), the modulus a face of either body presses with;
//! - h the pair's mean interface element length (its length over its element count).
//!
//! E*/h is the stiffness per unit area of a layer of the bodies one element deep. The
//! surfaces' own compliance to the shortest pressure wave the mesh resolves is
//! c_B = h/(π E*) (Westergaard, see [`crate::element::interface6::surface_compliance`]), so the
//! penalty's compliance 1/k = h/(10 E*) is π/10 ≈ 0.3 of it: the joint deforms less than the
//! finest detail of the bodies the mesh can show, while the stiffness stays within a decade
//! of the elements' own, so the condensed solves and Newton's contact iterations keep their
//! conditioning. The price is an overlap of the faces of about p/k under contact pressure p
//! (an error of order h that vanishes as the mesh is refined), and in stick an elastic
//! slip p_T/k ≤ μ p/k.
//!
//! [`ParameterDefault::Penalty`]: crate::contact::laws::ParameterDefault::Penalty

/// The factor on E*/h.
pub const PENALTY_FACTOR: f64 = 10.0;

/// The default penalty stiffness a pair got, for the log and `run.json`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PenaltyDefault {
    /// The contact pair's name.
    pub contact: String,
    /// The law parameters set to `stiffness` (`normal_stiffness`, `tangential_stiffness`).
    pub parameters: Vec<&'static str>,
    /// k = factor · E*/h in MPa/mm.
    pub stiffness: f64,
    pub factor: f64,
    /// E* in MPa (the length-weighted mean over the pair's elements).
    pub surface_modulus: f64,
    /// h in mm.
    pub element_length: f64,
}

impl PenaltyDefault {
    /// The default of pair `contact` from its elements' (surface moduli of sides A and B,
    /// length): `None` for a pair without length or with two rigid sides.
    pub fn new(
        contact: &str,
        parameters: Vec<&'static str>,
        elements: impl Iterator<Item = ([f64; 2], f64)>,
    ) -> Option<Self> {
        let (mut count, mut length, mut weighted) = (0usize, 0.0, 0.0);
        for ([a, b], h) in elements {
            count += 1;
            length += h;
            weighted += h / (1.0 / a + 1.0 / b);
        }
        let surface_modulus = weighted / length;
        let element_length = length / count as f64;
        let stiffness = PENALTY_FACTOR * surface_modulus / element_length;
        (stiffness.is_finite() && stiffness > 0.0).then(|| Self {
            contact: contact.to_string(),
            parameters,
            stiffness,
            factor: PENALTY_FACTOR,
            surface_modulus,
            element_length,
        })
    }

    /// The log line: what was set, to what, from what, and the overlap it causes.
    pub fn describe(&self) -> String {
        format!(
            "contact '{}': {} not given, set to {:.4e} MPa/mm = {} E*/h (E* = {:.6e} MPa, mean \
             interface element length h = {:.4e} mm); the faces overlap by about p/k = {:.3e} mm \
             per MPa of contact pressure (docs/guide/contact-defaults.md)",
            self.contact,
            self.parameters.join(" and "),
            self.stiffness,
            self.factor,
            self.surface_modulus,
            self.element_length,
            1.0 / self.stiffness
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_is_ten_surface_moduli_in_series_over_the_mean_length() {
        // Steel on steel (E' = 2e5 each, E* = 1e5), elements 0.5 and 1.5 mm: h = 1 mm.
        let d = PenaltyDefault::new(
            "joint",
            vec!["normal_stiffness"],
            [([2e5, 2e5], 0.5), ([2e5, 2e5], 1.5)].into_iter(),
        )
        .unwrap();
        assert_eq!((d.surface_modulus, d.element_length), (1e5, 1.0));
        assert_eq!(d.stiffness, 1e6);
        // A rigid side: E* is the other body's modulus.
        let rigid = PenaltyDefault::new("r", vec![], [([2e5, f64::INFINITY], 2.0)].into_iter());
        assert!((rigid.unwrap().stiffness - 1e6).abs() < 1e-9);
        assert!(PenaltyDefault::new("none", vec![], std::iter::empty()).is_none());
    }
}
