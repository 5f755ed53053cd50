//! The energy balance of a run (issue: cyclic loading): external work, stored elastic
//! energy, plastic and frictional dissipation, accumulated over the converged increments.
//! The imbalance of these terms is a convergence check a user can read.
//!
//! Per converged increment from the committed state n to the trial state n+1 (theory in
//! `docs/theory.md`, "Energy balance"):
//! - external work += ½ (F_n + F_{n+1})·(u_{n+1} − u_n) over all dofs, F the applied loads at
//!   free dofs and the reactions (internal forces) at prescribed dofs;
//! - elastic energy = Σ ½ σ:C⁻¹:σ dV of the bodies (a state function, from the states);
//! - plastic dissipation += Σ σ_{n+1}:Δεᵖ dV (backward Euler's plastic work);
//! - friction dissipation += Σ p_τ,{n+1}·Δu_τᵖ dA (Buczkowski & Kleiber (1994), Eq. 6; the
//!   tangential vectors (T, θ) with twist);
//! - wear work += Σ −½ (p_N,n + p_N,{n+1}) Δh dA (p_N ≤ 0: removed material takes energy out);
//! - numerical dissipation += Σ ½ (σ_n − σ_{n+1}):Δεᵖ dV + Σ ½ (p_τ,n − p_τ,{n+1})·Δu_τᵖ dA;
//! - thermal work += Σ ½ (σ_n + σ_{n+1}):Δε_th dV, the work of the stresses on the thermal
//!   strains (computed as the stress work on the total strain less the stored, plastic and
//!   numerical terms of the same point, for the bodies with an expansion coefficient);
//! - interface energy += the interfaces' trapezoidal work Σ ½ (p_n + p_{n+1})·Δu_rel dA minus
//!   their friction, numerical and wear terms (for a linear law without wear: Δ(½ p²/k)).
//!
//! Since the internal force is Bᵀσ and the relative displacement B u (small strains), the
//! trapezoidal work of the internal forces is exactly the sum of these terms; the imbalance
//! external − Σ is therefore the trapezoidal work of the out-of-balance forces of the
//! converged states, i.e. of the residual the Newton criteria accepted.

use std::ops::Sub;

use crate::contact::{self, InterfaceState};
use crate::element::ElementVector;
use crate::element::interface6::{InterfacePoint, interface_point, relative_displacement};
use crate::element::kinematics::point_kinematics;
use crate::element::quadrature::{MAX_CELL_POINTS, cell_rule};
use crate::element::set::ContinuumCell;
use crate::element::set::{INTERFACE_POINTS, InternalLayout};
use crate::material::{PointState, dot, equivalent_strain};
use crate::model::Model;

/// Energy totals from the unloaded start (N·mm = mJ; per unit thickness as the forces are).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Energy {
    /// Work of the external forces and of the reactions at prescribed displacements.
    pub external_work: f64,
    /// Elastic energy stored in the bodies.
    pub elastic_energy: f64,
    /// Elastic energy stored in the interfaces.
    pub interface_energy: f64,
    /// Plastic work of the bodies.
    pub plastic_dissipation: f64,
    /// Frictional dissipation ∫ p_τ·du_τ^p over the interfaces.
    pub friction_dissipation: f64,
    /// Energy removed with worn material (pressure times wear depth).
    pub wear_work: f64,
    /// Dissipation of the time discretisation itself (vanishes as increments shrink).
    pub numerical_dissipation: f64,
    /// Work of the bodies' stresses on their thermal strains, Σ ½ (σ_n + σ_{n+1}):Δε_th dV:
    /// the mechanical work the thermal expansion takes from the bodies (negative when a
    /// heated body pushes against its surroundings and so supplies work).
    #[serde(default)]
    pub thermal_work: f64,
}

impl Energy {
    /// Energy stored: elastic energy of the bodies and of the interfaces.
    pub fn stored(&self) -> f64 {
        self.elastic_energy + self.interface_energy
    }

    /// Physical dissipation: plastic, frictional and wear.
    pub fn dissipation(&self) -> f64 {
        self.plastic_dissipation + self.friction_dissipation + self.wear_work
    }

    /// External work minus everything it went into: the work of the out-of-balance forces
    /// the convergence criteria accepted (0 for exact equilibrium).
    pub fn imbalance(&self) -> f64 {
        self.external_work
            - self.stored()
            - self.dissipation()
            - self.numerical_dissipation
            - self.thermal_work
    }

