//! Incremental loading: the output increments of the case's load history (the frames of its
//! analysis steps and cycles, [`crate::model::timeline`]) are applied one after another; each
//! increment is solved by Newton-Raphson and its integration-point states are committed only
//! once it has converged. An increment that fails is halved and retried from the last
//! converged state, up to `max_cutbacks` times, and a sub-increment also ends on a breakpoint
//! of an amplitude ([`crate::model::Schedule::next_time`]); sub-increments are solved silently
//! and only the scheduled increments are handed to the output. The load cycles' hooks
//! ([`crate::solver::cycles`]) run before the first increment of every step and cycle and
//! after the commit of its last one.

use crate::assembly::{AssemblyInput, GlobalSystem};
use crate::contact::{ContactStatus, InterfaceState};
use crate::element::set::{ElementSet, INTERFACE_POINTS};
use crate::error::{Attempt, NoConvergence, ResidualAt};
use crate::material::PointState;
use crate::model::Model;
use crate::model::timeline::Frame;
use crate::solver::cycles;
use crate::solver::energy::{self, EnergyLedger};
use crate::solver::mechanics::Mechanics;
use crate::solver::newton::Problem;
use crate::solver::newton::{ForceAverage, Newton, NewtonLog, NewtonSettings, norm};
use crate::{Error, Result};

/// The evolving solution: displacements and integration-point states.
#[derive(Clone, Debug)]
pub struct Solution {
    /// Displacements over all dofs (2 per node).
    pub u: Vec<f64>,
    /// Continuum states committed at the last converged step.
    pub committed: Vec<PointState>,
    /// Continuum states of the current iteration.
    pub trial: Vec<PointState>,
    /// Interface states committed at the last converged step.
    pub interface_committed: Vec<InterfaceState>,
    /// Interface states of the current iteration.
    pub interface_trial: Vec<InterfaceState>,
    /// Energy totals of the converged increments.
    pub energy: EnergyLedger,
    /// Per contact pair, the largest share of its stability limit that the last cycle's wear
    /// jump added at a point (0 without a jump or wear; ≤ 1, or the jump was refused). Set by
    /// [`crate::solver::cycles::end_cycle`] for the cycle-end output; not part of the state a
    /// run continues from.
    pub jump_use: Vec<f64>,
}

impl Solution {
    /// The unloaded state of `model`: zero displacements, virgin integration points.
    pub fn new(model: &Model) -> Self {
        let states = model.continuum.cells.len() * crate::element::quadrature::MAX_CELL_POINTS;
        let interface = model.interface.elements.len() * INTERFACE_POINTS;
        Self {
            u: vec![0.0; model.dofs.dof_count()],
            committed: vec![PointState::default(); states],
            trial: vec![PointState::default(); states],
            interface_committed: vec![InterfaceState::default(); interface],
            interface_trial: vec![InterfaceState::default(); interface],
            energy: EnergyLedger::default(),
            jump_use: vec![0.0; model.interface.pairs.len()],
        }
    }

    /// Makes the trial states of a converged increment the committed ones.
    pub fn commit(&mut self) {
        self.committed.copy_from_slice(&self.trial);
        self.interface_committed
            .copy_from_slice(&self.interface_trial);
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
        };
        (&mut self.u, problem)
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
}

impl RunStatistics {
    fn add(&mut self, log: &NewtonLog) {
        self.increments += 1;
        self.iterations += log.iterations;
        self.unsymmetric_solves += log.unsymmetric_solves;
        self.krylov_iterations += log.krylov_iterations;
        self.assembly_seconds += log.assembly_seconds;
        self.factorization_seconds += log.factorization_seconds;
        self.solve_seconds += log.solve_seconds;
    }
}

