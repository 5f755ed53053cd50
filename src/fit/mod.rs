//! Joint-parameter identification (`asperity fit`): the parameters of an interface law
//! (paper Eqs. 1–5: normal compliance c_N, m; tangential stiffness R, S; friction μ_m with
//! slip hardening β, n) fitted to measured curves by Levenberg–Marquardt ([`lm`]).
//!
//! A fit file (TOML) names the law, the free parameters with their starting values and bounds,
//! the fixed ones, and the tests ([`experiment`]): normal loading/unloading and tangential
//! loading at constant pressure, evaluated on the law directly, or a full specimen model.
//!
//! ## Statistics at the optimum
//! With the weighted residuals r_i = (f_i(x) − y_i)/σ_i and J = ∂r/∂x (central differences in
//! the law's own parameters x, not the transformed ones), the covariance is
//! C = s² (JᵀJ)⁻¹, where s² = 1 when the tests state their measurement errors (σ is then an
//! absolute standard deviation, and χ²/(n − p) ≈ 1 checks it) and s² = χ²/(n − p) when they do
//! not. Standard errors are √C_ii; the 95 % intervals are x ± q·SE with q = 1.96 (stated
//! errors) or Student's t₀.₉₇₅ with n − p degrees of freedom (estimated scale); the
//! correlations are C_ij/(SE_i SE_j).
//!
//! ## Identifiability
//! The information matrix JᵀJ scaled to unit diagonal has eigenvalues between 0 and p; when the
//! smallest is below [`SINGULAR`] times the largest, the data do not determine the parameters
//! with the largest components in its eigenvector separately (e.g. R and S of k_T = p^S/R from
//! a single pressure): their standard errors and intervals are not reported (null), the
//! combination is named, and the result's `identifiable` is false. Pairs with
//! |correlation| > [`CORRELATION_WARNING`] are reported as poorly separable.

mod data;
pub mod experiment;
pub mod lm;
pub mod params;
mod report;
mod specimen;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use rayon::prelude::*;
use serde::Deserialize;

pub use data::{Dimension, Table};
pub use experiment::{Experiment, TestSpec};
pub use params::{ParameterSpec, Parameters};
pub use report::write;

use crate::{Error, Result};

/// Ratio of the smallest to the largest eigenvalue of the unit-diagonal information matrix
/// below which parameters are not separately identifiable. Central differences give
/// derivatives to about 1e-10 relative; exactly dependent columns then show ratios near
/// 1e-16…1e-12, while a merely poor design stays above 1e-8.
pub const SINGULAR: f64 = 1e-9;

/// |correlation| above which a pair of parameters is reported as poorly separable.
pub const CORRELATION_WARNING: f64 = 0.99;

/// The 97.5 % quantile of the standard normal distribution.
const NORMAL_975: f64 = 1.959_963_984_540_054;

/// A fit file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitFile {
    /// The law's name in the table of interface laws ([`crate::contact::laws`]).
    pub law: &'static crate::contact::laws::LawDescriptor,
    pub parameters: BTreeMap<String, ParameterSpec>,
    #[serde(rename = "test")]
    pub tests: Vec<TestSpec>,
    /// Most Levenberg–Marquardt iterations (default 200).
    pub max_iterations: Option<usize>,
}

/// A fit ready to run: parameters and experiments checked, data read.
#[derive(Debug)]
pub struct Fit {
    pub path: PathBuf,
    pub parameters: Parameters,
    pub experiments: Vec<Experiment>,
    pub max_iterations: usize,
}

/// One parameter of the result.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Estimate {
    pub name: &'static str,
    pub value: f64,
    pub free: bool,
    /// None when fixed or not identifiable.
    pub standard_error: Option<f64>,
    pub lower_95: Option<f64>,
    pub upper_95: Option<f64>,
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

