//! Post-processing of a converged step: nodal stresses recovered from the integration
//! points, the output grid of the bodies, and reaction forces.
//!
//! Gauss-point values are extrapolated to the nodes of each cell by the least-squares fit
//! of the cell's own shape functions to its integration-point values (exact for stress fields
//! in the element's polynomial space), then averaged over the cells of one body that share
//! the node. Bodies are never averaged across: a node on the boundary of two bodies becomes
//! one output point per body.

use std::sync::OnceLock;

use nalgebra::DMatrix;

use crate::element::quadrature::cell_rule;
use crate::element::shape::cell_shape;
use crate::material::{PointState, Voigt, ZZ, von_mises};
use crate::mesh::CellKind;
use crate::model::Model;
use crate::output::{Field, FieldValues, Grid, vtk_cell_type};

pub mod interface;
pub mod quantities;

/// Extrapolation matrix (nodes × integration points) of a cell kind.
fn extrapolation(kind: CellKind) -> &'static DMatrix<f64> {
    static QUAD8: OnceLock<DMatrix<f64>> = OnceLock::new();
    static TRI6: OnceLock<DMatrix<f64>> = OnceLock::new();
    let cell = match kind {
        CellKind::Quad8 => &QUAD8,
        CellKind::Tri6 => &TRI6,
    };
    cell.get_or_init(|| {
        let rule = cell_rule(kind);
        let nn = kind.node_count();
        let n = DMatrix::from_fn(rule.len(), nn, |g, i| {
            cell_shape(kind, rule[g].xi, rule[g].eta).n[i]
        });
        (n.transpose() * &n)
            .try_inverse()
            .expect("shape functions are unisolvent on the rule")
            * n.transpose()
    })
}

/// Output points: one per (body, node) pair used by the body's cells.
#[derive(Clone, Debug)]
pub struct BodyPoints {
    /// (body, mesh node) of each output point.
    pub points: Vec<(u32, u32)>,
    /// For body b and node n: output point index at `index[b][n]` (u32::MAX if unused).
    index: Vec<Vec<u32>>,
}

impl BodyPoints {
    /// Output points of the model's bodies.
    pub fn new(model: &Model) -> Self {
        let nodes = model.mesh.nodes.len();
        let mut index = vec![vec![u32::MAX; nodes]; model.bodies.len()];
        let mut points = Vec::new();
        for c in &model.continuum.cells {
            for &n in &c.nodes[..c.kind.node_count()] {
                let slot = &mut index[c.body as usize][n as usize];
                if *slot == u32::MAX {
                    *slot = points.len() as u32;
                    points.push((c.body, n));
                }
            }
        }
        Self { points, index }
    }

    /// Output point of node `n` in body `b`.
    pub fn point(&self, b: u32, n: u32) -> usize {
        self.index[b as usize][n as usize] as usize
    }
}

/// Nodal stresses (Voigt, solver order) and equivalent plastic strains per output point.
pub fn nodal_values(
    model: &Model,
    points: &BodyPoints,
    states: &[PointState],
) -> (Vec<Voigt>, Vec<f64>) {
    let mut stress = vec![Voigt::zeros(); points.points.len()];
    let mut eqp = vec![0.0; points.points.len()];
    let mut count = vec![0u32; points.points.len()];
    let ppe = crate::element::quadrature::MAX_CELL_POINTS;
    for (e, c) in model.continuum.cells.iter().enumerate() {
        let ex = extrapolation(c.kind);
        let gp = &states[e * ppe..e * ppe + ex.ncols()];
        for (i, &n) in c.nodes[..c.kind.node_count()].iter().enumerate() {
            let p = points.point(c.body, n);
            for (g, s) in gp.iter().enumerate() {
                stress[p] += ex[(i, g)] * s.stress;
                eqp[p] += ex[(i, g)] * s.equivalent_plastic_strain;
            }
            count[p] += 1;
        }
    }
    for ((s, e), &k) in stress.iter_mut().zip(&mut eqp).zip(&count) {
        *s /= k as f64;
        // ε̄ᵖ cannot be negative; extrapolation from the Gauss points can undershoot.
        *e = (*e / k as f64).max(0.0);
    }
    (stress, eqp)
}

/// The bodies' output grid of a step: quadratic cells, point data `displacement`, `stress`
/// (xx, yy, zz, xy, yz, xz; axisymmetric rr, zz, θθ → xx, yy, zz), `von_mises` and
/// `equivalent_plastic_strain`, cell data `body` (index into the case's bodies) and `plastic`
/// (1 if any integration point yielded in the step).
pub fn body_grid(model: &Model, points: &BodyPoints, u: &[f64], states: &[PointState]) -> Grid {
    let (stress, equivalent_plastic_strain) = nodal_values(model, points, states);
    let mut grid = Grid {
        points: points
            .points
            .iter()
            .map(|&(_, n)| model.mesh.nodes[n as usize])
            .collect(),
        ..Grid::default()
    };
    for c in &model.continuum.cells {
        grid.push_cell(
            vtk_cell_type(c.kind),
            c.nodes[..c.kind.node_count()]
                .iter()
                .map(|&n| points.point(c.body, n) as u64),
        );
    }
    let displacement = points
        .points
        .iter()
        .flat_map(|&(_, n)| [u[2 * n as usize], u[2 * n as usize + 1], 0.0])
        .collect();
    // Solver order (xx, yy, xy, zz) → VTK order (xx, yy, zz, xy, yz, xz).
    let tensor = stress
        .iter()
        .flat_map(|s| [s[0], s[1], s[ZZ], s[2], 0.0, 0.0])
        .collect();
    let vm = stress.iter().map(von_mises).collect();
    let body = model
        .continuum
        .cells
        .iter()
        .map(|c| c.body as i32)
        .collect();
    let ppe = crate::element::quadrature::MAX_CELL_POINTS;
    let plastic = (0..model.continuum.cells.len())
        .map(|e| states[e * ppe..(e + 1) * ppe].iter().any(|s| s.yielding) as i32)
        .collect();
    let scalar = |name: &str, values: Vec<f64>| Field {
        name: name.into(),
        components: 1,
        values: FieldValues::F64(values),
    };
    grid.point_data = vec![
        Field {
            name: "displacement".into(),
            components: 3,
            values: FieldValues::F64(displacement),
        },
        Field {
            name: "stress".into(),
            components: 6,
            values: FieldValues::F64(tensor),
        },
        scalar("von_mises", vm),
        scalar("equivalent_plastic_strain", equivalent_plastic_strain),
    ];
    grid.cell_data = vec![
        Field {
            name: "body".into(),
            components: 1,
            values: FieldValues::I32(body),
        },
        Field {
            name: "plastic".into(),
            components: 1,
            values: FieldValues::I32(plastic),
        },
    ];
    grid
}

/// Reaction force (sum over the support's prescribed dofs of internal minus external force)
/// of each support, as (F_x, F_y); in axisymmetry totals over the full circle.
pub fn reactions(model: &Model, internal: &[f64], external: &[f64]) -> Vec<[f64; 2]> {
    model
        .supports
        .iter()
        .map(|s| {
            let mut r = [0.0; 2];
            for &d in &s.dofs {
                r[d % 2] += internal[d] - external[d];
            }
            r
        })
        .collect()
}