/// Where the stepping loop stands after a converged increment: with the [`Solution`] and the
/// [`RunStatistics`], everything a run needs to continue bit for bit ([`Resume`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
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
        }
    }

    /// The state after step `step` converged: the next one starts with a full increment.
    fn next_step(self, step: usize) -> Self {
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

/// A run to continue: the loop state, the counters and the solution of a converged increment
/// (as a restart record stores them).
#[derive(Clone, Debug)]
pub struct Resume {
    pub state: LoopState,
    pub stats: RunStatistics,
    /// Displacements and committed states (trial states are made equal to them).
    pub solution: Solution,
}

/// A converged increment as the [`Observer`] sees it.
#[derive(Clone, Copy, Debug)]
pub struct Progress<'a> {
    pub state: LoopState,
    pub stats: &'a RunStatistics,
    pub solution: &'a Solution,
}

/// What the stepping loop reports to its caller (the output): converged steps, converged
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
}

/// An [`Observer`] of converged steps only.
struct OnStep<F>(F);

impl<F: FnMut(&StepResult) -> Result<f64>> Observer for OnStep<F> {
    fn step(&mut self, step: &StepResult, _: &Progress) -> Result<f64> {
        (self.0)(step)
    }
}

/// Runs all load steps of the model's schedule, calling `on_step` after each converged step
/// (it returns the seconds it spent writing). Stops with an error naming the step, its load
/// factor and the residual history if a step cannot be made to converge by cutting it back
/// ([`Error::Collapse`] when the structure's stiffness collapsed, see [`step_failure`],
/// [`Error::NoConvergence`] otherwise); the steps before it have been handed to `on_step`
/// already. A converged increment that is implausible for small-strain theory
/// ([`implausible_increment`]) counts as failed and is cut back.
pub fn run_steps(
    model: &Model,
    settings: &NewtonSettings,
    on_step: impl FnMut(&StepResult) -> Result<f64>,
) -> Result<(Solution, RunStatistics)> {
    if let Some(arc) = &model.control.arc_length {
        return crate::solver::arclength::run_arc_length(model, settings, arc, on_step);
    }
    run_steps_from(model, settings, None, &mut OnStep(on_step))
}