/// The outcome of a fit.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FitResult {
    pub fit_file: PathBuf,
    pub law: &'static str,
    pub parameters: Vec<Estimate>,
    /// Names of the free parameters, the order of `correlation`.
    pub free: Vec<&'static str>,
    /// Correlation matrix of the free parameters (NaN → null where not identifiable).
    pub correlation: Vec<Vec<Option<f64>>>,
    pub identifiable: bool,
    pub warnings: Vec<String>,
    pub chi_square: f64,
    pub points: usize,
    pub degrees_of_freedom: usize,
    /// Whether the tests stated measurement errors (else the scale s² = χ²/dof was estimated).
    pub errors_stated: bool,
    /// The multiplier of the standard errors in the 95 % intervals.
    pub quantile: f64,
    pub iterations: usize,
    pub evaluations: usize,
    pub stop: String,
    /// The case-file line with the fitted law.
    pub snippet: String,
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
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let file: FitFile = toml::from_str(&text).map_err(|e| Error::Case {
            path: path.to_path_buf(),
            message: e.to_string().trim_end().to_string(),
        })?;
        if file.tests.is_empty() {
            return Err(Error::Case {
                path: path.to_path_buf(),
                message: "no [[test]]: give at least one measured curve".into(),
            });
        }
        let parameters = Parameters::new(file.law, &file.parameters, path)?;
        let experiments = file
            .tests
            .iter()
            .enumerate()
            .map(|(i, t)| Experiment::read(t, i, path))
            .collect::<Result<Vec<_>>>()?;
        if experiments.iter().any(|e| e.stated) != experiments.iter().all(|e| e.stated) {
            return Err(Error::Case {
                path: path.to_path_buf(),
                message: "either every [[test]] states its measurement error (`error` or `relative_error`) or none \
                          does: stated and estimated scales cannot be mixed"
                    .into(),
            });
        }
        let fit = Self {
            path: path.to_path_buf(),
            parameters,
            experiments,
            max_iterations: file.max_iterations.unwrap_or(200),
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
        Ok(fit)
    }

    /// The simulated responses of every test with parameter values `x`, one vector per test.
    pub fn simulate(&self, x: &[f64]) -> Result<Vec<Vec<f64>>> {
        let law = self.parameters.build(x)?;
        self.experiments
            .iter()
            .map(|e| e.simulate(law.as_ref(), self.parameters.law, x))
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

    fn points(&self) -> usize {
        self.experiments.iter().map(|e| e.measured.len()).sum()
    }

    fn has_model(&self) -> bool {
        self.experiments
            .iter()
            .any(|e| matches!(e.kind, experiment::Kind::Model(_)))
    }

    /// Runs the fit.
    pub fn run(&self) -> Result<FitResult> {
        let settings = lm::Settings {
            max_iterations: self.max_iterations,
            ..lm::Settings::default()
        };
        let min = lm::minimize(&InTheta(self), self.parameters.start(), &settings)?;
        let x = self.parameters.values_at(&min.theta);
        let free_x: Vec<f64> = self.parameters.free.iter().map(|f| x[f.index]).collect();
        let jac = lm::jacobian(
            &InX(self),
            &DVector::from_vec(free_x.clone()),
            self.points(),
        )?;
        let chi_square = min.residuals.norm_squared();
        let n = self.points();
        let p = free_x.len();
        let dof = n - p;
        let errors_stated = self.experiments[0].stated;
        let scale = if errors_stated {
            1.0
        } else {
            chi_square / dof as f64
        };
        let quantile = if errors_stated {
            NORMAL_975
        } else {
            lm::t_quantile_975(dof as f64)
        };
        let stats = statistics(&jac, scale, &free_x);
        let mut warnings = stats.warnings(&self.parameters);
        if errors_stated && chi_square / dof as f64 > 4.0 {
            warnings.push(format!(
                "χ²/dof = {:.3}: the stated measurement errors are too small for these residuals, or the law does not \
                 describe the tests; the intervals are too narrow",
                chi_square / dof as f64
            ));
        }
        if min.stop == lm::Stop::MaxIterations {
            warnings.push(format!(
                "no convergence in {} iterations",
                self.max_iterations
            ));
        }
        let simulated = self.simulate(&x)?;
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
            let free = self.parameters.free.iter().position(|f| f.index == i);
            let se = free.and_then(|k| stats.standard_errors[k]);
            let at_bound = free.is_some_and(|k| {
                let f = &self.parameters.free[k];
                let range = match (f.min, f.max) {
                    (Some(a), Some(b)) => b - a,
                    _ => x[i].abs().max(1e-300),
                };
                [f.min, f.max]
                    .iter()
                    .flatten()
                    .any(|b| (x[i] - b).abs() <= 1e-6 * range)
            });
            parameters.push(Estimate {
                name,
                value: x[i],
                free: free.is_some(),
                standard_error: se,
                lower_95: se.map(|s| x[i] - quantile * s),
                upper_95: se.map(|s| x[i] + quantile * s),
                at_bound,
            });
        }
        for e in parameters.iter().filter(|e| e.at_bound) {
            warnings.push(format!(
                "{} = {} lies at a bound: the data push it out of its range; its interval assumes an interior optimum",
                e.name, e.value
            ));
        }
        Ok(FitResult {
            fit_file: self.path.clone(),
            law: self.parameters.law.name,
            parameters,
            free: self.parameters.free.iter().map(|f| f.name).collect(),
            correlation: stats.correlation,
            identifiable: stats.null_space.is_empty(),
            warnings,
            chi_square,
            points: n,
            degrees_of_freedom: dof,
            errors_stated,
            quantile,
            iterations: min.iterations,
            evaluations: min.evaluations,
            stop: format!("{:?}", min.stop),
            snippet: self.parameters.snippet(&x),
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

/// The fit as a problem in the transformed parameters θ (what LM moves).
struct InTheta<'f>(&'f Fit);

impl lm::Problem for InTheta<'_> {
    type Error = Error;
    fn residuals(&self, theta: &DVector<f64>) -> Result<DVector<f64>> {
        self.0.residuals_at(&self.0.parameters.values_at(theta))
    }
    fn residuals_many(&self, thetas: &[DVector<f64>]) -> Result<Vec<DVector<f64>>> {
        self.0.residuals_many(
            thetas
                .iter()
                .map(|t| self.0.parameters.values_at(t))
                .collect(),
        )
    }
}

/// The fit as a problem in the free parameters x themselves (for the Jacobian at the optimum).
struct InX<'f>(&'f Fit);

