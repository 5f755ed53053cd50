//! Von Mises (J2) plasticity with linear isotropic hardening, integrated implicitly.
//!
//! The paper integrates bulk plasticity explicitly with sub-increments; we use the implicit
//! (backward-Euler) return map instead, because it is unconditionally stable, exact for
//! proportional stress paths with linear hardening (so results do not depend on the step
//! size along such paths) and has an algorithmically consistent tangent that gives the global
//! Newton–Raphson iteration its quadratic convergence (docs/theory.md, "J2 plasticity of the bodies").
//!
//! # Model
//! - Yield function f = q(σ) − σ_y(ε̄ᵖ), with the von Mises equivalent stress
//!   q = √(3/2 s:s) (s the stress deviator) and the flow stress
//!   σ_y(ε̄ᵖ) = max(σ_Y + H ε̄ᵖ, 0).
//! - `H` is the **plastic** hardening modulus, the slope of uniaxial stress against uniaxial
//!   plastic strain. The slope of the uniaxial stress–total-strain curve (the tangent
//!   modulus) is E_t = E H / (E + H); see [`J2Plasticity::tangent_modulus`].
//! - Associative flow ε̇ᵖ = ε̄̇ᵖ · (3/2) s / q, so ε̄ᵖ = ∫ √(2/3 ε̇ᵖ:ε̇ᵖ) dt and the plastic
//!   strain is deviatoric (εᵖ_xx + εᵖ_yy + εᵖ_zz = 0).
//! - The floor at zero only matters for softening (H < 0): once σ_Y + H ε̄ᵖ reaches zero the
//!   point is *fully softened*, carries no deviatoric stress and its flow stress stays zero.
//!
//! # Conventions
//! - `PointState::plastic_strain` is a Voigt vector in the solver's order (xx, yy, xy, zz)
//!   with **engineering** shear, `plastic_strain[2] = γᵖ_xy = 2 εᵖ_xy`, exactly like the total
//!   strain, so the elastic strain is simply `strain − plastic_strain`.
//! - `PointState::equivalent_plastic_strain` is ε̄ᵖ (accumulated, never decreasing).
//! - `PointState::yielding` is true when the update took a plastic step.
//! - In plane stress ([`OutOfPlane::StressFree`]) `plastic_strain[3] = −(εᵖ_xx + εᵖ_yy)` (plastic
//!   incompressibility; it carries no independent history) and `strain[3]` returns the total
//!   out-of-plane strain ε_zz = −ν/E (σ_xx + σ_yy) + εᵖ_zz.
//! - The elastic/plastic decision uses the relative tolerance [`YIELD_TOL`], so re-evaluating a
//!   converged plastic state at the same strain is an elastic (no-op) update despite round-off.
//!
//! # Algorithms
//! - Given out-of-plane strain (plane strain, axisymmetry): classical radial return, Simo &
//!   Hughes, *Computational Inelasticity* (1998), Box 3.1, with the consistent tangent of
//!   Box 3.2 (§3.3); also de Souza Neto, Perić & Owen, *Computational Methods for Plasticity*
//!   (2008), ch. 7. With linear hardening the consistency condition is linear in Δγ and is
//!   solved in closed form.
//! - Plane stress: the plane-stress-projected return of Simo & Taylor (1986, IJNME 22,
//!   649–670), Simo & Hughes §3.4 and de Souza Neto et al. ch. 9 (Box 9.4): the return is done
//!   in the in-plane components only, where the yield condition is a nonlinear scalar equation
//!   in Δγ (even with linear hardening) solved by a bracketed Newton iteration to round-off;
//!   the consistent tangent is the corresponding 3×3 in-plane matrix.
//!
//! Softening (H < 0) is allowed down to the bound documented on [`J2Plasticity::new`], but a
//! boundary-value problem with a softening local continuum is ill posed: its results depend
//! on the mesh (strain localises into one band of elements). Use it with care.

use nalgebra::{Matrix3, Vector3};

use super::elastic::LinearElastic;
use super::{
    LinearRange, Material, OutOfPlane, PointState, SHEAR, Tangent, Voigt, ZZ, bracketed_root,
    engineering, identity, voigt, von_mises,
};
use crate::error::ParameterError;

