//! The tests a fit compares with, and how each is simulated:
//!
//! - **normal**: a flat joint under uniform pressure, loaded and unloaded. The measured closure
//!   (approach of the faces, column `closure`) drives the law point by point, in the order of the
//!   file, and the pressure it gives (paper Eqs. 1–2, with the unloading branch after the
//!   largest closure) is compared with column `pressure`.
//! - **tangential**: the joint first closed to the constant normal `pressure` of the test (the
//!   closure found by bisection on the law's normal response), then sheared through the
//!   measured tangential displacements (column `displacement`, monotonic or cyclic); the
//!   shear stress (Eqs. 3–5, return map) is compared with column `shear`.
//! - **model**: a full case file of a specimen; see the `specimen` module.
//!
//! Each residual is (simulated − measured) / σ with σ = `error` + `relative_error` · |measured|.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::data::{Dimension, Table};
use super::specimen::Specimen;
use crate::contact::laws::LawDescriptor;
use crate::contact::{InterfaceLaw, InterfaceState};
use crate::{Error, Result};

/// One `[[test]]` of the fit file.
#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum TestSpec {
    Normal {
        data: PathBuf,
        error: Option<f64>,
        relative_error: Option<f64>,
    },
    Tangential {
        data: PathBuf,
        /// The constant normal pressure in MPa.
        pressure: f64,
        error: Option<f64>,
        relative_error: Option<f64>,
    },
    Model {
        /// The specimen's case file.
        case: PathBuf,
        /// Index of the `[[contact]]` whose law is fitted.
        #[serde(default)]
        contact: usize,
        /// Columns `step` and `value`.
        data: PathBuf,
        /// Dotted path into a step of `summary.json`, e.g. `reactions.top.y`.
        quantity: String,
        error: Option<f64>,
        relative_error: Option<f64>,
    },
}

/// What a test simulates.
#[derive(Debug)]
pub enum Kind {
    /// Closures (mm) in order.
    Normal {
        closure: Vec<f64>,
    },
    /// Constant pressure (MPa) and tangential displacements (mm).
    Tangential {
        pressure: f64,
        displacement: Vec<f64>,
    },
    Model(Box<Specimen>),
}

/// A test with its measured responses and their standard deviations.
#[derive(Debug)]
pub struct Experiment {
    /// `test[i] (kind, file)`, for messages and plots.
    pub label: String,
    pub kind: Kind,
    /// The controlled quantity per point (for plots): closure, displacement or step.
    pub x: Vec<f64>,
    pub measured: Vec<f64>,
    pub sigma: Vec<f64>,
    /// Whether the file states measurement errors (else σ = 1 and the scale is estimated).
    pub stated: bool,
    /// The data file, the compared column and the file line of each point (for messages).
    pub data: PathBuf,
    pub column: &'static str,
    pub lines: Vec<usize>,
}

