//! Incremental loading: the output increments of the case's load history (the frames of its
//! analysis steps and cycles, [`crate::model::timeline`]) are applied one after another; each
//! increment is solved by Newton-Raphson and its integration-point states are committed only
//! once it has converged. An increment that fails is halved and retried from the last
//! converged state, up to `max_cutbacks` times, and a sub-increment also ends on a breakpoint
//! of an amplitude ([`crate::model::Schedule::next_time`]); sub-increments are solved silently
//! and only the scheduled increments are handed to the output. The load cycles' hooks
//! ([`Solution::start_cycle`], [`Solution::end_cycle`]) run before the first increment of
//! every step and cycle and after the commit of its last one; a wear jump is followed by a
//! re-equilibrium under the same loads (`settle_after_jump`), the driver's own increment.
//!
//! The run's state is [`crate::solver::state`] (re-exported here), its failure diagnosis
//! [`crate::solver::diagnosis`]; a case under arc-length control is handed to
//! [`crate::solver::arclength`].

use crate::assembly::{AssemblyInput, GlobalSystem};
use crate::contact::{ContactStatus, InterfaceState};
use crate::error::{Attempt, AttemptFailure, NoConvergence};
use crate::model::Model;
use crate::solver::coupling::Temperatures;
use crate::solver::diagnosis::{diagnose, implausible_increment, step_failure};
use crate::solver::energy::BodySums;
use crate::solver::newton::Problem;
use crate::solver::newton::{Newton, NewtonLog, NewtonSettings, distance, norm};
use crate::solver::state::{
    LoopState, Observer, Progress, Resume, RunStatistics, Solution, StepResult,
};
use crate::solver::strain_bound::StrainBound;
use crate::{Error, Result};

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
    run_steps_from(model, settings, None, &mut OnStep(on_step))
}

