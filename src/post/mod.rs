//! Post-processing of a converged step: nodal stresses and strains recovered from the
//! integration points, the output grids of the bodies and the interface ([`step_grids`]),
//! nodal and support reaction forces, and with twist the supports' reaction torques.
//!
//! Gauss-point values are extrapolated to the nodes of each cell by the least-squares fit
//! of the cell's own shape functions to its integration-point values (exact for stress fields
//! in the element's polynomial space), then averaged over the cells of one body that share
//! the node. Bodies are never averaged across: a node on the boundary of two bodies becomes
//! one output point per body.

use std::sync::OnceLock;

use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::assembly::filled_in_parallel;
use crate::element::quadrature::cell_rule;
use crate::element::shape::cell_shape;
use crate::material::{PointState, Voigt, von_mises};
use crate::mesh::CellKind;
use crate::model::Model;
use crate::output::{Field, FieldValues, Grid, tensor_component_names, vtk_cell_type, vtk_tensor};
use crate::solver::state::StepResult;
use interface::InterfaceOutput;

pub mod backstress;
pub mod fretting;
pub mod interface;
pub mod quantities;
pub mod thermal;

/// Extrapolation matrix (nodes × integration points) of a cell kind.
pub(crate) fn extrapolation(kind: CellKind) -> &'static DMatrix<f64> {
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
    /// The cells at each point, in cell order, with the point's node index in the cell:
    /// point p's are `cells[start[p]..start[p + 1]]`.
    start: Vec<u32>,
    cells: Vec<(u32, u8)>,
    /// Whether each point is the first of its mesh node's (a node two bodies share has a
    /// point in each).
    first_of_node: Vec<bool>,
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
        // Counting sort by point: each point's cells stay in cell order.
        let mut start = vec![0u32; points.len() + 1];
        let point_of =
            |c: &crate::element::set::ContinuumCell, n: u32| index[c.body as usize][n as usize];
        for c in &model.continuum.cells {
            for &n in &c.nodes[..c.kind.node_count()] {
                start[point_of(c, n) as usize + 1] += 1;
            }
        }
        for p in 0..points.len() {
            start[p + 1] += start[p];
        }
        let mut fill = start.clone();
        let mut cells = vec![(0u32, 0u8); start[points.len()] as usize];
        for (e, c) in model.continuum.cells.iter().enumerate() {
            for (i, &n) in c.nodes[..c.kind.node_count()].iter().enumerate() {
                let slot = &mut fill[point_of(c, n) as usize];
                cells[*slot as usize] = (e as u32, i as u8);
                *slot += 1;
            }
        }
        let mut seen = vec![false; nodes];
        let first_of_node = (points.iter())
            .map(|&(_, n)| !std::mem::replace(&mut seen[n as usize], true))
            .collect();
        Self {
            points,
            index,
            start,
            cells,
            first_of_node,
        }
    }

    /// The cells at point `p`, in cell order, with the point's node index in each.
    fn cells_at(&self, p: usize) -> &[(u32, u8)] {
        &self.cells[self.start[p] as usize..self.start[p + 1] as usize]
    }

    /// Output point of node `n` in body `b`.
    pub fn point(&self, b: u32, n: u32) -> usize {
        self.index[b as usize][n as usize] as usize
    }

    /// Output point of node `n` in body `b`, if the body has the node.
    pub fn find(&self, b: u32, n: u32) -> Option<usize> {
        let p = self.index[b as usize][n as usize];
        (p != u32::MAX).then_some(p as usize)
    }
}

/// Nodal values of one output point: Gauss-point values extrapolated and averaged.
#[derive(Clone, Copy, Debug)]
pub struct NodalValues {
    /// Stress, Voigt in solver order (xx, yy, xy, zz).
    pub stress: Voigt,
    /// Total strain, Voigt in solver order, engineering shear γ_xy.
    pub strain: Voigt,
    /// Equivalent plastic strain ε̄ᵖ.
    pub equivalent_plastic_strain: f64,
}

/// The nodal stress, strain and equivalent plastic strain of output point `p`: the mean over
/// the point's cells of their Gauss-point values extrapolated to it, summed in cell order.
pub fn nodal_value(
    model: &Model,
    points: &BodyPoints,
    states: &[PointState],
    p: usize,
) -> NodalValues {
    let ppe = crate::element::quadrature::MAX_CELL_POINTS;
    let cells = &model.continuum.cells;
    let mut v = NodalValues {
        stress: Voigt::zeros(),
        strain: Voigt::zeros(),
        equivalent_plastic_strain: 0.0,
    };
    let at = points.cells_at(p);
    for &(e, i) in at {
        let (e, i) = (e as usize, i as usize);
        let ex = extrapolation(cells[e].kind);
        let gp = &states[e * ppe..e * ppe + ex.ncols()];
        for (g, s) in gp.iter().enumerate() {
            v.stress += ex[(i, g)] * s.stress;
            v.strain += ex[(i, g)] * s.strain;
            v.equivalent_plastic_strain += ex[(i, g)] * s.equivalent_plastic_strain;
        }
    }
    let k = at.len() as f64;
    v.stress /= k;
    v.strain /= k;
    // ε̄ᵖ cannot be negative; extrapolation from the Gauss points can undershoot.
    v.equivalent_plastic_strain = (v.equivalent_plastic_strain / k).max(0.0);
    v
}

