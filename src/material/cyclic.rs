//! Von Mises plasticity with combined hardening for cyclic loading: Armstrong–Frederick
//! backstresses summed as in Chaboche (kinematic), Voce saturation plus linear hardening
//! (isotropic), integrated implicitly (docs/guide/plasticity.md).
//!
//! # Model
//! - Yield function f = √(3/2 (s − α):(s − α)) − σ_y(p), α = Σ_k α_k (the yield surface's
//!   centre), p = ε̄ᵖ the accumulated equivalent plastic strain.
//! - Isotropic hardening σ_y(p) = σ_Y + H p + Q (1 − e^(−b p)) (linear `hardening` H beside
//!   Voce's Q, b; both default to 0).
//! - Associative flow ε̇ᵖ = ṗ √(3/2) n with n = (s − α)/‖s − α‖.
//! - Armstrong–Frederick evolution of each backstress (Chaboche's sum of 1 to
//!   [`MAX_KINEMATIC_TERMS`] terms): α̇_k = ⅔ C_k ε̇ᵖ − γ_k α_k ṗ; γ_k = 0 is linear
//!   (Prager/Ziegler) kinematic hardening. In uniaxial stress with backstress X_k
//!   (α_k = X_k diag(⅔, −⅓, −⅓)) this reads dX_k = C_k dεᵖ − γ_k X_k |dεᵖ|, so a monotonic
//!   curve from the virgin state is σ = σ_y(εᵖ) + Σ (C_k/γ_k)(1 − e^(−γ_k εᵖ)).
//! - Free energy of the backstresses ψ = Σ 3/(4 C_k) α_k:α_k: stored, the rest of the plastic
//!   work is dissipated ([`Material::hardening_energy`]).
//!
//! # Integration
//! The flow direction is taken at the end of the increment (backward Euler), and over the
//! increment the linear equation dα_k/dp = √(2/3) C_k n − γ_k α_k is integrated exactly
//! for that direction:
//! α_k = e_k α_k,n + √(2/3) C_k φ_k n with e_k = e^(−γ_k Δp), φ_k = (1 − e_k)/γ_k (= Δp for
//! γ_k = 0). This exponential form of the backward-Euler return is exact along any path of
//! fixed flow direction (uniaxial cycles, radial loading), so closed-form uniaxial loops are
//! reproduced to round-off at any increment size, and it keeps every α_k inside its
//! saturation ball ‖α_k‖ ≤ √(2/3) C_k/γ_k; it tends to plain backward Euler as γ_k Δp → 0.
//! With the trial deviator s_tr = 2G dev(ε − εᵖ_n), ξ = s − α is parallel to
//! ξ̃(Δp) = s_tr − Σ e_k α_k,n, and the consistency condition is one scalar equation in Δp:
//!
//! F(Δp) = √(3/2) ‖ξ̃(Δp)‖ − 3G Δp − Σ C_k φ_k − σ_y(p_n + Δp) = 0,
//!
//! solved by Newton's method safeguarded by bisection. F decreases strictly (F′ ≤ −3G − σ_y′
//! because ‖α_k,n‖ stays in the saturation ball), so the root is unique when 3G + σ_y′ > 0,
//! which [`CyclicPlasticity::new`] ensures.
//!
//! The consistent tangent follows from differentiating the return (with
//! w = Σ γ_k e_k α_k,n, c = √(3/2) and D = −F′(Δp)):
//! dΔp = (2Gc/D) n:dε, dn = (I − n⊗n)(2G dev dε + w dΔp)/‖ξ̃‖,
//! dσ = C dε − 2Gc (n dΔp + Δp dn). It is unsymmetric when a backstress with γ_k > 0 is not
//! parallel to the flow direction (non-proportional loading). [`Material::update_with_history`]
//! returns it as it is when some γ_k > 0 ([`Material::has_unsymmetric_tangent`]: the bodies'
//! solvers then factor the tangent by sparse LU while such a point yields, and Newton stays
//! quadratic, tests/cyclic_newton.rs), and its symmetric part for Prager hardening (γ = 0),
//! where it is symmetric up to rounding, so that those bodies keep the Cholesky path.
//! [`CyclicPlasticity::return_map`] gives the exact one (tested by finite differences).
//!
//! Plane stress solves σ_zz(ε_zz) = 0 around the same return by Newton's method on ε_zz with
//! the consistent tangent's zz entry, and condenses the tangent onto the in-plane components
//! (de Souza Neto, Perić & Owen (2008), §9.2, the nested-iteration plane-stress enforcement).
//!
//! # Internal variables
//! Per integration point `terms × VOIGT_LEN` numbers: the backstresses α_k in stress-like
//! Voigt order (tensor shear), term after term ([`Material::internal_variables`]).

