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
mod driver;
pub mod experiment;
pub mod lm;
pub mod params;
pub mod profile;
mod report;
mod result;
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
pub use result::{Curve, Estimate, FitResult, FixedPenalty, Outcome, Start, Starts, Verdict};

use crate::{Error, Result};

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
