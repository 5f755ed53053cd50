//! Isotropic linear elasticity.

use super::{LinearRange, Material, OutOfPlane, PointState, SHEAR, Tangent, Voigt, ZZ};
use crate::error::ParameterError;

/// Isotropic linear-elastic material with Young's modulus `e` (MPa) and Poisson's ratio `nu`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearElastic {
    pub e: f64,
    pub nu: f64,
}

impl LinearElastic {
    /// The modulus with which the surface of a half-space of this material resists a normal
    /// load: the plane-strain modulus E / (1 − ν²) of contact mechanics in plane strain and
    /// axisymmetry (the surface is locally in plane strain), E in plane stress.
    pub fn surface_modulus(&self, plane_stress: bool) -> f64 {
        if plane_stress {
            self.e
        } else {
            self.e / (1.0 - self.nu * self.nu)
        }
    }

    /// Checks the parameters: E > 0 and −1 < ν < 0.5.
    pub fn new(e: f64, nu: f64) -> Result<Self, ParameterError> {
        if !(e.is_finite() && e > 0.0) {
            return Err(ParameterError::new(
                "E",
                e,
                "Young's modulus must be positive",
            ));
        }
        if !(nu > -1.0 && nu < 0.5) {
            return Err(ParameterError::new(
                "nu",
                nu,
                "Poisson's ratio must lie in (-1, 0.5)",
            ));
        }
        Ok(Self { e, nu })
    }

    /// Shear modulus μ.
    pub fn shear_modulus(&self) -> f64 {
        self.e / (2.0 * (1.0 + self.nu))
    }

    /// Lamé's first parameter λ.
    pub fn lame_lambda(&self) -> f64 {
        self.e * self.nu / ((1.0 + self.nu) * (1.0 - 2.0 * self.nu))
    }

    /// Elasticity matrix for the given out-of-plane condition.
    pub fn stiffness(&self, out_of_plane: OutOfPlane) -> Tangent {
        let mut d = Tangent::zeros();
        match out_of_plane {
            OutOfPlane::StrainGiven => {
                let (l, m) = (self.lame_lambda(), self.shear_modulus());
                for i in [0, 1, ZZ] {
                    for j in [0, 1, ZZ] {
                        d[(i, j)] = l;
                    }
                    d[(i, i)] += 2.0 * m;
                }
                for i in SHEAR {
                    d[(i, i)] = m;
                }
            }
            OutOfPlane::StressFree => {
                let c = self.e / (1.0 - self.nu * self.nu);
                d[(0, 0)] = c;
                d[(1, 1)] = c;
                d[(0, 1)] = c * self.nu;
                d[(1, 0)] = c * self.nu;
                d[(2, 2)] = self.shear_modulus();
            }
        }
        d
    }

    /// The complementary energy density ½ σ:C⁻¹:σ = [(1 + ν) σ:σ − ν (tr σ)²] / 2E of a
    /// stress in Voigt order (xx, yy, xy, zz, xθ, yθ); σ_zz is 0 in plane stress, so one formula
    /// serves every analysis.
    pub fn complementary_energy(&self, s: &Voigt) -> f64 {
        let trace = s[0] + s[1] + s[ZZ];
        let normal = s[0] * s[0] + s[1] * s[1] + s[ZZ] * s[ZZ];
        let contracted = SHEAR.iter().fold(normal, |acc, &i| acc + 2.0 * s[i] * s[i]);
        ((1.0 + self.nu) * contracted - self.nu * trace * trace) / (2.0 * self.e)
    }

    /// The out-of-plane strain of a plane-stress state with in-plane strains εxx, εyy.
    pub fn plane_stress_zz_strain(&self, exx: f64, eyy: f64) -> f64 {
        -self.nu / (1.0 - self.nu) * (exx + eyy)
    }
}

impl Material for LinearElastic {
    fn is_linear(&self) -> bool {
        true
    }

    fn linear_range(&self, _committed: &PointState) -> Option<LinearRange> {
        Some(LinearRange {
            von_mises: f64::INFINITY,
            shear_modulus: self.shear_modulus(),
        })
    }

    fn update(
        &self,
        strain: &Voigt,
        _committed: &PointState,
        out_of_plane: OutOfPlane,
    ) -> (PointState, Tangent) {
        let d = self.stiffness(out_of_plane);
        let mut strain = *strain;
        if out_of_plane == OutOfPlane::StressFree {
            strain[ZZ] = self.plane_stress_zz_strain(strain[0], strain[1]);
        }
        let stress = d * strain;
        (
            PointState {
                strain,
                stress,
                ..PointState::default()
            },
            d,
        )
    }

    fn elastic_energy(&self, state: &PointState) -> f64 {
        self.complementary_energy(&state.stress)
    }

    fn describe(&self) -> String {
        format!("linear elastic, E = {} MPa, nu = {}", self.e, self.nu)
    }

    fn elastic(&self) -> &LinearElastic {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::voigt;

    #[test]
    fn uniaxial_stress_in_plane_stress_gives_poisson_contraction() {
        let m = LinearElastic::new(200_000.0, 0.3).unwrap();
        let eps = voigt(1e-3, -0.3e-3, 0.0, 0.0);
        let (s, _) = m.update(&eps, &PointState::default(), OutOfPlane::StressFree);
        assert!((s.stress[0] - 200.0).abs() < 1e-9);
        assert!(s.stress[1].abs() < 1e-9);
        assert!((s.strain[ZZ] + 0.3e-3).abs() < 1e-15);
    }

    #[test]
    fn uniaxial_stress_in_3d_form() {
        let m = LinearElastic::new(200_000.0, 0.25).unwrap();
        let eps = voigt(1e-3, -0.25e-3, 0.0, -0.25e-3);
        let (s, _) = m.update(&eps, &PointState::default(), OutOfPlane::StrainGiven);
        assert!((s.stress[0] - 200.0).abs() < 1e-9);
        assert!(s.stress[1].abs() < 1e-9 && s.stress[ZZ].abs() < 1e-9);
    }

    /// ½ σ:ε for a general strain equals the compliance form, in every analysis.
    #[test]
    fn elastic_energy_is_half_stress_times_strain() {
        let m = LinearElastic::new(70_000.0, 0.33).unwrap();
        let eps = voigt(1.2e-3, -0.4e-3, 0.9e-3, 0.3e-3);
        for mode in [OutOfPlane::StrainGiven, OutOfPlane::StressFree] {
            let (s, _) = m.update(&eps, &PointState::default(), mode);
            let work = 0.5 * s.stress.dot(&s.strain);
            assert!(
                (m.elastic_energy(&s) - work).abs() < 1e-12 * work,
                "{mode:?}"
            );
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(LinearElastic::new(-1.0, 0.3).is_err());
        assert!(LinearElastic::new(1.0, 0.5).is_err());
    }

    #[test]
    fn surface_modulus_is_plane_strain_except_in_plane_stress() {
        let m = LinearElastic::new(200_000.0, 0.3).unwrap();
        assert_eq!(m.surface_modulus(true), 200_000.0);
        assert!((m.surface_modulus(false) - 200_000.0 / 0.91).abs() < 1e-9);
    }
}