use super::elastic::LinearElastic;
use super::j2::YIELD_TOL;
use super::{
    IN_PLANE, MAX_ITERATIONS, Material, OutOfPlane, PointState, Tangent, VOIGT_LEN, Voigt, ZZ,
    bracketed_root, contraction, deviator, engineering, identity,
};
use crate::error::ParameterError;

/// The largest number of Armstrong–Frederick terms of a material (Chaboche's sum).
pub const MAX_KINEMATIC_TERMS: usize = 5;

/// √(3/2): q = √(3/2) ‖s‖.
const SQRT_3_2: f64 = 1.224_744_871_391_589;

/// One Armstrong–Frederick backstress: α̇ = ⅔ C ε̇ᵖ − γ α ṗ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KinematicTerm {
    /// Initial kinematic hardening modulus C (MPa).
    pub c: f64,
    /// Rate of dynamic recovery γ (dimensionless); 0 is linear Prager hardening.
    pub gamma: f64,
}

impl KinematicTerm {
    /// The saturated uniaxial backstress C/γ (infinite for Prager hardening).
    pub fn saturation(&self) -> f64 {
        self.c / self.gamma
    }
}

/// Voce saturation hardening R(p) = Q (1 − e^(−b p)).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Voce {
    /// Saturation value Q (MPa); negative for cyclic softening.
    pub q: f64,
    /// Rate b (dimensionless).
    pub b: f64,
}

/// J2 plasticity with Chaboche kinematic and Voce + linear isotropic hardening. See the
/// module docs for the model and its integration.
#[derive(Clone, Debug, PartialEq)]
pub struct CyclicPlasticity {
    pub elastic: LinearElastic,
    /// Initial yield stress σ_Y (MPa).
    pub yield_stress: f64,
    /// Linear isotropic hardening modulus H (MPa).
    pub hardening: f64,
    pub isotropic: Voce,
    pub kinematic: Vec<KinematicTerm>,
}

/// The result of the return at given out-of-plane strain.
#[derive(Clone, Debug)]
pub struct Return {
    pub state: PointState,
    /// The backstresses α_k (stress-like Voigt), the first `terms` entries used.
    pub backstresses: [Voigt; MAX_KINEMATIC_TERMS],
    /// The exact consistent tangent dσ/dε (unsymmetric in general, see the module docs).
    pub tangent: Tangent,
}

