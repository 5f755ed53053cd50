//! The iterations of an arc-length increment (Riks–Crisfield, cylindrical: Crisfield 1981),
//! on the [`Newton`] solver's assembly, linear solves and workspaces. The load is λ f_ref and
//! the increment is constrained to a displacement "arc" ‖Δu‖ = Δl over the free dofs (no
//! load term), so the load factor λ is an unknown and a limit point can be passed.
//!
//! [`Newton::arc_tangent`] is the predictor: the tangent at the converged state, factored,
//! gives δu_f = K⁻¹ f_ref, and the increment starts along it with Δλ = ±Δl / ‖δu_f‖, in the
//! direction of the previous increment (Feng's criterion; forward at first).
//! [`Newton::solve_arc_increment`] corrects it: per iteration one tangent is assembled and
//! factored and two systems are solved with it (K δu_r = r, K δu_f = f_ref); δλ is the root
//! of the quadratic constraint ‖Δu + δu_r + δλ δu_f‖² = Δl² whose new increment points
//! closer to the current one. The tangent must be symmetric.
//!
//! Convergence is judged by the relative norms of [`super::NewtonSettings`] (the engineering
//! criteria's force average has no meaning while the load moves with λ): ‖r‖ ≤ tol_f ·
//! max(|λ| ‖f_ref‖, ‖f_int‖) and the last correction ‖δu‖/‖u‖ ≤ tol_u, or a residual
//! 1000 × below tol_f; the first evaluation (the predicted state) needs the latter.

use std::time::Instant;

use super::{Newton, NewtonLog, Problem, norm, out_of_balance, solve_factored};
use crate::error::ArcFailure;

/// The workspaces of arc-length increments, over the free dofs, made once per run.
#[derive(Debug)]
pub(super) struct ArcWork {
    /// The reference load f_ref.
    reference: Vec<f64>,
    /// δu_f = K⁻¹ f_ref at the last factored tangent.
    load_response: Vec<f64>,
    /// Δu of the increment so far.
    delta: Vec<f64>,
    /// Δu + δu_r of the present iteration.
    corrected: Vec<f64>,
}

/// An arc-length increment to solve.
#[derive(Clone, Copy, Debug)]
pub struct ArcIncrement<'a> {
    /// λ of the converged state it starts from.
    pub load_factor: f64,
    /// Its arc length Δl.
    pub radius: f64,
    /// Δu of the last converged increment over the free dofs (empty before the first).
    pub previous: &'a [f64],
}

/// A converged arc-length increment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArcConverged {
    /// Its load-factor change Δλ.
    pub load_change: f64,
    /// The corrector's evaluations (one more than its corrections, which the log counts).
    pub evaluations: usize,
}