impl lm::Problem for InX<'_> {
    type Error = Error;
    fn residuals(&self, x: &DVector<f64>) -> Result<DVector<f64>> {
        self.0
            .residuals_at(&self.0.parameters.with_free(x.as_slice()))
    }
    fn residuals_many(&self, xs: &[DVector<f64>]) -> Result<Vec<DVector<f64>>> {
        self.0.residuals_many(
            xs.iter()
                .map(|x| self.0.parameters.with_free(x.as_slice()))
                .collect(),
        )
    }
    /// Relative steps, kept inside the bounds (a parameter at 0 gets an absolute 1e-9).
    fn steps(&self, x: &DVector<f64>) -> DVector<f64> {
        DVector::from_iterator(
            x.len(),
            self.0.parameters.free.iter().zip(x.iter()).map(|(f, v)| {
                let h = 1e-6 * v.abs().max(1e-3);
                let room = [f.min.map(|a| v - a), f.max.map(|b| b - v)]
                    .into_iter()
                    .flatten()
                    .fold(f64::INFINITY, f64::min);
                if room > 0.0 { h.min(0.5 * room) } else { h }
            }),
        )
    }
}

/// Standard errors, correlations and the non-identifiable directions of a Jacobian.
struct Statistics {
    standard_errors: Vec<Option<f64>>,
    correlation: Vec<Vec<Option<f64>>>,
    /// Eigenvectors (of the unit-diagonal information matrix) with a vanishing eigenvalue.
    null_space: Vec<DVector<f64>>,
}

impl Statistics {
    /// Messages about poorly and non-identifiable parameters.
    fn warnings(&self, parameters: &Parameters) -> Vec<String> {
        let names: Vec<&str> = parameters.free.iter().map(|f| f.name).collect();
        let mut out = Vec::new();
        for v in &self.null_space {
            let involved: Vec<String> = v
                .iter()
                .enumerate()
                .filter(|(_, c)| c.abs() > 0.1)
                .map(|(k, c)| format!("{c:+.3} {}", names[k]))
                .collect();
            out.push(format!(
                "not identifiable: the data do not change along the direction {} (each parameter scaled by its \
                 sensitivity): fix one of {} or add a test that separates them (e.g. another pressure level)",
                involved.join(" "),
                v.iter()
                    .enumerate()
                    .filter(|(_, c)| c.abs() > 0.1)
                    .map(|(k, _)| names[k])
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        for i in 0..names.len() {
            for j in 0..i {
                if let Some(c) = self.correlation[i][j].filter(|c| c.abs() > CORRELATION_WARNING) {
                    out.push(format!(
                        "{} and {} are strongly correlated ({c:+.4}): the data hardly separate them",
                        names[j], names[i]
                    ));
                }
            }
        }
        out
    }
}

/// The statistics of Jacobian `jac` = ∂r/∂x at `x` with scale s² = `scale`.
fn statistics(jac: &DMatrix<f64>, scale: f64, x: &[f64]) -> Statistics {
    let p = x.len();
    let info = jac.transpose() * jac;
    // Relative scaling: unit diagonal (a zero column is itself non-identifiable).
    let d: Vec<f64> = (0..p).map(|i| info[(i, i)].sqrt()).collect();
    let mut unit = DMatrix::zeros(p, p);
    for i in 0..p {
        for j in 0..p {
            let dd = d[i] * d[j];
            unit[(i, j)] = if dd > 0.0 { info[(i, j)] / dd } else { 0.0 };
        }
    }
    let eig = SymmetricEigen::new(unit.clone());
    let largest = eig.eigenvalues.max().max(f64::MIN_POSITIVE);
    let mut null_space = Vec::new();
    let mut unidentified = vec![false; p];
    for (k, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda < SINGULAR * largest {
            let v = eig.eigenvectors.column(k).into_owned();
            for (i, c) in v.iter().enumerate() {
                unidentified[i] |= c.abs() > 0.1;
            }
            null_space.push(v);
        }
    }
    // C = s² D⁻¹ U⁻¹ D⁻¹ on the identifiable subspace (pseudo-inverse of U).
    let mut u_inv = DMatrix::zeros(p, p);
    for (k, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda >= SINGULAR * largest {
            let v = eig.eigenvectors.column(k);
            u_inv += v * v.transpose() / lambda;
        }
    }
    let standard_errors: Vec<Option<f64>> = (0..p)
        .map(|i| (!unidentified[i] && d[i] > 0.0).then(|| (scale * u_inv[(i, i)]).sqrt() / d[i]))
        .collect();
    let correlation = (0..p)
        .map(|i| {
            (0..p)
                .map(|j| {
                    let ok = !unidentified[i] && !unidentified[j];
                    ok.then(|| u_inv[(i, j)] / (u_inv[(i, i)] * u_inv[(j, j)]).sqrt())
                })
                .collect()
        })
        .collect();
    Statistics {
        standard_errors,
        correlation,
        null_space,
    }
}
