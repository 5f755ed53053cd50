//! Incremental loading: the load factors of the case are applied one after another; each
//! increment is solved by Newton-Raphson and its integration-point states are committed only
//! once it has converged. An increment that fails is halved and retried from the last
//! converged state, up to `max_cutbacks` times; sub-increments are solved silently and only
//! the scheduled steps are handed to the output.

use crate::contact::InterfaceState;
use crate::element::set::INTERFACE_POINTS;
use crate::error::{Attempt, NoConvergence};
use crate::material::PointState;
use crate::model::Model;
use crate::solver::mechanics::Mechanics;
use crate::solver::newton::{Newton, NewtonLog, NewtonSettings, norm};
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
#[derive(Clone, Debug, Default)]
pub struct RunStatistics {
    pub steps: usize,
    pub increments: usize,
    pub iterations: usize,
    pub cutbacks: usize,
    pub unsymmetric_solves: usize,
    pub krylov_iterations: usize,
    pub symbolic_seconds: f64,
    pub assembly_seconds: f64,
    pub factorization_seconds: f64,
    pub solve_seconds: f64,
    pub output_seconds: f64,
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

/// Runs all load steps of the model's schedule, calling `on_step` after each converged step
/// (it returns the seconds it spent writing). Stops with an error naming the step, its load
/// factor and the residual history if a step cannot be made to converge by cutting it back;
/// the steps before it have been handed to `on_step` already.
pub fn run_steps(
    model: &Model,
    settings: &NewtonSettings,
    mut on_step: impl FnMut(&StepResult) -> Result<f64>,
) -> Result<(Solution, RunStatistics)> {
    let mut stats = RunStatistics::default();
    let mut newton = Newton::new(*settings, &model.dofs, &model.pattern)?;
    stats.symbolic_seconds = newton.linear().symbolic_seconds();
    stats.factor_nnz = newton.linear().factor_nnz();
    let mut solution = Solution::new(model);
    let mut converged_u = solution.u.clone();
    let mut f_ext = vec![0.0; model.dofs.dof_count()];
    let mut force_floor: f64 = 0.0;
    // Pseudo-time: step j ends at time j (see `Schedule`).
    let mut time = 0.0;
    for step in 1..=model.schedule.steps() {
        let target = step as f64;
        let mut size = 1.0;
        let mut cutbacks = 0;
        let mut increments = 0;
        let mut iterations = 0;
        let mut attempts: Vec<Attempt> = Vec::new();
        let log = loop {
            let trial_time = if time + size >= target - 1e-12 {
                target
            } else {
                time + size
            };
            model.apply_prescribed(trial_time, &mut solution.u);
            model.external_force(trial_time, &mut f_ext);
            let (u, mut problem) = solution.split(model);
            let attempt = newton.solve_increment(&mut problem, u, &f_ext, force_floor);
            match attempt {
                Ok(log) if log.converged => {
                    stats.add(&log);
                    iterations += log.iterations;
                    increments += 1;
                    solution.commit();
                    converged_u.copy_from_slice(&solution.u);
                    time = trial_time;
                    if time == target {
                        break log;
                    }
                    // Grow the sub-increment again after a success.
                    size *= 2.0;
                }
                outcome => {
                    attempts.push(Attempt {
                        time: trial_time,
                        load_factor: model.schedule.value(0, trial_time),
                        iterations: outcome.as_ref().map_or(0, |log| log.iterations),
                        residuals: outcome
                            .as_ref()
                            .map_or_else(|_| Vec::new(), |log| log.residuals.clone()),
                        reason: outcome.as_ref().err().map(ToString::to_string),
                    });
                    if let Ok(log) = &outcome {
                        stats.add(log);
                    }
                    if cutbacks == settings.max_cutbacks {
                        return Err(Error::NoConvergence(Box::new(NoConvergence {
                            step,
                            load_factor: model.schedule.load_factor(step),
                            converged_time: time,
                            converged_load_factor: model.schedule.value(0, time),
                            cutbacks,
                            attempts,
                        })));
                    }
                    cutbacks += 1;
                    stats.cutbacks += 1;
                    solution.u.copy_from_slice(&converged_u);
                    size = 0.5 * (trial_time - time);
                    tracing::info!("step {step}: cutting back to time {:.6}", time + size);
                }
            }
        };
        let internal_force = &newton.system().internal_force;
        force_floor = force_floor.max(1e-3 * norm(internal_force));
        stats.steps += 1;
        stats.last_residual = *log.residuals.last().unwrap_or(&0.0);
        let result = StepResult {
            step,
            load_factor: model.schedule.load_factor(step),
            newton: NewtonLog { iterations, ..log },
            increments,
            cutbacks,
            solution: &solution,
            internal_force,
            external_force: &f_ext,
        };
        stats.output_seconds += on_step(&result)?;
    }
    Ok((solution, stats))
}
