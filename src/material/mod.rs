//! Constitutive models of the bulk (continuum) material, behind the [`Material`] trait.
//!
//! A material is a pure function from the total strain at an integration point and the state
//! committed at the end of the last converged step to the new stress, the new (trial) state
//! and the consistent tangent. It knows nothing of elements. The solver keeps two state
//! arrays, *committed* and *trial*; trial states are copied into committed ones only when a
//! load step converges, so a failed or cut-back step leaves history untouched.

pub mod cyclic;
pub mod elastic;
pub mod j2;

use nalgebra::{SMatrix, SVector};

/// Stress or strain in the solver's Voigt order (xx, yy, xy, zz, xθ, yθ); in axisymmetry
/// (rr, zz, rz, θθ, rθ, zθ). Strain uses engineering shear γ_xy = 2ε_xy. The last two
/// (out-of-plane shear) components are those of an axisymmetric body with twist; they are
/// zero in every other analysis.
pub type Voigt = SVector<f64, 6>;
/// Material tangent dσ/dε in Voigt order.
pub type Tangent = SMatrix<f64, 6, 6>;

/// Index of the out-of-plane (zz or θθ) component in [`Voigt`] vectors.
pub const ZZ: usize = 3;

/// Index of the rθ shear component (twist) in [`Voigt`] vectors.
pub const R_THETA: usize = 4;

/// Index of the zθ shear component (twist) in [`Voigt`] vectors.
pub const Z_THETA: usize = 5;

/// Number of components of a [`Voigt`] vector: the stride of a stress-like internal variable
/// (a backstress) in a point's internal-variable slice.
pub const VOIGT_LEN: usize = 6;

/// The most internal variables a material may have per point (five backstresses).
pub const MAX_INTERNAL_VARIABLES: usize = cyclic::MAX_KINEMATIC_TERMS * VOIGT_LEN;

/// Indices of the normal components in [`Voigt`] vectors (xx, yy, zz).
pub const NORMAL: [usize; 3] = [0, 1, ZZ];

/// Indices of the shear components in [`Voigt`] vectors (xy, xθ, yθ): a strain stores
/// engineering shear there, a stress the tensor component. Material code names components
/// through these constants and the helpers below, never by literal index.
pub const SHEAR: [usize; 3] = [2, R_THETA, Z_THETA];

/// The components of a plane-stress state (xx, yy, xy): there is no twist in plane stress,
/// and σ_zz = 0.
pub const IN_PLANE: [usize; 3] = [0, 1, 2];

/// A [`Voigt`] vector from its in-plane and out-of-plane normal components (xx, yy, xy, zz),
/// the twist shears zero.
pub fn voigt(xx: f64, yy: f64, xy: f64, zz: f64) -> Voigt {
    Voigt::new(xx, yy, xy, zz, 0.0, 0.0)
}

/// The identity m in Voigt form (1 on the normal components): tr σ = mᵀσ.
pub fn identity() -> Voigt {
    let mut m = Voigt::zeros();
    NORMAL.iter().for_each(|&i| m[i] = 1.0);
    m
}

/// The deviator s = σ − ⅓ (tr σ) m of a stress-like Voigt vector.
pub fn deviator(s: &Voigt) -> Voigt {
    let m = identity();
    s - m * (dot(&m, s) / 3.0)
}

/// The plain dot product aᵀb of two Voigt vectors (σᵀε = σ:ε for a stress and an
/// engineering strain). Summed as the in-plane four first, then the twist shears, so that
/// without twist the value is bit for bit the one of the four-component vectors asperity
/// had before twist (nalgebra sums a 4-vector pairwise, a longer one in sequence).
pub fn dot(a: &Voigt, b: &Voigt) -> f64 {
    let plane = a.fixed_rows::<4>(0).dot(&b.fixed_rows::<4>(0));
    plane + a[R_THETA] * b[R_THETA] + a[Z_THETA] * b[Z_THETA]
}

/// The tensor contraction a:b of two stress-like Voigt vectors (tensor shear components, so
/// each shear product counts twice).
pub fn contraction(a: &Voigt, b: &Voigt) -> f64 {
    dot(a, b) + SHEAR.iter().map(|&i| a[i] * b[i]).sum::<f64>()
}