    /// Whether the books still hold after a wear jump and its re-equilibrium. A jump's wear
    /// work (the pressure at the cycle's end times the depth) comes out of the interfaces'
    /// stored energy, which the bodies' re-seating on the worn faces refills. Explicit, it
    /// overestimates the work by what the pressure would have fallen while wearing: within
    /// the stability limit the pressure falls by at most k_eff per unit depth, and the depth
    /// is at most `jump_limit` ≤ 1 closures |p_N|/k_eff, so by at most half the jump's wear
    /// work. The stored energy may therefore be negative by up to half the wear work (plus
    /// [`JUMP_BALANCE_TOLERANCE`] |external work|); more means the jump wore more than the
    /// loads could supply. The imbalance must stay within ± [`JUMP_BALANCE_TOLERANCE`]
    /// |external work|.
    pub fn balanced_after_jump(&self) -> bool {
        let allowed = JUMP_BALANCE_TOLERANCE * self.external_work.abs();
        self.interface_energy >= -(0.5 * self.wear_work + allowed)
            && self.imbalance().abs() <= allowed
    }

    /// [`Self::imbalance`] relative to |external work|; `None` when no work was done.
    pub fn relative_imbalance(&self) -> Option<f64> {
        (self.external_work != 0.0).then(|| self.imbalance() / self.external_work.abs())
    }
}

/// The share of |external work| by which the work imbalance may differ from zero, and the
/// interfaces' stored energy may fall below what the wear jumps explain, after a wear jump
/// ([`Energy::balanced_after_jump`]): the Newton criteria keep the imbalance orders of
/// magnitude smaller (it is the work of the accepted residual).
pub const JUMP_BALANCE_TOLERANCE: f64 = 1e-2;

/// The change from `earlier` to `self`: work and dissipation of the interval, and the
/// change of the stored energies.
impl Sub for Energy {
    type Output = Energy;

    fn sub(self, earlier: Energy) -> Energy {
        Energy {
            external_work: self.external_work - earlier.external_work,
            elastic_energy: self.elastic_energy - earlier.elastic_energy,
            interface_energy: self.interface_energy - earlier.interface_energy,
            plastic_dissipation: self.plastic_dissipation - earlier.plastic_dissipation,
            friction_dissipation: self.friction_dissipation - earlier.friction_dissipation,
            wear_work: self.wear_work - earlier.wear_work,
            numerical_dissipation: self.numerical_dissipation - earlier.numerical_dissipation,
            thermal_work: self.thermal_work - earlier.thermal_work,
        }
    }
}

/// The running energy totals and what the next increment's trapezoidal work needs of the
/// last converged state.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EnergyLedger {
    pub total: Energy,
    /// Total nodal force (external loads at free dofs, reactions at prescribed dofs) of the
    /// last converged state; empty before the first increment.
    pub previous_force: Vec<f64>,
    /// The integration weights of the model's points, built at the first increment.
    #[serde(skip)]
    pub weights: Weights,
}

/// The volume dV of every continuum state slot and the geometry (with dA) of every
/// interface point, from the element kernels' own quadrature. Derived from the model, so it
/// is not part of a ledger's value: any two compare equal, and a restart record leaves it
/// to be rebuilt.
#[derive(Clone, Debug, Default)]
pub struct Weights {
    volumes: Vec<f64>,
    interface: Vec<InterfacePoint>,
}

impl PartialEq for Weights {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl Weights {
    /// Builds the continuum's point volumes of `model` unless they are built already (a
    /// linear bulk whose increments evaluate no element never needs them).
    fn ensure_volumes(&mut self, model: &Model) {
        let cells = &model.continuum.cells;
        if self.volumes.len() == cells.len() * MAX_CELL_POINTS {
            return;
        }
        self.volumes = vec![0.0; cells.len() * MAX_CELL_POINTS];
        for (cell, volumes) in cells
            .iter()
            .zip(self.volumes.chunks_exact_mut(MAX_CELL_POINTS))
        {
            for (dv, p) in volumes.iter_mut().zip(cell_rule(cell.kind)) {
                *dv = point_kinematics(&model.continuum.analysis, cell.kind, &cell.coords, p)
                    .expect("cell Jacobians are checked when the model is built")
                    .dvol;
            }
        }
    }