/// [`run_steps`] reporting every converged increment to `observer`, and starting from
/// `resume` when given (a run continued from a restart record reaches the same results, bit
/// for bit, as one that was never stopped: the loop state, the solution and the force floor
/// are all it depends on). Under arc-length control the run is
/// [`crate::solver::arclength::run_arc_length`].
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
    if let Some(arc) = &model.control.arc_length {
        return crate::solver::arclength::run_arc_length(model, settings, arc, resume, observer);
    }
    let mut newton = Newton::new(*settings, &model.dofs, &model.pattern)?;
    let resumed = resume.is_some();
    let Resume {
        mut state,
        mut stats,
        mut solution,
        last_increment,
    } = resume.unwrap_or_else(|| Resume::start(model));
    newton.restore_force_average(state.force_average);
    if let Some(last) = last_increment {
        newton.restore_last_increment(last);
    }
    solution.reset_trial();
    let mut temperatures = Temperatures::new(model, settings)?;
    temperatures.start(model, &mut solution, state.time)?;
    stats.add_work(&start_newton(model, &mut newton, &mut solution, resumed)?);
    let mut converged_u = solution.u.clone();
    let mut f_ext = vec![0.0; model.dofs.dof_count()];
    let constant_tangent = !model.control.plastic && model.interface.elements.is_empty();
    let schedule = &model.schedule;
    let mut warned_far_from_equilibrium = false;
    let mut bound = None;
    while state.step <= schedule.steps() {
        let step = state.step;
        // Every log line of the step (Newton iterations, cut-backs, its output) names it.
        let _span = tracing::info_span!("step", step).entered();
        let target = step as f64;
        let step_start = (step - 1) as f64;
        // A record written within this increment was made after the cycle had started.
        if state.time == step_start && schedule.timeline().starts_cycle(step) {
            solution.start_cycle();
        }
        let mut attempts: Vec<Attempt> = Vec::new();
        let log = loop {
            // The cap counts every solve: sub-increments and retried attempts alike.
            let solves = stats.increments + stats.cutbacks;
            if solves >= model.control.max_solves {
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
                return Err(Error::TooManySolves {
                    at: Box::new(schedule.load_point(state.time, target)),
                    count: solves,
                    limit: model.control.max_solves,
                    planned: false,
                });
            }
            let trial_time = schedule.next_time(state.time, state.size, target);
            model.apply_prescribed(trial_time, &mut solution.u);
            model.external_force(trial_time, &mut f_ext);
            if schedule.leaves_direction(state.time, trial_time) {
                release_slip(&mut solution.interface_committed);
            }
            let attempt = temperatures.solve_increment(
                model,
                &mut newton,
                &mut solution,
                trial_time,
                &f_ext,
                state.force_floor,
            );
            // A converged increment's point states are read once: for its strain
            // increment here, for the energy ledger if it is kept.
            let scan = match &attempt {
                Ok(log) if log.converged => Some(increment_sums(
                    model,
                    &mut newton,
                    &mut solution,
                    &converged_u,
                    &mut bound,
                )),
                _ => None,
            };
            let implausible = scan.as_ref().and_then(|scan| {
                implausible_increment(model, &solution, &converged_u, scan.strain_increment)
            });
            match (attempt, scan) {
                (Ok(log), Some(scan)) if log.converged && implausible.is_none() => {
                    stats.add(&log);
                    stats.work.increments += 1;
                    state.iterations += log.iterations;
                    state.increments += 1;
                    state.stiffness.record(
                        schedule.load_change(state.time, trial_time),
                        distance(&solution.u, &converged_u),
                    );
                    let internal_force = newton.system().internal_force.as_slice();
                    solution.record_energy(model, &converged_u, &f_ext, internal_force, scan);
                    solution.commit();
                    state.force_average = newton.force_average();
                    converged_u.copy_from_slice(&solution.u);
                    state.time = trial_time;
                    log_increment(model, &state, &log);
                    if !warned_far_from_equilibrium {
                        warned_far_from_equilibrium = warn_if_far_from_equilibrium(&state, &log);
                    }
                    if state.time == target {
                        break log;
                    }
                    // Grow the sub-increment again after a success.
                    state.size *= 2.0;
                    let progress = Progress {
                        state: state.clone(),
                        stats: &stats,
                        solution: &solution,
                        last_increment: newton.last_increment(),
                    };
                    observer.increment(&progress)?;
                }
                (outcome, _) => {
                    let singular = matches!(&outcome, Err(Error::Linear(_)));
                    let failure = match (implausible, &outcome) {
                        (Some(i), _) => Some(AttemptFailure::Implausible(i)),
                        (None, Err(Error::Linear(m))) => Some(AttemptFailure::Tangent(m.clone())),
                        (None, Err(e)) => Some(AttemptFailure::Other(e.to_string())),
                        (None, Ok(_)) => None,
                    };
                    attempts.push(Attempt {
                        time: trial_time,
                        load_factor: schedule.load_factor_at(trial_time),
                        at: schedule.load_point(trial_time, target),
                        iterations: outcome.as_ref().map_or(0, |log| log.iterations),
                        residuals: outcome
                            .as_ref()
                            .map_or_else(|_| Vec::new(), |log| log.residuals.clone()),
                        failure,
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
                                reached: schedule.load_point(state.time, target),
                                target: schedule.load_point(target, target),
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
        if schedule.timeline().ends_cycle(step).is_some() {
            solution.end_body_cycle(model, step);
        }
        let cycle_end = match schedule.timeline().ends_cycle(step) {
            None => Ok(()),
            Some(jump) => match solution.end_cycle(model, jump as f64) {
                Ok(true) => {
                    let floor = state.force_floor;
                    let mut settling = Settling {
                        newton: &mut newton,
                        converged_u: &mut converged_u,
                        bound: &mut bound,
                    };
                    settle_after_jump(model, &mut settling, &mut solution, &f_ext, floor)
                        .map(|log| {
                            stats.add(&log);
                            stats.work.increments += 1;
                            state.iterations += log.iterations;
                            state.force_average = newton.force_average();
                        })
                        .map_err(|reason| Error::JumpSettling {
                            step_index: None,
                            jump_cycles: jump as f64,
                            reason,
                        })
                        .and_then(|()| solution.check_jump_energy(model, jump as f64))
                }
                Ok(false) => Ok(()),
                Err(e) => Err(e),
            }
            .map_err(|e| {
                let analysis_step = schedule.timeline().frame(target).analysis_step;
                e.in_analysis_step(analysis_step - 1)
            }),
        };
        // A failed jump's files come from `report_partial`, which evaluates its states.
        let settled = !matches!(cycle_end, Err(Error::JumpSettling { .. }));
        let frame_states = if settled && (cycle_end.is_err() || observer.reads_point_states(step)) {
            complete_committed_states(model, &mut newton, &mut solution)
        } else {
            0.0
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
            stats.add_output(frame_states, false);
            observer.partial_step(&result, target)?;
            return Err(e);
        }
        state = state.next_step(step);
        let progress = Progress {
            state: state.clone(),
            stats: &stats,
            solution: &solution,
            last_increment: newton.last_increment(),
        };
        stats.add_output(frame_states + observer.step(&result, &progress)?, true);
    }
    // Read at the end: the symbolic analysis runs at the first factorisation.
    stats.symbolic_seconds = newton.symbolic_seconds();
    stats.factor_nnz = newton.linear().factor_nnz();
    stats.work.solver = *newton.work();
    stats.work.conduction = temperatures.work();
    Ok((solution, stats))
}

/// Starts `newton` at the committed state of `solution`, that of a new run or of one
/// `resumed` from a restart record ([`Newton::start_from`]), and evaluates again the
/// continuum states a record leaves out when they follow from the displacements.
pub(crate) fn start_newton(
    model: &Model,
    newton: &mut Newton,
    solution: &mut Solution,
    resumed: bool,
) -> Result<NewtonLog> {
    // States that follow the displacements are kept once, in the trial array, where
    // `start_from` makes them.
    let rebuild_states = resumed && model.states_follow_displacements();
    let (u, mut problem) = solution.split(model);
    newton.start_from(&mut problem, u, rebuild_states)
}

/// The pass of a converged increment over its bodies: its largest strain increment and its
/// energy terms ([`Solution::scan_increment`]). Where the point states follow the
/// displacements there are no committed states to compare: the strain increment is bounded
/// from the nodal increments ([`StrainBound`], made at the first increment) and found
/// exactly only when the bound exceeds `[solver] max_strain_increment`, from the point
/// states at `u_old` and at u made cell by cell ([`Newton::strain_increment`]: the
/// arithmetic of a pass over stored states, so that the plausibility verdict is the
/// states' own to the last bit — ε(Δu) would round differently, and a limit within rounding
/// of an increment's strain would then cut back differently). A linear bulk whose force is
/// K·u evaluated no element in the increment: its stored energy is ½ u·K u; under a
/// temperature field (K·u − G ΔT, or K·u for bodies that do not expand) its states are made
/// here, for the pass.
pub(crate) fn increment_sums(
    model: &Model,
    newton: &mut Newton,
    solution: &mut Solution,
    u_old: &[f64],
    bound: &mut Option<StrainBound>,
) -> BodySums {
    let energy = newton
        .linear_bulk_energy()
        .filter(|_| newton.states_pending());
    if energy.is_none() || !solution.states_follow_displacements {
        // The pass reads the point states, which a linear bulk's increment left out (under
        // a temperature field too: its stored and thermal energy terms are theirs).
        let (u, mut problem) = solution.split(model);
        newton.complete_increment_states(&mut problem, u);
    }
    if !solution.states_follow_displacements {
        return solution.scan_increment(model);
    }
    let mut sums = match energy {
        Some(energy) => BodySums::of_linear_bulk(model, energy),
        None => solution.scan_increment(model),
    };
    let bound = bound.get_or_insert_with(|| StrainBound::new(model));
    sums.strain_increment = bound.of(model, &solution.u, u_old);
    // A bound that is not a number (nor is Δu) is looked at exactly too.
    let plausible = sums.strain_increment <= model.control.max_strain_increment;
    if !plausible {
        let (u, mut problem) = solution.split(model);
        sums.strain_increment = newton.strain_increment(&mut problem, u_old, u);
    }
    sums
}

/// Makes the point states those of the converged state where a linear bulk's increments
/// left them out ([`Newton::states_pending`]); returns the seconds spent.
fn complete_committed_states(model: &Model, newton: &mut Newton, solution: &mut Solution) -> f64 {
    if !newton.states_pending() {
        return 0.0;
    }
    let (u, mut problem) = solution.split(model);
    newton.complete_states(&mut problem, u)
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
    settling: &mut Settling<'_, '_>,
    solution: &mut Solution,
    external_force: &[f64],
    force_floor: f64,
) -> std::result::Result<NewtonLog, String> {
    let mut solve = |solution: &mut Solution| {
        let outcome = settle_once(model, settling, solution, external_force, force_floor);
        if outcome.is_err() {
            solution.u.copy_from_slice(settling.converged_u);
            solution.reset_trial();
        }
        outcome
    };
    solve(solution).or_else(|_| {
        let statuses = solution.interface_committed.clone();
        release_slip(&mut solution.interface_committed);
        solve(solution).inspect_err(|_| solution.interface_committed = statuses)
    })
}

/// The stepping loop's state a re-equilibrium after a wear jump ([`settle_after_jump`])
/// works on.
struct Settling<'a, 'm> {
    newton: &'a mut Newton<'m>,
    /// The converged displacements, which a converged re-equilibrium replaces.
    converged_u: &'a mut [f64],
    bound: &'a mut Option<StrainBound>,
}

/// One re-equilibrium solve of [`settle_after_jump`]; commits it when it converges.
fn settle_once(
    model: &Model,
    settling: &mut Settling<'_, '_>,
    solution: &mut Solution,
    external_force: &[f64],
    force_floor: f64,
) -> std::result::Result<NewtonLog, String> {
    let Settling {
        newton,
        converged_u,
        bound,
    } = settling;
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
    let scan = increment_sums(model, newton, solution, converged_u, bound);
    let internal_force = newton.system().internal_force.as_slice();
    solution.record_energy(model, converged_u, external_force, internal_force, scan);
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
/// Relative residual (‖r‖ / max(‖f_ext‖, ‖f_int‖, ‖r₀‖)) of a converged increment above
/// which the run warns: the engineering criteria accept a residual relative to the average
/// force q̃, and a q̃ given far too large (`[solver] average_force`) or tolerances far too
/// loose accept states out of balance by a fraction of the loads. Converged increments of the
/// default criteria stay below 1e-6.
const FAR_FROM_EQUILIBRIUM: f64 = 1e-2;

/// Warns (once per run: returns whether it did) when the increment just accepted is
/// [`FAR_FROM_EQUILIBRIUM`].
fn warn_if_far_from_equilibrium(state: &LoopState, log: &NewtonLog) -> bool {
    let residual = log.residuals.last().copied().unwrap_or(0.0);
    let far = residual > FAR_FROM_EQUILIBRIUM;
    if far {
        tracing::warn!(
            "the increment to time {} was accepted with a relative residual of {residual:.2e}: \
             far from equilibrium (reactions and stresses may be wrong); check [solver] \
             average_force and the tolerances (docs/guide/solver.md)",
            state.time
        );
    }
    far
}

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