/// The equivalent strain √(⅔ ε:ε) of an engineering strain in Voigt order (tensor shears
/// are half the engineering ones, so each shear enters as ½ γ²). The plane terms are summed
/// first, so that without twist the value is bit for bit the four-component one.
pub fn equivalent_strain(e: &Voigt) -> f64 {
    let plane = e[0] * e[0] + e[1] * e[1] + e[ZZ] * e[ZZ] + 0.5 * e[2] * e[2];
    let twist = 0.5 * (e[R_THETA] * e[R_THETA] + e[Z_THETA] * e[Z_THETA]);
    (2.0 / 3.0 * (plane + twist)).sqrt()
}

/// A stress-like (tensor-component) Voigt vector as a strain-like one (engineering shear):
/// the shear components doubled.
pub fn engineering(tensor: &Voigt) -> Voigt {
    let mut v = *tensor;
    SHEAR.iter().for_each(|&i| v[i] *= 2.0);
    v
}

/// How the out-of-plane component is determined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutOfPlane {
    /// ε_zz is given by the kinematics (plane strain: 0, axisymmetry: u_r / r).
    StrainGiven,
    /// σ_zz = 0; the material returns the ε_zz that satisfies it.
    StressFree,
}

/// History and results at one integration point.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointState {
    /// Total strain, including the out-of-plane component the material determined in plane
    /// stress.
    pub strain: Voigt,
    pub stress: Voigt,
    pub plastic_strain: Voigt,
    /// Accumulated equivalent plastic strain ε̄ᵖ = ∫ √(2/3 dεᵖ:dεᵖ).
    pub equivalent_plastic_strain: f64,
    /// Whether the point yielded in the step that produced this state. A state with
    /// `yielding == false` must have come with the material's elastic tangent, the one of an
    /// update at zero strain from the default state (assembly keeps the matrices of cells
    /// none of whose points yielded, see
    /// [`ElementSet::tangent_is_reference`](crate::element::set::ElementSet::tangent_is_reference)).
    pub yielding: bool,
}

/// Where a point's update is linear elastic ([`Material::linear_range`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearRange {
    /// The von Mises stress below which the update is σ = D ε (infinite for an elastic
    /// material).
    pub von_mises: f64,
    /// The shear modulus G of D: a strain change Δε changes the von Mises stress by at most
    /// 3 G times its equivalent strain √(⅔ Δε:Δε) (dev Δσ = 2 G dev Δε).
    pub shear_modulus: f64,
}

/// A bulk constitutive model.
pub trait Material: Send + Sync + std::fmt::Debug {
    /// Stress update for the total strain `strain` (its zz entry is ignored when
    /// `out_of_plane` is [`OutOfPlane::StressFree`]) starting from the `committed` state.
    /// Returns the new state and the consistent tangent dσ/dε (with zero zz row and column in
    /// plane stress, where it is the condensed in-plane tangent).
    fn update(
        &self,
        strain: &Voigt,
        committed: &PointState,
        out_of_plane: OutOfPlane,
    ) -> (PointState, Tangent);

    /// Elastic strain energy per unit volume stored at `state`, ½ σ:C⁻¹:σ (N·mm/mm³ = MPa):
    /// what the energy balance counts as stored (the rest of the stress work is dissipated).
    fn elastic_energy(&self, state: &PointState) -> f64;

    /// Short description for logs, e.g. "elastic E=210000 nu=0.3".
    fn describe(&self) -> String;

    /// The elastic part of the model (its E and ν): what the material does before it yields.
    fn elastic(&self) -> &elastic::LinearElastic;

    /// Whether the stress is a fixed linear function of the strain, independent of the
    /// history (then the bodies' stiffness is constant and needs assembling only once).
    fn is_linear(&self) -> bool {
        false
    }