impl CyclicPlasticity {
    /// Checks the parameters; the names in errors are the case file's keys.
    ///
    /// - `yield_stress` σ_Y > 0, `hardening` H ≥ 0;
    /// - 0 to [`MAX_KINEMATIC_TERMS`] kinematic terms with C > 0, γ ≥ 0;
    /// - Voce b ≥ 0 and Q > −σ_Y (the yield stress stays positive); for cyclic softening
    ///   (Q < 0) also 3G + H + Q b > 0, which keeps the return's equation monotonic (module
    ///   docs).
    pub fn new(
        elastic: LinearElastic,
        yield_stress: f64,
        hardening: f64,
        isotropic: Voce,
        kinematic: &[KinematicTerm],
    ) -> Result<Self, ParameterError> {
        let elastic = LinearElastic::new(elastic.e, elastic.nu)?;
        if !(yield_stress.is_finite() && yield_stress > 0.0) {
            return Err(ParameterError::new(
                "yield_stress",
                yield_stress,
                "the yield stress (MPa) must be positive and finite",
            ));
        }
        if !(hardening.is_finite() && hardening >= 0.0) {
            return Err(ParameterError::new(
                "hardening",
                hardening,
                "with `kinematic` or `isotropic` the linear hardening modulus H (MPa) must be \
                 finite and non-negative",
            ));
        }
        if kinematic.len() > MAX_KINEMATIC_TERMS {
            return Err(ParameterError::new(
                "kinematic",
                kinematic.len() as f64,
                format!("at most {MAX_KINEMATIC_TERMS} backstress terms"),
            ));
        }
        for term in kinematic {
            if !(term.c.is_finite() && term.c > 0.0) {
                return Err(ParameterError::new(
                    "kinematic.C",
                    term.c,
                    "the kinematic hardening modulus C (MPa) must be positive and finite",
                ));
            }
            if !(term.gamma.is_finite() && term.gamma >= 0.0) {
                return Err(ParameterError::new(
                    "kinematic.gamma",
                    term.gamma,
                    "the recovery rate gamma must be finite and non-negative (0: Prager)",
                ));
            }
        }
        let Voce { q, b } = isotropic;
        if !(b.is_finite() && b >= 0.0) {
            return Err(ParameterError::new(
                "isotropic.b",
                b,
                "the Voce rate b must be finite and non-negative",
            ));
        }
        if !(q.is_finite() && q > -yield_stress) {
            return Err(ParameterError::new(
                "isotropic.Q",
                q,
                format!(
                    "the Voce saturation Q (MPa) must be finite and greater than \
                     -yield_stress = {} (the yield stress must stay positive)",
                    -yield_stress
                ),
            ));
        }
        let three_g = 3.0 * elastic.shear_modulus();
        if three_g + hardening + q.min(0.0) * b <= 0.0 {
            return Err(ParameterError::new(
                "isotropic.b",
                b,
                format!(
                    "cyclic softening Q b = {} MPa is steeper than 3G + H = {} MPa: the stress \
                     update would have no unique solution",
                    q * b,
                    three_g + hardening
                ),
            ));
        }
        Ok(Self {
            elastic,
            yield_stress,
            hardening,
            isotropic,
            kinematic: kinematic.to_vec(),
        })
    }

    /// Flow stress σ_y(p) = σ_Y + H p + Q (1 − e^(−b p)).
    pub fn flow_stress(&self, p: f64) -> f64 {
        let Voce { q, b } = self.isotropic;
        self.yield_stress + self.hardening * p - q * (-b * p).exp_m1()
    }

    /// Slope dσ_y/dp = H + Q b e^(−b p).
    fn flow_slope(&self, p: f64) -> f64 {
        let Voce { q, b } = self.isotropic;
        self.hardening + q * b * (-b * p).exp()
    }

    /// Number of backstress terms.
    pub fn terms(&self) -> usize {
        self.kinematic.len()
    }

    /// The backstresses of an internal-variable slice (unused entries zero).
    pub fn backstresses(&self, internal: &[f64]) -> [Voigt; MAX_KINEMATIC_TERMS] {
        let mut alphas = [Voigt::zeros(); MAX_KINEMATIC_TERMS];
        for (alpha, chunk) in alphas.iter_mut().zip(internal.chunks_exact(VOIGT_LEN)) {
            *alpha = Voigt::from_column_slice(chunk);
        }
        alphas
    }

