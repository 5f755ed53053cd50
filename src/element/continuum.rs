//! The 2D continuum element (quad8 with 3×3 Gauss points, tri6 with a 6-point rule) in plane
//! stress, plane strain and axisymmetry: paper Eqs. (33)–(34),
//! K = ∫ Bᵀ C B dV and F = ∫ Bᵀ σ dV, with dV = t dA or 2πr dA.
//!
//! # Formulations ([`Formulation`])
//! - **Full** (`"full"`): the standard displacement element above, every strain component
//!   sampled at every point of the full rule.
//! - **B-bar** (`"bbar"`, Hughes 1980, IJNME 15, 1413–1418; de Souza Neto, Perić & Owen,
//!   *Computational Methods for Plasticity* (2008) §15.2; Simo & Hughes (1998) §4.4): the
//!   volumetric strain θ = ε_xx + ε_yy + ε_zz (in axisymmetry ε_rr + ε_zz + ε_θθ with the hoop
//!   strain u_r / r) is replaced by its L2 projection θ̄ over the cell onto the linear fields
//!   (1, x, y), and the strain the material sees is ε̄ = ε + ⅓ (θ̄ − θ) m, m = (1, 1, 0, 1):
//!   the deviatoric part is untouched and fully integrated.
//!
//! Why: fully integrated quadratic elements *lock* when the material is (nearly)
//! incompressible — isochoric plastic flow, ν → ½ — because the 9 (6) volumetric constraints
//! per cell leave the mesh too few isochoric displacement fields. Measured: a
//! perfectly plastic thick cylinder (b/a = 2, ε_z = 0) under 1.05 p_L "converges" with full
//! integration to bore displacements of 7.7 mm, 117 mm and 1.8 m on 4, 8 and 16 quad8 through
//! the wall (tri6: 22 mm to 10 m), where no equilibrium exists; with B-bar Newton fails above
//! 1.00002 p_L. Nearly incompressible Lamé (ν = 0.4999, 4 cells): full integration −9 %
//! (quad8), B-bar −0.003 %.
//!
//! Choices, measured on those problems and on Prandtl's punch:
//! - Linear (3-term) projection for both kinds: the constant one (mean dilatation, Q8/P0 and
//!   P2/P0) collapses the cylinder at 0.987–0.999 p_L (from below), its stresses are poor (the
//!   plastic front of tri6 is off by up to 7 % of the wall) and it needs more Newton
//!   iterations; the linear one gives p_L within 2·10⁻⁵ from above, Hill's front within
//!   0.12 % of the wall (ν = 0.49) and Prandtl's (2 + π)k within +0.55 % (+1.05 % on a coarse
//!   mesh; full quad8: +1.5 % and still rising).
//!   For straight-sided tri6 in plane strain θ is already linear, so there B-bar equals full
//!   integration (P2/P1-discontinuous pressure), which on these problems does not lock.
//! - Not uniform 2×2 reduced integration: quad8 with 2×2 points has a spurious zero-energy
//!   mode, and the per-point state arrays and stress recovery would change.
//!
//! Properties: ε̄ is still linear in the nodal displacements, ε̄ = B̄ u with a fixed
//! B̄ = B + ⅓ m (b̄_vol − mᵀB), so the tangent ∫ B̄ᵀ D B̄ dV is the exact derivative of the
//! internal force ∫ B̄ᵀ σ(B̄ u) dV (symmetric, Newton stays quadratic); a constant strain field
//! is reproduced exactly (θ̄ = θ: the patch test passes); and since the deviatoric part keeps
//! the full rule the element has no spurious zero-energy (hourglass) modes. In plane strain
//! ε̄_zz = ⅓ (θ̄ − θ) is not zero pointwise, only its projection is. Plane stress has no
//! volumetric constraint (ε_zz is free), so the formulation does not apply there and is
//! rejected (see [`Formulation::for_body`], which also sets the defaults).

use super::kinematics::{CellPoints, PLANE_STRAINS, PointKinematics, fill_cell_kinematics};
use super::quadrature::{MAX_CELL_POINTS, cell_rule};
use super::shape::cell_shape;
use super::small::{
    add_transposed_matrix_product, add_transposed_product, matrix_product, product,
};
use super::{
    Analysis, ElementInput, ElementMatrix, ElementOutput, ElementVector, MAX_ELEMENT_DOFS,
    MAX_ELEMENT_NODES,
};
use crate::material::{Material, OutOfPlane, PointState, R_THETA, Tangent, Voigt, ZZ};
use crate::mesh::CellKind;
use nalgebra::{SMatrix, SVector};

/// How a continuum cell computes its strains (see the module docs); chosen per body by
/// `formulation = "full" | "bbar"` in a case file's `[[body]]`
/// ([`FormulationKind`](crate::config::FormulationKind)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Formulation {
    /// Standard displacement formulation, full integration.
    #[default]
    Full,
    /// B-bar: projected volumetric strain, fully integrated deviatoric strain (locking-free).
    Bbar,
}

/// Poisson's ratio from which elastic bodies in plane strain and axisymmetry get
/// [`Formulation::Bbar`] by default (see [`Formulation::for_body`]).
pub const BBAR_DEFAULT_NU: f64 = 0.45;