/// [`run_steps`] (load control only) reporting every converged increment to `observer`, and
/// starting from `resume` when given (a run continued from a restart record reaches the
/// same results, bit for bit, as one that was never stopped: the loop state, the solution
/// and the force floor are all it depends on).
///
/// A step fails without further cut-backs when the tangent is singular in a model whose
/// tangent cannot change (elastic bodies, no interface): a smaller increment meets the same
/// matrix.
pub fn run_steps_from(
    model: &Model,
    settings: &NewtonSettings,
    resume: Option<Resume>,
    observer: &mut impl Observer,
) -> Result<(Solution, RunStatistics)> {
    let mut newton = Newton::new(*settings, &model.dofs, &model.pattern)?;
    let (mut state, mut stats, mut solution) = match resume {
        Some(r) => (r.state, r.stats, r.solution),
        None => (
            LoopState::start(),
            RunStatistics::default(),
            Solution::new(model),
        ),
    };
    newton.restore_force_average(state.force_average);
    solution.trial.copy_from_slice(&solution.committed);
    solution
        .interface_trial
        .copy_from_slice(&solution.interface_committed);
    let mut converged_u = solution.u.clone();
    let mut f_ext = vec![0.0; model.dofs.dof_count()];
    let constant_tangent = !model.control.plastic && model.interface.elements.is_empty();
    let schedule = &model.schedule;
    while state.step <= schedule.steps() {
        let step = state.step;
        // Every log line of the step (Newton iterations, cut-backs, its output) names it.
        let _span = tracing::info_span!("step", step).entered();
        let target = step as f64;
        let step_start = (step - 1) as f64;
        // A record written within this increment was made after the cycle had started.
        if state.time == step_start && schedule.timeline().starts_cycle(step) {
            cycles::start_cycle(&mut solution);
        }
        let mut attempts: Vec<Attempt> = Vec::new();
        let log = loop {
            let trial_time = schedule.next_time(state.time, state.size, target);
            model.apply_prescribed(trial_time, &mut solution.u);
            model.external_force(trial_time, &mut f_ext);
            if schedule.leaves_direction(state.time, trial_time) {
                release_slip(&mut solution.interface_committed);
            }
            let (u, mut problem) = solution.split(model);
            let attempt = newton.solve_increment(&mut problem, u, &f_ext, state.force_floor);
            let implausible = match &attempt {
                Ok(log) if log.converged => implausible_increment(model, &solution, &converged_u),
                _ => None,
            };
            match attempt {
                Ok(log) if log.converged && implausible.is_none() => {
                    stats.add(&log);
                    state.iterations += log.iterations;
                    state.increments += 1;
                    state.stiffness.record(
                        schedule.load_change(state.time, trial_time),
                        distance(&solution.u, &converged_u),
                    );
                    let internal_force = newton.system().internal_force.as_slice();
                    energy::record(model, &mut solution, &converged_u, &f_ext, internal_force);
                    solution.commit();
                    state.force_average = newton.force_average();
                    converged_u.copy_from_slice(&solution.u);
                    state.time = trial_time;
                    log_increment(model, &state, &log);
                    if state.time == target {
                        break log;
                    }
                    // Grow the sub-increment again after a success.
                    state.size *= 2.0;
                    let progress = Progress {
                        state,
                        stats: &stats,
                        solution: &solution,
                    };
                    observer.increment(&progress)?;
                }
                outcome => {
                    let singular = matches!(&outcome, Err(Error::Linear(_)));
                    attempts.push(Attempt {
                        time: trial_time,
                        load_factor: schedule.load_factor_at(trial_time),
                        iterations: outcome.as_ref().map_or(0, |log| log.iterations),
                        residuals: outcome
                            .as_ref()
                            .map_or_else(|_| Vec::new(), |log| log.residuals.clone()),
                        reason: implausible
                            .or_else(|| outcome.as_ref().err().map(ToString::to_string)),
                    });
                    if let Ok(log) = &outcome {
                        stats.add(log);
                    }
                    if state.cutbacks == settings.max_cutbacks || (singular && constant_tangent) {
                        let failure = diagnose(
                            model,
                            &solution,
                            &f_ext,
                            newton.system().internal_force.as_slice(),
                            NoConvergence {
                                step,
                                load_factor: schedule.load_factor(step),
                                converged_time: state.time,
                                converged_load_factor: schedule.load_factor_at(state.time),
                                cutbacks: state.cutbacks,
                                attempts,
                                ..NoConvergence::default()
                            },
                        );
                        if state.time > step_start {
                            report_partial(
                                model,
                                &mut solution,
                                &converged_u,
                                &state,
                                settings,
                                observer,
                            )?;
                        }
                        return Err(step_failure(model, failure, &state.stiffness));
                    }
                    state.cutbacks += 1;
                    stats.cutbacks += 1;
                    solution.u.copy_from_slice(&converged_u);
                    state.size = 0.5 * (trial_time - state.time);
                    tracing::info!(
                        "step {step}: cutting back to time {:.6}",
                        state.time + state.size
                    );
                }
            }
        };
        // The cycle's last increment is committed: store its results and jump its wear
        // before anything is recorded, so that every record is a state to continue from.
        let cycle_end = match schedule.timeline().ends_cycle(step) {
            None => Ok(()),
            Some(jump) => match cycles::end_cycle(model, &mut solution, jump as f64) {
                Ok(true) => {
                    let floor = state.force_floor;
                    settle_after_jump(
                        model,
                        &mut newton,
                        &mut solution,
                        &mut converged_u,
                        &f_ext,
                        floor,
                    )
                    .map(|log| {
                        stats.add(&log);
                        state.iterations += log.iterations;
                        state.force_average = newton.force_average();
                    })
                    .map_err(|reason| Error::JumpSettling {
                        step_index: None,
                        jump_cycles: jump as f64,
                        reason,
                    })
                }
                Ok(false) => Ok(()),
                Err(e) => Err(e),
            }
            .map_err(|e| {
                let analysis_step = schedule.timeline().frame(target).analysis_step;
                e.in_analysis_step(analysis_step - 1)
            }),
        };
        let internal_force = &newton.system().internal_force;
        state.force_floor = state.force_floor.max(1e-3 * norm(internal_force));
        stats.steps += 1;
        stats.last_residual = *log.residuals.last().unwrap_or(&0.0);
        if let Err(e @ Error::JumpSettling { .. }) = cycle_end {
            // The solution is the converged one before the jump's re-equilibrium, with the
            // jumped wear: its forces are re-evaluated for the files kept.
            report_partial(
                model,
                &mut solution,
                &converged_u,
                &state,
                settings,
                observer,
            )?;
            return Err(e);
        }
        let mut frame = schedule.timeline().frame(target);
        // A cycle whose end failed (jump refused, worn through) is no completed cycle.
        frame.cycle_end &= cycle_end.is_ok();
        let result = StepResult {
            frame,
            step,
            load_factor: schedule.load_factor(step),
            newton: NewtonLog {
                iterations: state.iterations,
                ..log
            },
            increments: state.increments,
            cutbacks: state.cutbacks,
            solution: &solution,
            internal_force,
            external_force: &f_ext,
        };
        if let Err(e) = cycle_end {
            // The increment converged: its files are kept, without a restart record (a
            // resumed run meets the same error instead of continuing past it).
            observer.partial_step(&result, target)?;
            return Err(e);
        }
        let done = state.next_step(step);
        let progress = Progress {
            state: done,
            stats: &stats,
            solution: &solution,
        };
        stats.output_seconds += observer.step(&result, &progress)?;
        state = done;
    }
    // Read at the end: the symbolic analysis runs at the first factorisation.
    stats.symbolic_seconds = newton.linear().symbolic_seconds();
    stats.factor_nnz = newton.linear().factor_nnz();
    Ok((solution, stats))
}

