//! The kinematics of a continuum cell at its integration points: the isoparametric map, the
//! strain-displacement matrix B (paper Eq. (33)) with the hoop and twist rows of axisymmetry,
//! the volume weight, and the B-bar projection of the volumetric strain
//! ([`Formulation::Bbar`], whose reasons and measurements are in [`super::continuum`]).

use super::Analysis;
use super::continuum::Formulation;
use super::quadrature::{MAX_CELL_POINTS, QuadPoint, cell_rule};
use super::shape::{ShapeValues, cell_shape, rule_shapes};
use crate::material::ZZ;
use crate::mesh::CellKind;
use nalgebra::{SMatrix, SVector};

/// Number of terms of the volumetric-strain projection of [`Formulation::Bbar`]: 1
/// (constant, mean dilatation) or 3 (linear: 1, x, y). See the module docs for why 3.
pub const PROJECTION_TERMS: usize = 3;

/// Strain-displacement matrix: rows (xx, yy, xy, zz), columns (u_x1, u_y1, ..., u_x8, u_y8).
pub type StrainDisplacement = SMatrix<f64, 4, 16>;

/// The twist part of the strain-displacement matrix: rows (γ_rθ, γ_zθ), columns
/// (u_θ1, ..., u_θ8). The circumferential displacement enters no other strain and the
/// in-plane ones enter neither of these (the geometry does not depend on θ), so with twist
/// B is block diagonal in (u_r, u_z | u_θ) and the plane block is [`StrainDisplacement`].
pub type TwistStrainDisplacement = SMatrix<f64, 2, 8>;

/// Number of strain components of the plane block (xx, yy, xy, zz).
pub(super) const PLANE_STRAINS: usize = 4;

/// Kinematics at one integration point.
#[derive(Clone, Copy, Debug)]
pub struct PointKinematics {
    pub b: StrainDisplacement,
    /// The twist block (zero unless the analysis has twist).
    pub twist: TwistStrainDisplacement,
    /// Volume weight: quadrature weight × det J × (thickness or 2πr).
    pub dvol: f64,
    /// Physical position of the point.
    pub x: [f64; 2],
}

impl PointKinematics {
    /// All entries zero.
    #[inline(always)]
    pub fn zeroed() -> Self {
        Self {
            b: StrainDisplacement::zeros(),
            twist: TwistStrainDisplacement::zeros(),
            dvol: 0.0,
            x: [0.0; 2],
        }
    }
}

/// B matrix and volume weight of a cell with node coordinates `coords` at quadrature point
/// `p`. Returns `Err(det J)` when the mapping is not positive there (inverted or degenerate
/// cell). Integration points lie inside the cell, so r > 0 there and the hoop term N/r is
/// never evaluated on the axis.
#[inline(always)]
pub fn point_kinematics(
    analysis: &Analysis,
    kind: CellKind,
    coords: &[[f64; 2]; 8],
    p: &QuadPoint,
) -> Result<PointKinematics, f64> {
    let s = cell_shape(kind, p.xi, p.eta);
    let mut pk = PointKinematics::zeroed();
    kinematics_into(analysis, kind, coords, &s, p.weight, &mut pk)?;
    Ok(pk)
}