impl Formulation {
    /// The formulation of a body: the one `requested` in the case file, or by default
    /// - [`Formulation::Bbar`] in plane strain and axisymmetry for plastic bodies (J2 flow is
    ///   isochoric) and for elastic bodies with ν ≥ [`BBAR_DEFAULT_NU`];
    /// - [`Formulation::Full`] otherwise, and always in plane stress.
    ///
    /// Asking for B-bar in plane stress is an error: there is no volumetric constraint to
    /// relax there.
    pub fn for_body(
        requested: Option<Formulation>,
        analysis: &Analysis,
        plastic: bool,
        nu: f64,
    ) -> Result<Formulation, String> {
        match requested {
            Some(Formulation::Bbar) if analysis.is_plane_stress() => Err(
                "formulation = \"bbar\" does not apply to plane stress (sigma_zz = 0 leaves \
                 eps_zz free, so there is no volumetric locking to avoid); use \"full\" or omit \
                 the key"
                    .into(),
            ),
            Some(f) => Ok(f),
            None if analysis.is_plane_stress() => Ok(Formulation::Full),
            None if plastic || nu >= BBAR_DEFAULT_NU => Ok(Formulation::Bbar),
            None => Ok(Formulation::Full),
        }
    }

    /// Name as written in case files.
    pub fn name(self) -> &'static str {
        match self {
            Formulation::Full => "full",
            Formulation::Bbar => "bbar",
        }
    }
}

/// The thermal eigenstrain of a cell: its body's linear expansion coefficient α (1/K) and
/// the temperature change from the stress-free reference at its nodes (node order of the
/// cell; a uniform change has the same value at every node).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellTemperature {
    pub expansion: f64,
    pub nodal: [f64; 8],
}

/// The components of the isotropic unit strain m = (1, 1, 0, 1) (xx, yy, zz; rr, zz, θθ):
/// the directions a thermal strain α ΔT m stretches.
pub const NORMAL_COMPONENTS: [usize; 3] = [0, 1, ZZ];

/// The thermal strain magnitude α ΔT at every point of `kind`'s rule, ΔT interpolated from
/// the nodal values with the cell's shape functions.
#[inline(always)]
fn thermal_strains(kind: CellKind, t: &CellTemperature) -> [f64; MAX_CELL_POINTS] {
    let mut out = [0.0; MAX_CELL_POINTS];
    for (e, p) in out.iter_mut().zip(cell_rule(kind)) {
        let s = cell_shape(kind, p.xi, p.eta);
        let dt: f64 = (0..kind.node_count()).map(|i| s.n[i] * t.nodal[i]).sum();
        *e = t.expansion * dt;
    }
    out
}

/// What a cell takes from its body: the element formulation, the material, when the model
/// has temperatures the cell's thermal eigenstrain, and when the material has internal
/// variables (backstresses) their history.
pub struct CellBody<'a> {
    pub formulation: Formulation,
    pub material: &'a dyn Material,
    pub temperature: Option<&'a CellTemperature>,
    pub history: Option<CellHistory<'a>>,
}

/// Tangent stiffness and internal force of one continuum cell for element displacements `u`.
///
/// Each integration point's material is updated from `committed[g]` into `trial[g]`, and,
/// for a material with internal variables, from the cell's `history` (point after point,
/// [`Material::internal_variables`] each). The tangent is accumulated into `k` only when `k`
/// is given (residual-only evaluations skip it). Cells must have passed [`min_jacobian`](super::kinematics::min_jacobian) at
/// model set-up.
///
/// With a `temperature`, the material sees the mechanical strain ε − α ΔT m (the thermal
/// strain is a kinematic eigenstrain, as Abaqus' *EXPANSION); the state keeps the total
/// strain (in plane stress the material's out-of-plane ε_zz plus α ΔT). The tangent does
/// not depend on the temperature.
pub fn evaluate_cell(
    analysis: &Analysis,
    kind: CellKind,
    coords: &[[f64; 2]; 8],
    body: CellBody,
    input: &ElementInput<PointState>,
    output: ElementOutput<PointState>,
) {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has the features the function is compiled for.
        return unsafe { evaluate_cell_avx2(analysis, kind, coords, body, input, output) };
    }
    evaluate_cell_inline(analysis, kind, coords, body, input, output)
}

/// [`evaluate_cell`] compiled for AVX2 and FMA (x86-64-v3): the release build targets plain
/// x86-64, whose 128-bit vectors leave the small dense products of a cell scalar. The same
/// operations in the same order (Rust fuses no multiply-add unless asked), so the same bits
/// (unit test below; identical output files). Measured on the elasto-plastic flat punch (55
/// tangent assemblies of 7058 cells): assembly phase 0.88–0.94 → 0.56–0.59 s; a build for
/// x86-64-v3 as a whole gains no more (0.55–0.64 s).
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn evaluate_cell_avx2(
    analysis: &Analysis,
    kind: CellKind,
    coords: &[[f64; 2]; 8],
    body: CellBody,
    input: &ElementInput<PointState>,
    output: ElementOutput<PointState>,
) {
    evaluate_cell_inline(analysis, kind, coords, body, input, output)
}

