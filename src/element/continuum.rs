//! The 2D continuum element (quad8 with 3×3 Gauss points, tri6 with a 6-point rule) in plane
//! stress, plane strain and axisymmetry: paper Eqs. (33)–(34),
//! K = ∫ Bᵀ C B dV and F = ∫ Bᵀ σ dV, with dV = t dA or 2πr dA.

use nalgebra::SMatrix;

use super::quadrature::{QuadPoint, cell_rule};
use super::shape::{ShapeValues, cell_shape};
use super::{Analysis, ElementInput, ElementOutput};
use crate::material::{Material, OutOfPlane, PointState, Voigt, ZZ};
use crate::mesh::CellKind;

/// Strain-displacement matrix: rows (xx, yy, xy, zz), columns (u_x1, u_y1, ..., u_x8, u_y8).
pub type StrainDisplacement = SMatrix<f64, 4, 16>;

/// Kinematics at one integration point.
#[derive(Clone, Copy, Debug)]
pub struct PointKinematics {
    pub b: StrainDisplacement,
    /// Volume weight: quadrature weight × det J × (thickness or 2πr).
    pub dvol: f64,
    /// Physical position of the point.
    pub x: [f64; 2],
}

/// B matrix and volume weight of a cell with node coordinates `coords` at quadrature point
/// `p`. Returns `Err(det J)` when the mapping is not positive there (inverted or degenerate
/// cell). Integration points lie inside the cell, so r > 0 there and the hoop term N/r is
/// never evaluated on the axis.
pub fn point_kinematics(
    analysis: &Analysis,
    kind: CellKind,
    coords: &[[f64; 2]; 8],
    p: &QuadPoint,
) -> Result<PointKinematics, f64> {
    let s = cell_shape(kind, p.xi, p.eta);
    let nn = kind.node_count();
    let Mapping {
        j: [j11, j12, j21, j22],
        det,
        x: [x, y],
    } = mapping(&s, &coords[..nn]);
    if det.is_nan() || det <= 0.0 {
        return Err(det);
    }
    let mut b = StrainDisplacement::zeros();
    for i in 0..nn {
        let dx = (j22 * s.dxi[i] - j12 * s.deta[i]) / det;
        let dy = (-j21 * s.dxi[i] + j11 * s.deta[i]) / det;
        b[(0, 2 * i)] = dx;
        b[(1, 2 * i + 1)] = dy;
        b[(2, 2 * i)] = dy;
        b[(2, 2 * i + 1)] = dx;
        if analysis.is_axisymmetric() {
            b[(ZZ, 2 * i)] = s.n[i] / x;
        }
    }
    Ok(PointKinematics {
        b,
        dvol: p.weight * det * analysis.measure(x),
        x: [x, y],
    })
}

/// The isoparametric map at one point: Jacobian (∂x/∂ξ, ∂y/∂ξ, ∂x/∂η, ∂y/∂η), its
/// determinant and the mapped position.
struct Mapping {
    j: [f64; 4],
    det: f64,
    x: [f64; 2],
}

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

/// Tangent stiffness and internal force of one continuum cell for element displacements `u`.
///
/// Each integration point's material is updated from `committed[g]` into `trial[g]`. The
/// tangent is accumulated into `k` only when `k` is given (residual-only evaluations skip it).
/// Cells must have passed [`min_jacobian`] at model set-up.
pub fn evaluate_cell(
    analysis: &Analysis,
    kind: CellKind,
    coords: &[[f64; 2]; 8],
    material: &dyn Material,
    input: &ElementInput<PointState>,
    output: ElementOutput<PointState>,
) {
    let ElementInput { u, committed, .. } = *input;
    let ElementOutput { trial, mut k, f } = output;
    let out_of_plane = if analysis.is_plane_stress() {
        OutOfPlane::StressFree
    } else {
        OutOfPlane::StrainGiven
    };
    for (g, p) in cell_rule(kind).iter().enumerate() {
        let pk = point_kinematics(analysis, kind, coords, p)
            .expect("cell Jacobians are checked when the model is built");
        let strain: Voigt = pk.b * u;
        let (state, d) = material.update(&strain, &committed[g], out_of_plane);
        f.gemv_tr(pk.dvol, &pk.b, &state.stress, 1.0);
        if let Some(k) = k.as_deref_mut() {
            let db = d * pk.b;
            k.gemm_tr(pk.dvol, &pk.b, &db, 1.0);
        }
        trial[g] = state;
    }
}