/// [`point_kinematics`] at a point of weight `weight` whose shape functions are `s`, written
/// into `pk`, which must be zeroed ([`PointKinematics::zeroed`]): only the entries of B and
/// of the twist block that can be nonzero are written. In place, because a cell's points
/// (6 kB) returned by value were copied twice: a quarter of a state evaluation's time.
#[inline(always)]
fn kinematics_into(
    analysis: &Analysis,
    kind: CellKind,
    coords: &[[f64; 2]; 8],
    s: &ShapeValues,
    weight: f64,
    pk: &mut PointKinematics,
) -> Result<(), f64> {
    let nn = kind.node_count();
    let Mapping {
        j: [j11, j12, j21, j22],
        det,
        x: [x, y],
    } = mapping(s, &coords[..nn]);
    if det.is_nan() || det <= 0.0 {
        return Err(det);
    }
    let (b, twist) = (&mut pk.b, &mut pk.twist);
    // Reciprocals once per point: a division costs ~10 multiplications, and there were three
    // per node.
    let (inverse_det, inverse_x) = (1.0 / det, 1.0 / x);
    for i in 0..nn {
        let dx = (j22 * s.dxi[i] - j12 * s.deta[i]) * inverse_det;
        let dy = (-j21 * s.dxi[i] + j11 * s.deta[i]) * inverse_det;
        b[(0, 2 * i)] = dx;
        b[(1, 2 * i + 1)] = dy;
        b[(2, 2 * i)] = dy;
        b[(2, 2 * i + 1)] = dx;
        if analysis.is_axisymmetric() {
            b[(ZZ, 2 * i)] = s.n[i] * inverse_x;
        }
        if analysis.has_twist() {
            // γ_rθ = ∂u_θ/∂r − u_θ/r (the rigid rotation u_θ = φ r strains nothing) and
            // γ_zθ = ∂u_θ/∂z.
            twist[(0, i)] = dx - s.n[i] * inverse_x;
            twist[(1, i)] = dy;
        }
    }
    pk.dvol = weight * det * analysis.measure(x);
    pk.x = [x, y];
    Ok(())
}

/// The isoparametric map at one point: Jacobian (∂x/∂ξ, ∂y/∂ξ, ∂x/∂η, ∂y/∂η), its
/// determinant and the mapped position.
struct Mapping {
    j: [f64; 4],
    det: f64,
    x: [f64; 2],
}

#[inline(always)]
fn mapping(s: &ShapeValues, coords: &[[f64; 2]]) -> Mapping {
    let (mut j, mut x) = ([0.0; 4], [0.0; 2]);
    for (i, &[xi, yi]) in coords.iter().enumerate() {
        j[0] += s.dxi[i] * xi;
        j[1] += s.dxi[i] * yi;
        j[2] += s.deta[i] * xi;
        j[3] += s.deta[i] * yi;
        x[0] += s.n[i] * xi;
        x[1] += s.n[i] * yi;
    }
    Mapping {
        j,
        det: j[0] * j[3] - j[1] * j[2],
        x,
    }
}

/// The tags of the cells of `mesh` whose isoparametric map is not positive everywhere
/// ([`min_jacobian`] not above 0, or not a number): inverted, degenerate, or folded by a
/// mid-side node too far from its edge's middle. A model refuses them
/// ([`crate::Error::DistortedElement`]); `asperity mesh-info` lists them.
pub fn distorted_cells(mesh: &crate::mesh::Mesh) -> Vec<u64> {
    let folded = |cell: &&crate::mesh::Cell| {
        let det = min_jacobian(cell.kind, &mesh.cell_coords(cell));
        det.is_nan() || det <= 0.0
    };
    mesh.cells.iter().filter(folded).map(|c| c.tag).collect()
}

/// Smallest Jacobian determinant of a cell over its integration points and nodes; a
/// non-positive value means the cell is inverted or degenerate.
pub fn min_jacobian(kind: CellKind, coords: &[[f64; 2]; 8]) -> f64 {
    let nodes = super::shape::node_coordinates(kind)
        .iter()
        .map(|&(xi, eta)| QuadPoint {
            xi,
            eta,
            weight: 1.0,
        });
    cell_rule(kind)
        .iter()
        .copied()
        .chain(nodes)
        .map(|p| mapping(&cell_shape(kind, p.xi, p.eta), &coords[..kind.node_count()]).det)
        .fold(f64::INFINITY, f64::min)
}

