//! The fit's driver ([`Fit::run`]): Levenberg–Marquardt from every start, the best
//! minimum's statistics, the profile of each free parameter and its verdict, the estimates
//! and the warnings (see the module documentation of [`super`]).

use nalgebra::DVector;
use rayon::prelude::*;

use super::lm::Problem as _;
use super::params::Scale;
use super::profile::{self, Side};
use super::result::verdict_warning;
use super::{
    Curve, Estimate, Fit, FitResult, InZ, NORMAL_975, Outcome, RESOLUTION, SAME_MINIMUM, Start,
    Starts, Verdict, lm, starts, statistics,
};
use crate::Result;

impl Fit {
    /// Runs the fit: every start, then the statistics and profiles at the best minimum.
    pub fn run(&self) -> Result<FitResult> {
        let settings = lm::Settings {
            max_iterations: self.max_iterations,
            ..lm::Settings::default()
        };
        let problem = InZ(self);
        let initial = starts::points(&self.parameters, self.starts);
        let mut minima = self.minimize_from(&problem, &initial, &settings)?;
        let errors_stated = self.experiments[0].stated;
        let Some(best) = self.best_start(&minima, errors_stated) else {
            return Err(match minima.swap_remove(0) {
                Err(e) => e,
                Ok(_) => self.not_finite(&self.parameters.values_at(&initial[0])),
            });
        };
        let min = minima[best].as_ref().expect("the best start has a result");
        let optimum = self.optimum(&problem, min, errors_stated)?;
        let profile_settings = lm::Settings {
            step_tolerance: 1e-10,
            ..settings
        };
        let z = &min.theta;
        let searches = self.searches(
            z,
            &optimum.stats.standard_errors,
            &optimum.slope,
            optimum.quantile,
        );
        let walks: Vec<profile::Walk> = searches
            .par_iter()
            .map(|s| profile::walk(&problem, z, &optimum.target, s, &profile_settings))
            .collect::<Result<_>>()?;
        let unseparated = optimum.stats.unseparated(optimum.free_x.len());
        let verdicts = verdicts(&walks, &unseparated);
        let mut warnings = optimum.stats.warnings(&self.parameters);
        let parameters = self.estimates(&optimum, &walks, &verdicts, &unseparated, &mut warnings);
        warnings.extend(self.optimum_warnings(&optimum, &parameters, min, &walks));
        let starts = self.starts_summary(&initial, &minima, best, optimum.target.scale);
        warnings.extend(self.start_warnings(&starts, &parameters));
        let evaluations = minima
            .iter()
            .flatten()
            .map(|m| m.evaluations)
            .sum::<usize>()
            + 2 * optimum.free_x.len()
            + walks.iter().map(|w| w.evaluations).sum::<usize>();
        let simulated = self.simulate(&optimum.x)?;
        let Optimum {
            x,
            stats,
            target,
            quantile,
            ..
        } = optimum;
        let points = self.points();
        Ok(FitResult {
            fit_file: self.path.clone(),
            law: self.parameters.law.name,
            parameters,
            free: self.parameters.free.iter().map(|f| f.name).collect(),
            correlation: stats.correlation,
            identifiable: verdicts.iter().all(|v| *v == Verdict::Identified),
            warnings,
            chi_square: target.chi_square,
            points,
            degrees_of_freedom: points - self.parameters.free.len(),
            errors_stated,
            scale: target.scale,
            quantile,
            threshold: target.threshold,
            iterations: min.iterations,
            evaluations,
            stop: min.stop,
            starts,
            snippet: self.parameters.snippet(&x),
            penalty_defaults: self.penalty_defaults(),
            curves: self
                .experiments
                .iter()
                .zip(simulated)
                .map(|(e, f)| Curve {
                    label: e.label.clone(),
                    x: e.x.clone(),
                    measured: e.measured.clone(),
                    fitted: f,
                    sigma: e.sigma.clone(),
                })
                .collect(),
        })
    }

    /// Levenberg–Marquardt from each of the `initial` points (in parallel): a start that
    /// meets parameters the model cannot be solved at is a failed start, any other error
    /// the fit's.
    fn minimize_from(
        &self,
        problem: &InZ,
        initial: &[DVector<f64>],
        settings: &lm::Settings,
    ) -> Result<Vec<Result<lm::Minimum>>> {
        let runs: Vec<Result<lm::Minimum>> = initial
            .par_iter()
            .map(|z| lm::minimize(problem, z.clone(), settings))
            .collect();
        runs.into_iter()
            .map(|run| match run {
                Err(e) if !problem.infeasible(&e) => Err(e),
                run => Ok(run),
            })
            .collect()
    }

