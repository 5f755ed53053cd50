//! The parameters of a fit: which law, which parameters are free (with their range and scale)
//! and which are fixed, and the map between the vector z that Levenberg–Marquardt moves and
//! the law's parameters x.
//!
//! A free parameter is moved as z = x, or as z = ln x with `log = true` (for positive
//! parameters spanning decades). Its range is the closed interval of the fit file's `min` and
//! `max` within the bound of the law's own table ([`crate::contact::laws`]): x ≥ 0, x > 0 or
//! 0 < x ≤ 1, an excluded 0 becoming the smallest positive number. The optimiser, its
//! finite differences and the profiles keep z inside that range, so every law it builds is
//! valid.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::DVector;
use serde::Deserialize;

use crate::contact::InterfaceLaw;
use crate::contact::laws::{self, LawDescriptor, ParameterDescriptor};
use crate::{Error, Result};

/// One `[parameters]` entry of the fit file.
#[derive(Clone, Copy, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParameterSpec {
    /// A fixed value (the parameter is not fitted).
    pub value: Option<f64>,
    /// The starting value of a free parameter.
    pub initial: Option<f64>,
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// Fit ln x instead of x (x positive, spanning decades).
    #[serde(default)]
    pub log: bool,
}

/// How the optimiser moves a free parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// z = x.
    Linear,
    /// z = ln x.
    Log,
}

/// A free parameter.
#[derive(Clone, Debug)]
pub struct Free {
    pub name: &'static str,
    /// Index into the law's parameter list.
    pub index: usize,
    pub scale: Scale,
    /// The closed range of x (the fit file's bounds within the law's; ±∞ where neither has one).
    pub min: f64,
    pub max: f64,
    /// The fit file's starting value.
    pub initial: f64,
}

impl Free {
    /// z of value `x`.
    pub fn z(&self, x: f64) -> f64 {
        match self.scale {
            Scale::Linear => x,
            Scale::Log => x.ln(),
        }
    }

    /// The value x at `z`.
    pub fn x(&self, z: f64) -> f64 {
        match self.scale {
            Scale::Linear => z,
            Scale::Log => z.exp(),
        }
    }

    /// The closed range of z: that of x, and for a log parameter no further than e^z stays a
    /// positive finite number.
    pub fn z_range(&self) -> (f64, f64) {
        match self.scale {
            Scale::Linear => (self.min, self.max),
            Scale::Log => (
                self.min.max(f64::MIN_POSITIVE).ln(),
                self.max.min(f64::MAX).ln(),
            ),
        }
    }

    /// Whether `x` lies within 1e-6 of the range (or of |x|, for an open side) of a bound — of
    /// no more than the magnitude of x or of a nonzero bound, so that a bound far away on x's
    /// scale (`max = 1e308`) does not pass for a near one.
    pub fn at_bound(&self, x: f64) -> bool {
        let width = if (self.max - self.min).is_finite() {
            self.max - self.min
        } else {
            x.abs().max(f64::MIN_POSITIVE)
        };
        [self.min, self.max].iter().any(|&b| {
            // 0, or the smallest positive number standing for an excluded 0.
            let scale = if b.abs() <= f64::MIN_POSITIVE {
                width
            } else {
                width.min(x.abs().max(b.abs()))
            };
            b.is_finite() && (x - b).abs() <= 1e-6 * scale
        })
    }
}

/// The closed range of parameter `p` of a law: its bound, an excluded 0 replaced by the
/// smallest positive number.
fn law_range(p: &ParameterDescriptor) -> (f64, f64) {
    let ((lower, exclusive), upper) = p.bound.limits();
    let lower = if exclusive {
        lower.next_up().max(f64::MIN_POSITIVE)
    } else {
        lower
    };
    (lower, upper.unwrap_or(f64::INFINITY))
}

/// The law, its parameter values, and which of them are free.
#[derive(Clone, Debug)]
pub struct Parameters {
    pub law: &'static LawDescriptor,
    /// Every parameter's value (fixed values, defaults, and the initial values of the free
    /// ones), in the order of the law's parameters (NaN: an optional one left out).
    pub values: Vec<f64>,
    pub free: Vec<Free>,
    /// The fit file (for messages).
    pub path: PathBuf,
}