    /// Builds the interface points' weights of `model` unless they are built already.
    fn ensure_interface(&mut self, model: &Model) {
        let elements = &model.interface.elements;
        if self.interface.len() == elements.len() * INTERFACE_POINTS {
            return;
        }
        let analysis = &model.interface.analysis;
        self.interface = elements
            .iter()
            .flat_map(|e| {
                e.rule
                    .points()
                    .iter()
                    .map(|&(xi, w)| interface_point(analysis, &e.b_coords, xi, w))
            })
            .collect();
    }
}

/// The interface terms of one increment (N·mm), before they enter the totals.
#[derive(Clone, Copy, Debug, Default)]
struct InterfaceWork {
    /// Trapezoidal work of the contact stresses on the relative displacement.
    work: f64,
    friction: f64,
    numerical: f64,
    wear: f64,
}

/// A converged increment as the ledger reads it: the displacements before and after it, the
/// integration-point states at its start (committed) and end (trial), and the converged
/// state's forces over all dofs.
#[derive(Clone, Copy, Debug)]
pub struct Increment<'a> {
    pub u_old: &'a [f64],
    pub u: &'a [f64],
    pub committed: &'a [PointState],
    pub trial: &'a [PointState],
    pub interface_committed: &'a [InterfaceState],
    pub interface_trial: &'a [InterfaceState],
    /// The continuum's internal variables (backstresses) at the start and end.
    pub internal_layout: &'a InternalLayout,
    pub internal_committed: &'a [f64],
    pub internal_trial: &'a [f64],
    pub external_force: &'a [f64],
    pub internal_force: &'a [f64],
}

impl EnergyLedger {
    /// Adds the converged `increment`; the drivers call this (through
    /// [`crate::solver::state::Solution::record_energy`]) just before committing the trial
    /// states.
    ///
    /// Returns the increment's plastic dissipation per body.
    /// `bodies` is the increment's pass over its point states ([`Self::scan_bodies`]).
    pub fn record_increment(
        &mut self,
        model: &Model,
        increment: &Increment,
        bodies: BodySums,
    ) -> Vec<f64> {
        self.weights.ensure_interface(model);
        self.total.external_work += self.external_work(model, increment);
        let bodies = self.record_bodies(model, increment, bodies);
        let i = self.interface_work(model, increment);
        let t = &mut self.total;
        t.friction_dissipation += i.friction;
        t.wear_work += i.wear;
        t.numerical_dissipation += i.numerical;
        t.interface_energy += i.work - i.friction - i.numerical - i.wear;
        bodies
    }

    /// Accounts for wear added to interface point `point` (index into the interface states)
    /// outside an increment, by a cycle jump of `added_depth` (mm, both surfaces together)
    /// at the converged `state`: the work −p_N Δh dA the removed material takes out of the
    /// interface's stored energy moves to the wear work (their sum, and so the balance, is
    /// unchanged: the jump does no work on the bodies).
    pub fn record_wear_jump(
        &mut self,
        model: &Model,
        point: usize,
        state: &InterfaceState,
        added_depth: f64,
    ) {
        self.weights.ensure_interface(model);
        let work = -state.stress[1] * added_depth * self.weights.interface[point].da;
        self.total.wear_work += work;
        self.total.interface_energy -= work;
    }

    /// The trapezoidal work of the nodal forces F (loads at free dofs, reactions at
    /// prescribed ones) over the increment; keeps F_{n+1} for the next increment.
    fn external_work(&mut self, model: &Model, increment: &Increment) -> f64 {
        let Increment {
            u,
            u_old,
            external_force,
            internal_force,
            ..
        } = *increment;
        let n = model.dofs.dof_count();
        if self.previous_force.len() != n {
            // The unloaded start: no force.
            self.previous_force.clear();
            self.previous_force.resize(n, 0.0);
        }
        let mut work = 0.0;
        for (dof, previous) in self.previous_force.iter_mut().enumerate() {
            let force = if model.dofs.equation(dof).is_some() {
                external_force[dof]
            } else {
                internal_force[dof]
            };
            work += 0.5 * (*previous + force) * (u[dof] - u_old[dof]);
            *previous = force;
        }
        work
    }

    /// One pass over the point states of an increment from `committed` to `trial`: the
    /// bodies' energy terms and the largest equivalent strain increment. The drivers make it
    /// for a converged increment before they judge it ([`BodySums::strain_increment`]) and
    /// hand it to [`Self::record_increment`] if they keep it: the states are read once.
    pub fn scan_bodies(
        &mut self,
        model: &Model,
        committed: &[PointState],
        trial: &[PointState],
    ) -> BodySums {
        use rayon::prelude::*;
        self.weights.ensure_volumes(model);
        // Blocks of cells in parallel, their sums added in block order: the same bits on any
        // number of threads.
        let block = ENERGY_BLOCK * MAX_CELL_POINTS;
        model
            .continuum
            .cells
            .par_chunks(ENERGY_BLOCK)
            .zip(trial.par_chunks(block))
            .zip(committed.par_chunks(block))
            .zip(self.weights.volumes.par_chunks(block))
            .map(|(((cells, trial), committed), volumes)| {
                body_sums(model, cells, trial, committed, volumes)
            })
            .collect::<Vec<_>>()
            .into_iter()
            .fold(BodySums::new(model), BodySums::add)
    }

