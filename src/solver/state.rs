//! The run's state, apart from the drivers that advance it ([`crate::solver::stepping`] for
//! load control, [`crate::solver::arclength`] for arc-length control): the [`Solution`]
//! (displacements, integration-point states, energy ledger), what a converged step hands to
//! the output ([`StepResult`]), the run's counters ([`RunStatistics`]), the loop state a
//! restart record continues from ([`LoopState`], [`Resume`]) and the [`Observer`] through
//! which a driver reports its progress.
//!
//! The solution's energy and cycle hooks ([`Solution::record_energy`],
//! [`Solution::start_cycle`], [`Solution::end_cycle`]) hand [`crate::solver::energy`] and
//! [`crate::solver::cycles`] the slices they work on: those modules do not know this one.

use crate::Result;
use crate::assembly::filled_in_parallel;
use crate::contact::InterfaceState;
use crate::element::quadrature::MAX_CELL_POINTS;
use crate::element::set::{INTERFACE_POINTS, InternalLayout};
use crate::material::PointState;
use crate::model::Model;
use crate::model::timeline::Frame;
use crate::solver::cycles;
use crate::solver::energy::{BodySums, EnergyLedger, Increment};
use crate::solver::floor::Work;
use crate::solver::mechanics::Mechanics;
use crate::solver::newton::{ForceAverage, LastIncrement, NewtonLog};
use crate::solver::shakedown::BodyCycles;
use crate::thermal::ThermalState;

/// The evolving solution: displacements and integration-point states.
#[derive(Clone, Debug)]
pub struct Solution {
    /// Displacements over all dofs (2 per node).
    pub u: Vec<f64>,
    /// Continuum states committed at the last converged step; empty where they follow the
    /// displacements ([`Self::states_follow_displacements`]).
    pub committed: Vec<PointState>,
    /// Continuum states of the current iteration.
    pub trial: Vec<PointState>,
    /// Whether the continuum's point states follow from the displacements alone
    /// ([`Model::states_follow_displacements`]: linear elastic bodies, no temperature).
    /// Such states are kept once: no committed array (an element loop starts every point
    /// from the default state, which a linear elastic update does not read), the trial
    /// array holding those of the last evaluation, which committing leaves in place — the
    /// largest array of a model (930 MB at 3.84 M unknowns) is not kept twice.
    pub states_follow_displacements: bool,
    /// Interface states committed at the last converged step.
    pub interface_committed: Vec<InterfaceState>,
    /// Interface states of the current iteration.
    pub interface_trial: Vec<InterfaceState>,
    /// The continuum's internal variables (backstresses), committed and trial.
    pub internal: InternalVariables,
    /// Energy totals of the converged increments.
    pub energy: EnergyLedger,
    /// Per contact pair, the largest share of its stability limit that the last cycle's wear
    /// jump added at a point (0 without a jump or wear; ≤ 1, or the jump was refused). Set by
    /// [`Solution::end_cycle`] for the cycle-end output; not part of the state a run
    /// continues from.
    pub jump_use: Vec<f64>,
    /// The temperatures of the current increment (not part of a restart record: they follow
    /// from the model, the time and the interface states).
    pub thermal: ThermalState,
}

/// The point states of the converged state ([`Solution::point_states`]) from the fields
/// (borrowed apart from the rest of the solution).
fn converged<'s>(
    follow: bool,
    committed: &'s [PointState],
    trial: &'s [PointState],
) -> &'s [PointState] {
    if follow { trial } else { committed }
}

impl Solution {
    /// The unloaded state of `model`: zero displacements, virgin integration points.
    pub fn new(model: &Model) -> Self {
        Self::unloaded(model, model.continuum.cells.len() * MAX_CELL_POINTS)
    }

    /// The unloaded state of `model` without the continuum's integration-point states, for
    /// what reads only the displacements, the interface and the totals (the history row of
    /// the start): a model's point states are the largest part of its memory.
    pub fn without_point_states(model: &Model) -> Self {
        Self::unloaded(model, 0)
    }