impl Experiment {
    /// Reads test `i` of fit file `path` (relative paths relative to its folder).
    pub fn read(spec: &TestSpec, i: usize, path: &Path) -> Result<Self> {
        let dir = path.parent().unwrap_or(Path::new(""));
        let invalid = |key: &str, value: f64, reason: &str| Error::InvalidParameter {
            path: path.to_path_buf(),
            key: format!("test[{i}].{key}"),
            value: value.to_string(),
            reason: reason.into(),
        };
        let (data, error, relative) = match spec {
            TestSpec::Normal {
                data,
                error,
                relative_error,
            }
            | TestSpec::Tangential {
                data,
                error,
                relative_error,
                ..
            }
            | TestSpec::Model {
                data,
                error,
                relative_error,
                ..
            } => (dir.join(data), *error, *relative_error),
        };
        for (key, v) in [("error", error), ("relative_error", relative)] {
            if let Some(v) = v.filter(|v| !(v.is_finite() && *v >= 0.0)) {
                return Err(invalid(key, v, "must be zero or positive"));
            }
        }
        let table = Table::read(&data)?;
        let (kind, x, measured, name, column) = match spec {
            TestSpec::Normal { .. } => {
                let closure = table.column("closure", Dimension::Length)?;
                let measured = table.column("pressure", Dimension::Stress)?;
                (
                    Kind::Normal {
                        closure: closure.clone(),
                    },
                    closure,
                    measured,
                    "normal",
                    "pressure",
                )
            }
            TestSpec::Tangential { pressure, .. } => {
                if !(pressure.is_finite() && *pressure > 0.0) {
                    return Err(invalid("pressure", *pressure, "must be positive (MPa)"));
                }
                let displacement = table.column("displacement", Dimension::Length)?;
                let measured = table.column("shear", Dimension::Stress)?;
                let kind = Kind::Tangential {
                    pressure: *pressure,
                    displacement: displacement.clone(),
                };
                (kind, displacement, measured, "tangential", "shear")
            }
            TestSpec::Model {
                case,
                contact,
                quantity,
                ..
            } => {
                let steps = table.column("step", Dimension::Number)?;
                let measured = table.column("value", Dimension::Number)?;
                let specimen =
                    Specimen::new(&dir.join(case), *contact, quantity, &steps, &table.path)?;
                (
                    Kind::Model(Box::new(specimen)),
                    steps,
                    measured,
                    "model",
                    "value",
                )
            }
        };
        let sigma: Vec<f64> = measured
            .iter()
            .map(|y| error.unwrap_or(0.0) + relative.unwrap_or(0.0) * y.abs())
            .collect();
        let stated = error.is_some() || relative.is_some();
        if let Some(k) = sigma.iter().position(|s| stated && *s <= 0.0) {
            return Err(Error::InvalidParameter {
                path: path.to_path_buf(),
                key: format!("test[{i}].error"),
                value: "0".into(),
                reason: format!(
                    "the error of row {} of {} is zero (a zero measured value with only a relative error): give \
                     an absolute `error` as well",
                    k + 1,
                    data.display()
                ),
            });
        }
        Ok(Self {
            label: format!("test[{i}] {name} ({})", data.display()),
            kind,
            x,
            measured,
            sigma: if stated {
                sigma
            } else {
                vec![1.0; table.len()]
            },
            stated,
            lines: table.lines().to_vec(),
            data,
            column,
        })
    }

    /// The simulated responses with `law` (a model test gets the law's table entry `kind` and
    /// parameter values `x`).
    /// `law` is the law at `x`, given whenever some test is [at a point](Self::at_a_point).
    pub fn simulate(
        &self,
        law: Option<&dyn InterfaceLaw>,
        kind: &LawDescriptor,
        x: &[f64],
    ) -> Result<Vec<f64>> {
        let law = || law.expect("the caller builds the law for a test at a material point");
        Ok(match &self.kind {
            Kind::Normal { closure } => normal(law(), closure),
            Kind::Tangential {
                pressure,
                displacement,
            } => tangential(law(), *pressure, displacement),
            Kind::Model(specimen) => specimen.simulate(x, kind)?,
        })
    }

    /// Whether the test evaluates the law at a material point (not through a model).
    pub fn at_a_point(&self) -> bool {
        !matches!(self.kind, Kind::Model(_))
    }
}

/// Checks that χ² of `experiments` (with `points` points in all) cannot overflow: each
/// weighted measured value |y/σ| must stay below √(f64::MAX / 4·points), so that a residual
/// (f − y)/σ with |f| ≤ |y| squared and summed remains finite. A value beyond names the file,
/// the column and the line.
pub fn check_sum_of_squares(experiments: &[Experiment], points: usize) -> Result<()> {
    let limit = (f64::MAX / (4.0 * points as f64)).sqrt();
    for e in experiments {
        let row = e
            .measured
            .iter()
            .zip(&e.sigma)
            .position(|(y, s)| (y / s).abs() >= limit || (y / s).is_nan());
        if let Some(k) = row {
            return Err(Error::InvalidParameter {
                path: e.data.clone(),
                key: format!("column '{}', line {}", e.column, e.lines[k]),
                value: e.measured[k].to_string(),
                reason: format!(
                    "too large for a fit: divided by its error {} it exceeds {limit:.3e}, and its square would \
                     overflow the sum of squares; check the column's unit and the test's `error`",
                    e.sigma[k]
                ),
            });
        }
    }
    Ok(())
}