/// The body of [`evaluate_cell`], inlined into each compiled variant.
#[inline(always)]
fn evaluate_cell_inline(
    analysis: &Analysis,
    kind: CellKind,
    coords: &[[f64; 2]; 8],
    body: CellBody,
    input: &ElementInput<PointState>,
    output: ElementOutput<PointState>,
) {
    let CellBody {
        formulation,
        material,
        temperature,
        mut history,
    } = body;
    let ElementInput { u, committed, .. } = *input;
    let ElementOutput {
        trial,
        mut k,
        mut f,
    } = output;
    let out_of_plane = if analysis.is_plane_stress() {
        OutOfPlane::StressFree
    } else {
        OutOfPlane::StrainGiven
    };
    let stride = material.internal_variables();
    let mut points = CellPoints::zeroed(kind);
    fill_cell_kinematics(analysis, kind, coords, formulation, &mut points);
    let thermal = temperature
        .filter(|t| t.expansion != 0.0)
        .map(|t| thermal_strains(kind, t));
    let twist = analysis.has_twist();
    let (u_plane, u_theta) = split_components(u, twist);
    let mut blocks = twist.then(TwistBlocks::default);
    let (mut f_plane, mut f_theta) = (SVector::<f64, 16>::zeros(), SVector::<f64, 8>::zeros());
    for (g, pk) in points.iter().enumerate() {
        let mut strain = Voigt::zeros();
        strain
            .fixed_rows_mut::<PLANE_STRAINS>(0)
            .copy_from(&product(&pk.b, u_plane));
        if twist {
            strain
                .fixed_rows_mut::<2>(R_THETA)
                .copy_from(&product(&pk.twist, u_theta));
        }
        let eigen = thermal.map(|t| t[g]);
        for c in NORMAL_COMPONENTS {
            strain[c] -= eigen.unwrap_or_default();
        }
        let (mut state, d) = match history.as_mut() {
            Some(h) => {
                let slots = g * stride..(g + 1) * stride;
                material.update_with_history(
                    &strain,
                    &committed[g],
                    &h.committed[slots.clone()],
                    &mut h.trial[slots],
                    out_of_plane,
                )
            }
            None => material.update(&strain, &committed[g], out_of_plane),
        };
        if let Some(eigen) = eigen {
            for c in NORMAL_COMPONENTS {
                state.strain[c] += eigen;
            }
        }
        if let Some(k) = k.as_deref_mut() {
            let d_plane = d.fixed_view::<PLANE_STRAINS, PLANE_STRAINS>(0, 0);
            let db = matrix_product(&d_plane, &pk.b);
            match blocks.as_mut() {
                Some(blocks) => blocks.add(pk, &d, &db),
                None => add_transposed_matrix_product(
                    &mut k.fixed_view_mut::<16, 16>(0, 0),
                    pk.dvol,
                    &pk.b,
                    &db,
                ),
            }
        }
        if let Some(f) = f.as_deref_mut() {
            // With twist the plane and circumferential parts are kept apart until the end.
            let stress_plane = state.stress.fixed_rows::<PLANE_STRAINS>(0);
            if twist {
                let stress_theta = state.stress.fixed_rows::<2>(R_THETA);
                add_transposed_product(&mut f_plane, pk.dvol, &pk.b, &stress_plane);
                add_transposed_product(&mut f_theta, pk.dvol, &pk.twist, &stress_theta);
            } else {
                let mut f = f.fixed_rows_mut::<16>(0);
                add_transposed_product(&mut f, pk.dvol, &pk.b, &stress_plane);
            }
        }
        trial[g] = state;
    }
    if twist {
        if let Some(f) = f {
            for a in 0..16 {
                f[3 * (a / 2) + a % 2] += f_plane[a];
            }
            for i in 0..8 {
                f[3 * i + 2] += f_theta[i];
            }
        }
        if let (Some(k), Some(blocks)) = (k, blocks) {
            blocks.scatter(k);
        }
    }
}

/// The thermal load matrix G of a cell of a linear material: column j holds the nodal forces
/// of a unit temperature change at node j, G_j = ∫ B̄ᵀ (D m) α N_j dV (rows in the element
/// vector's order), so that the cell's internal force under nodal temperature changes ΔT is
/// K u − G ΔT: the thermal strain α ΔT m, with ΔT interpolated by the shape functions, is
/// subtracted from B̄ u before the linear material sees it ([`evaluate_cell`]). D m is the
/// material's own stress of the unit strain m (plane stress condenses it as the cell does).
/// Same points and weights as the cell's force.
pub fn thermal_load_matrix(
    analysis: &Analysis,
    kind: CellKind,
    coords: &[[f64; 2]; 8],
    formulation: Formulation,
    material: &dyn Material,
    expansion: f64,
) -> SMatrix<f64, MAX_ELEMENT_DOFS, MAX_ELEMENT_NODES> {
    let out_of_plane = if analysis.is_plane_stress() {
        OutOfPlane::StressFree
    } else {
        OutOfPlane::StrainGiven
    };
    let mut unit = Voigt::zeros();
    for c in NORMAL_COMPONENTS {
        unit[c] = 1.0;
    }
    let stress = material
        .update(&unit, &PointState::default(), out_of_plane)
        .0
        .stress;
    let (plane, theta) = (
        stress.fixed_rows::<PLANE_STRAINS>(0),
        stress.fixed_rows::<2>(R_THETA),
    );
    let mut points = CellPoints::zeroed(kind);
    fill_cell_kinematics(analysis, kind, coords, formulation, &mut points);
    let d = analysis.dofs_per_node();
    let twist = analysis.has_twist();
    let mut g = SMatrix::<f64, MAX_ELEMENT_DOFS, MAX_ELEMENT_NODES>::zeros();
    for (p, pk) in cell_rule(kind).iter().zip(points.iter()) {
        let (mut f_plane, mut f_theta) = (SVector::<f64, 16>::zeros(), SVector::<f64, 8>::zeros());
        add_transposed_product(&mut f_plane, pk.dvol * expansion, &pk.b, &plane);
        if twist {
            add_transposed_product(&mut f_theta, pk.dvol * expansion, &pk.twist, &theta);
        }
        let n = cell_shape(kind, p.xi, p.eta).n;
        for (j, &nj) in n.iter().enumerate().take(kind.node_count()) {
            for a in 0..16 {
                g[(d * (a / 2) + a % 2, j)] += f_plane[a] * nj;
            }
            if twist {
                for i in 0..8 {
                    g[(3 * i + 2, j)] += f_theta[i] * nj;
                }
            }
        }
    }
    g
}

