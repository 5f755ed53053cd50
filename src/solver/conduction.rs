//! The solve of the steady heat conduction ([`crate::thermal::Conduction`]) by static
//! condensation onto the joints, like the mechanics' ([`crate::solver::condensed`]).
//!
//! The conduction matrix is K = K_c + K_j: the cells' conductivity and the films' h N Nᵀ
//! (K_c) depend on neither the time nor the contact, and the joints' conductance (K_j) lives
//! only in the rows and columns of the conducting joints' nodes, changing with the contact
//! pressures at every exchange of a coupled increment. So K_c is factored once per run with
//! the joints' unknowns ordered last, leaving their Schur complement S_c; a solve assembles
//! K_j into a dense block over the joints' unknowns, factors S_c + K_j (dense LU of n_J
//! unknowns, n_J the joints' free nodes) and substitutes. K_c's factorisation needs no
//! contact: a region of the bodies whose nodes are not all the joints' is held by the
//! joints' unknowns (eliminated last), a prescribed temperature or a film (checked when the
//! model is built). A region that open joints cut off from every held one in a solve is tied
//! to the reference temperature at one of its joint nodes in the dense block
//! ([`Conduction::cut_off_ties`]).
//!
//! Measured on the tapered press fit at 244 k mechanical unknowns with a pressure-dependent
//! joint conductance (46 conduction solves): the conduction took 52 s of a 57 s run when
//! every solve ordered, analysed and factored the whole matrix (faer's sparse Cholesky).

use std::time::Instant;

use faer::Mat;
use faer::sparse::SparseColMatRef;

use crate::assembly::{DofMap, SparsityPattern};
use crate::contact::InterfaceState;
use crate::model::Model;
use crate::solver::condensed::CondensedSolver;
use crate::solver::floor::Tally;
use crate::thermal::{CellRegions, Conduction, HeatSolution};
use crate::{Error, Result};

/// The conduction solver of a model with conducting bodies, made once per run.
pub struct ConductionSolver {
    /// Equations of the conduction indices (prescribed temperatures have none).
    dofs: DofMap,
    condensed: CondensedSolver,
    /// The entries of K_c in a prescribed row or column (conduction indices, unsummed).
    prescribed: Vec<(u32, u32, f64)>,
    cells: CellRegions,
    /// The conductance that ties a cut-off region to the reference: K_c's largest entry.
    tie: f64,
    /// Per solve: K_j over the joints' unknowns, the right-hand side (free equations), K_j's
    /// entries in prescribed rows, and the links heat crosses at the joints.
    block: Mat<f64>,
    rhs: Vec<f64>,
    joint_prescribed_rows: Vec<(u32, u32, f64)>,
    links: Vec<(u32, u32)>,
    work: ConductionWork,
}

/// The conduction's work over a run, for `summary.json` and the run's floor.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConductionWork {
    /// The pattern, assembly, ordering and factorisation of K_c (one call per run).
    pub factorisation: Tally,
    /// Solves: the load, K_j, the dense interface LU, the substitutions and the heat flows.
    pub solves: Tally,
}

impl ConductionWork {
    /// Seconds of all the conduction's work.
    pub fn seconds(&self) -> f64 {
        self.factorisation.seconds + self.solves.seconds
    }
}

impl std::fmt::Debug for ConductionSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ConductionSolver")
            .field("unknowns", &self.dofs.free_count())
            .field("joint_unknowns", &self.block.nrows())
            .finish()
    }
}

impl ConductionSolver {
    /// The solver of `model`'s conduction (`None` when no body conducts): assembles and
    /// factors K_c.
    pub fn new(model: &Model) -> Result<Option<Self>> {
        let Some(c) = &model.thermal.conduction else {
            return Ok(None);
        };
        let started = Instant::now();
        let dofs = DofMap::new(&c.prescribed());
        let mut joint_nodes = c.joint_indices(&model.interface);
        joint_nodes.sort_unstable();
        joint_nodes.dedup();
        let joints: Vec<usize> = (joint_nodes.iter())
            .filter_map(|&i| dofs.equation(i as usize))
            .collect();
        // The joints' nodes couple in the pattern as one dense block (zero in K_c): the
        // factor's last supernode is then their whole Schur complement, with every subtree
        // of the bodies under it, a postorder whose subtrees the factorisation and the
        // substitutions run in parallel. Without it each body's joint nodes made supernodes
        // of their own, the bodies' subtrees hung under different ones, and everything ran
        // on one thread.
        let mut elements = c.element_nodes(&model.continuum, &model.interface);
        elements.push(joint_nodes);
        let pattern = SparsityPattern::new(c.size(), &dofs, elements.iter().map(|e| e.as_slice()));
        drop(elements);
        let mut condensed =
            CondensedSolver::for_conduction(&pattern, &joints).map_err(conduction_error)?;
        condensed.solve_exactly();
        let (values, prescribed, tie) = constant_matrix(c, model, &dofs, &pattern);
        let matrix = SparseColMatRef::new(pattern.symbolic().as_ref(), &values);
        condensed.factor_bulk(matrix).map_err(conduction_error)?;
        condensed.release_refactorisation_storage();
        let n_joint = condensed.interface_equations().len();
        let mut solver = Self {
            rhs: vec![0.0; dofs.free_count()],
            dofs,
            condensed,
            prescribed,
            cells: c.cell_regions(&model.continuum),
            tie,
            block: Mat::zeros(n_joint, n_joint),
            joint_prescribed_rows: Vec::new(),
            links: Vec::new(),
            work: ConductionWork::default(),
        };
        solver.work.factorisation.since(started);
        tracing::debug!(
            unknowns = solver.dofs.free_count(),
            joint_unknowns = n_joint,
            seconds = solver.work.factorisation.seconds,
            "conduction factored"
        );
        Ok(Some(solver))
    }