/// Re-equilibrates the bodies after a wear jump, under the loads of the converged state (one
/// solve, no load change), and commits the result (`converged_u` follows). The jump deepened
/// the gaps by the wear of the cycles it stands for; in reality the bodies follow that wear
/// gradually (a loaded cone sinks deeper into its seat), and that re-seating belongs to the
/// jumped cycles. Left to the next simulated cycle it would be counted as that cycle's slip
/// and dissipation, biased by a re-seating that grows with the jump. Its slip still
/// dissipates and wears, in the run's totals. A solve that does not converge is tried once
/// more with the slipping points released ([`release_slip`]); if that fails too, the solution
/// is left as it was before the solve and the solver's reason is returned.
fn settle_after_jump(
    model: &Model,
    newton: &mut Newton,
    solution: &mut Solution,
    converged_u: &mut [f64],
    external_force: &[f64],
    force_floor: f64,
) -> std::result::Result<NewtonLog, String> {
    let mut solve = |solution: &mut Solution| {
        let outcome = settle_once(
            model,
            newton,
            solution,
            converged_u,
            external_force,
            force_floor,
        );
        if outcome.is_err() {
            solution.u.copy_from_slice(converged_u);
            solution.trial.copy_from_slice(&solution.committed);
            solution
                .interface_trial
                .copy_from_slice(&solution.interface_committed);
        }
        outcome
    };
    solve(solution).or_else(|_| {
        let statuses = solution.interface_committed.clone();
        release_slip(&mut solution.interface_committed);
        solve(solution).inspect_err(|_| solution.interface_committed = statuses)
    })
}

/// One re-equilibrium solve of [`settle_after_jump`]; commits it when it converges.
fn settle_once(
    model: &Model,
    newton: &mut Newton,
    solution: &mut Solution,
    converged_u: &mut [f64],
    external_force: &[f64],
    force_floor: f64,
) -> std::result::Result<NewtonLog, String> {
    let (u, mut problem) = solution.split(model);
    let log = match newton.solve_increment(&mut problem, u, external_force, force_floor) {
        Ok(log) if log.converged => log,
        Ok(log) => {
            return Err(format!(
                "no convergence in {} iterations, residual {:.3e}",
                log.iterations,
                log.residuals.last().copied().unwrap_or(f64::NAN)
            ));
        }
        Err(e) => return Err(e.to_string()),
    };
    let internal_force = newton.system().internal_force.as_slice();
    energy::record(model, solution, converged_u, external_force, internal_force);
    solution.commit();
    converged_u.copy_from_slice(&solution.u);
    tracing::info!(
        iterations = log.iterations,
        "re-equilibrated after the wear jump"
    );
    Ok(log)
}

