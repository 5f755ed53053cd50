//! Arc-length (Riks–Crisfield, cylindrical) control of the load factor:
//! `[steps] control = "arc_length"`. The load is λ f_ref (f_ref: the case's loads at factor 1)
//! and each increment is constrained to a displacement "arc" ‖Δu‖ = Δl (Crisfield 1981,
//! cylindrical: no load term), so the load factor λ is an unknown and the path can be
//! followed up to a limit point, where load control fails.
//!
//! Per iteration one tangent is assembled and factorised and two systems are solved with it
//! (K δu_r = r, K δu_f = f_ref); δλ is the root of the quadratic constraint
//! ‖Δu + δu_r + δλ δu_f‖² = Δl² closer to the previous direction. Converged increments are
//! handed to the output as steps 1, 2, ... with their λ. The arc grows or shrinks with the
//! iteration count; a failed increment (no convergence, a complex root, a tangent that is not
//! positive definite, an implausible increment) is retried with half the arc. The run ends
//! normally at `max_load_factor`, after `max_increments`, when the path returns to λ ≤ 0, or
//! when the arc falls below
//! `min_arc_length` (the path cannot be followed further: for a perfectly plastic structure,
//! the plateau of the limit load); the largest λ reached is logged.

use crate::assembly::{AssemblyInput, GlobalSystem};
use crate::model::timeline::Frame;
use crate::model::{ArcLength, Model};
use crate::solver::energy;
use crate::solver::linear::CholeskySolver;
use crate::solver::newton::{NewtonLog, NewtonSettings, Problem, norm};
use crate::solver::stepping::{
    RunStatistics, Solution, StepResult, distance, implausible_increment,
};
use crate::{Error, Result};

/// Iterations per increment the arc length is adapted to.
const DESIRED_ITERATIONS: f64 = 5.0;

