//! Interface iterations: within one Newton iteration on the condensed path, the interface
//! law is solved to convergence against the bulk's linearisation before the bulk is
//! back-substituted.
//!
//! With the bulk linearised at u, K_B δ for its force change, and the interface elements
//! evaluated exactly, the bulk rows of the out-of-balance force vanish for
//! δ_B = K_BB⁻¹ (r_B − K_BI δ_I), and the interface rows become
//!
//!   R(δ_I) = g − S_c δ_I − [f_if(u + δ_I) − f_if(u)],   g = r_I − K_IB K_BB⁻¹ r_B,
//!
//! a system in the interface unknowns alone (S_c = K_II − K_IB K_BB⁻¹ K_BI). Its first Newton
//! step, (S_c + K_if(u)) Δ = g, is the plain Newton step of the whole model; the next ones
//! cost an evaluation of the interface elements and a dense LU of the interface system each,
//! not an assembly of the bodies nor a substitution through the bulk factor. The residual
//! after a step α Δ with the block K_if factored for it follows from the step itself,
//! (S_c + K_if) Δ = R giving S_c Δ = R − K_if Δ:
//!
//!   R(δ + α Δ) = (1 − α) R(δ) + α K_if Δ − [f_if(u + δ + α Δ) − f_if(u + δ)].
//!
//! A frictional interface's statuses (stick, slip, open) move by a few points per Newton
//! iteration, so the plain iteration converges about linearly while they settle (a punch's
//! first increment: residual ratio ~0.4 over seven iterations), each iteration paying for a
//! bulk assembly and a substitution; here the statuses settle inside one iteration. With a
//! linear bulk the model's increment is then solved (the iterates are those plain Newton
//! would reach, without the bulk's work between them); with a plastic bulk, the outer
//! iterations are left with the bulk's nonlinearity. Each step is taken with the Newton
//! loop's backtracking search, here on ‖R‖ (the first α ∈ {1, ½, … 1/16} that lowers it), so
//! that with a linear bulk the iterates are those of plain Newton with its line search; the
//! iterations stop when ‖R‖∞ is below the tolerance given, when a step leaves more than
//! [`SLOW_PROGRESS`] of ‖R‖ and the next would need a new LU (a block with the factored one's
//! bits keeps it: with the elastic contact matrix every step does), when no step lowers ‖R‖
//! (the first step then stays the full Newton step, which the Newton loop's line search
//! judges against the whole model), or after the limit.

use std::time::Instant;

use super::{Condensed, Newton, NewtonLog, Problem, max_abs, norm};
use crate::assembly::{AssemblyInput, DofMap, GlobalSystem};
use crate::contact::ContactAlgorithm;
use crate::solver::floor::SolverWork;

/// An interface step that leaves more than this fraction of ‖R‖ ends the iterations: they
/// stall (at round-off, or with statuses that flip back and forth), and a new LU would not
/// pay. Plain Newton iterations settling a stick–slip front reduce ‖R‖ to about 0.4 each.
const SLOW_PROGRESS: f64 = 0.9;

/// Step lengths an interface step tries, 1, ½, … 1/16, as the Newton loop's line search.
const LINE_SEARCH_STEPS: usize = 5;

/// The workspaces of the interface iterations, sized once for the model.
#[derive(Debug)]
pub(super) struct InterfaceIterations {
    /// The dof of each interface unknown (in the order of the interface block).
    dofs: Vec<usize>,
    /// Every dof the interface elements write a force to (prescribed ones included).
    written: Vec<usize>,
    /// The interface elements' forces over all dofs (zero outside `written`), swapped in for
    /// the system's while they are evaluated.
    force: Vec<f64>,
    /// The displacements the interface is evaluated at: u at the interface nodes' dofs (the
    /// only ones its elements read), with u + δ at the interface unknowns.
    u: Vec<f64>,
    /// Over the interface unknowns: u, δ, a trial δ + α Δ, the step Δ, K_if Δ, R(δ), a
    /// trial's R, and the interface force at u + δ and at a trial.
    u_start: Vec<f64>,
    delta: Vec<f64>,
    trial_delta: Vec<f64>,
    step: Vec<f64>,
    block_step: Vec<f64>,
    residual: Vec<f64>,
    trial_residual: Vec<f64>,
    force_at: Vec<f64>,
    trial_force: Vec<f64>,
}

impl InterfaceIterations {
    /// Workspaces for `dofs` (the dof of each interface unknown, in block order), the
    /// interface elements writing to `written`, over `dof_count` dofs.
    pub(super) fn new(dofs: Vec<usize>, written: Vec<usize>, dof_count: usize) -> Self {
        let n = dofs.len();
        Self {
            dofs,
            written,
            force: vec![0.0; dof_count],
            u: vec![0.0; dof_count],
            u_start: vec![0.0; n],
            delta: vec![0.0; n],
            trial_delta: vec![0.0; n],
            step: vec![0.0; n],
            block_step: vec![0.0; n],
            residual: vec![0.0; n],
            trial_residual: vec![0.0; n],
            force_at: vec![0.0; n],
            trial_force: vec![0.0; n],
        }
    }
}