/// Status stabilisation ([`crate::contact::sticks`]) keeps a point that slipped in the last
/// increment on the slip branch, which is right while the loads keep their direction. When
/// they reverse (unloading in a load cycle) or a load starts moving, such a point sticks
/// first: on the slip branch its zero (Coulomb) tangential stiffness would make the first
/// correction of the increment far too large, and with a stiff k_T Newton would not recover
/// (a load reversal on a Cattaneo–Mindlin contact failed after 8 cut-backs at k_T = 3e8 MPa/mm).
/// The slipping points are therefore marked as sticking before such an increment; the stress
/// of the committed state is unchanged, so is the solution it converges to.
fn release_slip(states: &mut [InterfaceState]) {
    for s in states
        .iter_mut()
        .filter(|s| s.status == ContactStatus::Slip)
    {
        s.status = ContactStatus::Stick;
    }
}

/// The INFO line of a converged increment (one per increment, for batch logs), naming its
/// analysis step and cycle.
fn log_increment(model: &Model, state: &LoopState, log: &NewtonLog) {
    let timeline = model.schedule.timeline();
    let frame = timeline.frame(state.time);
    tracing::info!(
        step = state.step,
        analysis_step = timeline.steps()[frame.analysis_step - 1].name.as_str(),
        cycle = frame.cycle,
        time = state.time,
        load_factor = model.schedule.load_factor_at(state.time),
        iterations = log.iterations,
        residual = *log.residuals.last().unwrap_or(&0.0),
        cutbacks = state.cutbacks,
        "increment converged"
    );
}

/// Hands the last converged sub-increment of a failed step to the observer. The solution is
/// re-evaluated there (one assembly, no solve) so that its internal forces (reactions)
/// belong to that state and not to the failed attempt.
fn report_partial(
    model: &Model,
    solution: &mut Solution,
    converged_u: &[f64],
    state: &LoopState,
    settings: &NewtonSettings,
    observer: &mut impl Observer,
) -> Result<()> {
    solution.u.copy_from_slice(converged_u);
    let mut system = GlobalSystem::new(model.pattern.clone(), model.dofs.dof_count());
    system.clear(false);
    let (u, mut problem) = solution.split(model);
    problem.assemble(
        &mut system,
        &AssemblyInput {
            dofs: &model.dofs,
            u,
            tangent: false,
            algorithm: settings.contact_algorithm,
        },
    );
    let mut external = vec![0.0; model.dofs.dof_count()];
    model.external_force(state.time, &mut external);
    let mut frame = model.schedule.timeline().frame(state.time);
    // A step that failed completed no cycle (its files carry no cycle results).
    frame.cycle_end = false;
    let result = StepResult {
        frame,
        step: state.step,
        load_factor: model.schedule.load_factor_at(state.time),
        newton: NewtonLog {
            iterations: state.iterations,
            ..NewtonLog::default()
        },
        increments: state.increments,
        cutbacks: state.cutbacks,
        solution,
        internal_force: &system.internal_force,
        external_force: &external,
    };
    observer.partial_step(&result, state.time)
}

/// Completes `failure` with where it happened: the node with the largest out-of-balance
/// force of the last attempt (and its body), how many interface points changed their
/// contact status against the last converged state, and a physical reading where one is
/// recognisable (a contact pair slipping everywhere: its friction cannot carry the load).
fn diagnose(
    model: &Model,
    solution: &Solution,
    f_ext: &[f64],
    f_int: &[f64],
    mut failure: NoConvergence,
) -> NoConvergence {
    failure.largest_residual = largest_residual(model, f_ext, f_int);
    failure.status_changes = solution
        .interface_trial
        .iter()
        .zip(&solution.interface_committed)
        .filter(|(t, c)| t.status != c.status)
        .count();
    failure.hint = friction_exceeded(model, solution).or_else(|| unsupported_bodies(model));
    failure
}

