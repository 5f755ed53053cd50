//! Joint-parameter identification (`asperity fit`): the parameters of an interface law
//! (paper Eqs. 1–5: normal compliance c_N, m; tangential stiffness R, S; friction μ_m with
//! slip hardening β, n) fitted to measured curves by Levenberg–Marquardt ([`lm`]) within
//! each parameter's range ([`params`]), from several starting points ([`starts`]).
//!
//! A fit file (TOML) names the law, the free parameters with their starting values and bounds,
//! the fixed ones, and the tests ([`experiment`]): normal loading/unloading and tangential
//! loading at constant pressure, evaluated on the law directly, or a full specimen model.
//!
//! ## Statistics at the optimum
//! With the weighted residuals r_i = (f_i(x) − y_i)/σ_i and J = ∂r/∂x (finite differences in
//! the optimiser's variables, converted to the law's own parameters x), the covariance is
//! C = s² (JᵀJ)⁻¹, where s² = 1 when the tests state their measurement errors (σ is then an
//! absolute standard deviation, and χ²/(n − p) ≈ 1 checks it) and s² = χ²/(n − p) when they do
//! not (never below the simulations' resolution, [`RESOLUTION`]). Standard errors are √C_ii;
//! the linearised 95 % intervals are x ± q·SE with q = 1.96 (stated errors) or Student's
//! t₀.₉₇₅ with n − p degrees of freedom (estimated scale); the correlations are
//! C_ij/(SE_i SE_j).
//!
//! ## Identifiability
//! What the data determine is judged by the profile of each free parameter ([`profile`]), not
//! by the slope at the point where the fit stopped: where χ², minimised over the others,
//! rises by the threshold q² (in units of s²) on both sides within the parameter's range, it
//! is *identified*, with the profile (likelihood-ratio) interval between the two crossings;
//! where it rises on one side only, *bounded below* or *bounded above* (a one-sided limit, no
//! value); where on neither, *not identified*. Parameters in a direction of the unit-diagonal
//! information matrix with a vanishing eigenvalue ([`statistics::SINGULAR`]) that involves two
//! or more of them (e.g. R and S of k_T = p^S/R from a single pressure) are not identified
//! separately whatever their profiles show. The linearised standard errors and intervals are
//! reported for identified parameters only, and the result's `identifiable` is whether every
//! free parameter is.

mod data;
pub mod experiment;
pub mod lm;
pub mod params;
pub mod profile;
mod report;
mod specimen;
pub mod starts;
pub mod statistics;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::DVector;
use rayon::prelude::*;
use serde::Deserialize;

pub use data::{Dimension, Table};
pub use experiment::{Experiment, TestSpec};
pub use params::{ParameterSpec, Parameters};
pub use report::{check_folder, write};

use crate::model::PenaltyDefault;
use crate::{Error, Result};
use lm::Problem as _;
use params::Scale;
use profile::Side;

/// The 97.5 % quantile of the standard normal distribution.
const NORMAL_975: f64 = 1.959_963_984_540_054;

/// The relative resolution of the simulated responses: an estimated scale s² is never taken
/// below (RESOLUTION · rms of the measured values)², so that exact synthetic data do not make
/// the profiles chase round-off.
pub const RESOLUTION: f64 = 1e-9;

/// Starts whose χ² lies within this (in units of s²) of the best reached the same minimum.
pub const SAME_MINIMUM: f64 = 0.01;

/// A fit file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitFile {
    /// The law's name in the table of interface laws ([`crate::contact::laws`]).
    pub law: &'static crate::contact::laws::LawDescriptor,
    pub parameters: BTreeMap<String, ParameterSpec>,
    #[serde(rename = "test")]
    pub tests: Vec<TestSpec>,
    /// Most Levenberg–Marquardt iterations of each start (default 200).
    pub max_iterations: Option<usize>,
    /// Starting points, the fit file's included (default [`starts::DEFAULT`], or
    /// [`starts::DEFAULT_MODEL`] with a model test).
    pub starts: Option<usize>,
}

/// A fit ready to run: parameters and experiments checked, data read.
#[derive(Debug)]
pub struct Fit {
    pub path: PathBuf,
    pub parameters: Parameters,
    pub experiments: Vec<Experiment>,
    pub max_iterations: usize,
    pub starts: usize,
}

/// What the data say about a free parameter (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    Identified,
    BoundedBelow,
    BoundedAbove,
    NotIdentified,
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Verdict::Identified => "identified",
            Verdict::BoundedBelow => "bounded below",
            Verdict::BoundedAbove => "bounded above",
            Verdict::NotIdentified => "not identified",
        })
    }
}