impl Newton<'_> {
    /// Sets the reference load f_ref (all dofs) of arc-length increments and makes their
    /// workspaces. Returns ‖f_ref‖ over the free dofs.
    pub fn set_arc_reference(&mut self, reference: &[f64]) -> f64 {
        let free = self.dofs.free_count();
        let mut work = ArcWork {
            reference: vec![0.0; free],
            load_response: vec![0.0; free],
            delta: vec![0.0; free],
            corrected: vec![0.0; free],
        };
        self.dofs.gather_free(reference, &mut work.reference);
        let size = norm(&work.reference);
        self.arc = Some(work);
        size
    }

    /// The predictor of an arc-length increment from the converged displacements `u`:
    /// assembles and factors the tangent there and solves K δu_f = f_ref. Returns ‖δu_f‖
    /// (the first increment's arc is set from it).
    pub fn arc_tangent(
        &mut self,
        problem: &mut impl Problem,
        u: &[f64],
        log: &mut NewtonLog,
    ) -> Result<f64, ArcFailure> {
        log.factorization_seconds += self.begin_increment(problem)?;
        log.assembly_seconds += self.update_thermal_force(problem);
        self.increment_start.copy_from_slice(u);
        self.evaluate_symmetric(problem, u, log)?;
        self.factor(log)?;
        let work = self
            .arc
            .as_mut()
            .expect("set_arc_reference before arc_tangent");
        let t = Instant::now();
        work.load_response.copy_from_slice(&work.reference);
        solve_factored(
            &mut self.condensed,
            &mut self.linear,
            &mut work.load_response,
            &mut self.work,
        );
        log.solve_seconds += t.elapsed().as_secs_f64();
        Ok(norm(&work.load_response))
    }

    /// Solves the arc-length `increment` after its predictor ([`Self::arc_tangent`]), from
    /// the converged displacements the predictor was given; `u` holds the last iterate.
    pub fn solve_arc_increment(
        &mut self,
        problem: &mut impl Problem,
        u: &mut [f64],
        increment: &ArcIncrement,
        log: &mut NewtonLog,
    ) -> Result<ArcConverged, ArcFailure> {
        let mut work = self
            .arc
            .take()
            .expect("set_arc_reference before solve_arc_increment");
        let outcome = self.correct(problem, u, increment, &mut work, log);
        self.arc = Some(work);
        outcome
    }

    /// The corrector of [`Self::solve_arc_increment`] on the workspaces `work`.
    fn correct(
        &mut self,
        problem: &mut impl Problem,
        u: &mut [f64],
        increment: &ArcIncrement,
        work: &mut ArcWork,
        log: &mut NewtonLog,
    ) -> Result<ArcConverged, ArcFailure> {
        let settings = self.settings;
        let dofs = self.dofs;
        let radius = increment.radius;
        let along = dot(increment.previous, &work.load_response);
        let sign = if along < 0.0 { -1.0 } else { 1.0 };
        let mut load_change = sign * radius / norm(&work.load_response);
        for (d, f) in work.delta.iter_mut().zip(&work.load_response) {
            *d = load_change * f;
        }
        let reference_size = norm(&work.reference);
        for iteration in 1..=settings.max_iterations {
            u.copy_from_slice(&self.increment_start);
            dofs.add_free(1.0, &work.delta, u);
            self.evaluate_symmetric(problem, u, log)?;
            let load_factor = increment.load_factor + load_change;
            for (e, f) in self.external.iter_mut().zip(&work.reference) {
                *e = load_factor * f;
            }
            let r = &mut self.residual;
            out_of_balance(dofs, &self.system.internal_force, &self.external, r);
            let reference = (load_factor.abs() * reference_size)
                .max(norm(&self.system.internal_force))
                .max(f64::MIN_POSITIVE);
            let residual = norm(r) / reference;
            log.residuals.push(residual);
            self.check_chord_contraction(&log.residuals);
            if !residual.is_finite() {
                return Err(ArcFailure::NotFinite);
            }
            let correction = log.corrections.last().copied().unwrap_or(f64::INFINITY);
            if settings.relative_norms_met(residual, false, correction) {
                return Ok(ArcConverged {
                    load_change,
                    evaluations: iteration,
                });
            }
            self.factor(log)?;
            let t = Instant::now();
            work.load_response.copy_from_slice(&work.reference);
            solve_factored(
                &mut self.condensed,
                &mut self.linear,
                &mut self.residual,
                &mut self.work,
            );
            solve_factored(
                &mut self.condensed,
                &mut self.linear,
                &mut work.load_response,
                &mut self.work,
            );
            log.solve_seconds += t.elapsed().as_secs_f64();
            let d_lambda = constraint_root(work, &self.residual, radius)?;
            load_change += d_lambda;
            let mut step_norm = 0.0;
            for ((d, r), f) in work
                .delta
                .iter_mut()
                .zip(&self.residual)
                .zip(&work.load_response)
            {
                let s = r + d_lambda * f;
                *d += s;
                step_norm += s * s;
            }
            let u_norm = norm(u).max(f64::MIN_POSITIVE);
            log.corrections.push(step_norm.sqrt() / u_norm);
            log.iterations = iteration;
        }
        Err(ArcFailure::NoConvergence {
            iterations: settings.max_iterations,
        })
    }

    /// Assembles the internal force and the tangent at `u` (always evaluating the bulk's
    /// elements, whose states the increment commits: for their states alone where the
    /// bulk's force is K_c u); an unsymmetric tangent is refused.
    fn evaluate_symmetric(
        &mut self,
        problem: &mut impl Problem,
        u: &[f64],
        log: &mut NewtonLog,
    ) -> Result<(), ArcFailure> {
        let t = Instant::now();
        let symmetric = self.evaluate(problem, u, true, true);
        log.assembly_seconds += t.elapsed().as_secs_f64();
        if symmetric {
            Ok(())
        } else {
            Err(ArcFailure::UnsymmetricTangent)
        }
    }
}

/// The root δλ of ‖Δu + δu_r + δλ δu_f‖² = Δl² (Δu in `work.delta`, δu_f in
/// `work.load_response`, δu_r in `correction`) whose new increment points closer to the
/// current one; `work.corrected` receives Δu + δu_r.
fn constraint_root(work: &mut ArcWork, correction: &[f64], radius: f64) -> Result<f64, ArcFailure> {
    for ((w, d), r) in work.corrected.iter_mut().zip(&work.delta).zip(correction) {
        *w = d + r;
    }
    let (w, f) = (&work.corrected, &work.load_response);
    let a = dot(f, f);
    let b = 2.0 * dot(f, w);
    let c = dot(w, w) - radius * radius;
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 || a == 0.0 {
        return Err(ArcFailure::NoRealRoot);
    }
    let roots = [
        (-b + disc.sqrt()) / (2.0 * a),
        (-b - disc.sqrt()) / (2.0 * a),
    ];
    let score = |x: f64| {
        w.iter()
            .zip(f)
            .zip(&work.delta)
            .map(|((wi, fi), di)| (wi + x * fi) * di)
            .sum::<f64>()
    };
    Ok(if score(roots[0]) >= score(roots[1]) {
        roots[0]
    } else {
        roots[1]
    })
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