/// The free node with the largest out-of-balance force |f_ext − f_int|, with its body.
fn largest_residual(model: &Model, f_ext: &[f64], f_int: &[f64]) -> Option<ResidualAt> {
    let mut best: Option<(usize, [f64; 2])> = None;
    let mut best_norm = 0.0;
    for (node, (e, i)) in f_ext.chunks_exact(2).zip(f_int.chunks_exact(2)).enumerate() {
        let mut r = [0.0; 2];
        for c in 0..2 {
            if model.dofs.equation(2 * node + c).is_some() {
                r[c] = e[c] - i[c];
            }
        }
        let size = r[0].hypot(r[1]);
        if size.is_finite() && size > best_norm {
            best_norm = size;
            best = Some((node, r));
        }
    }
    let (node, force) = best?;
    Some(ResidualAt {
        node: model
            .mesh
            .node_tags
            .get(node)
            .copied()
            .unwrap_or(node as u64),
        position: model.mesh.nodes[node],
        body: body_of_node(model, node),
        force,
    })
}

/// The name of a body that `node` belongs to.
fn body_of_node(model: &Model, node: usize) -> Option<String> {
    let cells = &model.continuum.cells;
    (0..cells.len())
        .find(|&e| model.continuum.nodes(e).contains(&(node as u32)))
        .map(|e| model.bodies[cells[e].body as usize].clone())
}

/// "Friction capacity exceeded" when, in the last attempt, every closed point of a contact
/// pair slips: the pair transmits at most μ·|p_N| everywhere and the tangential load asks
/// for more (Buczkowski & Kleiber (1994), Eq. 11: F = 0 at every point).
fn friction_exceeded(model: &Model, solution: &Solution) -> Option<String> {
    let pairs: Vec<&str> = model
        .interface
        .pairs
        .iter()
        .filter(|p| {
            let points = &solution.interface_trial
                [p.elements.start * INTERFACE_POINTS..p.elements.end * INTERFACE_POINTS];
            let closed = points.iter().filter(|s| s.status != ContactStatus::Open);
            let mut any = false;
            closed.clone().all(|s| {
                any = true;
                s.status == ContactStatus::Slip
            }) && any
        })
        .map(|p| p.name.as_str())
        .collect();
    (!pairs.is_empty()).then(|| {
        format!(
            "friction capacity exceeded: every closed point of contact '{}' slips, so friction \
             cannot carry the tangential load there (raise the friction or the normal load, or \
             support the sliding body)",
            pairs.join("', '")
        )
    })
}