/// [`nodal_value`] of every output point, points in parallel (the same bits on any number of
/// threads).
pub fn nodal_values(model: &Model, points: &BodyPoints, states: &[PointState]) -> Vec<NodalValues> {
    (0..points.points.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(|p| nodal_value(model, points, states, p))
        .collect()
}

/// The point fields of [`nodal_value`] over all output points, as written: `stress` and
/// `strain` in VTK's tensor order (6 per point), `von_mises`, `equivalent_plastic_strain`.
/// Points in parallel, each written into its place of the final arrays (no array of
/// [`NodalValues`] between: at 3.8M unknowns that was 190 MB of fresh memory per frame).
fn nodal_fields(model: &Model, points: &BodyPoints, states: &[PointState]) -> [Vec<f64>; 4] {
    let n = points.points.len();
    let [mut stress, mut strain] = [(); 2].map(|()| filled_in_parallel(0.0, 6 * n));
    let [mut mises, mut plastic] = [(); 2].map(|()| filled_in_parallel(0.0, n));
    stress
        .par_chunks_mut(6)
        .zip(strain.par_chunks_mut(6))
        .zip(mises.par_iter_mut())
        .zip(plastic.par_iter_mut())
        .enumerate()
        .with_min_len(4096)
        .for_each(|(p, (((stress, strain), mises), plastic))| {
            let v = nodal_value(model, points, states, p);
            // Solver order → VTK order, θ as VTK's z; the strain's shears halved (tensor shear).
            stress.copy_from_slice(&vtk_tensor(&v.stress, 1.0));
            strain.copy_from_slice(&vtk_tensor(&v.strain, 0.5));
            *mises = von_mises(&v.stress);
            *plastic = v.equivalent_plastic_strain;
        });
    [stress, strain, mises, plastic]
}

/// The bodies' output grid of a step: quadratic cells; point data `displacement` (with twist
/// u_θ as its third component), `stress` and `strain` (symmetric tensors in VTK's order xx,
/// yy, zz, xy, yz, xz with component names; axisymmetric rr, zz, θθ, rz, zθ, rθ, the last two
/// zero without twist; the strain with tensor shear ε_xy = γ_xy / 2, as ParaView's
/// tensor filters expect), `von_mises` and `equivalent_plastic_strain`; cell data `body`
/// (index into the case's bodies) and `plastic` (1 if any integration point yielded in the
/// step); field data `body_names` (so `body` k is `body_names[k]`) and `analysis`.
pub fn body_grid(model: &Model, points: &BodyPoints, u: &[f64], states: &[PointState]) -> Grid {
    let [stress, strain, mises, plastic_strain] = nodal_fields(model, points, states);
    let mut grid = Grid {
        points: (points.points.iter())
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
    let nodes: Vec<u32> = points.points.iter().map(|&(_, n)| n).collect();
    let names = tensor_component_names(model.analysis.is_axisymmetric());
    let ppe = crate::element::quadrature::MAX_CELL_POINTS;
    let plastic = (states.par_chunks(ppe))
        .with_min_len(4096)
        .map(|cell| cell.iter().any(|s| s.yielding) as i32)
        .collect();
    let dofs = model.analysis.dofs_per_node();
    grid.point_data = vec![
        nodal_vector("displacement", &nodes, u, dofs),
        Field::tensor("stress", stress, names),
        Field::tensor("strain", strain, names),
        Field::scalar("von_mises", mises),
        Field::scalar("equivalent_plastic_strain", plastic_strain),
    ];
    let body = model.continuum.cells.iter().map(|c| c.body as i32);
    grid.cell_data = vec![
        Field::new("body", 1, FieldValues::I32(body.collect())),
        Field::new("plastic", 1, FieldValues::I32(plastic)),
    ];
    grid.field_data = vec![
        Field::strings("body_names", model.bodies.clone()),
        Field::strings("analysis", vec![model.analysis.name().into()]),
    ];
    grid
}

/// A 3-component point field of the nodal values of the dof vector `v` (`dofs` per mesh
/// node) at the mesh nodes `nodes`: the third component is the circumferential one with
/// twist (`dofs` = 3), zero otherwise.
pub fn nodal_vector(name: &str, nodes: &[u32], v: &[f64], dofs: usize) -> Field {
    let values = (nodes.par_iter())
        .with_min_len(4096)
        .flat_map_iter(|&n| {
            let d = dofs * n as usize;
            let theta = if dofs == 3 { v[d + 2] } else { 0.0 };
            [v[d], v[d + 1], theta]
        })
        .collect();
    Field::new(name, 3, FieldValues::F64(values))
}

/// Nodal reaction forces (Abaqus' RF) as a dof vector: internal minus external force at every
/// prescribed dof, zero elsewhere; in axisymmetry totals over the full circle. Summed over a
/// support's nodes they are its reaction in `history.csv`.
pub fn nodal_reactions(model: &Model, internal: &[f64], external: &[f64]) -> Vec<f64> {
    let mut rf = vec![0.0; internal.len()];
    for &(d, _, _) in &model.prescribed {
        rf[d] = internal[d] - external[d];
    }
    rf
}

/// What a step's VTU files record about the step, as VTK FieldData.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepInfo {
    /// 1-based step number.
    pub step: usize,
    /// The time ParaView shows (`TimeValue`): the step's time where the case defines one,
    /// otherwise the step number (load factors may go down again when unloading).
    pub time: f64,
    pub load_factor: f64,
}

impl StepInfo {
    /// The field data arrays `TimeValue`, `step` and `load_factor`.
    fn field_data(&self) -> [Field; 3] {
        [
            Field::scalar("TimeValue", vec![self.time]),
            Field::new("step", 1, FieldValues::I32(vec![self.step as i32])),
            Field::scalar("load_factor", vec![self.load_factor]),
        ]
    }
}

/// The VTU grids of a converged step: the bodies ([`body_grid`], plus the nodal reaction
/// forces `reaction_force`, see [`nodal_reactions`]) and, when the model has contact pairs,
/// the interface ([`InterfaceOutput::grid`], plus the side-B `displacement`, so that it warps
/// with the bodies). Both carry the FieldData of `info` (time, step, load factor).
///
/// A node shared by two bodies of a conforming mesh is one output point per body; its
/// reaction is put on the first body's point only, so that sums over the grid are the
/// support reactions.
pub fn step_grids(
    model: &Model,
    points: &BodyPoints,
    interface: &InterfaceOutput,
    step: &StepResult,
    info: StepInfo,
) -> (Grid, Option<Grid>) {
    let solution = step.solution;
    let mut bodies = body_grid(model, points, &solution.u, solution.point_states());
    let rf = nodal_reactions(model, step.internal_force, step.external_force);
    let dofs = model.analysis.dofs_per_node();
    let values = (points.points.par_iter().enumerate())
        .with_min_len(4096)
        .flat_map_iter(|(p, &(_, n))| {
            let d = dofs * n as usize;
            if points.first_of_node[p] {
                [rf[d], rf[d + 1], if dofs == 3 { rf[d + 2] } else { 0.0 }]
            } else {
                [0.0; 3]
            }
        })
        .collect();
    bodies
        .point_data
        .push(Field::new("reaction_force", 3, FieldValues::F64(values)));
    bodies
        .point_data
        .extend(backstress::fields(model, points, &solution.internal));
    thermal::add_body_fields(&mut bodies, model, points, solution);
    bodies.field_data.extend(info.field_data());
    let interface = (!model.interface.elements.is_empty()).then(|| {
        let mut grid = interface.grid(model, &solution.interface_committed);
        interface.add_fretting(&mut grid, model, solution);
        interface.add_joint_heat(&mut grid, model, solution);
        grid.point_data.push(nodal_vector(
            "displacement",
            &interface.nodes(),
            &solution.u,
            model.analysis.dofs_per_node(),
        ));
        grid.field_data.extend(info.field_data());
        grid
    });
    (bodies, interface)
}

/// Reaction force (sum over the support's prescribed dofs of internal minus external force)
/// of each support, as (F_x, F_y); in axisymmetry totals over the full circle.
pub fn reactions(model: &Model, internal: &[f64], external: &[f64]) -> Vec<[f64; 2]> {
    let dofs = model.analysis.dofs_per_node();
    model
        .supports
        .iter()
        .map(|s| {
            let mut r = [0.0; 2];
            for &d in s.dofs.iter().filter(|&&d| d % dofs < 2) {
                r[d % dofs] += internal[d] - external[d];
            }
            r
        })
        .collect()
}

/// Reaction torque about the axis of each support, Σ r (f_int − f_ext)_θ over its prescribed
/// u_θ (N·mm, signed as the reaction forces: a support holding a shaft twisted by a torque T
/// reacts with −T); zero for every support without twist.
pub fn reaction_torques(model: &Model, internal: &[f64], external: &[f64]) -> Vec<f64> {
    let dofs = model.analysis.dofs_per_node();
    model
        .supports
        .iter()
        .map(|s| {
            let theta = s.dofs.iter().filter(|&&d| dofs == 3 && d % dofs == 2);
            theta
                .map(|&d| model.mesh.nodes[d / dofs][0] * (internal[d] - external[d]))
                .sum()
        })
        .collect()
}