/// Relative tolerance of the elastic/plastic decision: a trial state with
/// q_tr − σ_y(ε̄ᵖ_n) ≤ `YIELD_TOL` · σ_y(ε̄ᵖ_n) is elastic. It keeps round-off from turning a
/// point that sits on the yield surface after a converged step into a spurious plastic one.
pub const YIELD_TOL: f64 = 1e-12;

/// J2 plasticity with linear isotropic hardening: yield stress σ_y(ε̄ᵖ) = σ_Y + H ε̄ᵖ, where H
/// is the PLASTIC hardening modulus (slope of stress vs plastic strain in uniaxial tension;
/// the tangent modulus is E_t = E H / (E + H)). See the module docs for conventions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct J2Plasticity {
    /// Elastic part; its [`LinearElastic::stiffness`] is the elastic predictor.
    pub elastic: LinearElastic,
    /// Initial uniaxial yield stress σ_Y (MPa).
    pub yield_stress: f64,
    /// Plastic hardening modulus H (MPa); 0 is perfect plasticity, negative is softening.
    pub hardening: f64,
}

impl J2Plasticity {
    /// Checks the parameters.
    ///
    /// - `yield_stress` σ_Y must be positive and finite.
    /// - `hardening` H must be finite and exceed [`Self::min_hardening`] = −E / (2(1 − ν)).
    ///
    /// Why that bound and not just H > −E (no snap-back in uniaxial stress) or H > −3G (the
    /// bound of the 3D radial return): at fixed total strain the return solves
    /// q(λ) = σ_y(ε̄ᵖ_n + λ) for the plastic increment λ = Δε̄ᵖ, and q falls with λ at a rate
    /// that depends on the stress state: exactly 3G when ε_zz is given, and in plane stress at
    /// least E/(2(1 − ν)) (because q·(1 + Δγ E/(3(1 − ν))) is non-increasing in the multiplier
    /// Δγ, see `update_stress_free`), a rate attained in equibiaxial states. The return has a
    /// unique solution for every state under both out-of-plane conditions exactly when H is
    /// above minus the slowest rate; since E/(2(1 − ν)) ≤ E ≤ 3G for ν ≤ ½, this bound implies
    /// H > −E and H > −3G.
    pub fn new(
        elastic: LinearElastic,
        yield_stress: f64,
        hardening: f64,
    ) -> Result<Self, ParameterError> {
        let elastic = LinearElastic::new(elastic.e, elastic.nu)?;
        if !(yield_stress.is_finite() && yield_stress > 0.0) {
            return Err(ParameterError::new(
                "yield_stress",
                yield_stress,
                "the yield stress (MPa) must be positive and finite",
            ));
        }
        let bound = Self::min_hardening(&elastic);
        if !(hardening.is_finite() && hardening > bound) {
            return Err(ParameterError::new(
                "hardening",
                hardening,
                format!(
                    "the hardening modulus H (MPa) must be finite and greater than \
                     -E/(2(1-nu)) = {bound} MPa (softening steeper than that has no unique \
                     stress update; H <= -E is always rejected)"
                ),
            ));
        }
        Ok(Self {
            elastic,
            yield_stress,
            hardening,
        })
    }

    /// The exclusive lower bound −E/(2(1 − ν)) on the hardening modulus (see [`Self::new`]).
    pub fn min_hardening(elastic: &LinearElastic) -> f64 {
        -elastic.e / (2.0 * (1.0 - elastic.nu))
    }

    /// Flow stress σ_y(ε̄ᵖ) = max(σ_Y + H ε̄ᵖ, 0).
    pub fn flow_stress(&self, equivalent_plastic_strain: f64) -> f64 {
        (self.yield_stress + self.hardening * equivalent_plastic_strain).max(0.0)
    }

    /// Slope dσ_y/dε̄ᵖ: H, or 0 once a softening material is fully softened.
    fn hardening_at(&self, equivalent_plastic_strain: f64) -> f64 {
        if self.yield_stress + self.hardening * equivalent_plastic_strain > 0.0 {
            self.hardening
        } else {
            0.0
        }
    }

    /// Uniaxial tangent modulus E_t = E H / (E + H), the slope of the uniaxial stress–strain
    /// curve during plastic loading (from dσ = H dεᵖ and dε = dσ/E + dεᵖ).
    pub fn tangent_modulus(&self) -> f64 {
        let e = self.elastic.e;
        e * self.hardening / (e + self.hardening)
    }

