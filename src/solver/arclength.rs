//! Arc-length (Riks–Crisfield, cylindrical) control of the load factor:
//! `[steps] control = "arc_length"`. The load is λ f_ref (f_ref: the case's loads at factor 1)
//! and each increment is constrained to a displacement "arc" ‖Δu‖ = Δl (Crisfield 1981,
//! cylindrical: no load term), so the load factor λ is an unknown and the path can be
//! followed up to a limit point, where load control fails. The increments are solved by the
//! run's [`Newton`] solver ([`crate::solver::newton::arc`]); this driver chooses their arcs
//! and hands them to the output.
//!
//! Converged increments are handed to the output as steps 1, 2, ... with their λ, and with
//! the loop state ([`ArcState`] in [`LoopState::arc`]) from which a restart record continues
//! them bit for bit. The arc grows or shrinks with the iteration count; a failed increment
//! (no convergence, a complex root, a tangent that is not symmetric or not positive definite,
//! an implausible increment) is retried with half the arc. The run ends normally at
//! `max_load_factor`, after `max_increments`, when the path returns to λ ≤ 0, or when the arc
//! falls below `min_arc_length` (the path cannot be followed further: for a perfectly plastic
//! structure, the plateau of the limit load); the largest λ reached is logged.

use crate::error::ArcFailure;
use crate::model::timeline::Frame;
use crate::model::{ArcLength, Model};
use crate::solver::diagnosis::implausible_increment;
use crate::solver::energy::BodySums;
use crate::solver::newton::{
    ArcConverged, ArcIncrement, Newton, NewtonLog, NewtonSettings, distance,
};
use crate::solver::state::{
    ArcState, LoopState, Observer, Progress, Resume, RunStatistics, Solution, StepResult,
};
use crate::solver::stepping::increment_sums;
use crate::solver::strain_bound::StrainBound;
use crate::{Error, Result};

/// Iterations per increment the arc length is adapted to.
const DESIRED_ITERATIONS: f64 = 5.0;

/// Runs the arc-length stepping of `model` (see the module docs) from `resume` when given,
/// reporting each converged increment to `observer` as a step.
pub fn run_arc_length(
    model: &Model,
    settings: &NewtonSettings,
    arc: &ArcLength,
    resume: Option<Resume>,
    observer: &mut impl Observer,
) -> Result<(Solution, RunStatistics)> {
    let dofs = &model.dofs;
    let mut newton = Newton::new(*settings, dofs, &model.pattern)?;
    // The reference load over all dofs.
    let mut reference = vec![0.0; dofs.dof_count()];
    for &(dof, value, _) in &model.nodal_loads {
        reference[dof] += value;
    }
    if newton.set_arc_reference(&reference) == 0.0 {
        return Err(Error::ArcLengthNoLoad);
    }
    let resumed = resume.is_some();
    // Arc-length control has its own predictor (along the path's tangent).
    let Resume {
        mut state,
        mut stats,
        mut solution,
        last_increment: _,
    } = resume.unwrap_or_else(|| Resume::start(model));
    // A record of this case always holds the arc state (a record of another case is refused).
    let mut path = state.arc.take().unwrap_or_else(ArcState::start);
    solution.reset_trial();
    // Every arc-length increment evaluates the bulk's elements: only a resumed run needs
    // a start (for the continuum states its record may have left out).
    if resumed {
        stats.add_work(&crate::solver::stepping::start_newton(
            model,
            &mut newton,
            &mut solution,
            true,
        )?);
    }
    let mut converged_u = solution.u.clone();
    let mut f_ext = vec![0.0; dofs.dof_count()];
    let mut bound = None;
    let stop = loop {
        if path.load_factor >= arc.max_load_factor {
            break "max_load_factor reached";
        }
        if path.largest_load_factor > 0.0 && path.load_factor <= 0.0 {
            break "the path returned to zero load";
        }
        if state.step > arc.max_increments {
            break "max_increments reached";
        }
        let step = state.step;
        solution.u.copy_from_slice(&converged_u);
        let mut log = NewtonLog::sized(settings.max_iterations);
        let outcome = attempt(
            model,
            arc,
            &mut newton,
            &mut solution,
            Converged {
                u: &converged_u,
                bound: &mut bound,
            },
            &mut path,
            &mut log,
        );
        log.converged = outcome.is_ok();
        stats.add_work(&log);
        let (radius, converged, scan) = match outcome {
            Ok(converged) => converged,
            Err(reason) => {
                stats.cutbacks += 1;
                tracing::info!("arc-length increment failed ({reason}); halving the arc");
                let halved = path.radius.map(|r| r * 0.5);
                if halved.is_none_or(|r| r < path.min_radius) {
                    if step == 1 {
                        return Err(Error::ArcLengthStart(reason));
                    }
                    break "the arc fell below min_arc_length (limit point: the path cannot be \
                           followed further)";
                }
                path.radius = halved;
                continue;
            }
        };
        stats.increments += 1;
        stats.work.increments += 1;
        stats.steps += 1;
        path.load_factor += converged.load_change;
        path.largest_load_factor = path.largest_load_factor.max(path.load_factor);
        record_increment(
            model,
            &solution.u,
            &converged_u,
            &mut path.previous_increment,
        );
        let lambda = path.load_factor;
        tracing::info!(
            "arc-length increment {step}: load factor {lambda:.6}, arc {radius:.3e}, \
             {} iterations, ‖Δu‖ {:.3e}",
            converged.evaluations,
            distance(&solution.u, &converged_u)
        );
        for (f, r) in f_ext.iter_mut().zip(&reference) {
            *f = lambda * r;
        }
        let internal_force = newton.system().internal_force.as_slice();
        solution.record_energy(model, &converged_u, &f_ext, internal_force, scan);
        solution.commit();
        converged_u.copy_from_slice(&solution.u);
        stats.last_residual = *log.residuals.last().unwrap_or(&0.0);
        path.radius = Some(next_radius(radius, &converged, &path));
        // One analysis step, its time the load factor's progress to its bound.
        let frame = Frame {
            analysis_step: 1,
            cycle: 1,
            cycles: 1.0,
            step_time: (lambda / arc.max_load_factor).clamp(0.0, 1.0),
            cycle_end: false,
        };
        let result = StepResult {
            frame,
            step,
            load_factor: lambda,
            newton: log,
            increments: 1,
            cutbacks: 0,
            solution: &solution,
            internal_force,
            external_force: &f_ext,
        };
        state = state.next_step(step);
        let progress = Progress {
            state: LoopState {
                arc: Some(path.clone()),
                ..state.clone()
            },
            stats: &stats,
            solution: &solution,
            last_increment: None,
        };
        stats.add_output(observer.step(&result, &progress)?, true);
    };
    tracing::info!(
        "arc-length control stopped after {} increments ({stop}): largest load factor \
         {:.6}, last {:.6}",
        state.step - 1,
        path.largest_load_factor,
        path.load_factor
    );
    // Leave the converged state (not a failed attempt's) in the solution; point states that
    // follow the displacements are kept once, so a failed attempt's are made again.
    let attempted = solution.u != converged_u;
    solution.u.copy_from_slice(&converged_u);
    solution.reset_trial();
    if attempted && solution.states_follow_displacements {
        let (u, mut problem) = solution.split(model);
        newton.states_at(&mut problem, u);
    }
    stats.symbolic_seconds = newton.symbolic_seconds();
    stats.factor_nnz = newton.linear().factor_nnz();
    stats.work.solver = *newton.work();
    Ok((solution, stats))
}