    /// The return at given out-of-plane strain (`strain` complete, zz included) from the
    /// `committed` state and backstresses, with the exact (unsymmetric) consistent tangent.
    pub fn return_map(
        &self,
        strain: &Voigt,
        committed: &PointState,
        alphas_n: &[Voigt; MAX_KINEMATIC_TERMS],
    ) -> Return {
        let terms = &self.kinematic[..];
        let d = self.elastic.stiffness(OutOfPlane::StrainGiven);
        let g = self.elastic.shear_modulus();
        let p_n = committed.equivalent_plastic_strain;
        let sigma_tr = d * (strain - committed.plastic_strain);
        let s_tr = deviator(&sigma_tr);
        let alpha_n: Voigt = alphas_n.iter().sum();
        let sy_n = self.flow_stress(p_n);
        let norm = |v: &Voigt| contraction(v, v).sqrt();
        let elastic = Return {
            state: PointState {
                strain: *strain,
                stress: sigma_tr,
                plastic_strain: committed.plastic_strain,
                equivalent_plastic_strain: p_n,
                yielding: false,
            },
            backstresses: *alphas_n,
            tangent: d,
        };
        let f_tr = SQRT_3_2 * norm(&(s_tr - alpha_n)) - sy_n;
        if f_tr <= YIELD_TOL * sy_n {
            return elastic;
        }

        // ξ̃(Δp), its derivative's w, and F with F′ (module docs).
        let decay = |k: usize, dp: f64| (-terms[k].gamma * dp).exp();
        let phi = |k: usize, dp: f64| {
            let gamma = terms[k].gamma;
            if gamma == 0.0 {
                dp
            } else {
                -(-gamma * dp).exp_m1() / gamma
            }
        };
        let xi_tilde = |dp: f64| {
            let mut xi = s_tr;
            let mut w = Voigt::zeros();
            for k in 0..terms.len() {
                let e = decay(k, dp);
                xi -= alphas_n[k] * e;
                w += alphas_n[k] * (terms[k].gamma * e);
            }
            (xi, w)
        };
        let residual = |dp: f64| {
            let (xi, w) = xi_tilde(dp);
            let xi_norm = norm(&xi);
            let n = xi / xi_norm;
            let kinematic: f64 = (0..terms.len()).map(|k| terms[k].c * phi(k, dp)).sum();
            let kinematic_slope: f64 = (0..terms.len()).map(|k| terms[k].c * decay(k, dp)).sum();
            let f = SQRT_3_2 * xi_norm - 3.0 * g * dp - kinematic - self.flow_stress(p_n + dp);
            let slope = 3.0 * g + kinematic_slope + self.flow_slope(p_n + dp)
                - SQRT_3_2 * contraction(&n, &w);
            (f, slope)
        };

        // Bracket: F(0) > 0, and since ‖ξ̃‖ ≤ ‖s_tr‖ + Σ‖α_k,n‖ and σ_y > 0, F < 0 beyond
        // hi = √(3/2)(‖s_tr‖ + Σ‖α_k,n‖)/3G.
        let alpha_norms: f64 = alphas_n.iter().map(norm).sum();
        let hi = SQRT_3_2 * (norm(&s_tr) + alpha_norms) / (3.0 * g);
        // `residual` returns F and −dF/dΔp.
        let dp = bracketed_root(hi, |dp| {
            let (f, slope) = residual(dp);
            (f, -slope)
        });

        let (xi, w) = xi_tilde(dp);
        let xi_norm = norm(&xi);
        let n = xi / xi_norm;
        let mut backstresses = [Voigt::zeros(); MAX_KINEMATIC_TERMS];
        for k in 0..terms.len() {
            backstresses[k] = alphas_n[k] * decay(k, dp) + n * (terms[k].c * phi(k, dp) / SQRT_3_2);
        }
        let plastic_strain = committed.plastic_strain + engineering(&(n * (SQRT_3_2 * dp)));
        let stress = d * (strain - plastic_strain);

        // Consistent tangent (module docs). As Voigt matrices acting on engineering strain:
        // 2G dev dε = D_dev dε with D_dev = C − K m mᵀ, and n:dε = nᵀdε (n has tensor
        // shear components).
        let (_, slope) = residual(dp);
        let m = identity();
        let bulk = self.elastic.lame_lambda() + 2.0 * g / 3.0;
        let d_dev = d - bulk * m * m.transpose();
        let g_row = n.transpose() * (2.0 * g * SQRT_3_2 / slope);
        let w_perp = w - n * contraction(&n, &w);
        let dn = (d_dev - 2.0 * g * n * n.transpose() + w_perp * g_row) / xi_norm;
        let tangent = d - 2.0 * g * SQRT_3_2 * (n * g_row + dp * dn);
        Return {
            state: PointState {
                strain: *strain,
                stress,
                plastic_strain,
                equivalent_plastic_strain: p_n + dp,
                yielding: true,
            },
            backstresses,
            tangent,
        }
    }