/// One parameter of the result.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Estimate {
    pub name: &'static str,
    pub value: f64,
    pub free: bool,
    /// None when fixed.
    pub verdict: Option<Verdict>,
    /// Linearised standard error and 95 % interval; None unless identified.
    pub standard_error: Option<f64>,
    pub lower_95: Option<f64>,
    pub upper_95: Option<f64>,
    /// Where the profile rises by the threshold below and above the value (None: it does not
    /// within the parameter's range).
    pub profile_lower_95: Option<f64>,
    pub profile_upper_95: Option<f64>,
    /// Whether the optimum lies within 1e-6 (relative to the range) of a bound.
    pub at_bound: bool,
}

/// The simulated and measured curve of one test at the optimum.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Curve {
    pub label: String,
    pub x: Vec<f64>,
    pub measured: Vec<f64>,
    pub fitted: Vec<f64>,
    pub sigma: Vec<f64>,
}

/// Where a start ended compared with the best.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The reported minimum.
    Best,
    /// χ² within [`SAME_MINIMUM`] of the best.
    Same,
    /// A clearly higher χ²: a local minimum, or stopped short of one.
    Higher,
    /// No result (the responses overflow, or the model cannot be solved there).
    Failed,
}

/// One start of the fit.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Start {
    /// The free parameters' starting and fitted values (in the order of `free`).
    pub initial: Vec<f64>,
    pub fitted: Option<Vec<f64>>,
    pub chi_square: Option<f64>,
    pub iterations: usize,
    pub stop: Option<lm::Stop>,
    pub outcome: Outcome,
    /// Why it failed.
    pub error: Option<String>,
}

/// The starts of the fit: the fit file's first.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Starts {
    pub count: usize,
    /// How many reached the best χ² within `tolerance` (the best included).
    pub same_minimum: usize,
    /// [`SAME_MINIMUM`], in units of s².
    pub tolerance: f64,
    pub runs: Vec<Start>,
}

/// A penalty stiffness that the fitted law leaves out, fixed for the whole fit at the default
/// a model test's specimen gives it (10 E*/h on its mesh).
#[derive(Clone, Debug, serde::Serialize)]
pub struct FixedPenalty {
    /// The test's label.
    pub test: String,
    /// The contact, the parameters, the stiffness and what it comes from.
    #[serde(flatten)]
    pub default: PenaltyDefault,
}

/// The outcome of a fit.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FitResult {
    pub fit_file: PathBuf,
    pub law: &'static str,
    pub parameters: Vec<Estimate>,
    /// Names of the free parameters, the order of `correlation`.
    pub free: Vec<&'static str>,
    /// Correlation matrix of the free parameters (null where not identifiable).
    pub correlation: Vec<Vec<Option<f64>>>,
    /// Whether every free parameter is identified.
    pub identifiable: bool,
    pub warnings: Vec<String>,
    pub chi_square: f64,
    pub points: usize,
    pub degrees_of_freedom: usize,
    /// Whether the tests stated measurement errors (else the scale s² = χ²/dof was estimated).
    pub errors_stated: bool,
    /// s²: 1 with stated errors, else the estimated scale.
    pub scale: f64,
    /// The multiplier of the standard errors in the 95 % intervals.
    pub quantile: f64,
    /// The rise of χ²/s² that bounds the profile intervals: `quantile`².
    pub threshold: f64,
    pub iterations: usize,
    pub evaluations: usize,
    pub stop: lm::Stop,
    pub starts: Starts,
    /// The case-file line with the fitted law.
    pub snippet: String,
    /// The penalty stiffnesses the model tests fixed at their specimens' defaults: the values
    /// every evaluation used.
    pub penalty_defaults: Vec<FixedPenalty>,
    pub curves: Vec<Curve>,
}

impl FitResult {
    /// The estimate of `name`.
    pub fn get(&self, name: &str) -> Option<&Estimate> {
        self.parameters.iter().find(|e| e.name == name)
    }
}