/// The in-plane (u_x, u_y) and circumferential (u_θ) nodal displacements of an element
/// vector: without twist the leading 16 entries and zeros.
#[inline(always)]
fn split_components(u: &ElementVector, twist: bool) -> (SVector<f64, 16>, SVector<f64, 8>) {
    if !twist {
        return (u.fixed_rows::<16>(0).into_owned(), SVector::zeros());
    }
    let plane = SVector::<f64, 16>::from_fn(|a, _| u[3 * (a / 2) + a % 2]);
    let theta = SVector::<f64, 8>::from_fn(|i, _| u[3 * i + 2]);
    (plane, theta)
}

/// The four blocks of a twist cell's tangent, in-plane (p) and circumferential (θ) dofs,
/// accumulated over the points and scattered into the element matrix's node-by-node order
/// once.
#[derive(Default)]
struct TwistBlocks {
    pp: SMatrix<f64, 16, 16>,
    p_theta: SMatrix<f64, 16, 8>,
    theta_p: SMatrix<f64, 8, 16>,
    theta_theta: SMatrix<f64, 8, 8>,
}

impl TwistBlocks {
    /// Adds one point's Bᵀ D B dV, `db` = D_pp B (the plane block).
    #[inline(always)]
    fn add(&mut self, pk: &PointKinematics, d: &Tangent, db: &SMatrix<f64, 4, 16>) {
        let d_p_theta = d.fixed_view::<PLANE_STRAINS, 2>(0, R_THETA);
        let d_theta_p = d.fixed_view::<2, PLANE_STRAINS>(R_THETA, 0);
        let d_theta_theta = d.fixed_view::<2, 2>(R_THETA, R_THETA);
        let dv = pk.dvol;
        add_transposed_matrix_product(&mut self.pp, dv, &pk.b, db);
        let d_p_theta_twist = matrix_product(&d_p_theta, &pk.twist);
        add_transposed_matrix_product(&mut self.p_theta, dv, &pk.b, &d_p_theta_twist);
        let d_theta_p_b = matrix_product(&d_theta_p, &pk.b);
        add_transposed_matrix_product(&mut self.theta_p, dv, &pk.twist, &d_theta_p_b);
        let d_theta_theta_twist = matrix_product(&d_theta_theta, &pk.twist);
        add_transposed_matrix_product(&mut self.theta_theta, dv, &pk.twist, &d_theta_theta_twist);
    }

    /// Adds the blocks to `k` in element dof order 3·i + c.
    #[inline(always)]
    fn scatter(&self, k: &mut ElementMatrix) {
        let plane = |a: usize| 3 * (a / 2) + a % 2;
        let theta = |i: usize| 3 * i + 2;
        for a in 0..16 {
            for b in 0..16 {
                k[(plane(a), plane(b))] += self.pp[(a, b)];
            }
            for j in 0..8 {
                k[(plane(a), theta(j))] += self.p_theta[(a, j)];
                k[(theta(j), plane(a))] += self.theta_p[(j, a)];
            }
        }
        for i in 0..8 {
            for j in 0..8 {
                k[(theta(i), theta(j))] += self.theta_theta[(i, j)];
            }
        }
    }
}