    /// Of the starts that reached the lowest minimum, the first: the fit file's own where it
    /// did (the same minimum; its values then do not depend on the other starts). `None`
    /// when no start reached a finite χ².
    fn best_start(&self, minima: &[Result<lm::Minimum>], errors_stated: bool) -> Option<usize> {
        let chi: Vec<f64> = minima
            .iter()
            .map(|m| m.as_ref().map_or(f64::INFINITY, |m| m.chi_square()))
            .collect();
        let lowest = chi.iter().copied().fold(f64::INFINITY, f64::min);
        lowest.is_finite().then(|| {
            let scale = self.scale(lowest, errors_stated);
            chi.iter()
                .position(|c| (c - lowest) / scale <= SAME_MINIMUM)
                .expect("the lowest is among them")
        })
    }

    /// The statistics at the minimum `min` (see the module documentation): J in the law's
    /// own parameters, the scale s², the quantile of the 95 % intervals and the profiles'
    /// target.
    fn optimum(&self, problem: &InZ, min: &lm::Minimum, errors_stated: bool) -> Result<Optimum> {
        let z = &min.theta;
        let x = self.parameters.values_at(z);
        let free_x = self.parameters.free_values(z);
        // dx/dz of each free parameter: J in x is J in z divided by it.
        let slope: Vec<f64> = self
            .parameters
            .free
            .iter()
            .zip(&free_x)
            .map(|(f, x)| match f.scale {
                Scale::Linear => 1.0,
                Scale::Log => *x,
            })
            .collect();
        let mut jac = lm::jacobian(problem, z, &min.residuals)?;
        for (j, d) in slope.iter().enumerate() {
            jac.column_mut(j).unscale_mut(*d);
        }
        let chi_square = min.chi_square();
        let dof = self.points() - free_x.len();
        let scale = self.scale(chi_square, errors_stated);
        let quantile = if errors_stated {
            NORMAL_975
        } else {
            lm::t_quantile_975(dof as f64)
        };
        let stats = statistics::statistics(&jac, scale, &free_x);
        Ok(Optimum {
            x,
            free_x,
            slope,
            stats,
            quantile,
            errors_stated,
            target: profile::Target {
                chi_square,
                scale,
                threshold: quantile * quantile,
            },
        })
    }

    /// Every parameter of the law at the optimum, fixed ones included (a parameter the law
    /// does not use left out); the warning of each free one the data do not identify (and
    /// that is not one of several the data cannot separate, which the statistics warn of)
    /// goes to `warnings`.
    fn estimates(
        &self,
        optimum: &Optimum,
        walks: &[profile::Walk],
        verdicts: &[Verdict],
        unseparated: &[bool],
        warnings: &mut Vec<String>,
    ) -> Vec<Estimate> {
        let Optimum {
            x,
            stats,
            quantile,
            target,
            ..
        } = optimum;
        let mut parameters = Vec::new();
        for (i, name) in self
            .parameters
            .law
            .parameters
            .iter()
            .map(|p| p.key)
            .enumerate()
        {
            if x[i].is_nan() {
                continue;
            }
            let Some(k) = self.parameters.free.iter().position(|f| f.index == i) else {
                parameters.push(Estimate {
                    name,
                    value: x[i],
                    free: false,
                    verdict: None,
                    standard_error: None,
                    lower_95: None,
                    upper_95: None,
                    profile_lower_95: None,
                    profile_upper_95: None,
                    at_bound: false,
                });
                continue;
            };
            let f = &self.parameters.free[k];
            let identified = verdicts[k] == Verdict::Identified;
            let se = stats.standard_errors[k].filter(|_| identified);
            let crossing = |w: &profile::Walk| match w.side {
                Side::Crossed(z) => Some(f.x(z)),
                Side::Open { .. } => None,
            };
            let (lower, upper) = (&walks[2 * k], &walks[2 * k + 1]);
            let estimate = Estimate {
                name,
                value: x[i],
                free: true,
                verdict: Some(verdicts[k]),
                standard_error: se,
                lower_95: se.map(|s| x[i] - quantile * s),
                upper_95: se.map(|s| x[i] + quantile * s),
                profile_lower_95: crossing(lower),
                profile_upper_95: crossing(upper),
                at_bound: f.at_bound(x[i]),
            };
            if !identified && !unseparated[k] {
                warnings.push(verdict_warning(&estimate, f, lower, upper, target));
            }
            parameters.push(estimate);
        }
        parameters
    }