/// The kinematics of a cell at all points of its rule, with the B matrices of
/// `formulation` (B̄ for [`Formulation::Bbar`] outside plane stress; the plain B otherwise).
#[inline(always)]
pub fn cell_kinematics(
    analysis: &Analysis,
    kind: CellKind,
    coords: &[[f64; 2]; 8],
    formulation: Formulation,
) -> CellPoints {
    let mut points = CellPoints::zeroed(kind);
    fill_cell_kinematics(analysis, kind, coords, formulation, &mut points);
    points
}

/// [`cell_kinematics`] into `points`, which must be [`CellPoints::zeroed`] for `kind`.
#[inline(always)]
pub(super) fn fill_cell_kinematics(
    analysis: &Analysis,
    kind: CellKind,
    coords: &[[f64; 2]; 8],
    formulation: Formulation,
    points: &mut CellPoints,
) {
    let rule = cell_rule(kind);
    for ((pk, p), s) in points.points.iter_mut().zip(rule).zip(rule_shapes(kind)) {
        kinematics_into(analysis, kind, coords, s, p.weight, pk)
            .expect("cell Jacobians are checked when the model is built");
    }
    if formulation == Formulation::Bbar && !analysis.is_plane_stress() {
        project_volumetric::<PROJECTION_TERMS>(points, &coords[..kind.node_count()]);
    }
}

/// The points of one cell (fixed capacity, so evaluation allocates nothing).
#[derive(Clone, Copy, Debug)]
pub struct CellPoints {
    len: usize,
    points: [PointKinematics; MAX_CELL_POINTS],
}

impl CellPoints {
    /// The points of a `kind` cell, all zero.
    #[inline(always)]
    pub(super) fn zeroed(kind: CellKind) -> Self {
        Self {
            len: cell_rule(kind).len(),
            points: [PointKinematics::zeroed(); MAX_CELL_POINTS],
        }
    }
}

impl std::ops::Deref for CellPoints {
    type Target = [PointKinematics];
    fn deref(&self) -> &[PointKinematics] {
        &self.points[..self.len]
    }
}

/// Replaces each point's B by B̄ = B + ⅓ m (b̄_vol − mᵀ B): the volumetric row mᵀ B
/// (m = (1, 1, 0, 1)) is L2-projected over the cell (weight dV, so 2πr in axisymmetry) onto
/// the N-term space π = (1, (x − x_c)/L, (y − y_c)/L) (N = 1: constants, N = 3: linear
/// fields; x_c, L the node centroid and extent, for conditioning only):
/// b̄_vol(x) = π(x)ᵀ H⁻¹ G, H = ∫ π πᵀ dV, G = ∫ π mᵀ B dV, with the cell's own rule.
#[inline(always)]
fn project_volumetric<const N: usize>(points: &mut CellPoints, coords: &[[f64; 2]]) {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for x in coords {
        for c in 0..2 {
            lo[c] = lo[c].min(x[c]);
            hi[c] = hi[c].max(x[c]);
        }
    }
    let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let basis = |x: [f64; 2]| {
        let all = [1.0, (x[0] - centre[0]) / size, (x[1] - centre[1]) / size];
        SVector::<f64, N>::from_fn(|i, _| all[i])
    };
    let volumetric = |b: &StrainDisplacement| b.row(0) + b.row(1) + b.row(ZZ);
    let mut h = SMatrix::<f64, N, N>::zeros();
    let mut g = SMatrix::<f64, N, 16>::zeros();
    for pk in points.iter() {
        let pi = basis(pk.x);
        h += pi * pi.transpose() * pk.dvol;
        g += pi * volumetric(&pk.b) * pk.dvol;
    }
    let projector = h
        .try_inverse()
        .expect("the projection space is unisolvent on the cell rule")
        * g;
    for pk in points.points[..points.len].iter_mut() {
        let change = (basis(pk.x).transpose() * projector - volumetric(&pk.b)) / 3.0;
        for r in [0, 1, ZZ] {
            let mut row = pk.b.row_mut(r);
            row += change;
        }
    }
}