    /// The plane-stress return: ε_zz such that σ_zz = 0, by Newton's method around
    /// [`Self::return_map`], with the tangent condensed onto the in-plane components (its
    /// zz row and column zero); an elastic update returns the plane-stress elastic matrix
    /// itself (the [`PointState::yielding`] contract).
    fn return_stress_free(
        &self,
        strain: &Voigt,
        committed: &PointState,
        alphas_n: &[Voigt; MAX_KINEMATIC_TERMS],
    ) -> Return {
        let nu = self.elastic.nu;
        let ep = &committed.plastic_strain;
        // Elastic guess: the ε_zz with σ_zz = 0 at the committed plastic strain.
        let mut eps = *strain;
        eps[ZZ] = ep[ZZ] - nu / (1.0 - nu) * (strain[0] - ep[0] + strain[1] - ep[1]);
        let mut result = self.return_map(&eps, committed, alphas_n);
        if !result.state.yielding {
            let d = self.elastic.stiffness(OutOfPlane::StressFree);
            let mut stress = d * (strain - ep);
            stress[ZZ] = 0.0;
            result.state.stress = stress;
            result.tangent = d;
            return result;
        }
        let scale = self.flow_stress(result.state.equivalent_plastic_strain);
        for _ in 0..MAX_ITERATIONS {
            let szz = result.state.stress[ZZ];
            if szz.abs() <= 1e-13 * scale {
                break;
            }
            eps[ZZ] -= szz / result.tangent[(ZZ, ZZ)];
            result = self.return_map(&eps, committed, alphas_n);
        }
        result.state.stress[ZZ] = 0.0;
        if !result.state.yielding {
            result.tangent = self.elastic.stiffness(OutOfPlane::StressFree);
            return result;
        }
        let d = result.tangent;
        let mut condensed = Tangent::zeros();
        for i in IN_PLANE {
            for j in IN_PLANE {
                condensed[(i, j)] = d[(i, j)] - d[(i, ZZ)] * d[(ZZ, j)] / d[(ZZ, ZZ)];
            }
        }
        result.tangent = condensed;
        result
    }

    /// The return under `out_of_plane`, with the exact consistent tangent.
    pub fn update_exact(
        &self,
        strain: &Voigt,
        committed: &PointState,
        committed_internal: &[f64],
        out_of_plane: OutOfPlane,
    ) -> Return {
        let alphas_n = self.backstresses(committed_internal);
        match out_of_plane {
            OutOfPlane::StrainGiven => self.return_map(strain, committed, &alphas_n),
            OutOfPlane::StressFree => self.return_stress_free(strain, committed, &alphas_n),
        }
    }
}

impl Material for CyclicPlasticity {
    /// The update from virgin backstresses (the history of the backstresses is kept by
    /// [`Material::update_with_history`], which the elements call).
    fn update(
        &self,
        strain: &Voigt,
        committed: &PointState,
        out_of_plane: OutOfPlane,
    ) -> (PointState, Tangent) {
        let virgin = vec![0.0; self.internal_variables()];
        let mut scratch = virgin.clone();
        self.update_with_history(strain, committed, &virgin, &mut scratch, out_of_plane)
    }

    fn update_with_history(
        &self,
        strain: &Voigt,
        committed: &PointState,
        committed_internal: &[f64],
        trial_internal: &mut [f64],
        out_of_plane: OutOfPlane,
    ) -> (PointState, Tangent) {
        let result = self.update_exact(strain, committed, committed_internal, out_of_plane);
        for (chunk, alpha) in trial_internal
            .chunks_exact_mut(VOIGT_LEN)
            .zip(&result.backstresses)
        {
            chunk.copy_from_slice(alpha.as_slice());
        }
        // Prager hardening's exact tangent is symmetric up to rounding: symmetrised, so that
        // its bodies keep the Cholesky path.
        let tangent = if result.state.yielding && !self.has_unsymmetric_tangent() {
            (result.tangent + result.tangent.transpose()) * 0.5
        } else {
            result.tangent
        };
        (result.state, tangent)
    }

