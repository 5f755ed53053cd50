//! The cells of a plastic model that an evaluation may leave out: those whose points provably
//! stay linear elastic, so that their force is their elastic matrix times their displacements
//! and K_ref u (the sum of all cells' elastic matrices, which the assembly of a plastic bulk
//! keeps anyway) stands for it ([`crate::assembly::GlobalSystem::assemble_reusing`]).
//!
//! A point whose committed state never yielded (J2: no plastic strain) updates to σ = D ε
//! while the von Mises value of D ε stays below the initial yield stress
//! ([`crate::material::Material::linear_range`]; an elastic material always). The first
//! evaluation of every Newton solve evaluates every cell (the anchor, displacements u_a); for
//! a later one at u, since dev Δσ = 2 G dev Δε for an isotropic D,
//!
//! ```text
//! σ_eq(D ε(u)) ≤ σ_eq(σ_a) + 3 G ε_eq(ε(u) − ε(u_a)) ≤ σ_eq(σ_a) + 3 G β_e(u − u_a),
//! ```
//!
//! with σ_a the point's stress at the anchor and β_e the cell's bound on the equivalent
//! strain change of its points from its nodal displacement changes
//! ([`StrainBound::of_cell`]). A cell all of whose points keep this below their limit is
//! left out: the same force and tangent as its evaluation (to rounding), at the cost of the
//! bound (a few dozen flops) instead of its points' kinematics and material updates. Far
//! from a punch's edge most cells of a plastic body never come near yielding.
//!
//! A left-out cell's trial states are not updated: a converged increment makes every cell's
//! states before they are read ([`crate::solver::newton::Newton::states_pending`]). Cells
//! with a prescribed dof are always evaluated (their force in the prescribed rows is
//! reactions, which K_ref over the free equations does not give), as are all cells under a
//! temperature field (the thermal strain is not D ε's) and every cell of an arc-length
//! iteration (each of its evaluations is a solve's first). An evaluation that could leave
//! out fewer than half the cells evaluates all of them: with cells left out, every evaluated
//! cell also makes its elastic matrix to take off its elastic force, which costs about as
//! much as its evaluation.
//!
//! Everything here follows from the anchor's displacements and states, made by the solve's
//! first evaluation, not from earlier increments.

use rayon::prelude::*;

use crate::assembly::DofMap;
use crate::element::quadrature::{MAX_CELL_POINTS, cell_rule};
use crate::material::{PointState, von_mises};
use crate::model::Model;
use crate::solver::strain_bound::StrainBound;

/// Relative margin below a point's limit of linearity: well above the rounding of the
/// stresses and the bound, far below anything that changes which cells pay off.
const LIMIT_MARGIN: f64 = 1e-6;

/// The cells an evaluation may leave out, and the anchor they are judged from.
#[derive(Debug)]
pub struct ElasticCells {
    bound: StrainBound,
    /// Whether each cell has a prescribed dof (never left out).
    held: Vec<bool>,
    /// The displacements (all dofs) of the anchor, valid if `anchored`.
    anchor: Vec<f64>,
    anchored: bool,
    /// Per cell: the equivalent strain change from the anchor within which every point of
    /// the cell stays linear elastic (≤ 0: none).
    room: Vec<f64>,
    /// The cells the last evaluation left out.
    left_out: Vec<bool>,
    /// Whether the last evaluation left cells out (their trial states are not its own).
    pending: bool,
}

impl ElasticCells {
    /// The cells of `model` (dofs numbered by `dofs`) that evaluations may leave out; `None`
    /// when none ever can: under a temperature field, or when no body's material has a
    /// linear range.
    pub fn new(model: &Model, dofs: &DofMap) -> Option<Self> {
        let continuum = &model.continuum;
        let virgin = PointState::default();
        let some_linear = (continuum.materials.iter()).any(|m| m.linear_range(&virgin).is_some());
        if model.has_temperature() || !some_linear {
            return None;
        }
        let d = continuum.analysis.dofs_per_node();
        let held: Vec<bool> = (continuum.cells.par_iter())
            .map(|cell| dofs.holds_prescribed(&cell.nodes[..cell.kind.node_count()], d))
            .collect();
        let cells = held.len();
        Some(Self {
            bound: StrainBound::new(model),
            held,
            anchor: vec![0.0; dofs.dof_count()],
            anchored: false,
            room: vec![0.0; cells],
            left_out: vec![false; cells],
            pending: false,
        })
    }

    /// Forgets the anchor: the next evaluation evaluates every cell and anchors there.
    pub fn unanchor(&mut self) {
        self.anchored = false;
    }

    /// Whether an anchor is set.
    pub fn anchored(&self) -> bool {
        self.anchored
    }

    /// Whether the last evaluation left cells out: their trial states are not those of its
    /// displacements.
    pub fn states_pending(&self) -> bool {
        self.pending
    }

    /// Every cell's trial states were made at the last evaluation's displacements.
    pub fn states_made(&mut self) {
        self.pending = false;
    }

    /// The cells an evaluation at `u` (all dofs) leaves out, `None` for none (no anchor, or
    /// fewer than half of them).
    pub fn select(&mut self, model: &Model, u: &[f64]) -> Option<&[bool]> {
        self.pending = false;
        if !self.anchored {
            return None;
        }
        let (bound, anchor, room) = (&self.bound, &self.anchor, &self.room);
        (self.left_out.par_iter_mut().enumerate())
            .with_min_len(256)
            .for_each(|(e, out)| {
                // A bound that is not a number (nor is u) leaves nothing out.
                *out = room[e] > 0.0 && bound.of_cell(model, e, u, anchor) < room[e];
            });
        let count = self.left_out.iter().filter(|&&out| out).count();
        tracing::debug!(
            left_out = count,
            cells = self.left_out.len(),
            "elastic cells"
        );
        if 2 * count < self.left_out.len() {
            return None;
        }
        self.pending = true;
        Some(&self.left_out)
    }

    /// Anchors at the displacements `u` of an evaluation of every cell, whose trial states
    /// are `trial` (from the `committed` ones).
    pub fn anchor(
        &mut self,
        model: &Model,
        committed: &[PointState],
        trial: &[PointState],
        u: &[f64],
    ) {
        let continuum = &model.continuum;
        let held = &self.held;
        (self.room.par_iter_mut().enumerate())
            .with_min_len(256)
            .for_each(|(e, room)| {
                let cell = &continuum.cells[e];
                let material = &continuum.materials[cell.body as usize];
                let points = e * MAX_CELL_POINTS..e * MAX_CELL_POINTS + cell_rule(cell.kind).len();
                let point_room = |(c, t): (&PointState, &PointState)| {
                    material.linear_range(c).map_or(-1.0, |r| {
                        (r.von_mises * (1.0 - LIMIT_MARGIN) - von_mises(&t.stress))
                            / (3.0 * r.shear_modulus)
                    })
                };
                *room = if held[e] {
                    -1.0
                } else {
                    (committed[points.clone()].iter())
                        .zip(&trial[points])
                        .map(point_room)
                        .map(|r| if r.is_nan() { -1.0 } else { r })
                        .fold(f64::INFINITY, f64::min)
                };
            });
        self.anchor.copy_from_slice(u);
        self.anchored = true;
    }
}