    /// What to doubt about the optimum: a parameter at a bound, stated errors too small for
    /// the residuals, a start out of iterations, profiles that found a lower χ².
    fn optimum_warnings(
        &self,
        optimum: &Optimum,
        parameters: &[Estimate],
        min: &lm::Minimum,
        walks: &[profile::Walk],
    ) -> Vec<String> {
        let mut warnings = Vec::new();
        for e in parameters.iter().filter(|e| e.at_bound) {
            warnings.push(format!(
                "{} = {} lies at a bound of its range: the data push it there",
                e.name, e.value
            ));
        }
        let profile::Target {
            chi_square, scale, ..
        } = optimum.target;
        let dof = self.points() - optimum.free_x.len();
        if optimum.errors_stated && chi_square / dof as f64 > 4.0 {
            warnings.push(format!(
                "χ²/dof = {:.3}: the stated measurement errors are too small for these residuals, or the law does not \
                 describe the tests; the intervals are too narrow",
                chi_square / dof as f64
            ));
        }
        if min.stop == lm::Stop::MaxIterations {
            warnings.push(format!(
                "no convergence in {} iterations (`max_iterations`)",
                self.max_iterations
            ));
        }
        if let Some(w) = walks
            .iter()
            .min_by(|a, b| a.lowest.0.total_cmp(&b.lowest.0))
            .filter(|w| (chi_square - w.lowest.0) / scale > SAME_MINIMUM)
        {
            let at = self.parameters.free_values(&w.lowest.1);
            warnings.push(format!(
                "the profiles met χ² = {:.6e} below the fit's {:.6e} (at {}): the fit stopped short of the minimum, \
                 and the intervals are approximate; try more `starts` or other starting values",
                w.lowest.0,
                chi_square,
                self.named(&at)
            ));
        }
        warnings
    }

    /// s² at a minimum χ² = `chi_square`: 1 with stated errors, else χ²/dof, never below the
    /// resolution floor.
    fn scale(&self, chi_square: f64, errors_stated: bool) -> f64 {
        if errors_stated {
            1.0
        } else {
            let dof = self.points() - self.parameters.free.len();
            (chi_square / dof as f64)
                .max(self.resolution_floor())
                .max(f64::MIN_POSITIVE)
        }
    }

    /// The floor of an estimated scale: (RESOLUTION · rms of the weighted measured values)².
    fn resolution_floor(&self) -> f64 {
        let (sum, n) = self
            .experiments
            .iter()
            .flat_map(|e| e.measured.iter().zip(&e.sigma))
            .fold((0.0, 0usize), |(s, n), (y, sigma)| {
                (s + (y / sigma).powi(2), n + 1)
            });
        RESOLUTION * RESOLUTION * sum / n as f64
    }

    /// The two sides of each free parameter's profile to walk from the optimum `z` (lower,
    /// upper per parameter), with first steps from the linearised standard errors `se` (in x;
    /// `slope` = dx/dz) where there are some.
    fn searches(
        &self,
        z: &DVector<f64>,
        se: &[Option<f64>],
        slope: &[f64],
        quantile: f64,
    ) -> Vec<profile::Search> {
        let mut out = Vec::new();
        for (j, f) in self.parameters.free.iter().enumerate() {
            let (lo, hi) = f.z_range();
            let x = f.x(z[j]);
            let (below, above) = match f.scale {
                Scale::Log => {
                    let reach = profile::REACH.ln();
                    (x.min(f.initial).ln() - reach, x.max(f.initial).ln() + reach)
                }
                Scale::Linear => {
                    let magnitude = x.abs().max(f.initial.abs());
                    let reach = profile::REACH * if magnitude > 0.0 { magnitude } else { 1.0 };
                    (z[j] - reach, z[j] + reach)
                }
            };
            let default_step = match f.scale {
                Scale::Log => 0.5,
                Scale::Linear => 0.1 * x.abs().max(f.initial.abs()).max(f64::MIN_POSITIVE),
            };
            let first_step = se[j]
                .map(|s| quantile * s / slope[j])
                .filter(|h| h.is_finite() && *h > 0.0)
                .unwrap_or(default_step);
            for (end, end_is_bound) in [
                if lo >= below {
                    (lo, true)
                } else {
                    (below, false)
                },
                if hi <= above {
                    (hi, true)
                } else {
                    (above, false)
                },
            ] {
                out.push(profile::Search {
                    j,
                    end,
                    end_is_bound,
                    first_step,
                });
            }
        }
        out
    }

