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
/// factor and the residual history if a step cannot be made to converge by cutting it back
/// ([`Error::Collapse`] when the structure's stiffness collapsed, see [`step_failure`],
/// [`Error::NoConvergence`] otherwise); the steps before it have been handed to `on_step`
/// already. A converged increment that is implausible for small-strain theory
/// ([`implausible_increment`]) counts as failed and is cut back.
pub fn run_steps(
    model: &Model,
    settings: &NewtonSettings,
    mut on_step: impl FnMut(&StepResult) -> Result<f64>,
) -> Result<(Solution, RunStatistics)> {
    if let Some(arc) = &model.control.arc_length {
        return crate::solver::arclength::run_arc_length(model, settings, arc, on_step);
    }
    let mut stats = RunStatistics::default();
    let mut newton = Newton::new(*settings, &model.dofs, &model.pattern)?;
    stats.symbolic_seconds = newton.linear().symbolic_seconds();
    stats.factor_nnz = newton.linear().factor_nnz();
    let mut solution = Solution::new(model);
    let mut converged_u = solution.u.clone();
    let mut f_ext = vec![0.0; model.dofs.dof_count()];
    let mut force_floor: f64 = 0.0;
    let mut stiffness = StiffnessHistory::default();
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
            let implausible = match &attempt {
                Ok(log) if log.converged => implausible_increment(model, &solution, &converged_u),
                _ => None,
            };
            match attempt {
                Ok(log) if log.converged && implausible.is_none() => {
                    stats.add(&log);
                    iterations += log.iterations;
                    increments += 1;
                    stiffness.record(
                        model.schedule.value(0, trial_time) - model.schedule.value(0, time),
                        distance(&solution.u, &converged_u),
                    );
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
                        reason: implausible
                            .or_else(|| outcome.as_ref().err().map(ToString::to_string)),
                    });
                    if let Ok(log) = &outcome {
                        stats.add(log);
                    }
                    if cutbacks == settings.max_cutbacks {
                        let failure = NoConvergence {
                            step,
                            load_factor: model.schedule.load_factor(step),
                            converged_time: time,
                            converged_load_factor: model.schedule.value(0, time),
                            cutbacks,
                            attempts,
                        };
                        return Err(step_failure(model, failure, &stiffness));
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

/// Secant stiffnesses Δλ/‖Δu‖ of the converged increments of a run: the first one (the
/// reference) and the latest.
#[derive(Clone, Copy, Debug, Default)]
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