    fn unloaded(model: &Model, states: usize) -> Self {
        let interface = model.interface.elements.len() * INTERFACE_POINTS;
        let follow = model.states_follow_displacements();
        Self {
            u: vec![0.0; model.dofs.dof_count()],
            committed: filled_in_parallel(PointState::default(), if follow { 0 } else { states }),
            trial: filled_in_parallel(PointState::default(), states),
            states_follow_displacements: follow,
            interface_committed: vec![InterfaceState::default(); interface],
            interface_trial: vec![InterfaceState::default(); interface],
            internal: InternalVariables::new(model),
            energy: EnergyLedger::default(),
            jump_use: vec![0.0; model.interface.pairs.len()],
            thermal: ThermalState::default(),
        }
    }

    /// The point states of the converged state, for what reads them (frames, cycle ends,
    /// restart records): the committed ones, or where the states follow the displacements
    /// the only ones, those of the last evaluation (made for the converged state's
    /// displacements where they are read: [`crate::solver::newton::Newton::complete_states`]).
    pub fn point_states(&self) -> &[PointState] {
        converged(
            self.states_follow_displacements,
            &self.committed,
            &self.trial,
        )
    }

    /// [`Self::point_states`], to change (a test's prescribed stress field).
    pub fn point_states_mut(&mut self) -> &mut [PointState] {
        if self.states_follow_displacements {
            &mut self.trial
        } else {
            &mut self.committed
        }
    }

    /// Makes the trial states of a converged increment the committed ones. The bodies'
    /// point states are swapped, not copied (930 MB per increment at 3.84M unknowns): the
    /// trial array then holds older states, which nothing reads before an element loop
    /// writes them again — every assembly evaluates every cell, and a failed attempt starts
    /// over from [`Self::reset_trial`]. States that follow the displacements stay where
    /// they are ([`Self::states_follow_displacements`]).
    pub fn commit(&mut self) {
        if !self.states_follow_displacements {
            std::mem::swap(&mut self.committed, &mut self.trial);
        }
        self.interface_committed
            .copy_from_slice(&self.interface_trial);
        self.internal
            .committed
            .copy_from_slice(&self.internal.trial);
    }

    /// Makes the trial states the committed ones again (after a failed attempt, or before
    /// the first increment of a resumed run).
    pub fn reset_trial(&mut self) {
        // States that follow the displacements are made again by the next evaluation.
        if !self.states_follow_displacements {
            self.trial.copy_from_slice(&self.committed);
        }
        self.interface_trial
            .copy_from_slice(&self.interface_committed);
        self.internal
            .trial
            .copy_from_slice(&self.internal.committed);
    }