    /// The bodies' stored energy (from the trial states), plastic work and the numerical
    /// part of the trapezoidal rule on it, from the increment's pass `sums`; returns the
    /// plastic dissipation per body.
    fn record_bodies(&mut self, model: &Model, increment: &Increment, sums: BodySums) -> Vec<f64> {
        let mut bodies = sums.bodies;
        if !increment.internal_layout.is_empty() {
            self.weights.ensure_volumes(model);
        }
        let (stored, released) =
            hardening_energy(model, increment, &self.weights.volumes, &mut bodies);
        let t = &mut self.total;
        t.elastic_energy = sums.elastic + stored;
        t.plastic_dissipation += sums.plastic - released;
        t.numerical_dissipation += sums.numerical;
        t.thermal_work += sums.thermal;
        bodies
    }

    /// The interface terms of the increment.
    fn interface_work(&self, model: &Model, increment: &Increment) -> InterfaceWork {
        let Increment { u, u_old, .. } = *increment;
        let mut sum = InterfaceWork::default();
        let states = increment
            .interface_trial
            .chunks_exact(INTERFACE_POINTS)
            .zip(increment.interface_committed.chunks_exact(INTERFACE_POINTS))
            .zip(self.weights.interface.chunks_exact(INTERFACE_POINTS));
        for (element, ((trial, committed), points)) in model.interface.elements.iter().zip(states) {
            let d = model.analysis.dofs_per_node();
            let mut du = ElementVector::zeros();
            for (i, &node) in element.nodes.iter().enumerate() {
                for c in 0..d {
                    let dof = d * node as usize + c;
                    du[d * i + c] = u[dof] - u_old[dof];
                }
            }
            for ((t, c), p) in trial.iter().zip(committed).zip(points) {
                let jump = relative_displacement(&model.analysis, p, &du);
                let mean: [f64; 3] = std::array::from_fn(|k| 0.5 * (c.stress[k] + t.stress[k]));
                let slip = [
                    t.plastic_slip[0] - c.plastic_slip[0],
                    t.plastic_slip[1] - c.plastic_slip[1],
                ];
                let wear =
                    t.history.wear[0] + t.history.wear[1] - c.history.wear[0] - c.history.wear[1];
                sum.work += (mean[0] * jump[0] + mean[1] * jump[1] + mean[2] * jump[2]) * p.da;
                let (shear, shear_n) =
                    (contact::tangential(t.stress), contact::tangential(c.stress));
                sum.friction += contact::dot(shear, slip) * p.da;
                let change = [shear_n[0] - shear[0], shear_n[1] - shear[1]];
                sum.numerical += 0.5 * contact::dot(change, slip) * p.da;
                sum.wear -= mean[1] * wear * p.da;
            }
        }
        sum
    }
}

/// Cells per task of the bodies' energy sums (fixed, for the same sums on any number of
/// threads).
const ENERGY_BLOCK: usize = 4096;

/// The bodies' energy terms of some cells' integration points over an increment, and its
/// largest strain increment ([`EnergyLedger::scan_bodies`]).
#[derive(Clone, Debug)]
pub struct BodySums {
    elastic: f64,
    plastic: f64,
    numerical: f64,
    thermal: f64,
    /// Plastic work per body.
    bodies: Vec<f64>,
    /// The largest equivalent strain increment √(⅔ Δε:Δε) of any point (0 without points;
    /// NaN if a strain is not a number) — for a linear bulk whose force is K·u, where it is
    /// not above `[solver] max_strain_increment`, a bound on it
    /// ([`crate::solver::strain_bound`]).
    pub strain_increment: f64,
}

impl BodySums {
    fn new(model: &Model) -> Self {
        Self {
            elastic: 0.0,
            plastic: 0.0,
            numerical: 0.0,
            thermal: 0.0,
            bodies: vec![0.0; model.bodies.len()],
            strain_increment: 0.0,
        }
    }

    /// The pass of a converged increment of a linear bulk whose force is K_c u, made
    /// without its point states: the bodies' stored energy `elastic`, ½ u·K_c u from the
    /// product (the states' Σ ½ σ:ε dV to rounding), no plastic, numerical or thermal terms
    /// (elastic bodies, no temperature); its strain increment is the caller's to find.
    pub fn of_linear_bulk(model: &Model, elastic: f64) -> Self {
        Self {
            elastic,
            ..Self::new(model)
        }
    }