    /// The work so far.
    pub fn work(&self) -> ConductionWork {
        self.work
    }

    /// The steady conduction of `model` at pseudo-time `time` with the joints in the
    /// interface `states`.
    pub fn solve(
        &mut self,
        model: &Model,
        time: f64,
        states: &[InterfaceState],
    ) -> Result<HeatSolution> {
        let started = Instant::now();
        let c = model
            .thermal
            .conduction
            .as_ref()
            .expect("a conducting model");
        let multiplier = |k: usize| model.schedule.value(k, time);
        let load = c.load(&multiplier);
        let mut t = vec![0.0; c.size()];
        c.set_prescribed(&multiplier, &mut t);
        self.dofs.gather_free(&load.f, &mut self.rhs);
        for &(i, j, v) in &self.prescribed {
            if let Some(e) = self.dofs.equation(i as usize) {
                self.rhs[e] -= v * t[j as usize];
            }
        }
        self.add_joints(c, model, states, &t);
        let condensed = &self.condensed;
        let dofs = &self.dofs;
        let joint_unknown =
            |i: u32| (dofs.equation(i as usize)).and_then(|e| condensed.local_index(e));
        let links = self.links.iter().copied();
        let ties = c.cut_off_ties(&model.continuum, &self.cells, links, &load.f, |i| {
            joint_unknown(i).is_some()
        })?;
        for i in ties {
            let k = joint_unknown(i).expect("a tieable node");
            self.block[(k, k)] += self.tie;
        }
        self.condensed
            .solve(self.block.as_ref(), &mut self.rhs)
            .map_err(|_| singular())?;
        for (i, ti) in t.iter_mut().enumerate() {
            if let Some(e) = self.dofs.equation(i) {
                *ti = self.rhs[e];
            }
        }
        if t.iter().any(|v| !v.is_finite()) {
            return Err(singular());
        }
        let reaction = self.reaction(&t, &load.f);
        let heat = c.heat_solution(&model.interface, states, &multiplier, &t, &reaction, load);
        self.work.solves.since(started);
        Ok(heat)
    }

    /// Assembles K_j in the contact `states` into the dense block, its entries in the
    /// prescribed columns into the right-hand side (temperatures `t`) and those in
    /// prescribed rows aside, and collects the links heat crosses.
    fn add_joints(&mut self, c: &Conduction, model: &Model, states: &[InterfaceState], t: &[f64]) {
        let Self {
            dofs,
            condensed,
            block,
            rhs,
            joint_prescribed_rows,
            links,
            ..
        } = self;
        block.fill(0.0);
        joint_prescribed_rows.clear();
        links.clear();
        c.joint_entries(&model.interface, states, |i, j, v| {
            if i != j {
                links.push((i, j));
            }
            match (dofs.equation(i as usize), dofs.equation(j as usize)) {
                (Some(ei), Some(ej)) => {
                    let local = |e| condensed.local_index(e).expect("a joint unknown");
                    block[(local(ei), local(ej))] += v;
                }
                (Some(ei), None) => rhs[ei] -= v * t[j as usize],
                (None, _) => joint_prescribed_rows.push((i, j, v)),
            }
        });
    }

    /// K T − f at the prescribed nodes (0 elsewhere).
    fn reaction(&self, t: &[f64], f: &[f64]) -> Vec<f64> {
        let mut reaction = vec![0.0; t.len()];
        for (i, r) in reaction.iter_mut().enumerate() {
            if self.dofs.equation(i).is_none() {
                *r = -f[i];
            }
        }
        let entries = self.prescribed.iter().chain(&self.joint_prescribed_rows);
        for &(i, j, v) in entries {
            if self.dofs.equation(i as usize).is_none() {
                reaction[i as usize] += v * t[j as usize];
            }
        }
        reaction
    }
}

/// K_c over `pattern` (the free equations' values), its entries in a prescribed row or
/// column, and its largest entry (at least 1).
fn constant_matrix(
    c: &Conduction,
    model: &Model,
    dofs: &DofMap,
    pattern: &SparsityPattern,
) -> (Vec<f64>, Vec<(u32, u32, f64)>, f64) {
    let symbolic = pattern.symbolic();
    let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
    let mut values = vec![0.0; pattern.nnz()];
    let mut prescribed = Vec::new();
    let mut largest = 1.0_f64;
    c.constant_entries(&model.continuum, |i, j, v| {
        largest = largest.max(v.abs());
        match (dofs.equation(i as usize), dofs.equation(j as usize)) {
            (Some(ei), Some(ej)) => {
                let column = col_ptr[ej] as usize..col_ptr[ej + 1] as usize;
                let rows = &row_idx[column.clone()];
                let k = rows
                    .binary_search(&(ei as u32))
                    .expect("the pattern holds every cell's couplings");
                values[column.start + k] += v;
            }
            _ => prescribed.push((i, j, v)),
        }
    });
    (values, prescribed, largest)
}

/// The condensed solver's errors about the conduction matrix as the conduction's (failed
/// or refused allocations stay memory errors).
fn conduction_error(e: Error) -> Error {
    match e {
        Error::Linear(message) => Error::Conduction(format!(
            "the conductivity matrix cannot be factored: {message}"
        )),
        other => other,
    }
}

fn singular() -> Error {
    Error::Conduction("the temperature is not finite: the conductivity matrix is singular".into())
}