    /// Armstrong–Frederick recovery (some γ_k > 0) makes the tangent unsymmetric under
    /// non-proportional flow (module docs).
    fn has_unsymmetric_tangent(&self) -> bool {
        self.kinematic.iter().any(|term| term.gamma > 0.0)
    }

    fn internal_variables(&self) -> usize {
        self.terms() * VOIGT_LEN
    }

    fn backstress(&self, internal: &[f64]) -> Voigt {
        self.backstresses(internal).iter().sum()
    }

    fn hardening_energy(&self, internal: &[f64]) -> f64 {
        let alphas = self.backstresses(internal);
        self.kinematic
            .iter()
            .zip(&alphas)
            .map(|(term, alpha)| 0.75 / term.c * contraction(alpha, alpha))
            .sum()
    }

    fn elastic_energy(&self, state: &PointState) -> f64 {
        self.elastic.complementary_energy(&state.stress)
    }

    fn describe(&self) -> String {
        let mut text = format!(
            "J2 plasticity with combined hardening, E = {} MPa, nu = {}, yield stress = {} MPa",
            self.elastic.e, self.elastic.nu, self.yield_stress
        );
        if self.hardening != 0.0 {
            text += &format!(", H = {} MPa", self.hardening);
        }
        let Voce { q, b } = self.isotropic;
        if q != 0.0 {
            text += &format!(", Voce Q = {q} MPa, b = {b}");
        }
        for (k, term) in self.kinematic.iter().enumerate() {
            text += &format!(
                ", backstress {}: C = {} MPa, gamma = {}",
                k + 1,
                term.c,
                term.gamma
            );
        }
        text
    }

    fn elastic(&self) -> &LinearElastic {
        &self.elastic
    }
}