    fn add(mut self, other: Self) -> Self {
        self.elastic += other.elastic;
        self.plastic += other.plastic;
        self.numerical += other.numerical;
        self.thermal += other.thermal;
        for (a, b) in self.bodies.iter_mut().zip(other.bodies) {
            *a += b;
        }
        self.strain_increment = largest(self.strain_increment, other.strain_increment);
        self
    }
}

/// The larger of `a` and `b`, NaN if either is (f64::max would drop a NaN).
pub(crate) fn largest(a: f64, b: f64) -> f64 {
    if a.is_nan() || a > b { a } else { b }
}

/// The stored energy (from the trial states), plastic work, numerical dissipation and
/// thermal work of the points of `cells`, whose trial and committed states and volumes are
/// `trial`, `committed` and `volumes` ([`MAX_CELL_POINTS`] slots per cell).
fn body_sums(
    model: &Model,
    cells: &[ContinuumCell],
    trial: &[PointState],
    committed: &[PointState],
    volumes: &[f64],
) -> BodySums {
    let mut sums = BodySums::new(model);
    let slots = trial
        .chunks_exact(MAX_CELL_POINTS)
        .zip(committed.chunks_exact(MAX_CELL_POINTS))
        .zip(volumes.chunks_exact(MAX_CELL_POINTS));
    for (cell, ((trial, committed), volumes)) in cells.iter().zip(slots) {
        let material = model.continuum.materials[cell.body as usize].as_ref();
        let expands = model.continuum.expansions[cell.body as usize] != 0.0;
        let points = cell_rule(cell.kind).len();
        for ((t, c), &dv) in trial.iter().zip(committed).zip(volumes).take(points) {
            sums.strain_increment = largest(
                sums.strain_increment,
                equivalent_strain(&(t.strain - c.strain)),
            );
            let plastic_increment = t.plastic_strain - c.plastic_strain;
            let stored = material.elastic_energy(t);
            let point_plastic = dot(&t.stress, &plastic_increment);
            let point_numerical = 0.5 * dot(&(c.stress - t.stress), &plastic_increment);
            sums.elastic += stored * dv;
            sums.plastic += point_plastic * dv;
            sums.bodies[cell.body as usize] += point_plastic * dv;
            sums.numerical += point_numerical * dv;
            if expands {
                // The stress work on the total strain less its mechanical part (the stored,
                // plastic and numerical terms above): the work on α ΔT m.
                let work = 0.5 * dot(&(c.stress + t.stress), &(t.strain - c.strain));
                let mechanical =
                    stored - material.elastic_energy(c) + point_plastic + point_numerical;
                sums.thermal += (work - mechanical) * dv;
            }
        }
    }
    sums
}

/// The energy stored in the backstresses of kinematic hardening at the end of `increment`,
/// Σ ψ dV with ψ = Σ_k 3/(4 C_k) α_k:α_k, and its change over the increment: counted as
/// stored (with the elastic energy), so the plastic work σ:Δεᵖ minus that change is the
/// plastic dissipation. (0, 0) without internal variables. `volumes` are the slots' dV; the
/// change is also taken off each body's plastic dissipation in `bodies`.
fn hardening_energy(
    model: &Model,
    increment: &Increment,
    volumes: &[f64],
    bodies: &mut [f64],
) -> (f64, f64) {
    let layout = increment.internal_layout;
    if layout.is_empty() {
        return (0.0, 0.0);
    }
    let (mut stored, mut change) = (0.0, 0.0);
    let continuum = &model.continuum;
    for (e, cell) in continuum.cells.iter().enumerate() {
        let material = continuum.materials[cell.body as usize].as_ref();
        let stride = material.internal_variables();
        let range = layout.range(e);
        if stride == 0 || range.is_empty() {
            continue;
        }
        let trial = increment.internal_trial[range.clone()].chunks_exact(stride);
        let committed = increment.internal_committed[range].chunks_exact(stride);
        let cell_volumes = &volumes[e * MAX_CELL_POINTS..(e + 1) * MAX_CELL_POINTS];
        for ((t, c), &dv) in trial.zip(committed).zip(cell_volumes) {
            let psi = material.hardening_energy(t);
            let released = (psi - material.hardening_energy(c)) * dv;
            stored += psi * dv;
            change += released;
            bodies[cell.body as usize] -= released;
        }
    }
    (stored, change)
}