    /// Radial return with given ε_zz (Simo & Hughes Box 3.1) and its consistent tangent
    /// (Box 3.2). Here Δγ is the increment of ε̄ᵖ, so Simo & Hughes' Δγ is √(3/2) times ours.
    fn update_strain_given(&self, strain: &Voigt, committed: &PointState) -> (PointState, Tangent) {
        let c = self.elastic.stiffness(OutOfPlane::StrainGiven);
        let g = self.elastic.shear_modulus();
        let ep_n = committed.equivalent_plastic_strain;
        let sy_n = self.flow_stress(ep_n);

        // Elastic predictor: σ_tr = C (ε − εᵖ_n); both strains use engineering shear.
        let sigma_tr = c * (strain - committed.plastic_strain);
        let q_tr = von_mises(&sigma_tr);
        let mut state = PointState {
            strain: *strain,
            stress: sigma_tr,
            plastic_strain: committed.plastic_strain,
            equivalent_plastic_strain: ep_n,
            yielding: false,
        };
        if q_tr - sy_n <= YIELD_TOL * sy_n {
            return (state, c);
        }

        // Plastic corrector. The deviator shrinks radially, s = θ s_tr, so
        // q = q_tr − 3G Δγ and the consistency q = σ_y_n + H Δγ gives Δγ = f_tr / (3G + H).
        let m = identity();
        let p = (sigma_tr[0] + sigma_tr[1] + sigma_tr[ZZ]) / 3.0;
        let s_tr = sigma_tr - p * m;
        let h = self.hardening_at(ep_n);
        let mut dgamma = (q_tr - sy_n) / (3.0 * g + h);
        let (theta, h_alg) = if sy_n + h * dgamma > 0.0 {
            (1.0 - 3.0 * g * dgamma / q_tr, h)
        } else {
            // Softening past zero strength (or already there): σ_y = 0, so q = 0.
            dgamma = q_tr / (3.0 * g);
            (0.0, 0.0)
        };
        state.stress = p * m + theta * s_tr;

        // Unit flow direction n = s_tr / ‖s_tr‖ in tensor components (‖s‖ = √(2/3) q);
        // Δεᵖ = √(3/2) Δγ n, written to Voigt with engineering shear (×2 on the shears).
        let n = s_tr * (1.5_f64.sqrt() / q_tr);
        state.plastic_strain += engineering(&(n * (1.5_f64.sqrt() * dgamma)));
        state.equivalent_plastic_strain += dgamma;
        state.yielding = true;

        // C_ep = K 1⊗1 + 2Gθ I_dev − 2Gθ̄ n⊗n = C − 2G(1 − θ) I_dev − 2Gθ̄ n⊗n with
        // θ̄ = 1/(1 + H/3G) − (1 − θ). As a Voigt matrix acting on engineering strain, the
        // symmetric identity has ½ on the shear diagonal, and n⊗n uses the tensor components
        // of n (n : dε = n_xx dε_xx + … + n_xy γ_xy).
        let theta_bar = 1.0 / (1.0 + h_alg / (3.0 * g)) - (1.0 - theta);
        let mut identity_diagonal = m;
        SHEAR.iter().for_each(|&i| identity_diagonal[i] = 0.5);
        let i_dev = Tangent::from_diagonal(&identity_diagonal) - m * m.transpose() / 3.0;
        let tangent = c - 2.0 * g * (1.0 - theta) * i_dev - 2.0 * g * theta_bar * n * n.transpose();
        (state, tangent)
    }

