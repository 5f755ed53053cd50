//! What a fit reports ([`FitResult`]): each parameter's value and verdict with its
//! intervals, the starts, the curves at the optimum, and the warnings of a parameter the
//! data do not identify.

use std::path::PathBuf;

use super::profile::{self, Side};
use super::{lm, params};
use crate::model::PenaltyDefault;

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
    /// χ² within [`SAME_MINIMUM`](super::SAME_MINIMUM) of the best.
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
    /// [`SAME_MINIMUM`](super::SAME_MINIMUM), in units of s².
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

/// The warning of a free parameter that is not identified: what its profile shows.
pub(super) fn verdict_warning(
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