/// Pressures along a closure history (no shear).
pub fn normal(law: &dyn InterfaceLaw, closure: &[f64]) -> Vec<f64> {
    let mut state = InterfaceState::default();
    closure
        .iter()
        .map(|c| {
            state = law.update([0.0, -c, 0.0], &state).0;
            -state.stress[1]
        })
        .collect()
}

/// Shear stresses along a tangential displacement history at constant `pressure`.
pub fn tangential(law: &dyn InterfaceLaw, pressure: f64, displacement: &[f64]) -> Vec<f64> {
    let closure = closure_at(law, pressure);
    let mut state = law
        .update([0.0, -closure, 0.0], &InterfaceState::default())
        .0;
    displacement
        .iter()
        .map(|u| {
            state = law.update([*u, -closure, 0.0], &state).0;
            state.stress[0]
        })
        .collect()
}

/// The closure at which `law`, loaded from the open state, carries `pressure`: bisection on
/// the (monotonic) first-loading response, to round-off.
fn closure_at(law: &dyn InterfaceLaw, pressure: f64) -> f64 {
    let p = |c: f64| {
        -law.update([0.0, -c, 0.0], &InterfaceState::default())
            .0
            .stress[1]
    };
    let mut hi = 1e-6;
    while p(hi) < pressure && hi < 1e6 {
        hi *= 2.0;
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if p(mid) < pressure {
            lo = mid
        } else {
            hi = mid
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::rough::RoughJoint;

    fn joint() -> RoughJoint {
        RoughJoint::new(RoughJoint {
            c_n: 2e-3,
            m: 0.5,
            unloading: None,
            r: 2e-3,
            s: 0.5,
            mu_m: 0.3,
            beta: 0.6,
            n: 50.0,
            starting_pressure: 0.1,
        })
        .unwrap()
    }

    /// Loading follows the closed form p = (c/c_N)^(1/m) (paper Eq. 1).
    #[test]
    fn normal_curve_is_the_power_law() {
        let p = normal(&joint(), &[1e-3, 4e-3, 8e-3]);
        for (c, p) in [1e-3, 4e-3, 8e-3].iter().zip(p) {
            assert!((p - (c / 2e-3f64).powi(2)).abs() < 1e-12 * p);
        }
    }

    /// Monotonic shear at constant pressure: stick with k_T = (p² + p₀²)^(S/2)/R (Eq. 3), then
    /// slip at μ_F(ū) p with μ_F from Eq. 4 and ū the slip beyond the elastic part.
    #[test]
    fn tangential_curve_sticks_then_slips_at_the_hardening_friction() {
        let law = joint();
        let p = 10.0;
        let kt = (p * p + 0.01f64).powf(0.25) / 2e-3;
        let t = tangential(&law, p, &[1e-4, 0.05]);
        assert!(
            (t[0] - kt * 1e-4).abs() < 1e-9 * t[0],
            "{} vs {}",
            t[0],
            kt * 1e-4
        );
        // In slip: p_T = μ_F(ū) p with ū = u_T − p_T/k_T; solve that for p_T by iteration.
        let mut pt = 0.3 * p;
        for _ in 0..100 {
            let slip = 0.05 - pt / kt;
            pt = 0.3 * (1.0 - 0.4 * (-50.0 * slip).exp()) * p;
        }
        assert!((t[1] - pt).abs() < 1e-9 * pt, "{} vs {pt}", t[1]);
    }
}