impl Fit {
    /// Reads and checks fit file `path` and its data.
    pub fn from_file(path: &Path) -> Result<Self> {
        let text = crate::config::read_input(path)?;
        let file: FitFile = toml::from_str(&text).map_err(|e| Error::toml(path, &e))?;
        if file.tests.is_empty() {
            return Err(Error::Case {
                path: path.to_path_buf(),
                message: "no [[test]]: give at least one measured curve".into(),
            });
        }
        for (key, value) in [
            ("max_iterations", file.max_iterations),
            ("starts", file.starts),
        ] {
            if value == Some(0) {
                return Err(Error::InvalidParameter {
                    path: path.to_path_buf(),
                    key: key.into(),
                    value: "0".into(),
                    reason: "must be at least 1".into(),
                });
            }
        }
        if let Some(starts) = file.starts.filter(|&s| s > starts::MAX) {
            return Err(Error::InvalidParameter {
                path: path.to_path_buf(),
                key: "starts".into(),
                value: starts.to_string(),
                reason: format!("at most {} starting points", starts::MAX),
            });
        }
        let parameters = Parameters::new(file.law, &file.parameters, path)?;
        let mut experiments = file
            .tests
            .iter()
            .enumerate()
            .map(|(i, t)| Experiment::read(t, i, path))
            .collect::<Result<Vec<_>>>()?;
        let at_a_point = experiments.iter().any(Experiment::at_a_point);
        let defaulted = file.law.defaulted_penalties(&parameters.values);
        if let (true, Some(key)) = (at_a_point, defaulted.first()) {
            return Err(Error::InvalidParameter {
                path: path.to_path_buf(),
                key: format!("parameters.{key}"),
                value: String::new(),
                reason: "missing: a material-point [[test]] (normal, tangential) has no mesh to \
                         default a penalty stiffness from (only a model test's case does, 10 E*/h): \
                         give it fixed (`value`) or free (`initial`)"
                    .into(),
            });
        }
        for e in &mut experiments {
            if let experiment::Kind::Model(specimen) = &mut e.kind {
                specimen.fix_penalty(&parameters.values, file.law)?;
            }
        }
        if experiments.iter().any(|e| e.stated) != experiments.iter().all(|e| e.stated) {
            return Err(Error::Case {
                path: path.to_path_buf(),
                message: "either every [[test]] states its measurement error (`error` or `relative_error`) or none \
                          does: stated and estimated scales cannot be mixed"
                    .into(),
            });
        }
        let has_model = experiments
            .iter()
            .any(|e| matches!(e.kind, experiment::Kind::Model(_)));
        let default_starts = if has_model {
            starts::DEFAULT_MODEL
        } else {
            starts::DEFAULT
        };
        let fit = Self {
            path: path.to_path_buf(),
            parameters,
            experiments,
            max_iterations: file.max_iterations.unwrap_or(200),
            starts: file.starts.unwrap_or(default_starts),
        };
        let points: usize = fit.experiments.iter().map(|e| e.measured.len()).sum();
        if points <= fit.parameters.free.len() {
            return Err(Error::Case {
                path: path.to_path_buf(),
                message: format!(
                    "{points} measured points cannot determine {} free parameters",
                    fit.parameters.free.len()
                ),
            });
        }
        experiment::check_sum_of_squares(&fit.experiments, points)?;
        Ok(fit)
    }

    /// The simulated responses of every test with parameter values `x`, one vector per test.
    pub fn simulate(&self, x: &[f64]) -> Result<Vec<Vec<f64>>> {
        // Only the material-point tests evaluate the law here; a model test builds its own,
        // whose penalty stiffnesses left out default to its mesh's.
        let law = match self.experiments.iter().any(Experiment::at_a_point) {
            true => Some(self.parameters.build(x)?),
            false => None,
        };
        self.experiments
            .iter()
            .map(|e| e.simulate(law.as_deref(), self.parameters.law, x))
            .collect()
    }

    /// Weighted residuals at parameter values `x`.
    fn residuals_at(&self, x: &[f64]) -> Result<DVector<f64>> {
        let simulated = self.simulate(x)?;
        let r = self.experiments.iter().zip(&simulated).flat_map(|(e, f)| {
            f.iter()
                .zip(&e.measured)
                .zip(&e.sigma)
                .map(|((f, y), s)| (f - y) / s)
        });
        Ok(DVector::from_iterator(self.points(), r))
    }

    /// The penalty stiffnesses the model tests fixed at their specimens' defaults.
    fn penalty_defaults(&self) -> Vec<FixedPenalty> {
        let fixed = self.experiments.iter().filter_map(|e| match &e.kind {
            experiment::Kind::Model(specimen) => Some((e, specimen.penalty.clone()?)),
            _ => None,
        });
        fixed
            .map(|(e, default)| FixedPenalty {
                test: e.label.clone(),
                default,
            })
            .collect()
    }

    fn points(&self) -> usize {
        self.experiments.iter().map(|e| e.measured.len()).sum()
    }

    fn has_model(&self) -> bool {
        self.experiments
            .iter()
            .any(|e| matches!(e.kind, experiment::Kind::Model(_)))
    }