    /// Plane-stress-projected return (Simo & Taylor 1986; Simo & Hughes §3.4).
    ///
    /// In-plane vectors σ = (σ_xx, σ_yy, σ_xy), ε = (ε_xx, ε_yy, γ_xy). With
    /// P = [[2, −1, 0], [−1, 2, 0], [0, 0, 6]] / 3 one has σᵀPσ = s:s (σ_zz = 0), the yield
    /// condition reads ½ σᵀPσ = ⅓ σ_y² and the flow εᵖ ← εᵖ_n + Δγ P σ (engineering shear,
    /// here Δγ is Simo's multiplier, not Δε̄ᵖ). Backward Euler gives
    /// σ = Ξ(Δγ) C⁻¹ σ_tr with Ξ = (C⁻¹ + Δγ P)⁻¹. C and P share the eigenvectors
    /// (1, 1, 0)/√2, (1, −1, 0)/√2, (0, 0, 1) with eigenvalues c = (E/(1 − ν), 2G, G) and
    /// p = (⅓, 1, 2), so in that basis everything is diagonal:
    /// σ̂_i = â_i / (1 + Δγ c_i p_i), ξ(Δγ) = σᵀPσ = Σ p_i σ̂_i², q = √(3/2 ξ), and the plastic
    /// increment Δε̄ᵖ = Δγ √(2/3 ξ) = ⅔ Δγ q.
    ///
    /// The consistency condition q(Δγ) = σ_y(ε̄ᵖ_n + ⅔ Δγ q) (Simo's ½ξ − ⅓σ_y² = 0) is solved in
    /// the reciprocal form F(Δγ) = 1/σ_y − 1/q = 0: 1/q is exactly linear in Δγ when a single
    /// mode is active, so Newton needs few iterations (in the tests 4–6 including the final
    /// round-off step, at most 9, against up to 16 for the residual q − σ_y). The iteration is
    /// safeguarded by a bisection bracket. The root is unique: with α = min c_i p_i =
    /// E/(3(1 − ν)), q·(1 + αΔγ) is non-increasing in Δγ, so q falls with Δε̄ᵖ at a rate of at
    /// least 3α/2 = E/(2(1 − ν)), which beats any softening allowed by [`Self::new`]; hence
    /// q − σ_y, and with it the sign of F, changes once.
    fn update_stress_free(&self, strain: &Voigt, committed: &PointState) -> (PointState, Tangent) {
        let c4 = self.elastic.stiffness(OutOfPlane::StressFree);
        let c: Matrix3<f64> = c4.fixed_view::<3, 3>(0, 0).into_owned();
        let (e, nu) = (self.elastic.e, self.elastic.nu);
        let ep_n = committed.equivalent_plastic_strain;
        let sy_n = self.flow_stress(ep_n);

        let eps = Vector3::new(strain[0], strain[1], strain[2]);
        let epp_n = Vector3::new(
            committed.plastic_strain[0],
            committed.plastic_strain[1],
            committed.plastic_strain[2],
        );
        let sigma_tr = c * (eps - epp_n);

        // Common eigenbasis of C and P (Q is symmetric and its own inverse).
        let r = std::f64::consts::FRAC_1_SQRT_2;
        let q_basis = Matrix3::new(r, r, 0.0, r, -r, 0.0, 0.0, 0.0, 1.0);
        #[rustfmt::skip]
        let proj = Matrix3::new(
            2.0 / 3.0, -1.0 / 3.0, 0.0,
            -1.0 / 3.0, 2.0 / 3.0, 0.0,
            0.0, 0.0, 2.0,
        );
        let c_diag = (q_basis * c * q_basis).diagonal();
        let p_diag = (q_basis * proj * q_basis).diagonal();
        let a = q_basis * sigma_tr;
        let modes = Modes {
            c: c_diag.into(),
            p: p_diag.into(),
            a: a.into(),
        };

        let q_tr = (1.5 * modes.xi(0.0)).sqrt();
        let finish = |stress: Vector3<f64>, plastic: Vector3<f64>, ep: f64, yielding: bool| {
            let ep_zz = -(plastic[0] + plastic[1]);
            let e_zz = -nu / e * (stress[0] + stress[1]) + ep_zz;
            PointState {
                strain: voigt(strain[0], strain[1], strain[2], e_zz),
                stress: voigt(stress[0], stress[1], stress[2], 0.0),
                plastic_strain: voigt(plastic[0], plastic[1], plastic[2], ep_zz),
                equivalent_plastic_strain: ep,
                yielding,
            }
        };
        if q_tr - sy_n <= YIELD_TOL * sy_n {
            return (finish(sigma_tr, epp_n, ep_n, false), c4);
        }

        let h = self.hardening;
        // Limit of Δε̄ᵖ as Δγ → ∞ (the whole trial elastic strain turned plastic):
        // λ_∞ = ⅔ √(3/2) √(Σ p_i â_i² / (c_i p_i)²).
        let lambda_inf = (2.0 / 3.0
            * (0..3)
                .map(|i| modes.a[i].powi(2) / (modes.c[i].powi(2) * modes.p[i]))
                .sum::<f64>())
        .sqrt();
        let sy_inf = self.yield_stress + h * (ep_n + lambda_inf);
        if sy_n <= 0.0 || (h < 0.0 && sy_inf <= 0.0) {
            // Fully softened: σ_y reaches 0 before q does, so q > σ_y for every finite Δγ and
            // the return is the limit Δγ → ∞: σ = 0, all of the trial elastic strain
            // C⁻¹σ_tr = ε − εᵖ_n becomes plastic, and the tangent is zero.
            let dep = eps - epp_n;
            let dep_zz = -(dep[0] + dep[1]);
            let norm2 = dep[0].powi(2) + dep[1].powi(2) + dep_zz.powi(2) + 0.5 * dep[2].powi(2);
            let ep = ep_n + (2.0 / 3.0 * norm2).sqrt();
            return (finish(Vector3::zeros(), eps, ep, true), Tangent::zeros());
        }

        // Bracket: F(0) > 0 since q_tr > σ_y_n, and since q(Δγ) ≤ q_tr / (1 + α Δγ) with
        // α = min c_i p_i while σ_y ≥ σ_min > 0 on the reachable range, F(hi) ≤ 0 for
        // hi = (q_tr/σ_min − 1)/α.
        let alpha = (0..3)
            .map(|i| modes.c[i] * modes.p[i])
            .fold(f64::INFINITY, f64::min);
        let sy_min = if h < 0.0 { sy_inf } else { sy_n };
        let hi = (q_tr / sy_min - 1.0) / alpha;
        let residual = |dg: f64| {
            let xi = modes.xi(dg);
            let q = (1.5 * xi).sqrt();
            let dq = 0.75 * modes.dxi(dg) / q;
            let ep = ep_n + 2.0 / 3.0 * dg * q;
            let dep = 2.0 / 3.0 * (q + dg * dq);
            let sy = self.flow_stress(ep);
            (
                1.0 / sy - 1.0 / q,
                dq / (q * q) - self.hardening_at(ep) * dep / (sy * sy),
            )
        };
        let dgamma = bracketed_root(hi, residual);

        let factors = Vector3::from_fn(|i, _| 1.0 / (1.0 + dgamma * modes.c[i] * modes.p[i]));
        let stress = q_basis * a.component_mul(&factors);
        let xi = modes.xi(dgamma);
        let q = (1.5 * xi).sqrt();
        let n = proj * stress;
        let plastic = epp_n + dgamma * n;
        let ep = ep_n + 2.0 / 3.0 * dgamma * q;

        // Consistent tangent (Simo & Hughes §3.4, Simo & Taylor 1986): differentiating
        // σ = C(ε − εᵖ), εᵖ = εᵖ_n + Δγ Pσ, ε̄ᵖ = ε̄ᵖ_n + Δγ √(⅔ξ) and ½ξ = ⅓σ_y² gives
        // C_ep = Ξ − (Ξn)(Ξn)ᵀ / (nᵀΞn + β̄), n = Pσ, β̄ = ⅔ ξ H / (1 − ⅔ H Δγ).
        let h_alg = self.hardening_at(ep);
        let xi_mat = q_basis
            * Matrix3::from_diagonal(&Vector3::from_fn(|i, _| modes.c[i] * factors[i]))
            * q_basis;
        let xn = xi_mat * n;
        let beta = 2.0 / 3.0 * xi * h_alg / (1.0 - 2.0 / 3.0 * h_alg * dgamma);
        let cep = xi_mat - xn * xn.transpose() / (n.dot(&xn) + beta);
        let mut tangent = Tangent::zeros();
        tangent.fixed_view_mut::<3, 3>(0, 0).copy_from(&cep);
        (finish(stress, plastic, ep, true), tangent)
    }
}