/// The von Mises norm √(3/2 α:α) of a (deviatoric) backstress: the distance of the yield
/// surface's centre from the origin in stress units.
pub fn centre_norm(alpha: &Voigt) -> f64 {
    SQRT_3_2 * contraction(alpha, alpha).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::voigt;

    fn material(kinematic: &[KinematicTerm], voce: Voce) -> CyclicPlasticity {
        let elastic = LinearElastic::new(200_000.0, 0.3).unwrap();
        CyclicPlasticity::new(elastic, 250.0, 500.0, voce, kinematic).unwrap()
    }

    const TWO_TERMS: [KinematicTerm; 2] = [
        KinematicTerm {
            c: 40_000.0,
            gamma: 400.0,
        },
        KinematicTerm {
            c: 5_000.0,
            gamma: 0.0,
        },
    ];

    /// The exact tangent against central differences of the return, at a committed state
    /// with backstresses not parallel to the new flow direction (non-proportional), under
    /// both out-of-plane conditions.
    #[test]
    fn tangent_matches_finite_differences() {
        let m = material(&TWO_TERMS, Voce { q: 80.0, b: 20.0 });
        for mode in [OutOfPlane::StrainGiven, OutOfPlane::StressFree] {
            let first = m.update_exact(
                &voigt(3e-3, -1e-3, 2e-3, 0.0),
                &PointState::default(),
                &[0.0; 2 * VOIGT_LEN],
                mode,
            );
            let mut internal = [0.0; 2 * VOIGT_LEN];
            for (chunk, a) in internal
                .chunks_exact_mut(VOIGT_LEN)
                .zip(&first.backstresses)
            {
                chunk.copy_from_slice(a.as_slice());
            }
            let strain = voigt(1e-3, 4e-3, -2e-3, 5e-4);
            let exact = m.update_exact(&strain, &first.state, &internal, mode);
            assert!(exact.state.yielding);
            let h = 1e-8;
            let columns = if mode == OutOfPlane::StressFree { 3 } else { 4 };
            for j in 0..columns {
                let mut plus = strain;
                let mut minus = strain;
                plus[j] += h;
                minus[j] -= h;
                let sp = m
                    .update_exact(&plus, &first.state, &internal, mode)
                    .state
                    .stress;
                let sm = m
                    .update_exact(&minus, &first.state, &internal, mode)
                    .state
                    .stress;
                let fd = (sp - sm) / (2.0 * h);
                let error = (fd - exact.tangent.column(j)).norm();
                // Central differences: O(h²) truncation plus round-off ~ ε σ / h ≈ 1e-5 of
                // the entries (~1e5 MPa): 1e-6 relative to E is far above both.
                assert!(error < 1e-6 * m.elastic.e, "{mode:?} column {j}: {error}");
            }
        }
    }

    /// With no backstress and no Voce term the model is the linear-hardening J2 model.
    #[test]
    fn without_new_terms_equals_linear_j2() {
        let m = material(&[], Voce::default());
        let j2 = super::super::j2::J2Plasticity::new(m.elastic, 250.0, 500.0).unwrap();
        for mode in [OutOfPlane::StrainGiven, OutOfPlane::StressFree] {
            let eps = voigt(4e-3, -1e-3, 3e-3, 5e-4);
            let (a, da) = m.update(&eps, &PointState::default(), mode);
            let (b, db) = j2.update(&eps, &PointState::default(), mode);
            assert!(
                (a.stress - b.stress).norm() <= 1e-9 * b.stress.norm(),
                "{mode:?}"
            );
            assert!((a.strain - b.strain).norm() <= 1e-12, "{mode:?}");
            assert!((da - db).norm() <= 1e-8 * db.norm(), "{mode:?}");
        }
    }

    #[test]
    fn returned_state_is_on_the_shifted_yield_surface_and_alphas_saturate() {
        let m = material(&TWO_TERMS, Voce { q: 80.0, b: 20.0 });
        let (state, internal) = {
            let mut internal = [0.0; 2 * VOIGT_LEN];
            let (s, _) = m.update_with_history(
                &voigt(0.05, -0.02, 0.01, 0.0),
                &PointState::default(),
                &[0.0; 2 * VOIGT_LEN],
                &mut internal,
                OutOfPlane::StrainGiven,
            );
            (s, internal)
        };
        let alphas = m.backstresses(&internal);
        let centre = alphas[0] + alphas[1];
        let q = SQRT_3_2
            * contraction(
                &(deviator(&state.stress) - centre),
                &(deviator(&state.stress) - centre),
            )
            .sqrt();
        let sy = m.flow_stress(state.equivalent_plastic_strain);
        assert!((q - sy).abs() <= 1e-10 * sy);
        assert!(centre_norm(&alphas[0]) <= TWO_TERMS[0].saturation() * (1.0 + 1e-12));
        assert!(m.hardening_energy(&internal) > 0.0);
    }

    #[test]
    fn rejects_bad_parameters_naming_the_key() {
        let elastic = LinearElastic::new(200_000.0, 0.3).unwrap();
        let bad = |h: f64, voce: Voce, terms: &[KinematicTerm]| {
            CyclicPlasticity::new(elastic, 250.0, h, voce, terms)
                .unwrap_err()
                .name
        };
        let term = |c, gamma| KinematicTerm { c, gamma };
        assert_eq!(bad(0.0, Voce::default(), &[term(-1.0, 0.0)]), "kinematic.C");
        assert_eq!(
            bad(0.0, Voce::default(), &[term(1.0, -1.0)]),
            "kinematic.gamma"
        );
        assert_eq!(bad(0.0, Voce::default(), &[term(1.0, 0.0); 6]), "kinematic");
        assert_eq!(bad(0.0, Voce { q: -300.0, b: 1.0 }, &[]), "isotropic.Q");
        assert_eq!(
            bad(
                0.0,
                Voce {
                    q: 1.0,
                    b: f64::NAN
                },
                &[]
            ),
            "isotropic.b"
        );
        assert_eq!(bad(-1.0, Voce::default(), &[]), "hardening");
    }
}
