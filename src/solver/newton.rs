//! Newton-Raphson for one load increment (Buczkowski & Kleiber (1994), Eq. 32):
//! K_T(u_i) δu = Q − F(u_i), u_{i+1} = u_i + δu, until both the out-of-balance force and the
//! correction are small.
//!
//! Convergence is declared when ‖r‖ ≤ tol_f · max(‖f_ext‖, ‖f_int‖, ‖r₀‖, f_floor) over the
//! free dofs (‖f_int‖ over all dofs includes the reactions, so displacement-driven problems
//! have a meaningful reference; ‖r₀‖, the out-of-balance force at the start of the
//! increment, gives one when the solution is stress-free, e.g. a body lifted off a contact)
//! and the last correction satisfied ‖δu‖ ≤ tol_u · ‖u‖. As in Abaqus' "linear increment"
//! rule, a residual a thousand times below the force tolerance is accepted without the
//! correction check: a linear problem then needs one solve, not two.
//!
//! [`Newton`] owns the global system, the linear solver and every vector the loop needs, all
//! sized once for the model: an iteration allocates nothing, which keeps the many small
//! iterations of contact problems free of allocator traffic.

use crate::Result;
use crate::assembly::{AssemblyInput, DofMap, GlobalSystem, SparsityPattern};
use crate::contact::ContactAlgorithm;
use crate::solver::linear::CholeskySolver;

/// Settings of the Newton loop (public fields, as in dolfinx's `NewtonSolver`).
#[derive(Clone, Copy, Debug)]
pub struct NewtonSettings {
    pub max_iterations: usize,
    pub force_tolerance: f64,
    pub displacement_tolerance: f64,
    /// How often a failed increment is halved and retried.
    pub max_cutbacks: usize,
    /// Which interface tangent the iterations use (Buczkowski & Kleiber (1994), §2.4 and
    /// conclusions 2–3). A choice of the solution method, not of the model: every algorithm
    /// has the same residual, hence the same solution.
    pub contact_algorithm: ContactAlgorithm,
}

/// A problem the Newton loop can solve: it assembles internal forces and the tangent.
pub trait Problem {
    /// Assembles the internal force over all dofs (and the tangent over the free dofs if
    /// `input.tangent`) into the cleared `system` at the displacements `input.u`, updating
    /// trial states. Returns whether the tangent is symmetric.
    fn assemble(&mut self, system: &mut GlobalSystem, input: &AssemblyInput) -> bool;
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

/// Relative residual above which corrections are checked by a line search. Below it Newton is
/// in its quadratic phase and full steps are taken without the extra residual evaluation.
const LINE_SEARCH_ABOVE: f64 = 1e-3;

/// The Newton-Raphson solver of a model's increments, with its workspaces.
#[derive(Debug)]
pub struct Newton<'a> {
    settings: NewtonSettings,
    dofs: &'a DofMap,
    system: GlobalSystem,
    linear: CholeskySolver,
    /// Out-of-balance force over the free dofs; the linear solve turns it into the correction.
    residual: Vec<f64>,
    /// External forces over the free dofs.
    external: Vec<f64>,
    /// Line search: the displacements it starts from, and a trial step's out-of-balance force.
    start: Vec<f64>,
    trial_residual: Vec<f64>,
}

impl<'a> Newton<'a> {
    /// A solver for the dofs `dofs` whose matrices have the pattern `pattern`: orders and
    /// factors the pattern symbolically and allocates the system and all workspaces.
    pub fn new(
        settings: NewtonSettings,
        dofs: &'a DofMap,
        pattern: &SparsityPattern,
    ) -> Result<Self> {
        let linear = CholeskySolver::new(pattern)?;
        let free = dofs.free_count();
        Ok(Self {
            settings,
            dofs,
            system: GlobalSystem::new(pattern.clone(), dofs.dof_count()),
            linear,
            residual: vec![0.0; free],
            external: vec![0.0; free],
            start: vec![0.0; dofs.dof_count()],
            trial_residual: vec![0.0; free],
        })
    }

    /// The settings this solver was made with.
    pub fn settings(&self) -> &NewtonSettings {
        &self.settings
    }

    /// The system of the last assembly: its internal forces are those of the last solution.
    pub fn system(&self) -> &GlobalSystem {
        &self.system
    }

    /// The linear solver (for its statistics).
    pub fn linear(&self) -> &CholeskySolver {
        &self.linear
    }