impl Parameters {
    /// Checks the `[parameters]` table of fit file `path` against `law`.
    pub fn new(
        law: &'static LawDescriptor,
        specs: &BTreeMap<String, ParameterSpec>,
        path: &Path,
    ) -> Result<Self> {
        let invalid = |key: &str, value: String, reason: String| Error::InvalidParameter {
            path: path.to_path_buf(),
            key: format!("parameters.{key}"),
            value,
            reason,
        };
        if let Some(unknown) = specs.keys().find(|k| law.index(k).is_none()) {
            let known: Vec<&str> = law.parameters.iter().map(|p| p.key).collect();
            return Err(invalid(
                unknown,
                String::new(),
                format!(
                    "not a parameter of {} (those are: {})",
                    law.name,
                    known.join(", ")
                ),
            ));
        }
        let mut values = Vec::with_capacity(law.parameters.len());
        let mut free = Vec::new();
        for (index, parameter) in law.parameters.iter().enumerate() {
            let (name, default) = (parameter.key, parameter.default_value());
            let spec = specs.get(name).copied();
            let value = match (spec, default) {
                (None, Some(d)) => d,
                (None, None) => {
                    return Err(invalid(
                        name,
                        String::new(),
                        format!(
                            "missing: {} needs it fixed (`value`) or free (`initial`)",
                            law.name
                        ),
                    ));
                }
                (Some(s), _) => match (s.value, s.initial) {
                    (Some(v), None) if s.min.is_none() && s.max.is_none() && !s.log => v,
                    (None, Some(x0)) => {
                        let f = free_parameter(parameter, index, s, x0)
                            .map_err(|r| invalid(name, x0.to_string(), r))?;
                        free.push(f);
                        x0
                    }
                    _ => {
                        return Err(invalid(
                            name,
                            String::new(),
                            "give either `value` (fixed) or `initial` with optional `min`, `max`, `log` (free)"
                                .into(),
                        ));
                    }
                },
            };
            if !(value.is_finite() || (value.is_nan() && default.is_some_and(f64::is_nan))) {
                return Err(invalid(name, value.to_string(), "must be finite".into()));
            }
            values.push(value);
        }
        if free.is_empty() {
            return Err(invalid(
                "",
                String::new(),
                "no free parameter: give at least one an `initial` value".into(),
            ));
        }
        let p = Self {
            law,
            values,
            free,
            path: path.to_path_buf(),
        };
        // The starting law must be valid; a penalty stiffness left to the specimen model's
        // default is checked with a stand-in (it stays fixed at that default).
        p.build(&law.with_penalty(&p.values, 1.0))?;
        Ok(p)
    }

    /// z of the starting values.
    pub fn start(&self) -> DVector<f64> {
        DVector::from_iterator(
            self.free.len(),
            self.free.iter().map(|f| f.z(self.values[f.index])),
        )
    }

    /// Every parameter's value at z.
    pub fn values_at(&self, z: &DVector<f64>) -> Vec<f64> {
        let mut x = self.values.clone();
        for (f, t) in self.free.iter().zip(z.iter()) {
            x[f.index] = f.x(*t);
        }
        x
    }

    /// The free parameters' values at z.
    pub fn free_values(&self, z: &DVector<f64>) -> Vec<f64> {
        self.free
            .iter()
            .zip(z.iter())
            .map(|(f, t)| f.x(*t))
            .collect()
    }

    /// The law at parameter values `x`; a value out of the law's range is an error naming the
    /// parameter in the fit file.
    pub fn build(&self, x: &[f64]) -> Result<Box<dyn InterfaceLaw>> {
        self.law.build(x).map_err(|e| Error::InvalidParameter {
            path: self.path.clone(),
            key: format!("parameters.{}", e.name),
            value: laws::shown(e.value),
            reason: e.reason,
        })
    }

    /// The paste-ready case-file line `law = { type = "...", ... }` for values `x`.
    pub fn snippet(&self, x: &[f64]) -> String {
        let items: Vec<String> = self
            .law
            .parameters
            .iter()
            .zip(x)
            .filter(|(_, v)| !v.is_nan())
            .map(|(p, v)| format!("{} = {}", p.key, toml::Value::Float(*v)))
            .collect();
        format!(
            "law = {{ type = \"{}\", {} }}",
            self.law.name,
            items.join(", ")
        )
    }
}