    /// The displacements and, apart from them, the mechanical problem of `model` over this
    /// solution's states: the Newton loop updates the one while the other assembles.
    pub fn split<'a>(&'a mut self, model: &'a Model) -> (&'a mut [f64], Mechanics<'a>) {
        let problem = Mechanics {
            model,
            committed: &self.committed,
            trial: &mut self.trial,
            interface_committed: &self.interface_committed,
            interface_trial: &mut self.interface_trial,
            internal_layout: &self.internal.layout,
            internal_committed: &self.internal.committed,
            internal_trial: &mut self.internal.trial,
            temperature: &self.thermal.field,
        };
        (&mut self.u, problem)
    }

    /// Records the converged increment from the committed to the trial states (displacements
    /// from `u_old` to `self.u`) in the energy ledger; `external_force` and `internal_force`
    /// are those of the converged state over all dofs. The drivers call this just before
    /// [`Self::commit`].
    /// `bodies` is the increment's pass over the point states ([`Self::scan_increment`]).
    pub fn record_energy(
        &mut self,
        model: &Model,
        u_old: &[f64],
        external_force: &[f64],
        internal_force: &[f64],
        bodies: BodySums,
    ) {
        let increment = Increment {
            u_old,
            u: &self.u,
            committed: &self.committed,
            trial: &self.trial,
            interface_committed: &self.interface_committed,
            interface_trial: &self.interface_trial,
            internal_layout: &self.internal.layout,
            internal_committed: &self.internal.committed,
            internal_trial: &self.internal.trial,
            external_force,
            internal_force,
        };
        let bodies = self.energy.record_increment(model, &increment, bodies);
        self.internal.cycles.record(&bodies);
    }

    /// One pass over the point states of the increment from the committed to the trial
    /// states ([`EnergyLedger::scan_bodies`]): its largest strain increment, which
    /// [`crate::solver::diagnosis::implausible_increment`] judges, and the bodies' energy
    /// terms [`Self::record_energy`] takes. Where the states follow the displacements there
    /// are no committed ones: the pass sees the trial states at both ends (their stored
    /// energy; no plastic or thermal term, as for elastic bodies without temperature) and
    /// leaves the strain increment 0, for the caller to find
    /// ([`crate::solver::newton::Newton::strain_increment`]).
    pub fn scan_increment(&mut self, model: &Model) -> BodySums {
        let committed = converged(
            self.states_follow_displacements,
            &self.committed,
            &self.trial,
        );
        self.energy.scan_bodies(model, committed, &self.trial)
    }

    /// Starts a load cycle (or a step) at every interface point of the committed state
    /// ([`cycles::start_cycle`]); the trial states follow.
    pub fn start_cycle(&mut self) {
        let states = converged(
            self.states_follow_displacements,
            &self.committed,
            &self.trial,
        );
        self.internal.cycles.start_cycle(states);
        cycles::start_cycle(&mut self.interface_committed);
        self.interface_trial
            .copy_from_slice(&self.interface_committed);
    }

    /// Ends a simulated load cycle that stands for `jump_cycles` cycles
    /// ([`cycles::end_cycle`]: its wear is extrapolated, the jump's wear work recorded in the
    /// ledger, [`Self::jump_use`] set); the trial states follow. Errs, leaving the solution
    /// unchanged, when the jump is refused: by the wear's stability limit, or because a body
    /// ratcheted in the cycle ([`BodyCycles::check_jump`]; call [`Self::end_body_cycle`]
    /// first). Returns whether the jump added wear.
    pub fn end_cycle(&mut self, model: &Model, jump_cycles: f64) -> Result<bool> {
        self.internal
            .cycles
            .check_jump(model, jump_cycles as usize)?;
        let end = cycles::end_cycle(
            model,
            &mut self.interface_committed,
            &mut self.energy,
            jump_cycles,
        )?;
        self.jump_use = end.jump_use;
        self.interface_trial
            .copy_from_slice(&self.interface_committed);
        Ok(end.worn)
    }

    /// Ends the bodies' cycle of output increment `step` at the committed states (before
    /// [`Self::end_cycle`]'s wear jump): their plastic dissipation and ratcheting over the
    /// cycle and, at the end of a cyclic step, their shakedown verdicts
    /// ([`BodyCycles::end_cycle`]).
    pub fn end_body_cycle(&mut self, model: &Model, step: usize) {
        let states = converged(
            self.states_follow_displacements,
            &self.committed,
            &self.trial,
        );
        self.internal.cycles.end_cycle(model, step, states);
    }

    /// Checks the energy balance after a wear jump and the re-equilibrium that followed it
    /// ([`cycles::check_jump_energy`]).
    pub fn check_jump_energy(&self, model: &Model, jump_cycles: f64) -> Result<()> {
        cycles::check_jump_energy(model, &self.energy.total, &self.jump_use, jump_cycles)
    }
}

/// The continuum's internal variables (the backstresses of kinematic hardening): a flat
/// array per state, committed and trial like the integration-point states, laid out by
/// [`InternalLayout`]. All three are empty for a model without any, which so pays nothing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InternalVariables {
    pub layout: InternalLayout,
    pub committed: Vec<f64>,
    pub trial: Vec<f64>,
    /// The bodies' cycle trackers (plastic dissipation and ratcheting per cycle, shakedown
    /// verdicts), of the committed state.
    pub cycles: BodyCycles,
}

impl InternalVariables {
    /// Zero internal variables of `model`'s bodies.
    pub fn new(model: &Model) -> Self {
        let layout = InternalLayout::new(&model.continuum);
        let len = layout.len();
        Self {
            layout,
            committed: vec![0.0; len],
            trial: vec![0.0; len],
            cycles: BodyCycles::new(model),
        }
    }
}