/// What the interface iterations of one Newton iteration did.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct InterfaceIterationLog {
    /// Steps taken beyond the first (each after a new interface LU).
    pub(super) steps: usize,
    /// Those of them with an unsymmetric interface tangent.
    pub(super) unsymmetric_solves: usize,
    pub(super) evaluation_seconds: f64,
    pub(super) factorisation_seconds: f64,
}

impl Newton<'_> {
    /// The correction of a Newton iteration on the condensed path, with interface
    /// iterations ([`Self::solve_with_interface_iterations`] to R_l q̃, q̃ = `average`), its
    /// work and time entered in `log` and the run's tallies (the evaluations as assembly, the
    /// interface LUs as factorisation, the rest as the solve).
    pub(super) fn solve_iterating_interface(
        &mut self,
        problem: &mut impl Problem,
        u: &[f64],
        average: f64,
        log: &mut NewtonLog,
    ) {
        let t = Instant::now();
        let tolerance = self.settings.criteria.linear_residual;
        let inner = self.solve_with_interface_iterations(problem, u, tolerance, average);
        let inner_seconds = inner.evaluation_seconds + inner.factorisation_seconds;
        // The tally first: as with `solve_factored`, the phase's time (read after it) is
        // never below the floor's.
        self.work
            .solves
            .add(t.elapsed().as_secs_f64() - inner_seconds);
        log.assembly_seconds += inner.evaluation_seconds;
        log.factorization_seconds += inner.factorisation_seconds;
        log.solve_seconds += t.elapsed().as_secs_f64() - inner_seconds;
        log.interface_iterations += inner.steps;
        log.unsymmetric_solves += inner.unsymmetric_solves;
        self.work.interface_iterations += inner.steps;
        tracing::debug!(steps = inner.steps, "interface iterations");
    }

    /// Solves the tangent factored by [`Newton::factor`] for the correction (in
    /// `self.residual`, free dofs, in place) with the interface law iterated to
    /// convergence against the bulk's linearisation (module docs), until ‖R‖∞ is below
    /// `tolerance` times the average force q̃ = `average` (times ‖g‖∞ while q̃ is zero, at
    /// an unloaded start), while a step lowers ‖R‖ well, for at most
    /// [`NewtonSettings::interface_iterations`](super::NewtonSettings) steps; from the
    /// displacements `u` (all dofs), whose out-of-balance force the residual is.
    fn solve_with_interface_iterations(
        &mut self,
        problem: &mut impl Problem,
        u: &[f64],
        tolerance: f64,
        average: f64,
    ) -> InterfaceIterationLog {
        let mut log = InterfaceIterationLog::default();
        let limit = self.settings.interface_iterations;
        let mut at = Evaluation {
            dofs: self.dofs,
            algorithm: self.settings.contact_algorithm,
            system: &mut self.system,
            work: &mut self.work,
            seconds: 0.0,
        };
        let c = self.condensed.as_mut().expect("condensed path");
        c.solver.condense(&self.residual);
        let it = &mut c.iterations;
        // R(0) = g, and the first step Δ = (S_c + K_if(u))⁻¹ g: the plain Newton step.
        it.residual.copy_from_slice(c.solver.condensed_rhs());
        // The first increment's q̃ can be zero (an unloaded start): then g sets the scale.
        let scale = if average > 0.0 {
            average
        } else {
            max_abs(&it.residual)
        };
        let tolerance = tolerance * scale;
        it.step.copy_from_slice(&it.residual);
        c.solver.solve_interface(&mut it.step);
        // The interface elements read their nodes' dofs alone: only those of u are copied.
        for &dof in &it.written {
            it.u[dof] = u[dof];
        }
        for (s, &dof) in it.u_start.iter_mut().zip(&it.dofs) {
            *s = u[dof];
        }
        it.trial_delta.fill(0.0);
        at.interface(problem, c, false);
        let it = &mut c.iterations;
        std::mem::swap(&mut it.force_at, &mut it.trial_force);
        it.delta.fill(0.0);
        let mut residual_norm = norm(&it.residual);
        for k in 0.. {
            block_product(c);
            let (mut accepted, mut slow, mut symmetric) = (false, false, true);
            let mut alpha = 1.0;
            for _ in 0..LINE_SEARCH_STEPS {
                let it = &mut c.iterations;
                for ((t, d), s) in it.trial_delta.iter_mut().zip(&it.delta).zip(&it.step) {
                    *t = d + alpha * s;
                }
                symmetric = at.interface(problem, c, true);
                let it = &mut c.iterations;
                let trial_norm = trial_residual(it, alpha);
                if trial_norm < residual_norm {
                    std::mem::swap(&mut it.delta, &mut it.trial_delta);
                    std::mem::swap(&mut it.residual, &mut it.trial_residual);
                    std::mem::swap(&mut it.force_at, &mut it.trial_force);
                    slow = trial_norm > SLOW_PROGRESS * residual_norm;
                    residual_norm = trial_norm;
                    accepted = true;
                    break;
                }
                alpha *= 0.5;
            }
            let it = &mut c.iterations;
            if !accepted {
                if k == 0 {
                    // No step along the Newton direction lowers ‖R‖: that direction is the
                    // Newton iteration's own, for its line search to judge against the
                    // whole model.
                    it.delta.copy_from_slice(&it.step);
                }
                break;
            }
            // A block with the bits of the factored one (statuses and tangents unchanged, as
            // with the elastic contact matrix) keeps the LU: the next step costs an evaluation
            // and a solve, worth taking however slowly ‖R‖ falls.
            let t = Instant::now();
            let converged = max_abs(&it.residual) <= tolerance;
            let lu_holds = c.interface_lu_holds();
            if (slow && !lu_holds) || converged || log.steps == limit {
                break;
            }
            if lu_holds {
                at.work.kept_interface_factorisations.since(t);
            } else if c.solver.factor_interface(c.block.as_ref()).is_err() {
                // Singular at δ (e.g. a body held by the interface alone, which the step
                // opened): δ is the iterations' last word, the Newton loop judges it.
                c.interface_lu_current = false;
                break;
            } else {
                c.record_factored_block();
                at.work.interface_factorisations.since(t);
            }
            log.factorisation_seconds += t.elapsed().as_secs_f64();
            let it = &mut c.iterations;
            it.step.copy_from_slice(&it.residual);
            c.solver.solve_interface(&mut it.step);
            log.steps += 1;
            log.unsymmetric_solves += usize::from(!symmetric);
        }
        log.evaluation_seconds = at.seconds;
        c.solver.expand(&c.iterations.delta, &mut self.residual);
        log
    }
}