    /// The range within which an update from `committed` is linear elastic: the stress is
    /// the elastic stiffness times the whole strain (the reference tangent's D ε) while its
    /// von Mises value stays below [`LinearRange::von_mises`]. `None` (the default) where
    /// that is not so: a point that has yielded (its plastic strain enters the stress), a
    /// material with other internal variables. Lets assembly leave such points' cells out
    /// while they provably stay in the range (`solver::elastic_cells`).
    fn linear_range(&self, _committed: &PointState) -> Option<LinearRange> {
        None
    }

    /// Whether the consistent tangent of a yielding point may be unsymmetric (kinematic
    /// hardening with dynamic recovery). The bodies' solvers then factor the tangent by LU
    /// while a point of such a material yields, and by Cholesky otherwise. `false` (the
    /// default): the tangent is always symmetric.
    fn has_unsymmetric_tangent(&self) -> bool {
        false
    }

    /// Number of internal variables per integration point beyond [`PointState`] (the UMAT
    /// "NSTATV"): the backstress components of kinematic hardening. 0 (the default) for a
    /// material without them, which then costs no storage.
    fn internal_variables(&self) -> usize {
        0
    }

    /// [`Self::update`] of a material with internal variables: reads the committed ones
    /// from `committed_internal` and writes the new ones to `trial_internal` (both
    /// [`Self::internal_variables`] long). The default, for materials without any, is
    /// [`Self::update`].
    fn update_with_history(
        &self,
        strain: &Voigt,
        committed: &PointState,
        committed_internal: &[f64],
        trial_internal: &mut [f64],
        out_of_plane: OutOfPlane,
    ) -> (PointState, Tangent) {
        debug_assert!(committed_internal.is_empty() && trial_internal.is_empty());
        self.update(strain, committed, out_of_plane)
    }

    /// The centre of the yield surface, the total backstress α = Σ α_k (stress-like Voigt),
    /// of a point whose internal variables are `internal`; zero by default.
    fn backstress(&self, _internal: &[f64]) -> Voigt {
        Voigt::zeros()
    }

    /// Energy per unit volume stored in the internal variables (MPa): the free energy of
    /// the backstresses, Σ 3/(4 C_k) α_k:α_k. Counted as stored by the energy balance; the
    /// plastic work minus its change is dissipated. 0 by default.
    fn hardening_energy(&self, _internal: &[f64]) -> f64 {
        0.0
    }
}

/// Iteration cap of [`bracketed_root`] (the return maps converge in a handful of
/// iterations; the cap only guards the bisection fallback).
pub(crate) const MAX_ITERATIONS: usize = 200;

/// The root in (0, `hi`) of a scalar return-mapping equation F with F(0) > 0 ≥ F(`hi`):
/// Newton's iteration safeguarded by bisection (a step that leaves the shrinking bracket is
/// replaced by its midpoint), to round-off. `residual` returns F and dF/dx. Used by the
/// plane-stress J2 return ([`j2`]) and the Armstrong–Frederick return ([`cyclic`]).
pub(crate) fn bracketed_root(mut hi: f64, residual: impl Fn(f64) -> (f64, f64)) -> f64 {
    let (mut lo, mut x) = (0.0, 0.0);
    for _ in 0..MAX_ITERATIONS {
        let (f, slope) = residual(x);
        if f == 0.0 {
            break;
        }
        if f > 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let mut next = x - f / slope;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        let step = next - x;
        x = next;
        // Quadratic convergence: once the Newton correction is at round-off level the
        // iterate is the root to machine precision.
        if step.abs() <= 4.0 * f64::EPSILON * x || hi - lo <= 4.0 * f64::EPSILON * hi {
            break;
        }
    }
    x
}

/// Von Mises equivalent stress of a Voigt stress (xx, yy, xy, zz, xθ, yθ).
pub fn von_mises(s: &Voigt) -> f64 {
    let (xx, yy, zz) = (s[0], s[1], s[ZZ]);
    let normal = 0.5 * ((xx - yy).powi(2) + (yy - zz).powi(2) + (zz - xx).powi(2));
    // Shear terms added one by one (3 τ τ each), so that without twist the value is the
    // plane formula's bit for bit.
    SHEAR
        .iter()
        .fold(normal, |acc, &i| acc + 3.0 * s[i] * s[i])
        .sqrt()
}