/// A converged step as handed to the output.
#[derive(Debug)]
pub struct StepResult<'a> {
    /// 1-based step number.
    pub step: usize,
    pub load_factor: f64,
    /// Where the step lies in the case's load history.
    pub frame: Frame,
    /// Newton log of the last (sub-)increment; `iterations` counts all sub-increments.
    pub newton: NewtonLog,
    /// Number of increments the step took (1 unless it was cut back).
    pub increments: usize,
    /// Failed increments of the step that were halved and retried.
    pub cutbacks: usize,
    pub solution: &'a Solution,
    /// Internal forces over all dofs (reactions at prescribed dofs).
    pub internal_force: &'a [f64],
    /// External forces over all dofs.
    pub external_force: &'a [f64],
}

/// Timings and counters of a whole run.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct RunStatistics {
    pub steps: usize,
    pub increments: usize,
    pub iterations: usize,
    pub cutbacks: usize,
    pub unsymmetric_solves: usize,
    pub krylov_iterations: usize,
    /// Measured again by a resumed run (with `factor_nnz`): not in its restart record.
    #[serde(skip)]
    pub symbolic_seconds: f64,
    pub assembly_seconds: f64,
    pub factorization_seconds: f64,
    pub solve_seconds: f64,
    pub output_seconds: f64,
    #[serde(skip)]
    pub factor_nnz: usize,
    /// Final relative residual of the last step.
    pub last_residual: f64,
    /// The work of this process by kind, for the run's floor (not in the restart record: a
    /// resumed run's floor is that of the part it ran).
    #[serde(skip)]
    pub work: Work,
}

impl RunStatistics {
    /// Adds a converged increment's solves and timings.
    pub(crate) fn add(&mut self, log: &NewtonLog) {
        self.increments += 1;
        self.add_work(log);
    }

    /// Adds the solves and timings of an attempt (converged or not).
    pub(crate) fn add_work(&mut self, log: &NewtonLog) {
        self.iterations += log.iterations;
        self.unsymmetric_solves += log.unsymmetric_solves;
        self.krylov_iterations += log.krylov_iterations;
        self.assembly_seconds += log.assembly_seconds;
        self.factorization_seconds += log.factorization_seconds;
        self.solve_seconds += log.solve_seconds;
    }

    /// Adds the `seconds` spent writing a `frame`'s files, or else writing without a new
    /// frame (the last wait for the writer thread).
    pub(crate) fn add_output(&mut self, seconds: f64, frame: bool) {
        self.output_seconds += seconds;
        if frame {
            self.work.frames.add(seconds);
        } else {
            self.work.frames.seconds += seconds;
        }
    }
}

/// Where the stepping loop stands after a converged increment: with the [`Solution`] and the
/// [`RunStatistics`], everything a run needs to continue bit for bit ([`Resume`]).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LoopState {
    /// The step being worked on (1-based); `steps() + 1` once every step has converged.
    pub step: usize,
    /// Pseudo-time of the last converged state (step j ends at time j).
    pub time: f64,
    /// Size of the next sub-increment in pseudo-time.
    pub size: f64,
    /// Cut-backs, converged increments and Newton iterations of the current step so far.
    pub cutbacks: usize,
    pub increments: usize,
    pub iterations: usize,
    /// The absolute force level below which residuals count as zero.
    pub force_floor: f64,
    pub stiffness: StiffnessHistory,
    /// The converged increments' part of the convergence criteria's average force q̃.
    pub force_average: ForceAverage,
    /// Arc-length control's own state (`None` under load control).
    pub arc: Option<ArcState>,
}

impl LoopState {
    /// The state before the first increment.
    pub fn start() -> Self {
        Self {
            step: 1,
            time: 0.0,
            size: 1.0,
            cutbacks: 0,
            increments: 0,
            iterations: 0,
            force_floor: 0.0,
            stiffness: StiffnessHistory::default(),
            force_average: ForceAverage::default(),
            arc: None,
        }
    }

    /// The state after step `step` converged: the next one starts with a full increment.
    pub(crate) fn next_step(self, step: usize) -> Self {
        Self {
            step: step + 1,
            time: step as f64,
            size: 1.0,
            cutbacks: 0,
            increments: 0,
            iterations: 0,
            ..self
        }
    }
}