    /// Runs the fit: every start, then the statistics and profiles at the best minimum.
    pub fn run(&self) -> Result<FitResult> {
        let settings = lm::Settings {
            max_iterations: self.max_iterations,
            ..lm::Settings::default()
        };
        let problem = InZ(self);
        let initial = starts::points(&self.parameters, self.starts);
        let runs: Vec<Result<lm::Minimum>> = initial
            .par_iter()
            .map(|z| lm::minimize(&problem, z.clone(), &settings))
            .collect();
        let mut minima = Vec::with_capacity(runs.len());
        for run in runs {
            minima.push(match run {
                Ok(m) => Ok(m),
                Err(e) if problem.infeasible(&e) => Err(e),
                Err(e) => return Err(e),
            });
        }
        let chi: Vec<f64> = minima
            .iter()
            .map(|m| m.as_ref().map_or(f64::INFINITY, |m| m.chi_square()))
            .collect();
        let lowest = chi.iter().copied().fold(f64::INFINITY, f64::min);
        // Of the starts that reached the lowest minimum, the first: the fit file's own where it
        // did (the same minimum; its values then do not depend on the other starts).
        let errors_stated = self.experiments[0].stated;
        let best = lowest.is_finite().then(|| {
            let scale = self.scale(lowest, errors_stated);
            chi.iter()
                .position(|c| (c - lowest) / scale <= SAME_MINIMUM)
                .expect("the lowest is among them")
        });
        let Some(best) = best else {
            return Err(match minima.swap_remove(0) {
                Err(e) => e,
                Ok(_) => self.not_finite(&self.parameters.values_at(&initial[0])),
            });
        };
        let min = minima[best].as_ref().expect("the best start has a result");
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
        let mut jac = lm::jacobian(&problem, z, &min.residuals)?;
        for (j, d) in slope.iter().enumerate() {
            jac.column_mut(j).unscale_mut(*d);
        }
        let chi_square = min.chi_square();
        let n = self.points();
        let p = free_x.len();
        let dof = n - p;
        let scale = self.scale(chi_square, errors_stated);
        let quantile = if errors_stated {
            NORMAL_975
        } else {
            lm::t_quantile_975(dof as f64)
        };
        let target = profile::Target {
            chi_square,
            scale,
            threshold: quantile * quantile,
        };
        let stats = statistics::statistics(&jac, scale, &free_x);
        let searches = self.searches(z, &stats.standard_errors, &slope, quantile);
        let profile_settings = lm::Settings {
            step_tolerance: 1e-10,
            ..settings
        };
        let walks: Vec<profile::Walk> = searches
            .par_iter()
            .map(|s| profile::walk(&problem, z, &target, s, &profile_settings))
            .collect::<Result<_>>()?;
        let unseparated = stats.unseparated(p);
        let verdicts: Vec<Verdict> = (0..p)
            .map(|j| {
                let crossed = |w: &profile::Walk| matches!(w.side, Side::Crossed(_));
                match (crossed(&walks[2 * j]), crossed(&walks[2 * j + 1])) {
                    _ if unseparated[j] => Verdict::NotIdentified,
                    (true, true) => Verdict::Identified,
                    (true, false) => Verdict::BoundedBelow,
                    (false, true) => Verdict::BoundedAbove,
                    (false, false) => Verdict::NotIdentified,
                }
            })
            .collect();

        let mut warnings = stats.warnings(&self.parameters);
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
            let (lower, upper) = (walks[2 * k].clone(), walks[2 * k + 1].clone());
            let estimate = Estimate {
                name,
                value: x[i],
                free: true,
                verdict: Some(verdicts[k]),
                standard_error: se,
                lower_95: se.map(|s| x[i] - quantile * s),
                upper_95: se.map(|s| x[i] + quantile * s),
                profile_lower_95: crossing(&lower),
                profile_upper_95: crossing(&upper),
                at_bound: f.at_bound(x[i]),
            };
            if !identified && !unseparated[k] {
                warnings.push(verdict_warning(&estimate, f, &lower, &upper, &target));
            }
            parameters.push(estimate);
        }
        for e in parameters.iter().filter(|e| e.at_bound) {
            warnings.push(format!(
                "{} = {} lies at a bound of its range: the data push it there",
                e.name, e.value
            ));
        }
        if errors_stated && chi_square / dof as f64 > 4.0 {
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
        let starts = self.starts_summary(&initial, &minima, best, scale);
        warnings.extend(self.start_warnings(&starts, &parameters));
        let evaluations = minima
            .iter()
            .flatten()
            .map(|m| m.evaluations)
            .sum::<usize>()
            + 2 * p
            + walks.iter().map(|w| w.evaluations).sum::<usize>();
        let simulated = self.simulate(&x)?;
        Ok(FitResult {
            fit_file: self.path.clone(),
            law: self.parameters.law.name,
            parameters,
            free: self.parameters.free.iter().map(|f| f.name).collect(),
            correlation: stats.correlation,
            identifiable: verdicts.iter().all(|v| *v == Verdict::Identified),
            warnings,
            chi_square,
            points: n,
            degrees_of_freedom: dof,
            errors_stated,
            scale,
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
    fn named(&self, x: &[f64]) -> String {
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

    /// The error of a start whose simulated responses are not finite: the first such value.
    fn not_finite(&self, x: &[f64]) -> Error {
        let message = match self.simulate(x) {
            Ok(simulated) => self
                .experiments
                .iter()
                .zip(simulated)
                .find_map(|(e, f)| {
                    let row = f
                        .iter()
                        .zip(&e.measured)
                        .zip(&e.sigma)
                        .position(|((f, y), s)| !((f - y) / s).is_finite())?;
                    Some(format!(
                        "{}, row {}: the law gives {} against the measured {} at the starting values ({}); \
                         give starting values nearer the data",
                        e.label,
                        row + 1,
                        f[row],
                        e.measured[row],
                        self.named(&self.parameters.free.iter().map(|p| x[p.index]).collect::<Vec<_>>())
                    ))
                })
                .unwrap_or_else(|| "the residuals at the starting values are not finite".into()),
            Err(e) => e.to_string(),
        };
        Error::Case {
            path: self.path.clone(),
            message,
        }
    }

    /// Residuals at many parameter vectors: in parallel when a test runs a full model (each
    /// run is an independent solve), sequentially for material-point tests (microseconds).
    fn residuals_many(&self, xs: Vec<Vec<f64>>) -> Result<Vec<DVector<f64>>> {
        if self.has_model() {
            xs.par_iter().map(|x| self.residuals_at(x)).collect()
        } else {
            xs.iter().map(|x| self.residuals_at(x)).collect()
        }
    }
}

/// The warning of a free parameter that is not identified: what its profile shows.
fn verdict_warning(
    e: &Estimate,
    f: &params::Free,
    lower: &profile::Walk,
    upper: &profile::Walk,
    target: &profile::Target,
) -> String {
    let open = |w: &profile::Walk| match w.side {
        Side::Open { until, bound } => {
            let x = f.x(until);
            Some(if bound {
                format!("{x:.6e} (its bound)")
            } else {
                format!("{x:.6e}")
            })
        }
        Side::Crossed(_) => None,
    };
    let rise = format!("Δχ²/s² = {:.3}", target.threshold);
    match e.verdict {
        Some(Verdict::BoundedBelow) => format!(
            "{}: bounded below only: the data give {} ≥ {:.6e} (95 %, profile) but no upper limit (χ² stays within \
             {rise} of its minimum up to {}); its value {:.6e} is where the fit stopped, not an estimate",
            e.name,
            e.name,
            e.profile_lower_95.unwrap_or(f64::NAN),
            open(upper).unwrap_or_default(),
            e.value
        ),
        Some(Verdict::BoundedAbove) => format!(
            "{}: bounded above only: the data give {} ≤ {:.6e} (95 %, profile) but no lower limit (χ² stays within \
             {rise} of its minimum down to {}); its value {:.6e} is where the fit stopped, not an estimate",
            e.name,
            e.name,
            e.profile_upper_95.unwrap_or(f64::NAN),
            open(lower).unwrap_or_default(),
            e.value
        ),
        _ => format!(
            "{}: not identified: χ² stays within {rise} of its minimum from {} to {}; fix it or add a test that \
             depends on it",
            e.name,
            open(lower).unwrap_or_default(),
            open(upper).unwrap_or_default()
        ),
    }
}

/// The fit as a problem in the optimiser's variables z (what LM moves).
struct InZ<'f>(&'f Fit);

impl lm::Problem for InZ<'_> {
    type Error = Error;
    fn residuals(&self, z: &DVector<f64>) -> Result<DVector<f64>> {
        self.0.residuals_at(&self.0.parameters.values_at(z))
    }
    fn residuals_many(&self, zs: &[DVector<f64>]) -> Result<Vec<DVector<f64>>> {
        self.0
            .residuals_many(zs.iter().map(|z| self.0.parameters.values_at(z)).collect())
    }
    fn range(&self, i: usize) -> (f64, f64) {
        self.0.parameters.free[i].z_range()
    }
    /// A model that cannot be solved at trial parameters (no convergence, collapse): the
    /// parameters are out of what the specimen can carry, not the input wrong.
    fn infeasible(&self, e: &Error) -> bool {
        matches!(e.exit_code(), 1 | 5)
    }
}