/// The trial stress in the common eigenbasis of the plane-stress C and P.
struct Modes {
    /// Eigenvalues of C: E/(1 − ν), 2G, G.
    c: [f64; 3],
    /// Eigenvalues of P: ⅓, 1, 2.
    p: [f64; 3],
    /// Components â of the trial stress.
    a: [f64; 3],
}

impl Modes {
    /// ξ(Δγ) = σᵀPσ of the returned stress = Σ p_i â_i² / (1 + Δγ c_i p_i)².
    fn xi(&self, dgamma: f64) -> f64 {
        (0..3)
            .map(|i| self.p[i] * self.a[i].powi(2) / (1.0 + dgamma * self.c[i] * self.p[i]).powi(2))
            .sum()
    }

    /// dξ/dΔγ = −2 Σ c_i p_i² â_i² / (1 + Δγ c_i p_i)³.
    fn dxi(&self, dgamma: f64) -> f64 {
        (0..3)
            .map(|i| {
                -2.0 * self.c[i] * self.p[i].powi(2) * self.a[i].powi(2)
                    / (1.0 + dgamma * self.c[i] * self.p[i]).powi(3)
            })
            .sum()
    }
}

impl Material for J2Plasticity {
    fn update(
        &self,
        strain: &Voigt,
        committed: &PointState,
        out_of_plane: OutOfPlane,
    ) -> (PointState, Tangent) {
        match out_of_plane {
            OutOfPlane::StrainGiven => self.update_strain_given(strain, committed),
            OutOfPlane::StressFree => self.update_stress_free(strain, committed),
        }
    }

