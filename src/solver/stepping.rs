//! Incremental loading: the load factors of the case are applied one after another; each
//! increment is solved by Newton-Raphson and its integration-point states are committed only
//! once it has converged.

use crate::assembly::GlobalSystem;
use crate::material::PointState;
use crate::model::Model;
use crate::solver::linear::CholeskySolver;
use crate::solver::newton::{NewtonLog, NewtonSettings, Problem, solve_increment};
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
}

/// The mechanical problem of a model with its solution state.
struct Mechanics<'a> {
    model: &'a Model,
    committed: &'a [PointState],
    trial: &'a mut [PointState],
}

impl Problem for Mechanics<'_> {
    fn assemble(&mut self, u: &[f64], system: &mut GlobalSystem, with_tangent: bool) {
        let m = self.model;
        system.assemble(
            &m.continuum,
            &m.continuum_coloring,
            &m.dofs,
            u,
            self.committed,
            self.trial,
            with_tangent,
        );
    }
}

/// A converged step as handed to the output.
#[derive(Debug)]
pub struct StepResult<'a> {
    /// 1-based step number.
    pub step: usize,
    pub load_factor: f64,
    pub newton: NewtonLog,
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
    pub iterations: usize,
    pub symbolic_seconds: f64,
    pub assembly_seconds: f64,
    pub factorization_seconds: f64,
    pub solve_seconds: f64,
    pub output_seconds: f64,
    pub factor_nnz: usize,
    /// Final relative residual of the last step.
    pub last_residual: f64,
}

/// Runs all load steps of `factors`, calling `on_step` after each converged step. Stops with
/// an error naming the step, its load factor and the residual history if a step does not
/// converge; the steps before it have been handed to `on_step` already.
pub fn run_steps(
    model: &Model,
    factors: &[f64],
    settings: &NewtonSettings,
    mut on_step: impl FnMut(&StepResult) -> Result<f64>,
) -> Result<(Solution, RunStatistics)> {
    let mut stats = RunStatistics::default();
    let t = std::time::Instant::now();
    let mut linear = CholeskySolver::new(&model.pattern)?;
    stats.symbolic_seconds = t.elapsed().as_secs_f64();
    stats.factor_nnz = linear.factor_nnz();
    let mut system = GlobalSystem::new(model.pattern.clone(), model.dofs.dof_count());
    let states = model.continuum.cells.len() * crate::element::quadrature::MAX_CELL_POINTS;
    let mut solution = Solution {
        u: vec![0.0; model.dofs.dof_count()],
        committed: vec![PointState::default(); states],
        trial: vec![PointState::default(); states],
    };
    let mut f_ext = vec![0.0; model.dofs.dof_count()];
    let mut force_floor: f64 = 0.0;
    for (i, &factor) in factors.iter().enumerate() {
        for &(dof, value) in &model.prescribed {
            solution.u[dof] = factor * value;
        }
        for (f, r) in f_ext.iter_mut().zip(&model.reference_load) {
            *f = factor * r;
        }
        let Solution {
            u,
            committed,
            trial,
        } = &mut solution;
        let mut problem = Mechanics {
            model,
            committed,
            trial,
        };
        let log = solve_increment(
            &mut problem,
            &model.dofs,
            &mut system,
            &mut linear,
            u,
            &f_ext,
            settings,
            force_floor,
        )?;
        stats.iterations += log.iterations;
        stats.assembly_seconds += log.assembly_seconds;
        stats.factorization_seconds += log.factorization_seconds;
        stats.solve_seconds += log.solve_seconds;
        stats.last_residual = *log.residuals.last().unwrap_or(&0.0);
        if !log.converged {
            return Err(Error::NoConvergence(format!(
                "step {} (load factor {factor}) did not converge in {} iterations; relative residuals: {}",
                i + 1,
                log.iterations,
                log.residuals
                    .iter()
                    .map(|r| format!("{r:.3e}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        solution.committed.copy_from_slice(&solution.trial);
        force_floor = force_floor.max(1e-3 * crate::solver::newton::norm(&system.internal_force));
        stats.steps += 1;
        let result = StepResult {
            step: i + 1,
            load_factor: factor,
            newton: log,
            solution: &solution,
            internal_force: &system.internal_force,
            external_force: &f_ext,
        };
        stats.output_seconds += on_step(&result)?;
    }
    Ok((solution, stats))
}