/// What an evaluation of the interface alone needs of the Newton solver.
struct Evaluation<'a> {
    dofs: &'a DofMap,
    algorithm: ContactAlgorithm,
    system: &'a mut GlobalSystem,
    work: &'a mut SolverWork,
    /// The time the evaluations took.
    seconds: f64,
}

impl Evaluation<'_> {
    /// Evaluates the interface elements at u + δ, δ = `trial_delta` at the interface
    /// unknowns: their force into `trial_force` and, if `tangent`, their tangent into the
    /// block (its element entries set, the rest left zero). The system's forces are left
    /// as they were. Returns whether the tangent is symmetric.
    fn interface(&mut self, problem: &mut impl Problem, c: &mut Condensed, tangent: bool) -> bool {
        let t = Instant::now();
        if tangent {
            c.clear_block();
        }
        let it = &mut c.iterations;
        for ((&dof, &u), &d) in it.dofs.iter().zip(&it.u_start).zip(&it.trial_delta) {
            it.u[dof] = u + d;
        }
        let system = &mut *self.system;
        std::mem::swap(&mut system.internal_force, &mut it.force);
        let input = AssemblyInput {
            dofs: self.dofs,
            u: &it.u,
            tangent,
            algorithm: self.algorithm,
        };
        let symmetric = problem.assemble_interface(system, &input, c.block.as_mut(), &c.map);
        let force = &mut system.internal_force;
        for (f, &dof) in it.trial_force.iter_mut().zip(&it.dofs) {
            *f = force[dof];
        }
        for &dof in &it.written {
            force[dof] = 0.0;
        }
        std::mem::swap(&mut system.internal_force, &mut it.force);
        let tally = if tangent {
            &mut self.work.interface_tangent_assemblies
        } else {
            &mut self.work.interface_force_assemblies
        };
        tally.since(t);
        self.seconds += t.elapsed().as_secs_f64();
        symmetric
    }
}

/// K_if Δ into `block_step`, over the block's element entries.
fn block_product(c: &mut Condensed) {
    let it = &mut c.iterations;
    let n = c.block.n;
    it.block_step.fill(0.0);
    for &k in &c.block_entries {
        let (i, j) = (k % n, k / n);
        it.block_step[i] += c.block.values[k] * it.step[j];
    }
}

/// R(δ + α Δ) = (1 − α) R(δ) + α K_if Δ − [f_if(u + δ + α Δ) − f_if(u + δ)] into
/// `trial_residual`; returns its Euclidean norm.
fn trial_residual(it: &mut InterfaceIterations, alpha: f64) -> f64 {
    for (k, r) in it.trial_residual.iter_mut().enumerate() {
        *r = (1.0 - alpha) * it.residual[k] + alpha * it.block_step[k]
            - (it.trial_force[k] - it.force_at[k]);
    }
    norm(&it.trial_residual)
}