    /// A point that never yielded (no plastic strain, none accumulated) stays elastic while
    /// the trial stress D ε is below the initial yield stress (the elastic check of the
    /// updates above, whose tolerance only widens it).
    fn linear_range(&self, committed: &PointState) -> Option<LinearRange> {
        let virgin = committed.equivalent_plastic_strain == 0.0
            && committed.plastic_strain.iter().all(|&e| e == 0.0);
        virgin.then(|| LinearRange {
            von_mises: self.flow_stress(0.0),
            shear_modulus: self.elastic.shear_modulus(),
        })
    }

    /// The elastic part of the strain alone stores energy; the plastic work σ:dεᵖ (including
    /// what the hardening locks in) counts as dissipated.
    fn elastic_energy(&self, state: &PointState) -> f64 {
        self.elastic.complementary_energy(&state.stress)
    }

    fn describe(&self) -> String {
        format!(
            "J2 plasticity with linear isotropic hardening, E = {} MPa, nu = {}, \
             yield stress = {} MPa, H = {} MPa",
            self.elastic.e, self.elastic.nu, self.yield_stress, self.hardening
        )
    }

    fn elastic(&self) -> &LinearElastic {
        &self.elastic
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steel(h: f64) -> J2Plasticity {
        J2Plasticity::new(LinearElastic::new(200_000.0, 0.3).unwrap(), 250.0, h).unwrap()
    }

    const MODES: [OutOfPlane; 2] = [OutOfPlane::StrainGiven, OutOfPlane::StressFree];

    /// After yielding, the stored energy is ½ σ:(ε − εᵖ): the elastic strain's alone.
    #[test]
    fn elastic_energy_is_that_of_the_elastic_strain() {
        let m = steel(1_000.0);
        let eps = voigt(4e-3, -1e-3, 3e-3, 0.0);
        for mode in MODES {
            let (s, _) = m.update(&eps, &PointState::default(), mode);
            assert!(s.equivalent_plastic_strain > 0.0, "{mode:?} yields");
            let stored = 0.5 * s.stress.dot(&(s.strain - s.plastic_strain));
            assert!(
                (m.elastic_energy(&s) - stored).abs() < 1e-10 * stored,
                "{mode:?}"
            );
        }
    }

    #[test]
    fn elastic_range_matches_linear_elastic() {
        let m = steel(1000.0);
        let eps = voigt(3e-4, -2e-4, 4e-4, 1e-4);
        for mode in MODES {
            let (s, d) = m.update(&eps, &PointState::default(), mode);
            let (se, de) = m.elastic.update(&eps, &PointState::default(), mode);
            assert!(!s.yielding);
            assert!((s.stress - se.stress).norm() <= 1e-12 * se.stress.norm());
            assert!((s.strain - se.strain).norm() <= 1e-15);
            assert_eq!(d, de);
        }
    }

    #[test]
    fn tangent_is_symmetric_and_plastic_state_returns_to_surface() {
        for h in [5000.0, 0.0, -30_000.0] {
            let m = steel(h);
            let eps = voigt(4e-3, -1e-3, 3e-3, 5e-4);
            for mode in MODES {
                let (s, d) = m.update(&eps, &PointState::default(), mode);
                assert!(s.yielding);
                let sy = m.flow_stress(s.equivalent_plastic_strain);
                assert!(
                    (von_mises(&s.stress) - sy).abs() <= 1e-12 * sy,
                    "{mode:?} H={h}"
                );
                assert!((d - d.transpose()).norm() <= 1e-12 * d.norm());
            }
        }
    }

    #[test]
    fn reevaluating_a_converged_state_is_elastic_and_unchanged() {
        let m = steel(2000.0);
        let eps = voigt(5e-3, 1e-3, -2e-3, 0.0);
        for mode in MODES {
            let (s1, _) = m.update(&eps, &PointState::default(), mode);
            let (s2, d2) = m.update(&s1.strain, &s1, mode);
            assert!(!s2.yielding, "{mode:?}");
            assert_eq!(s2.plastic_strain, s1.plastic_strain);
            assert_eq!(s2.equivalent_plastic_strain, s1.equivalent_plastic_strain);
            assert!((s2.stress - s1.stress).norm() <= 1e-11 * s1.stress.norm());
            assert_eq!(d2, m.elastic.stiffness(mode));
        }
    }

    #[test]
    fn plane_stress_equals_3d_return_at_the_returned_zz_strain() {
        // The plane-stress return is the 3D backward-Euler return constrained by σ_zz = 0, so
        // feeding its ε_zz to the 3D update must reproduce it.
        let m = steel(3000.0);
        let committed = m
            .update(
                &voigt(2e-3, 1.5e-3, 0.0, 0.0),
                &PointState::default(),
                OutOfPlane::StressFree,
            )
            .0;
        let eps = voigt(1e-3, 4e-3, -3e-3, 0.0);
        let (ps, _) = m.update(&eps, &committed, OutOfPlane::StressFree);
        let (full, _) = m.update(&ps.strain, &committed, OutOfPlane::StrainGiven);
        assert!(ps.yielding && full.yielding);
        assert!(full.stress[ZZ].abs() <= 1e-10 * ps.stress.norm());
        assert!((full.stress - ps.stress).norm() <= 1e-10 * ps.stress.norm());
        assert!(
            (full.plastic_strain - ps.plastic_strain).norm() <= 1e-10 * ps.plastic_strain.norm()
        );
        let dep = full.equivalent_plastic_strain - ps.equivalent_plastic_strain;
        assert!(dep.abs() <= 1e-10 * ps.equivalent_plastic_strain);
    }

    #[test]
    fn fully_softened_point_carries_no_deviatoric_stress() {
        let m = steel(-50_000.0); // σ_y reaches 0 at ε̄ᵖ = 0.005
        let eps = voigt(0.02, -0.01, 0.0, -0.01);
        let (s, d) = m.update(&eps, &PointState::default(), OutOfPlane::StrainGiven);
        assert!(s.yielding && m.flow_stress(s.equivalent_plastic_strain) == 0.0);
        assert!(von_mises(&s.stress) <= 1e-9);
        // Only the bulk response is left: K 1⊗1.
        let k = m.elastic.e / (3.0 * (1.0 - 2.0 * m.elastic.nu));
        let m1 = voigt(1.0, 1.0, 0.0, 1.0);
        assert!((d - k * m1 * m1.transpose()).norm() <= 1e-9 * k);

        let (s, d) = m.update(&eps, &PointState::default(), OutOfPlane::StressFree);
        assert!(s.yielding && s.stress == Voigt::zeros() && d == Tangent::zeros());
        assert_eq!(s.plastic_strain.fixed_rows::<3>(0), eps.fixed_rows::<3>(0));
        assert!(s.equivalent_plastic_strain >= 0.005);
        let trace = s.plastic_strain[0] + s.plastic_strain[1] + s.plastic_strain[ZZ];
        assert!(trace.abs() <= 1e-18);
    }

    #[test]
    fn tangent_modulus_and_description() {
        let m = steel(10_000.0);
        assert!((m.tangent_modulus() - 200_000.0 * 10_000.0 / 210_000.0).abs() < 1e-9);
        assert!(m.describe().contains("yield stress = 250"));
        assert!((J2Plasticity::min_hardening(&m.elastic) + 200_000.0 / 1.4).abs() < 1e-9);
    }
}