/// The converged state an attempt starts from: its displacements, and the bound on the
/// strain increment from them ([`increment_sums`]; made at the first increment).
struct Converged<'a> {
    u: &'a [f64],
    bound: &'a mut Option<StrainBound>,
}

/// One attempt at the next increment from the converged displacements `start` (also in
/// `solution.u`): the predictor's tangent, the arc (the first increment's is set from that
/// tangent), the corrector, and the plausibility of the result. Returns the arc with the
/// converged increment and its pass over the point states (for the energy ledger).
fn attempt(
    model: &Model,
    arc: &ArcLength,
    newton: &mut Newton,
    solution: &mut Solution,
    start: Converged,
    path: &mut ArcState,
    log: &mut NewtonLog,
) -> std::result::Result<(f64, ArcConverged, BodySums), ArcFailure> {
    let (u, mut problem) = solution.split(model);
    let tangent = newton.arc_tangent(&mut problem, u, log)?;
    let radius = match path.radius {
        Some(radius) => radius,
        None => {
            let first = arc.initial_increment * tangent;
            path.min_radius = arc.min_arc_length * first;
            path.max_radius = arc.max_arc_length * first;
            path.radius = Some(first);
            first
        }
    };
    let increment = ArcIncrement {
        load_factor: path.load_factor,
        radius,
        previous: &path.previous_increment,
    };
    let converged = newton.solve_arc_increment(&mut problem, u, &increment, log)?;
    let scan = increment_sums(model, newton, solution, start.u, start.bound);
    match implausible_increment(model, solution, start.u, scan.strain_increment) {
        Some(reason) => Err(ArcFailure::Implausible(reason)),
        None => Ok((radius, converged, scan)),
    }
}

/// Stores Δu = `u` − `converged_u` over the free dofs in `previous` (sized at the first).
fn record_increment(model: &Model, u: &[f64], converged_u: &[f64], previous: &mut Vec<f64>) {
    let dofs = &model.dofs;
    previous.resize(dofs.free_count(), 0.0);
    for (dof, (a, b)) in u.iter().zip(converged_u).enumerate() {
        if let Some(eq) = dofs.equation(dof) {
            previous[eq] = a - b;
        }
    }
}

/// The arc after a converged increment of arc `radius`: scaled by √(desired / actual
/// iterations) within [½, 2], and kept within the run's bounds.
fn next_radius(radius: f64, converged: &ArcConverged, path: &ArcState) -> f64 {
    let factor = (DESIRED_ITERATIONS / converged.evaluations.max(1) as f64)
        .sqrt()
        .clamp(0.5, 2.0);
    (radius * factor).clamp(path.min_radius, path.max_radius)
}