/// Where arc-length control stands after a converged increment (its steps are its
/// increments: [`LoopState::step`] is the next one, [`LoopState::time`] the number
/// converged).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ArcState {
    /// λ of the last converged increment.
    pub load_factor: f64,
    /// The largest λ reached so far.
    pub largest_load_factor: f64,
    /// The arc length Δl of the next increment; `None` until the first increment's tangent
    /// sets it (`initial_increment` × ‖K⁻¹ f_ref‖).
    pub radius: Option<f64>,
    /// The bounds of the arc length: `min_arc_length` and `max_arc_length` times the first
    /// arc (0 and ∞ until it is set).
    pub min_radius: f64,
    pub max_radius: f64,
    /// Δu of the last converged increment over the free dofs (empty before the first): the
    /// next increment's predictor keeps its direction (Feng's criterion).
    pub previous_increment: Vec<f64>,
}

impl ArcState {
    /// The state before the first increment.
    pub fn start() -> Self {
        Self {
            max_radius: f64::INFINITY,
            ..Self::default()
        }
    }
}

/// Secant stiffnesses Δλ/‖Δu‖ of the converged increments of a run: the first one (the
/// reference) and the latest.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StiffnessHistory {
    pub first: Option<f64>,
    pub last: Option<f64>,
}

impl StiffnessHistory {
    /// Records a converged increment of load factor `d_lambda` and displacement norm `du`
    /// (increments that change neither are skipped).
    pub fn record(&mut self, d_lambda: f64, du: f64) {
        if d_lambda == 0.0 || du == 0.0 || !du.is_finite() {
            return;
        }
        let k = d_lambda.abs() / du;
        self.first.get_or_insert(k);
        self.last = Some(k);
    }

    /// The latest secant stiffness relative to the first one.
    pub fn ratio(&self) -> Option<f64> {
        Some(self.last? / self.first?)
    }
}

/// A run to continue: the loop state, the counters and the solution of a converged increment
/// (as a restart record stores them).
#[derive(Clone, Debug)]
pub struct Resume {
    pub state: LoopState,
    pub stats: RunStatistics,
    /// Displacements and committed states (trial states are made equal to them).
    pub solution: Solution,
    /// The converged increment the predictor extrapolates the next one from (load control
    /// with `extrapolate` on).
    pub last_increment: Option<LastIncrement>,
}

impl Resume {
    /// The unloaded start of a run of `model`: what a driver continues without a record.
    pub fn start(model: &Model) -> Self {
        Self {
            state: LoopState::start(),
            stats: RunStatistics::default(),
            solution: Solution::new(model),
            last_increment: None,
        }
    }
}

/// A converged increment as the [`Observer`] sees it.
#[derive(Clone, Debug)]
pub struct Progress<'a> {
    pub state: LoopState,
    pub stats: &'a RunStatistics,
    pub solution: &'a Solution,
    /// The predictor's last converged increment ([`Resume::last_increment`]).
    pub last_increment: Option<&'a LastIncrement>,
}

impl Progress<'_> {
    /// The state a run continues from after this increment (what a restart record holds).
    pub fn to_resume(&self) -> Resume {
        Resume {
            state: self.state.clone(),
            stats: self.stats.clone(),
            solution: self.solution.clone(),
            last_increment: self.last_increment.cloned(),
        }
    }
}

/// What a driver reports to its caller (the output): converged steps, converged
/// sub-increments in between, and the last converged sub-increment of a step that failed.
pub trait Observer {
    /// After a converged step; `progress` is the state from which the run continues with the
    /// next step. Returns the seconds spent (writing files).
    fn step(&mut self, step: &StepResult, progress: &Progress) -> Result<f64>;
    /// After a converged sub-increment that does not end its step.
    fn increment(&mut self, _progress: &Progress) -> Result<()> {
        Ok(())
    }
    /// When step `step.step` failed after some of its sub-increments had converged: `step`
    /// holds the last of them, at pseudo-time `time` (its `load_factor` is the one reached),
    /// so that the state closest to the failure can be looked at.
    fn partial_step(&mut self, _step: &StepResult, _time: f64) -> Result<()> {
        Ok(())
    }
    /// Whether [`Self::step`] reads the bodies' point states of output step `step` (its
    /// field output does). A linear bulk whose force is K·u evaluates none in its increments:
    /// they are made for the steps that read them (all, unless the observer says otherwise).
    fn reads_point_states(&self, _step: usize) -> bool {
        true
    }
}
