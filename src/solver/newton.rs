//! Newton-Raphson for one load increment (paper Eq. 32):
//! K_T(u_i) δu = Q − F(u_i), u_{i+1} = u_i + δu, until both the out-of-balance force and the
//! correction are small.
//!
//! Convergence is declared when ‖r‖ ≤ tol_f · max(‖f_ext‖, ‖f_int‖, ‖r₀‖, f_floor) over the
//! free dofs (‖f_int‖ over all dofs includes the reactions, so displacement-driven problems
//! have a meaningful reference; ‖r₀‖, the out-of-balance force at the start of the
//! increment, gives one when the solution is stress-free, e.g. a body lifted off a contact) and the last correction satisfied ‖δu‖ ≤ tol_u · ‖u‖. As in
//! Abaqus' "linear increment" rule, a residual a thousand times below the force tolerance is
//! accepted without the correction check: a linear problem then needs one solve, not two.

use crate::Result;
use crate::assembly::{DofMap, GlobalSystem};
use crate::solver::linear::CholeskySolver;

/// Settings of the Newton loop (public fields, as in dolfinx's `NewtonSolver`).
#[derive(Clone, Copy, Debug)]
pub struct NewtonSettings {
    pub max_iterations: usize,
    pub force_tolerance: f64,
    pub displacement_tolerance: f64,
    /// How often a failed increment is halved and retried.
    pub max_cutbacks: usize,
}

impl From<crate::config::SolverSpec> for NewtonSettings {
    fn from(s: crate::config::SolverSpec) -> Self {
        Self {
            max_iterations: s.max_iterations,
            force_tolerance: s.force_tolerance,
            displacement_tolerance: s.displacement_tolerance,
            max_cutbacks: s.max_cutbacks,
        }
    }
}

/// A problem the Newton loop can solve: it assembles internal forces and the tangent.
pub trait Problem {
    /// Assembles the internal force over all dofs (and the tangent over the free dofs if
    /// `with_tangent`) into `system` at displacements `u`, updating trial states. Returns
    /// whether the tangent is symmetric.
    fn assemble(&mut self, u: &[f64], system: &mut GlobalSystem, with_tangent: bool) -> bool;
}

/// What happened in one increment.
#[derive(Clone, Debug, Default)]
pub struct NewtonLog {
    /// Number of linear solves.
    pub iterations: usize,
    /// Relative force residual before each solve and after the last one.
    pub residuals: Vec<f64>,
    /// Relative size ‖δu‖/‖u‖ of each correction.
    pub corrections: Vec<f64>,
    /// Linear solves with an unsymmetric tangent, and their BiCGSTAB iterations.
    pub unsymmetric_solves: usize,
    pub krylov_iterations: usize,
    pub converged: bool,
    /// Seconds spent assembling, factorising and solving.
    pub assembly_seconds: f64,
    pub factorization_seconds: f64,
    pub solve_seconds: f64,
}

/// Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Solves one increment from the displacements in `u` (whose prescribed components already
/// hold this increment's values) for the external forces `f_ext` (all dofs). `force_floor`
/// is an absolute force level below which residuals count as zero (e.g. from earlier steps),
/// for increments whose loads vanish.
#[allow(clippy::too_many_arguments)]
pub fn solve_increment(
    problem: &mut impl Problem,
    dofs: &DofMap,
    system: &mut GlobalSystem,
    linear: &mut CholeskySolver,
    u: &mut [f64],
    f_ext: &[f64],
    settings: &NewtonSettings,
    force_floor: f64,
) -> Result<NewtonLog> {
    let mut log = NewtonLog::default();
    let mut r = vec![0.0; dofs.free_count()];
    let mut ext = vec![0.0; dofs.free_count()];
    dofs.gather_free(f_ext, &mut ext);
    let f_ext_norm = norm(f_ext);
    let mut last_correction = f64::INFINITY;
    let mut initial_residual = None;
    loop {
        let t = std::time::Instant::now();
        system.clear(true);
        let symmetric = problem.assemble(u, system, true);
        log.assembly_seconds += t.elapsed().as_secs_f64();
        dofs.gather_free(&system.internal_force, &mut r);
        for (ri, ei) in r.iter_mut().zip(&ext) {
            *ri = ei - *ri;
        }
        let r0 = *initial_residual.get_or_insert(norm(&r));
        let reference = f_ext_norm
            .max(norm(&system.internal_force))
            .max(r0)
            .max(force_floor)
            .max(f64::MIN_POSITIVE);
        let residual = norm(&r) / reference;
        log.residuals.push(residual);
        tracing::debug!(
            iteration = log.iterations,
            residual,
            correction = last_correction,
            "newton"
        );
        let balanced = residual <= settings.force_tolerance;
        let linear_increment = residual <= 1e-3 * settings.force_tolerance;
        if balanced
            && (log.iterations == 0
                || linear_increment
                || last_correction <= settings.displacement_tolerance)
        {
            log.converged = true;
            return Ok(log);
        }
        if log.iterations == settings.max_iterations || !residual.is_finite() {
            return Ok(log);
        }
        let t = std::time::Instant::now();
        if symmetric {
            linear.factorize(system.matrix())?;
            log.factorization_seconds += t.elapsed().as_secs_f64();
            let t = std::time::Instant::now();
            linear.solve_in_place(&mut r);
            log.solve_seconds += t.elapsed().as_secs_f64();
        } else {
            // Inexact Newton (Eisenstat & Walker): solve only as accurately as the current
            // residual warrants, η_k = 1e-2 ‖r_k‖ (relative), which keeps quadratic convergence.
            let forcing = (1e-2 * residual).clamp(1e-12, 1e-3);
            log.krylov_iterations += linear.solve_unsymmetric(
                system.matrix(),
                system.preconditioner_matrix(),
                &mut r,
                forcing,
            )?;
            log.unsymmetric_solves += 1;
            log.solve_seconds += t.elapsed().as_secs_f64();
        }
        let before = norm(u);
        let step = if residual > LINE_SEARCH_ABOVE {
            let t = std::time::Instant::now();
            let current = residual * reference;
            let alpha = line_search(problem, dofs, system, u, &r, &ext, current);
            log.assembly_seconds += t.elapsed().as_secs_f64();
            alpha
        } else {
            dofs.add_free(&r, u);
            1.0
        };
        last_correction = step * norm(&r) / norm(u).max(before).max(f64::MIN_POSITIVE);
        log.corrections.push(last_correction);
        log.iterations += 1;
    }
}

/// Relative residual above which corrections are checked by a line search. Below it Newton is
/// in its quadratic phase and full steps are taken without the extra residual evaluation.
const LINE_SEARCH_ABOVE: f64 = 1e-3;

/// Backtracking line search along the Newton correction `du`: takes u + α du with the first
/// α ∈ {1, ½, ¼, ⅛, 1/16} that lowers the out-of-balance force ‖r‖ below `current`, or the
/// α with the smallest ‖r‖. Contact and friction make the residual piecewise smooth, and a
/// point flipping between stick and slip (or open and closed) can make full Newton steps
/// cycle; shortening the step breaks the cycle. Returns α; `u` holds u + α du.
fn line_search(
    problem: &mut impl Problem,
    dofs: &DofMap,
    system: &mut GlobalSystem,
    u: &mut [f64],
    du: &[f64],
    ext: &[f64],
    current: f64,
) -> f64 {
    let start = u.to_vec();
    let mut residual = vec![0.0; du.len()];
    let mut best = (f64::INFINITY, 1.0);
    let mut alpha = 1.0;
    for _ in 0..5 {
        u.copy_from_slice(&start);
        let scaled: Vec<f64> = du.iter().map(|d| alpha * d).collect();
        dofs.add_free(&scaled, u);
        system.clear(false);
        problem.assemble(u, system, false);
        dofs.gather_free(&system.internal_force, &mut residual);
        let value = norm(
            &residual
                .iter()
                .zip(ext)
                .map(|(fi, fe)| fe - fi)
                .collect::<Vec<_>>(),
        );
        if value < best.0 {
            best = (value, alpha);
        }
        if value < current {
            return alpha;
        }
        alpha *= 0.5;
    }
    u.copy_from_slice(&start);
    let scaled: Vec<f64> = du.iter().map(|d| best.1 * d).collect();
    dofs.add_free(&scaled, u);
    best.1
}