/// Free parameter `parameter` (number `index` of its law) starting at `x0`, or why its spec is
/// wrong.
fn free_parameter(
    parameter: &ParameterDescriptor,
    index: usize,
    s: ParameterSpec,
    x0: f64,
) -> std::result::Result<Free, String> {
    if !x0.is_finite() {
        return Err("`initial` must be finite".into());
    }
    for (key, v) in [("min", s.min), ("max", s.max)] {
        if v.is_some_and(|v| !v.is_finite()) {
            return Err(format!(
                "`{key}` must be finite (leave it out for no bound)"
            ));
        }
    }
    if let (Some(a), Some(b)) = (s.min, s.max)
        && a >= b
    {
        return Err(format!(
            "`min` = {} must be below `max` = {}",
            laws::shown(a),
            laws::shown(b)
        ));
    }
    let (law_min, law_max) = law_range(parameter);
    let (min, max) = (
        s.min.map_or(law_min, |a| a.max(law_min)),
        s.max.map_or(law_max, |b| b.min(law_max)),
    );
    if min >= max {
        return Err(format!(
            "`min`..`max` leaves no room within the law's range {}..{}",
            laws::shown(law_min),
            laws::shown(law_max)
        ));
    }
    if !(min <= x0 && x0 <= max) {
        return Err(format!(
            "`initial` must lie within {}..{} (`min`..`max` within the law's range)",
            laws::shown(min),
            laws::shown(max)
        ));
    }
    let scale = if s.log {
        if x0 <= 0.0 {
            return Err("`log = true` needs a positive `initial`".into());
        }
        Scale::Log
    } else {
        Scale::Linear
    };
    Ok(Free {
        name: parameter.key,
        index,
        scale,
        min,
        max,
        initial: x0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Near a bound means within 1e-6 of the range — and of x's magnitude when the bound is
    /// not 0: `max = 1e308` is not near 0.49.
    #[test]
    fn a_bound_is_near_on_the_scale_of_the_range_and_of_x() {
        let free = |min: f64, max: f64| Free {
            min,
            max,
            scale: Scale::Linear,
            ..free_parameter(
                &crate::contact::rough::LAW.parameters[1],
                1,
                ParameterSpec::default(),
                0.5,
            )
            .unwrap()
        };
        assert!(!free(0.05, 1e308).at_bound(0.489));
        assert!(free(0.05, 1e308).at_bound(0.05 * (1.0 + 1e-9)));
        assert!(free(0.05, 1.5).at_bound(1.5 - 1e-9));
        // A zero bound (or the excluded zero of a positive parameter) on the range's scale.
        assert!(free(0.0, 1.0).at_bound(1e-9));
        assert!(free(f64::MIN_POSITIVE, 1.0).at_bound(1e-12));
        assert!(!free(0.0, 1.0).at_bound(0.3));
    }

    /// The range of a free parameter is the fit file's bounds within the law's table: beta of
    /// the rough joint lies in (0, 1], so `min = 0` becomes the smallest positive number and a
    /// `max` above 1 becomes 1; a log parameter never reaches 0 or infinity.
    #[test]
    fn ranges_are_the_fit_files_bounds_within_the_laws() {
        let law = &crate::contact::rough::LAW;
        let beta = &law.parameters[law.index("beta").unwrap()];
        let spec = ParameterSpec {
            min: Some(0.0),
            max: Some(3.0),
            ..Default::default()
        };
        let f = free_parameter(beta, 7, spec, 0.5).unwrap();
        assert_eq!((f.min, f.max), (f64::MIN_POSITIVE, 1.0));
        assert!(
            law.build(&[
                2e-3,
                0.5,
                f64::NAN,
                f64::NAN,
                1e-3,
                0.5,
                0.3,
                f.min,
                0.0,
                0.1
            ])
            .is_ok()
        );
        let c_n = &law.parameters[0];
        let log = ParameterSpec {
            log: true,
            ..Default::default()
        };
        let f = free_parameter(c_n, 0, log, 2e-3).unwrap();
        let (lo, hi) = f.z_range();
        assert!(f.x(lo) > 0.0 && f.x(hi).is_finite());
        assert!((f.x(f.z(2e-3)) - 2e-3).abs() < 1e-18);
        // A start outside the law's range, and bounds that leave no room.
        assert!(free_parameter(beta, 7, ParameterSpec::default(), 1.5).is_err());
        let above = ParameterSpec {
            min: Some(1.0),
            ..Default::default()
        };
        assert!(free_parameter(beta, 7, above, 1.0).is_err());
    }

    #[test]
    fn snippet_parses_as_a_case_law() {
        let mut specs = BTreeMap::new();
        for (k, v) in [
            ("c_n", 2e-3),
            ("m", 0.5),
            ("R", 1e-3),
            ("S", 0.5),
            ("mu_m", 0.3),
        ] {
            let spec = ParameterSpec {
                value: Some(v),
                ..Default::default()
            };
            specs.insert(k.to_string(), spec);
        }
        specs.get_mut("m").unwrap().value = None;
        specs.get_mut("m").unwrap().initial = Some(0.5);
        let law = &crate::contact::rough::LAW;
        let p = Parameters::new(law, &specs, Path::new("f.toml")).unwrap();
        let line = p.snippet(&p.values);
        let table: toml::Table = toml::from_str(&line).unwrap();
        let spec: crate::config::LawSpec = table["law"].clone().try_into().unwrap();
        assert_eq!(spec.law.name, "rough_joint", "{line}");
        let values = ["c_n", "m", "S", "beta"].map(|k| spec.get(k));
        assert_eq!(values, [Some(2e-3), Some(0.5), Some(0.5), Some(1.0)]);
    }
}