/// Runs the arc-length stepping of `model` (see the module docs), calling `on_step` after each
/// converged increment.
pub fn run_arc_length(
    model: &Model,
    settings: &NewtonSettings,
    arc: &ArcLength,
    mut on_step: impl FnMut(&StepResult) -> Result<f64>,
) -> Result<(Solution, RunStatistics)> {
    let dofs = &model.dofs;
    let free = dofs.free_count();
    let n = dofs.dof_count();
    let mut stats = RunStatistics::default();
    let mut linear = CholeskySolver::new(&model.pattern)?;
    stats.symbolic_seconds = linear.symbolic_seconds();
    stats.factor_nnz = linear.factor_nnz();
    let mut system = GlobalSystem::new(model.pattern.clone(), n);
    let mut solution = Solution::new(model);
    // The reference load over all dofs and over the free ones.
    let mut f_ref_full = vec![0.0; n];
    for &(dof, value, _) in &model.nodal_loads {
        f_ref_full[dof] += value;
    }
    let mut f_ref = vec![0.0; free];
    dofs.gather_free(&f_ref_full, &mut f_ref);
    if norm(&f_ref) == 0.0 {
        return Err(Error::ArcLength(
            "[steps] control = \"arc_length\" needs a non-zero load (pressure, traction or force)"
                .into(),
        ));
    }
    let (mut u_c, mut lambda) = (solution.u.clone(), 0.0_f64);
    let mut previous = vec![0.0; free]; // Δu of the last converged increment (free dofs)
    let (mut du_r, mut du_f, mut r) = (vec![0.0; free], vec![0.0; free], vec![0.0; free]);
    let mut delta = vec![0.0; free];
    let mut arc_length: Option<f64> = None;
    let (mut min_arc, mut max_arc) = (0.0, f64::INFINITY);
    let mut lambda_max: f64 = 0.0;
    let mut step = 0;
    let mut f_ext = vec![0.0; n];
    let mut stop = "max_increments reached";
    while step < arc.max_increments {
        // --- predictor: the tangent at the converged state ---------------------------------
        solution.u.copy_from_slice(&u_c);
        let mut log = NewtonLog::default();
        let outcome = (|| -> std::result::Result<(f64, usize), String> {
            assemble(model, settings, &mut solution, &mut system, &mut log)?;
            factorize_and_solve(&mut linear, &system, &mut [&mut du_f], &[&f_ref], &mut log)?;
            let dl = *arc_length.get_or_insert_with(|| {
                let l = arc.initial_increment * norm(&du_f);
                min_arc = arc.min_arc_length * l;
                max_arc = arc.max_arc_length * l;
                l
            });
            // Direction: along the previous increment (Feng's criterion), forward at first.
            let along: f64 = previous.iter().zip(&du_f).map(|(a, b)| a * b).sum();
            let sign = if along < 0.0 { -1.0 } else { 1.0 };
            let mut d_lambda = sign * dl / norm(&du_f);
            for (d, f) in delta.iter_mut().zip(&du_f) {
                *d = d_lambda * f;
            }
            // --- corrector --------------------------------------------------------------
            for iteration in 1..=settings.max_iterations {
                solution.u.copy_from_slice(&u_c);
                dofs.add_free(1.0, &delta, &mut solution.u);
                assemble(model, settings, &mut solution, &mut system, &mut log)?;
                let lam = lambda + d_lambda;
                dofs.gather_free(&system.internal_force, &mut r);
                for (ri, fi) in r.iter_mut().zip(&f_ref) {
                    *ri = lam * fi - *ri;
                }
                let reference = (lam.abs() * norm(&f_ref))
                    .max(norm(&system.internal_force))
                    .max(f64::MIN_POSITIVE);
                let residual = norm(&r) / reference;
                log.residuals.push(residual);
                if !residual.is_finite() {
                    return Err("the residual is not finite".into());
                }
                let converged_force = residual <= settings.force_tolerance;
                let correction = log.corrections.last().copied().unwrap_or(f64::INFINITY);
                if converged_force
                    && (iteration > 1 && correction <= settings.displacement_tolerance
                        || residual <= 1e-3 * settings.force_tolerance)
                {
                    return Ok((d_lambda, iteration));
                }
                factorize_and_solve(
                    &mut linear,
                    &system,
                    &mut [&mut du_r, &mut du_f],
                    &[&r, &f_ref],
                    &mut log,
                )?;
                // ‖Δu + δu_r + δλ δu_f‖² = Δl²
                let w: Vec<f64> = delta.iter().zip(&du_r).map(|(a, b)| a + b).collect();
                let a = dot(&du_f, &du_f);
                let b = 2.0 * dot(&du_f, &w);
                let c = dot(&w, &w) - dl * dl;
                let disc = b * b - 4.0 * a * c;
                if disc < 0.0 || a == 0.0 {
                    return Err("the arc-length constraint has no real root".into());
                }
                let roots = [
                    (-b + disc.sqrt()) / (2.0 * a),
                    (-b - disc.sqrt()) / (2.0 * a),
                ];
                // The root whose new increment points closer to the current one.
                let score = |x: f64| {
                    w.iter()
                        .zip(&du_f)
                        .zip(&delta)
                        .map(|((wi, fi), di)| (wi + x * fi) * di)
                        .sum::<f64>()
                };
                let dlam = if score(roots[0]) >= score(roots[1]) {
                    roots[0]
                } else {
                    roots[1]
                };
                d_lambda += dlam;
                let mut step_norm = 0.0;
                for ((d, ri), fi) in delta.iter_mut().zip(&du_r).zip(&du_f) {
                    let s = ri + dlam * fi;
                    *d += s;
                    step_norm += s * s;
                }
                let u_norm = norm(&solution.u).max(f64::MIN_POSITIVE);
                log.corrections.push(step_norm.sqrt() / u_norm);
                log.iterations = iteration;
            }
            Err(format!(
                "no convergence in {} iterations",
                settings.max_iterations
            ))
        })();
        let accepted = match outcome {
            Ok((d_lambda, iterations)) => match implausible_increment(model, &solution, &u_c) {
                Some(reason) => Err(reason),
                None => Ok((d_lambda, iterations)),
            },
            Err(e) => Err(e),
        };
        log.converged = accepted.is_ok();
        stats.iterations += log.iterations;
        stats.assembly_seconds += log.assembly_seconds;
        stats.factorization_seconds += log.factorization_seconds;
        stats.solve_seconds += log.solve_seconds;
        let dl = arc_length.unwrap_or(0.0);
        match accepted {
            Ok((d_lambda, iterations)) => {
                step += 1;
                stats.increments += 1;
                stats.steps += 1;
                lambda += d_lambda;
                lambda_max = lambda_max.max(lambda);
                dofs.gather_free(&solution.u, &mut previous);
                let mut old = vec![0.0; free];
                dofs.gather_free(&u_c, &mut old);
                for (p, o) in previous.iter_mut().zip(&old) {
                    *p -= o;
                }
                tracing::info!(
                    "arc-length increment {step}: load factor {lambda:.6}, arc {dl:.3e}, \
                     {iterations} iterations, ‖Δu‖ {:.3e}",
                    distance(&solution.u, &u_c)
                );
                for (f, r) in f_ext.iter_mut().zip(&f_ref_full) {
                    *f = lambda * r;
                }
                energy::record(model, &mut solution, &u_c, &f_ext, &system.internal_force);
                solution.commit();
                u_c.copy_from_slice(&solution.u);
                stats.last_residual = *log.residuals.last().unwrap_or(&0.0);
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
                    internal_force: &system.internal_force,
                    external_force: &f_ext,
                };
                stats.output_seconds += on_step(&result)?;
                let factor = (DESIRED_ITERATIONS / iterations.max(1) as f64)
                    .sqrt()
                    .clamp(0.5, 2.0);
                arc_length = Some((dl * factor).clamp(min_arc, max_arc));
                if lambda >= arc.max_load_factor {
                    stop = "max_load_factor reached";
                    break;
                }
                if lambda_max > 0.0 && lambda <= 0.0 {
                    stop = "the path returned to zero load";
                    break;
                }
            }
            Err(reason) => {
                stats.cutbacks += 1;
                tracing::info!("arc-length increment failed ({reason}); halving the arc");
                if dl * 0.5 < min_arc || arc_length.is_none() {
                    if step == 0 {
                        return Err(Error::ArcLength(format!(
                            "the first increment failed: {reason}"
                        )));
                    }
                    stop = "the arc fell below min_arc_length (limit point: the path cannot be \
                            followed further)";
                    break;
                }
                arc_length = Some(dl * 0.5);
            }
        }
    }
    tracing::info!(
        "arc-length control stopped after {step} increments ({stop}): largest load factor \
         {lambda_max:.6}, last {lambda:.6}"
    );
    // Leave the converged state (not a failed attempt's) in the solution.
    solution.u.copy_from_slice(&u_c);
    solution.trial.copy_from_slice(&solution.committed);
    solution
        .interface_trial
        .copy_from_slice(&solution.interface_committed);
    Ok((solution, stats))
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Assembles internal force and tangent at `solution.u`; an unsymmetric tangent (friction)
/// is refused.
fn assemble(
    model: &Model,
    settings: &NewtonSettings,
    solution: &mut Solution,
    system: &mut GlobalSystem,
    log: &mut NewtonLog,
) -> std::result::Result<(), String> {
    let t = std::time::Instant::now();
    system.clear(true);
    let (u, mut problem) = solution.split(model);
    let input = AssemblyInput {
        dofs: &model.dofs,
        u,
        tangent: true,
        algorithm: settings.contact_algorithm,
    };
    let symmetric = problem.assemble(system, &input);
    log.assembly_seconds += t.elapsed().as_secs_f64();
    if symmetric {
        Ok(())
    } else {
        Err("arc-length control needs a symmetric tangent (no slipping friction)".into())
    }
}

/// Factorises the tangent once and solves it for each right-hand side.
fn factorize_and_solve(
    linear: &mut CholeskySolver,
    system: &GlobalSystem,
    out: &mut [&mut Vec<f64>],
    rhs: &[&Vec<f64>],
    log: &mut NewtonLog,
) -> std::result::Result<(), String> {
    let t = std::time::Instant::now();
    linear
        .factorize(system.matrix())
        .map_err(|e| e.to_string())?;
    log.factorization_seconds += t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    for (x, b) in out.iter_mut().zip(rhs) {
        x.copy_from_slice(b);
        linear.solve_in_place(x);
    }
    log.solve_seconds += t.elapsed().as_secs_f64();
    Ok(())
}