/// The internal variables of one cell's points ([`Material::internal_variables`] per point,
/// point after point): the committed ones read, the trial ones written.
#[derive(Debug)]
pub struct CellHistory<'a> {
    pub committed: &'a [f64],
    pub trial: &'a mut [f64],
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::kinematics::{cell_kinematics, point_kinematics};
    use crate::element::quadrature::QuadPoint;
    use crate::element::{ElementMatrix, ElementVector};
    use crate::material::elastic::LinearElastic;
    use crate::material::j2::J2Plasticity;
    use nalgebra::{DMatrix, SymmetricEigen};

    const PLANE: Analysis = Analysis::PlaneStrain { thickness: 1.0 };
    const AXI: Analysis = Analysis::Axisymmetric;

    /// A distorted, curved quad8 and a distorted tri6 away from the axis.
    fn cell(kind: CellKind) -> [[f64; 2]; 8] {
        match kind {
            CellKind::Quad8 => [
                [1.0, 0.0],
                [2.2, 0.1],
                [2.0, 1.3],
                [0.9, 1.0],
                [1.6, 0.1],
                [2.15, 0.7],
                [1.45, 1.2],
                [0.95, 0.5],
            ],
            CellKind::Tri6 => [
                [1.0, 0.0],
                [2.1, 0.2],
                [1.3, 1.1],
                [1.55, 0.05],
                [1.75, 0.7],
                [1.1, 0.55],
                [0.0, 0.0],
                [0.0, 0.0],
            ],
        }
    }

    fn evaluate(
        analysis: &Analysis,
        kind: CellKind,
        formulation: Formulation,
        material: &dyn Material,
        committed: &[PointState],
        u: &ElementVector,
        k: Option<&mut ElementMatrix>,
    ) -> (ElementVector, Vec<PointState>) {
        let mut f = ElementVector::zeros();
        let mut trial = vec![PointState::default(); MAX_CELL_POINTS];
        evaluate_cell(
            analysis,
            kind,
            &cell(kind),
            CellBody {
                formulation,
                material,
                temperature: None,
                history: None,
            },
            &ElementInput {
                u,
                committed,
                algorithm: Default::default(),
            },
            ElementOutput {
                trial: &mut trial,
                k,
                f: Some(&mut f),
            },
        );
        (f, trial)
    }

    /// Element displacements of a smooth field with a large volumetric part, scaled by `s`.
    fn field(kind: CellKind, s: f64) -> ElementVector {
        let mut u = ElementVector::zeros();
        for (i, x) in cell(kind)[..kind.node_count()].iter().enumerate() {
            u[2 * i] = s * (0.8 * x[0] + 0.3 * x[1] * x[1] - 0.2 * x[0] * x[1]);
            u[2 * i + 1] = s * (-0.4 * x[1] + 0.5 * x[0] * x[0] + 0.1 * x[1] * x[1]);
        }
        u
    }

    const TWIST: Analysis = Analysis::AxisymmetricTwist;

    /// A displacement field of a twist cell (3 dofs per node): the in-plane part of
    /// [`field`] and a circumferential u_θ = s (0.6 r z + 0.2 r² − 0.1 z²).
    fn twist_field(kind: CellKind, s: f64) -> ElementVector {
        let plane = field(kind, s);
        let mut u = ElementVector::zeros();
        for (i, x) in cell(kind)[..kind.node_count()].iter().enumerate() {
            u[3 * i] = plane[2 * i];
            u[3 * i + 1] = plane[2 * i + 1];
            u[3 * i + 2] = s * (0.6 * x[0] * x[1] + 0.2 * x[0] * x[0] - 0.1 * x[1] * x[1]);
        }
        u
    }

    /// The thermal load matrix against the element itself: for nodal temperature changes
    /// ΔT and displacements u, the cell's force under ΔT is its force without it less G ΔT
    /// (f = K u − G ΔT), for every analysis, both formulations and both kinds.
    #[test]
    fn the_thermal_load_matrix_gives_the_cells_thermal_force() {
        let elastic = LinearElastic::new(200_000.0, 0.3).unwrap();
        let expansion = 1.2e-5;
        let nodal = [30.0, -12.0, 55.0, 8.0, 21.0, -40.0, 3.0, 17.0];
        let stress = Analysis::PlaneStress { thickness: 2.0 };
        let cases = [(PLANE, false), (stress, false), (AXI, false), (TWIST, true)];
        let virgin = vec![PointState::default(); MAX_CELL_POINTS];
        for (analysis, twist) in cases {
            for kind in [CellKind::Quad8, CellKind::Tri6] {
                for formulation in [Formulation::Full, Formulation::Bbar] {
                    if formulation == Formulation::Bbar && analysis.is_plane_stress() {
                        continue;
                    }
                    let n = kind.node_count();
                    let mut dt = [0.0; 8];
                    dt[..n].copy_from_slice(&nodal[..n]);
                    let u = if twist {
                        twist_field(kind, 1e-3)
                    } else {
                        field(kind, 1e-3)
                    };
                    let force = |temperature: Option<&CellTemperature>| {
                        let mut f = ElementVector::zeros();
                        let mut trial = vec![PointState::default(); MAX_CELL_POINTS];
                        evaluate_cell(
                            &analysis,
                            kind,
                            &cell(kind),
                            CellBody {
                                formulation,
                                material: &elastic,
                                temperature,
                                history: None,
                            },
                            &ElementInput {
                                u: &u,
                                committed: &virgin,
                                algorithm: Default::default(),
                            },
                            ElementOutput {
                                trial: &mut trial,
                                k: None,
                                f: Some(&mut f),
                            },
                        );
                        f
                    };
                    let heated = CellTemperature {
                        expansion,
                        nodal: dt,
                    };
                    let g = thermal_load_matrix(
                        &analysis,
                        kind,
                        &cell(kind),
                        formulation,
                        &elastic,
                        expansion,
                    );
                    let dt = SVector::<f64, 8>::from(dt);
                    let expected = force(None) - g * dt;
                    let got = force(Some(&heated));
                    let scale = (g * dt).amax();
                    assert!(scale > 1.0, "{analysis:?} {kind:?}: a thermal force");
                    let error = (got - expected).amax() / scale;
                    assert!(
                        error < 1e-12,
                        "{analysis:?} {kind:?} {formulation:?}: relative error {error:e}"
                    );
                    // Only the element's own dofs carry forces.
                    let d = analysis.dofs_per_node();
                    assert!(g.rows(d * n, MAX_ELEMENT_DOFS - d * n).amax() == 0.0);
                }
            }
        }
    }

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_avx2_variant_gives_the_plain_variants_bits() {
        if !(std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")) {
            return;
        }
        let elastic = LinearElastic::new(200_000.0, 0.3).unwrap();
        let j2 = J2Plasticity::new(elastic, 250.0, 1500.0).unwrap();
        let virgin = vec![PointState::default(); MAX_CELL_POINTS];
        let cases = [(PLANE, 2, false), (AXI, 2, false), (TWIST, 3, true)];
        for (analysis, d, twist) in cases {
            for kind in [CellKind::Quad8, CellKind::Tri6] {
                for formulation in [Formulation::Full, Formulation::Bbar] {
                    // Past yield: plastic points and their consistent tangent.
                    let u = if twist {
                        twist_field(kind, 4e-3)
                    } else {
                        field(kind, 4e-3)
                    };
                    let run = |avx2: bool| {
                        let (mut k, mut f) = (ElementMatrix::zeros(), ElementVector::zeros());
                        let mut trial = vec![PointState::default(); MAX_CELL_POINTS];
                        let body = CellBody {
                            formulation,
                            material: &j2,
                            temperature: None,
                            history: None,
                        };
                        let input = ElementInput {
                            u: &u,
                            committed: &virgin,
                            algorithm: Default::default(),
                        };
                        let output = ElementOutput {
                            trial: &mut trial,
                            k: Some(&mut k),
                            f: Some(&mut f),
                        };
                        let coords = cell(kind);
                        if avx2 {
                            // SAFETY: the features were detected above.
                            unsafe {
                                evaluate_cell_avx2(&analysis, kind, &coords, body, &input, output)
                            }
                        } else {
                            evaluate_cell_inline(&analysis, kind, &coords, body, &input, output)
                        }
                        (k, f, trial)
                    };
                    let ((k1, f1, t1), (k2, f2, t2)) = (run(false), run(true));
                    assert!(t1.iter().any(|p| p.yielding), "{analysis:?} {kind:?}");
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(k1.as_slice()), bits(k2.as_slice()), "{analysis:?} {d}");
                    assert_eq!(bits(f1.as_slice()), bits(f2.as_slice()));
                    assert_eq!(t1, t2);
                }
            }
        }
    }

    #[test]
    fn twist_strains_of_a_rigid_rotation_and_a_torsion_field() {
        // u_θ = φ r (rigid rotation about the axis) strains nothing; u_θ = κ r z (uniform
        // torsion of a shaft) gives γ_zθ = κ r and γ_rθ = 0. On straight-sided cells (affine
        // map) both fields are in the quadratic space, so exactly, at every point.
        let (phi, kappa) = (2e-3, 5e-4);
        let mid = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        let [p, q, r, t] = [[1.0, 0.0], [2.0, 0.2], [2.3, 1.2], [1.3, 1.0]];
        let quad = [p, q, r, t, mid(p, q), mid(q, r), mid(r, t), mid(t, p)];
        let tri = [p, q, t, mid(p, q), mid(q, t), mid(t, p), [0.0; 2], [0.0; 2]];
        for (kind, coords) in [(CellKind::Quad8, quad), (CellKind::Tri6, tri)] {
            let nodes = &coords[..kind.node_count()];
            let theta = |f: &dyn Fn([f64; 2]) -> f64| {
                SVector::<f64, 8>::from_fn(|i, _| nodes.get(i).map_or(0.0, |&x| f(x)))
            };
            let rotation = theta(&|x| phi * x[0]);
            let torsion = theta(&|x| kappa * x[0] * x[1]);
            for pk in cell_kinematics(&TWIST, kind, &coords, Formulation::Bbar).iter() {
                assert!((pk.twist * rotation).amax() < 1e-17, "{kind:?}");
                let g = pk.twist * torsion;
                assert!(g[0].abs() < 1e-16 && (g[1] - kappa * pk.x[0]).abs() < 1e-16);
            }
        }
    }

    #[test]
    fn twist_cell_tangent_matches_finite_differences_in_plastic_states() {
        // J2 in six components couples the twist shears with the meridional stresses once
        // the point yields: the off-diagonal blocks of the tangent must be right too.
        let elastic = LinearElastic::new(200_000.0, 0.3).unwrap();
        let j2 = J2Plasticity::new(elastic, 250.0, 1500.0).unwrap();
        for kind in [CellKind::Quad8, CellKind::Tri6] {
            for formulation in [Formulation::Full, Formulation::Bbar] {
                let virgin = vec![PointState::default(); MAX_CELL_POINTS];
                let eval =
                    |committed: &[PointState], u: &ElementVector, k: Option<&mut ElementMatrix>| {
                        evaluate(&TWIST, kind, formulation, &j2, committed, u, k)
                    };
                let (_, committed) = eval(&virgin, &twist_field(kind, 2e-3), None);
                let u = twist_field(kind, 3e-3) + twist_field(kind, 4e-4).map(|x| x.sin());
                let mut k = ElementMatrix::zeros();
                let (_, trial) = eval(&committed, &u, Some(&mut k));
                let n = cell_rule(kind).len();
                assert!(trial[..n].iter().all(|s| s.yielding && s.stress[5] != 0.0));
                let (h, dofs, scale) = (1e-8, 3 * kind.node_count(), k.amax());
                for j in 0..dofs {
                    let (mut up, mut um) = (u, u);
                    up[j] += h;
                    um[j] -= h;
                    let fd =
                        (eval(&committed, &up, None).0 - eval(&committed, &um, None).0) / (2.0 * h);
                    for i in 0..dofs {
                        // As in the plane test: O(h²) differences, far below 1e-6.
                        assert!(
                            (fd[i] - k[(i, j)]).abs() < 1e-6 * scale,
                            "{kind:?} {formulation:?} K[{i},{j}] = {} vs fd {}",
                            k[(i, j)],
                            fd[i]
                        );
                    }
                }
                assert!((k - k.transpose()).amax() < 1e-9 * scale);
                assert!(k.rows(dofs, 24 - dofs).amax() == 0.0);
            }
        }
    }

    #[test]
    fn twist_cell_without_circumferential_motion_equals_the_axisymmetric_cell() {
        // With u_θ = 0 an elastic twist cell's meridional forces and stiffness are those of
        // the plain axisymmetric cell (isotropic elasticity does not couple the blocks).
        let elastic = LinearElastic::new(200_000.0, 0.3).unwrap();
        for kind in [CellKind::Quad8, CellKind::Tri6] {
            let virgin = vec![PointState::default(); MAX_CELL_POINTS];
            let plane = field(kind, 1e-3);
            let mut u = ElementVector::zeros();
            for i in 0..kind.node_count() {
                u[3 * i] = plane[2 * i];
                u[3 * i + 1] = plane[2 * i + 1];
            }
            let (mut ka, mut kt) = (ElementMatrix::zeros(), ElementMatrix::zeros());
            let full = Formulation::Full;
            let (fa, _) = evaluate(&AXI, kind, full, &elastic, &virgin, &plane, Some(&mut ka));
            let (ft, _) = evaluate(&TWIST, kind, full, &elastic, &virgin, &u, Some(&mut kt));
            for a in 0..2 * kind.node_count() {
                let ta = 3 * (a / 2) + a % 2;
                assert!((fa[a] - ft[ta]).abs() <= 1e-12 * fa.amax());
                for b in 0..2 * kind.node_count() {
                    let tb = 3 * (b / 2) + b % 2;
                    assert!((ka[(a, b)] - kt[(ta, tb)]).abs() <= 1e-12 * ka.amax());
                }
                for i in 0..kind.node_count() {
                    assert_eq!(kt[(ta, 3 * i + 2)], 0.0);
                }
            }
        }
    }

    #[test]
    fn tangent_matches_finite_differences_in_plastic_states() {
        let elastic = LinearElastic::new(200_000.0, 0.3).unwrap();
        let j2 = J2Plasticity::new(elastic, 250.0, 1500.0).unwrap();
        for analysis in [PLANE, AXI] {
            for kind in [CellKind::Quad8, CellKind::Tri6] {
                for formulation in [Formulation::Full, Formulation::Bbar] {
                    // Committed: a plastic state from a first load; then a further load.
                    let committed = vec![PointState::default(); MAX_CELL_POINTS];
                    let (_, committed) = evaluate(
                        &analysis,
                        kind,
                        formulation,
                        &j2,
                        &committed,
                        &field(kind, 2e-3),
                        None,
                    );
                    let u = field(kind, 3e-3) + field(kind, 4e-4).map(|x| x.sin());
                    let mut k = ElementMatrix::zeros();
                    let (_, trial) = evaluate(
                        &analysis,
                        kind,
                        formulation,
                        &j2,
                        &committed,
                        &u,
                        Some(&mut k),
                    );
                    let n = cell_rule(kind).len();
                    assert!(
                        trial[..n].iter().all(|s| s.yielding),
                        "{analysis:?} {kind:?} {formulation:?}: every point should yield"
                    );
                    let h = 1e-8;
                    let dofs = 2 * kind.node_count();
                    let scale = k.amax();
                    for j in 0..dofs {
                        let (mut up, mut um) = (u, u);
                        up[j] += h;
                        um[j] -= h;
                        let eval = |u: &ElementVector| {
                            evaluate(&analysis, kind, formulation, &j2, &committed, u, None).0
                        };
                        let fd = (eval(&up) - eval(&um)) / (2.0 * h);
                        for i in 0..dofs {
                            // Central differences of a piecewise-smooth return map: error
                            // O(h²) relative, far below 1e-6 of the largest entry.
                            assert!(
                                (fd[i] - k[(i, j)]).abs() < 1e-6 * scale,
                                "{analysis:?} {kind:?} {formulation:?} K[{i},{j}] = {} vs fd {}",
                                k[(i, j)],
                                fd[i]
                            );
                        }
                    }
                    // The B-bar tangent is symmetric like the full one.
                    assert!((k - k.transpose()).amax() < 1e-9 * scale);
                }
            }
        }
    }

    #[test]
    fn bbar_leaves_linear_displacement_fields_unchanged() {
        // A constant strain field: θ̄ = θ, so B̄ u = B u at every point (patch test), also
        // in axisymmetry where u_r = c r gives a constant hoop strain.
        for analysis in [PLANE, AXI] {
            for kind in [CellKind::Quad8, CellKind::Tri6] {
                let mut u = ElementVector::zeros();
                for (i, x) in cell(kind)[..kind.node_count()].iter().enumerate() {
                    u[2 * i] = 1e-3 * x[0] + if analysis == AXI { 0.0 } else { 4e-4 * x[1] };
                    u[2 * i + 1] = -7e-4 * x[1] + 2e-4 * x[0];
                }
                let full = cell_kinematics(&analysis, kind, &cell(kind), Formulation::Full);
                let bbar = cell_kinematics(&analysis, kind, &cell(kind), Formulation::Bbar);
                for (p, q) in full.iter().zip(bbar.iter()) {
                    assert!(
                        (p.b * u.fixed_rows::<16>(0) - q.b * u.fixed_rows::<16>(0)).amax() < 1e-15,
                        "{analysis:?} {kind:?}: {} vs {}",
                        p.b * u.fixed_rows::<16>(0),
                        q.b * u.fixed_rows::<16>(0)
                    );
                    assert_eq!(p.dvol, q.dvol);
                }
            }
        }
    }

    #[test]
    fn bbar_projects_the_volumetric_strain() {
        // For a non-uniform field, B̄ differs from B only in its volumetric part: the
        // deviatoric strain is unchanged pointwise, and the volumetric strain integrates to
        // the same total over the cell (the constant is in the projection space).
        let m = nalgebra::Vector4::new(1.0, 1.0, 0.0, 1.0);
        for analysis in [PLANE, AXI] {
            for kind in [CellKind::Quad8, CellKind::Tri6] {
                let u = field(kind, 1e-3);
                let full = cell_kinematics(&analysis, kind, &cell(kind), Formulation::Full);
                let bbar = cell_kinematics(&analysis, kind, &cell(kind), Formulation::Bbar);
                let (mut total, mut total_bar, mut change) = (0.0, 0.0, 0.0_f64);
                for (p, q) in full.iter().zip(bbar.iter()) {
                    let plane = u.fixed_rows::<16>(0);
                    let (e, e_bar) = (p.b * plane, q.b * plane);
                    let (t, t_bar) = (m.dot(&e), m.dot(&e_bar));
                    let dev = |e: nalgebra::Vector4<f64>, t: f64| e - m * (t / 3.0);
                    assert!((dev(e, t) - dev(e_bar, t_bar)).amax() < 1e-16);
                    total += t * p.dvol;
                    total_bar += t_bar * q.dvol;
                    change = change.max((t - t_bar).abs());
                }
                assert!((total - total_bar).abs() < 1e-13 * total.abs());
                assert!(
                    change > 1e-6,
                    "{analysis:?} {kind:?}: nothing was projected"
                );
            }
        }
    }

    /// Eigenvalues of the elastic stiffness of one cell, ascending.
    fn spectrum(analysis: &Analysis, kind: CellKind, formulation: Formulation) -> Vec<f64> {
        let elastic = LinearElastic::new(1.0, 0.3).unwrap();
        let mut k = ElementMatrix::zeros();
        let state = vec![PointState::default(); MAX_CELL_POINTS];
        let u = ElementVector::zeros();
        evaluate(
            analysis,
            kind,
            formulation,
            &elastic,
            &state,
            &u,
            Some(&mut k),
        );
        let n = 2 * kind.node_count();
        let k = DMatrix::from_fn(n, n, |i, j| k[(i, j)]);
        let mut values: Vec<f64> = SymmetricEigen::new(k).eigenvalues.iter().copied().collect();
        values.sort_by(f64::total_cmp);
        values
    }

    #[test]
    fn bbar_has_no_spurious_zero_energy_modes() {
        // Rigid-body modes only: 3 in plane strain, 1 (axial translation) in axisymmetry.
        // B-bar keeps the full rule for the deviatoric strain, so no hourglass modes appear
        // (unlike uniform 2×2 reduced integration of quad8, which has one).
        for (analysis, rigid) in [(PLANE, 3), (AXI, 1)] {
            for kind in [CellKind::Quad8, CellKind::Tri6] {
                for formulation in [Formulation::Full, Formulation::Bbar] {
                    let values = spectrum(&analysis, kind, formulation);
                    let largest = values.last().unwrap();
                    let zero = values.iter().filter(|v| v.abs() < 1e-10 * largest).count();
                    assert_eq!(
                        zero, rigid,
                        "{analysis:?} {kind:?} {formulation:?}: eigenvalues {values:?}"
                    );
                    // The smallest non-rigid eigenvalue is a fair fraction of the largest.
                }
            }
        }
        // For contrast, uniform 2×2 reduced integration of quad8 has one spurious mode.
        let g = 1.0 / 3f64.sqrt();
        let d = LinearElastic::new(1.0, 0.3)
            .unwrap()
            .stiffness(OutOfPlane::StrainGiven);
        let mut k = DMatrix::<f64>::zeros(16, 16);
        for (xi, eta) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
            let p = QuadPoint {
                xi,
                eta,
                weight: 1.0,
            };
            let pk = point_kinematics(&PLANE, CellKind::Quad8, &cell(CellKind::Quad8), &p).unwrap();
            let b = DMatrix::from_fn(4, 16, |i, j| pk.b[(i, j)]);
            k += b.transpose() * DMatrix::from_fn(4, 4, |i, j| d[(i, j)]) * b * pk.dvol;
        }
        let values = SymmetricEigen::new(k).eigenvalues;
        let largest = values.amax();
        let zero = values.iter().filter(|v| v.abs() < 1e-10 * largest).count();
        assert_eq!(zero, 4, "2×2 quad8: {values:?}");
    }

    #[test]
    fn default_formulations() {
        let stress = Analysis::PlaneStress { thickness: 1.0 };
        let f = |requested, analysis: &Analysis, plastic, nu| {
            Formulation::for_body(requested, analysis, plastic, nu)
        };
        assert_eq!(f(None, &PLANE, true, 0.3), Ok(Formulation::Bbar));
        assert_eq!(f(None, &AXI, true, 0.3), Ok(Formulation::Bbar));
        assert_eq!(f(None, &PLANE, false, 0.3), Ok(Formulation::Full));
        assert_eq!(f(None, &AXI, false, 0.4999), Ok(Formulation::Bbar));
        assert_eq!(f(None, &stress, true, 0.4999), Ok(Formulation::Full));
        assert_eq!(
            f(Some(Formulation::Full), &PLANE, true, 0.3),
            Ok(Formulation::Full)
        );
        assert_eq!(
            f(Some(Formulation::Bbar), &PLANE, false, 0.3),
            Ok(Formulation::Bbar)
        );
        let e = f(Some(Formulation::Bbar), &stress, true, 0.3).unwrap_err();
        assert!(e.contains("plane stress") && e.contains("bbar"), "{e}");
    }
}