/// "A body without support" when a group of bodies joined by shared nodes or interface
/// elements has no prescribed dof in x or in y: nothing stops its rigid translation.
fn unsupported_bodies(model: &Model) -> Option<String> {
    let nodes = model.mesh.nodes.len();
    let mut parent: Vec<usize> = (0..nodes).collect();
    fn root(parent: &mut [usize], mut n: usize) -> usize {
        while parent[n] != n {
            parent[n] = parent[parent[n]];
            n = parent[n];
        }
        n
    }
    let mut join = |nodes: &[u32]| {
        let first = root(&mut parent, nodes[0] as usize);
        for &n in &nodes[1..] {
            let r = root(&mut parent, n as usize);
            parent[r] = first;
        }
    };
    for e in 0..model.continuum.cells.len() {
        join(model.continuum.nodes(e));
    }
    for e in 0..model.interface.elements.len() {
        join(model.interface.nodes(e));
    }
    let mut held = vec![[false; 2]; nodes];
    for &(dof, _, _) in &model.prescribed {
        let r = root(&mut parent, dof / 2);
        held[r][dof % 2] = true;
    }
    let mut free: Vec<(String, &str)> = Vec::new();
    for cell in &model.continuum.cells {
        let r = root(&mut parent, cell.nodes[0] as usize);
        let body = &model.bodies[cell.body as usize];
        let missing = match held[r] {
            [false, false] => "x and y",
            [false, true] => "x",
            [true, false] => "y",
            [true, true] => continue,
        };
        if !free.iter().any(|(b, _)| b == body) {
            free.push((body.clone(), missing));
        }
    }
    (!free.is_empty()).then(|| {
        let list: Vec<String> = free
            .iter()
            .map(|(b, m)| format!("'{b}' (free to move in {m})"))
            .collect();
        format!(
            "a body without support: {} — no support holds it, directly or through another \
             body or a contact interface, against rigid-body motion",
            list.join(", ")
        )
    })
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

/// The Euclidean distance between two displacement vectors.
pub fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// Why a converged increment from `converged_u` to `solution` is implausible for
/// small-strain theory, if it is: a nodal displacement increment larger than
/// `[solver] max_displacement_increment` × the model size, or an equivalent strain increment
/// √(⅔ Δε:Δε) larger than `[solver] max_strain_increment` at an integration point. Such an
/// "equilibrium" is a locked mesh or a mechanism, not an answer.
pub fn implausible_increment(
    model: &Model,
    solution: &Solution,
    converged_u: &[f64],
) -> Option<String> {
    let control = &model.control;
    let limit = control.max_displacement_increment * model.size;
    let (node, du) = solution
        .u
        .chunks_exact(2)
        .zip(converged_u.chunks_exact(2))
        .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
        .enumerate()
        .fold(
            (0, 0.0),
            |best, (n, d)| if d > best.1 { (n, d) } else { best },
        );
    if !du.is_finite() || du > limit {
        return Some(format!(
            "implausible increment: node {} moves by {du:.3e} mm in one increment, more than \
             {} of the model size {:.3e} mm ([solver] max_displacement_increment); small-strain \
             theory does not hold there (a collapse mechanism, or a locked mesh)",
            model
                .mesh
                .node_tags
                .get(node)
                .copied()
                .unwrap_or(node as u64),
            control.max_displacement_increment,
            model.size
        ));
    }
    let de = solution
        .trial
        .iter()
        .zip(&solution.committed)
        .map(|(t, c)| equivalent_strain(&(t.strain - c.strain)))
        .fold(0.0, f64::max);
    if !de.is_finite() || de > control.max_strain_increment {
        return Some(format!(
            "implausible increment: an equivalent strain increment of {de:.3e}, more than {} \
             ([solver] max_strain_increment); small-strain theory does not hold there (a \
             collapse mechanism, or a locked mesh)",
            control.max_strain_increment
        ));
    }
    None
}

/// √(⅔ ε:ε) of a strain in Voigt order (xx, yy, γ_xy, zz), γ the engineering shear strain.
fn equivalent_strain(e: &crate::material::Voigt) -> f64 {
    let tensor = e[0] * e[0] + e[1] * e[1] + e[3] * e[3] + 0.5 * e[2] * e[2];
    (2.0 / 3.0 * tensor).sqrt()
}

/// The error of a step that could not be completed: [`Error::Collapse`] when the load was
/// rising and the structure's stiffness collapsed — the secant stiffness of the last
/// converged increment fell below `[solver] collapse_stiffness_ratio` of the first one, or
/// (with a plastic body) an attempt met a tangent that is not positive definite or an
/// implausible increment — and [`Error::NoConvergence`] otherwise.
pub fn step_failure(model: &Model, failure: NoConvergence, stiffness: &StiffnessHistory) -> Error {
    let converged = failure.converged_load_factor;
    let failed = failure
        .attempts
        .last()
        .map_or(failure.load_factor, |a| a.load_factor);
    let rising = failed.abs() > converged.abs();
    let ratio = stiffness.ratio();
    let reasons = |pattern: &str| {
        failure
            .attempts
            .iter()
            .any(|a| a.reason.as_deref().is_some_and(|r| r.contains(pattern)))
    };
    let indicator = if let Some(r) = ratio.filter(|&r| r < model.control.collapse_stiffness_ratio) {
        Some(format!(
            "the secant stiffness fell to {r:.2e} of the first increment's"
        ))
    } else if model.control.plastic && reasons("not positive definite") {
        Some("the tangent of the plastic model lost positive definiteness".to_string())
    } else if model.control.plastic && reasons("implausible increment") {
        Some("the plastic model only converged to implausibly large increments".to_string())
    } else {
        None
    };
    match indicator {
        Some(indicator) if rising => Error::Collapse {
            step: failure.step,
            converged_load_factor: converged,
            failed_load_factor: failed,
            indicator,
            details: Box::new(failure),
        },
        _ => Error::NoConvergence(Box::new(failure)),
    }
}