    /// `name = value` of the free parameters' values `x`.
    pub(super) fn named(&self, x: &[f64]) -> String {
        self.parameters
            .free
            .iter()
            .zip(x)
            .map(|(f, v)| format!("{} = {v:.6e}", f.name))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Each start's result and how it compares with the best (number `best`).
    fn starts_summary(
        &self,
        initial: &[DVector<f64>],
        minima: &[Result<lm::Minimum>],
        best: usize,
        scale: f64,
    ) -> Starts {
        let best_chi = minima[best].as_ref().map_or(f64::NAN, |m| m.chi_square());
        let runs: Vec<Start> = initial
            .iter()
            .zip(minima)
            .enumerate()
            .map(|(k, (z0, m))| {
                let initial = self.parameters.free_values(z0);
                match m {
                    Ok(m) if m.chi_square().is_finite() => Start {
                        initial,
                        fitted: Some(self.parameters.free_values(&m.theta)),
                        chi_square: Some(m.chi_square()),
                        iterations: m.iterations,
                        stop: Some(m.stop),
                        outcome: if k == best {
                            Outcome::Best
                        } else if (m.chi_square() - best_chi) / scale <= SAME_MINIMUM {
                            Outcome::Same
                        } else {
                            Outcome::Higher
                        },
                        error: None,
                    },
                    Ok(m) => Start {
                        initial,
                        fitted: None,
                        chi_square: None,
                        iterations: m.iterations,
                        stop: Some(m.stop),
                        outcome: Outcome::Failed,
                        error: Some("the simulated responses are not finite numbers".into()),
                    },
                    Err(e) => Start {
                        initial,
                        fitted: None,
                        chi_square: None,
                        iterations: 0,
                        stop: None,
                        outcome: Outcome::Failed,
                        error: Some(e.to_string()),
                    },
                }
            })
            .collect();
        Starts {
            count: runs.len(),
            same_minimum: runs
                .iter()
                .filter(|r| matches!(r.outcome, Outcome::Best | Outcome::Same))
                .count(),
            tolerance: SAME_MINIMUM,
            runs,
        }
    }

    /// Warnings about the starts: the fit file's own start did not reach the reported minimum,
    /// or another start reached the same χ² with an identified parameter outside its interval
    /// (a distinct minimum).
    fn start_warnings(&self, starts: &Starts, estimates: &[Estimate]) -> Vec<String> {
        let mut out = Vec::new();
        let best = starts
            .runs
            .iter()
            .position(|r| r.outcome == Outcome::Best)
            .expect("a best start");
        let own = &starts.runs[0];
        match own.outcome {
            Outcome::Best | Outcome::Same => {}
            Outcome::Higher => out.push(format!(
                "from the fit file's starting values the fit stopped at χ² = {:.6e} (a local minimum, or short of \
                 one); start {best} of {} reached χ² = {:.6e} and is reported (its starting values: {})",
                own.chi_square.unwrap_or(f64::NAN),
                starts.count,
                starts.runs[best].chi_square.unwrap_or(f64::NAN),
                self.named(&starts.runs[best].initial)
            )),
            Outcome::Failed => out.push(format!(
                "the fit from the fit file's starting values failed ({}); start {best} of {} is reported",
                own.error.as_deref().unwrap_or("no result"),
                starts.count
            )),
        }
        let free: Vec<&Estimate> = estimates.iter().filter(|e| e.free).collect();
        for (k, run) in starts.runs.iter().enumerate() {
            let (Outcome::Same, Some(fitted)) = (run.outcome, &run.fitted) else {
                continue;
            };
            let outside: Vec<String> = free
                .iter()
                .zip(fitted)
                .filter(|(e, v)| {
                    e.verdict == Some(Verdict::Identified)
                        && !(e.profile_lower_95.unwrap_or(f64::NEG_INFINITY) <= **v
                            && **v <= e.profile_upper_95.unwrap_or(f64::INFINITY))
                })
                .map(|(e, v)| format!("{} = {v:.6e}", e.name))
                .collect();
            if !outside.is_empty() {
                out.push(format!(
                    "start {k} reached the same χ² at a distinct point ({}, outside the 95 % intervals): the \
                     minimum is not unique",
                    outside.join(", ")
                ));
            }
        }
        out
    }
}

/// The statistics at the best minimum ([`Fit::optimum`]).
struct Optimum {
    /// The law's parameters, and the free ones alone.
    x: Vec<f64>,
    free_x: Vec<f64>,
    /// dx/dz of each free parameter.
    slope: Vec<f64>,
    stats: statistics::Statistics,
    /// The multiplier of the standard errors in the 95 % intervals.
    quantile: f64,
    errors_stated: bool,
    /// χ², s² and the rise of χ²/s² that bounds the profile intervals.
    target: profile::Target,
}

/// The verdict of each free parameter from its two profile walks (below and above, in
/// `walks[2j]` and `walks[2j + 1]`): one the data cannot separate from others is not
/// identified whatever its profile shows.
fn verdicts(walks: &[profile::Walk], unseparated: &[bool]) -> Vec<Verdict> {
    let crossed = |w: &profile::Walk| matches!(w.side, Side::Crossed(_));
    unseparated
        .iter()
        .enumerate()
        .map(
            |(j, &unseparated)| match (crossed(&walks[2 * j]), crossed(&walks[2 * j + 1])) {
                _ if unseparated => Verdict::NotIdentified,
                (true, true) => Verdict::Identified,
                (true, false) => Verdict::BoundedBelow,
                (false, true) => Verdict::BoundedAbove,
                (false, false) => Verdict::NotIdentified,
            },
        )
        .collect()
}