    /// Solves one increment from the displacements in `u` (whose prescribed components
    /// already hold this increment's values) for the external forces `f_ext` (all dofs).
    /// `force_floor` is an absolute force level below which residuals count as zero (e.g.
    /// from earlier steps), for increments whose loads vanish.
    pub fn solve_increment(
        &mut self,
        problem: &mut impl Problem,
        u: &mut [f64],
        f_ext: &[f64],
        force_floor: f64,
    ) -> Result<NewtonLog> {
        let settings = self.settings;
        let dofs = self.dofs;
        // Sized for the longest increment, so that logging an iteration allocates nothing.
        let mut log = NewtonLog {
            residuals: Vec::with_capacity(settings.max_iterations + 1),
            corrections: Vec::with_capacity(settings.max_iterations),
            ..NewtonLog::default()
        };
        dofs.gather_free(f_ext, &mut self.external);
        let f_ext_norm = norm(f_ext);
        let mut last_correction = f64::INFINITY;
        let mut initial_residual = None;
        loop {
            let t = std::time::Instant::now();
            self.system.clear(true);
            let input = self.input(u, true);
            let symmetric = problem.assemble(&mut self.system, &input);
            log.assembly_seconds += t.elapsed().as_secs_f64();
            let r = &mut self.residual;
            out_of_balance(dofs, &self.system.internal_force, &self.external, r);
            let r0 = *initial_residual.get_or_insert(norm(r));
            let reference = f_ext_norm
                .max(norm(&self.system.internal_force))
                .max(r0)
                .max(force_floor)
                .max(f64::MIN_POSITIVE);
            let residual = norm(r) / reference;
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
                self.linear.factorize(self.system.matrix())?;
                log.factorization_seconds += t.elapsed().as_secs_f64();
                let t = std::time::Instant::now();
                self.linear.solve_in_place(r);
                log.solve_seconds += t.elapsed().as_secs_f64();
            } else {
                // Inexact Newton (Eisenstat & Walker): solve only as accurately as the current
                // residual warrants, η_k = 1e-2 ‖r_k‖ (relative), which keeps quadratic
                // convergence.
                let forcing = (1e-2 * residual).clamp(1e-12, 1e-3);
                log.krylov_iterations += self.linear.solve_unsymmetric(
                    self.system.matrix(),
                    self.system.preconditioner_matrix(),
                    r,
                    forcing,
                )?;
                log.unsymmetric_solves += 1;
                log.solve_seconds += t.elapsed().as_secs_f64();
            }
            let before = norm(u);
            let step = if residual > LINE_SEARCH_ABOVE {
                let t = std::time::Instant::now();
                let alpha = self.line_search(problem, u, residual * reference);
                log.assembly_seconds += t.elapsed().as_secs_f64();
                alpha
            } else {
                dofs.add_free(1.0, &self.residual, u);
                1.0
            };
            last_correction =
                step * norm(&self.residual) / norm(u).max(before).max(f64::MIN_POSITIVE);
            log.corrections.push(last_correction);
            log.iterations += 1;
        }
    }

    /// The assembly of this solver's dofs at `u`, with the tangent if `tangent`.
    fn input<'u>(&self, u: &'u [f64], tangent: bool) -> AssemblyInput<'u>
    where
        'a: 'u,
    {
        AssemblyInput {
            dofs: self.dofs,
            u,
            tangent,
            algorithm: self.settings.contact_algorithm,
        }
    }

    /// Backtracking line search along the Newton correction δu held in the residual: takes
    /// u + α δu with the first α ∈ {1, ½, ¼, ⅛, 1/16} that lowers the out-of-balance force
    /// ‖r‖ below `current`, or the α with the smallest ‖r‖. Contact and friction make the
    /// residual piecewise smooth, and a point flipping between stick and slip (or open and
    /// closed) can make full Newton steps cycle; shortening the step breaks the cycle.
    /// Returns α; `u` holds u + α δu.
    fn line_search(&mut self, problem: &mut impl Problem, u: &mut [f64], current: f64) -> f64 {
        self.start.copy_from_slice(u);
        let mut best = (f64::INFINITY, 1.0);
        let mut alpha = 1.0;
        for _ in 0..5 {
            u.copy_from_slice(&self.start);
            self.dofs.add_free(alpha, &self.residual, u);
            self.system.clear(false);
            let input = self.input(u, false);
            problem.assemble(&mut self.system, &input);
            let trial = &mut self.trial_residual;
            out_of_balance(
                self.dofs,
                &self.system.internal_force,
                &self.external,
                trial,
            );
            let value = norm(trial);
            if value < best.0 {
                best = (value, alpha);
            }
            if value < current {
                return alpha;
            }
            alpha *= 0.5;
        }
        u.copy_from_slice(&self.start);
        self.dofs.add_free(best.1, &self.residual, u);
        best.1
    }
}

/// The out-of-balance force Q − F over the free dofs, from the external forces `external`
/// (free dofs) and the internal forces `internal` (all dofs), into `out`.
fn out_of_balance(dofs: &DofMap, internal: &[f64], external: &[f64], out: &mut [f64]) {
    dofs.gather_free(internal, out);
    for (ri, ei) in out.iter_mut().zip(external) {
        *ri = ei - *ri;
    }
}
