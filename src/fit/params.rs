//! The parameters of a fit: which law, which parameters are free (with bounds or a log
//! transform) and which are fixed, and the map between the unconstrained vector θ that
//! Levenberg–Marquardt moves and the law's parameters x.
//!
//! Transforms keep x inside its bounds whatever θ is: x = a + (b − a)(1 + tanh θ)/2 between
//! two bounds, x = a + e^θ above a lower bound, x = b − e^θ below an upper one, x = e^θ with
//! `log = true`, and x = θ without bounds (then a step that leaves the law's range is an
//! error telling the user to give bounds).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::DVector;
use serde::Deserialize;

use crate::contact::InterfaceLaw;
use crate::contact::laws::{self, LawDescriptor};
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
    /// Fit ln x instead of x (keeps x positive).
    #[serde(default)]
    pub log: bool,
}

/// How a free parameter's x follows from θ.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Transform {
    Linear,
    Log,
    Above(f64),
    Below(f64),
    Between(f64, f64),
}

impl Transform {
    fn x(self, t: f64) -> f64 {
        match self {
            Transform::Linear => t,
            Transform::Log => t.exp(),
            Transform::Above(a) => a + t.exp(),
            Transform::Below(b) => b - t.exp(),
            Transform::Between(a, b) => a + 0.5 * (b - a) * (1.0 + t.tanh()),
        }
    }

    fn theta(self, x: f64) -> f64 {
        match self {
            Transform::Linear => x,
            Transform::Log => x.ln(),
            Transform::Above(a) => (x - a).ln(),
            Transform::Below(b) => (b - x).ln(),
            Transform::Between(a, b) => (2.0 * (x - a) / (b - a) - 1.0).atanh(),
        }
    }
}

/// A free parameter.
#[derive(Clone, Debug)]
pub struct Free {
    pub name: &'static str,
    /// Index into the law's parameter list.
    pub index: usize,
    pub min: Option<f64>,
    pub max: Option<f64>,
    transform: Transform,
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
                        let transform =
                            transform(name, s, x0).map_err(|r| invalid(name, x0.to_string(), r))?;
                        free.push(Free {
                            name,
                            index,
                            min: s.min,
                            max: s.max,
                            transform,
                        });
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
        p.build(&p.values)?; // the starting law must be valid
        Ok(p)
    }

    /// θ of the starting values.
    pub fn start(&self) -> DVector<f64> {
        DVector::from_iterator(
            self.free.len(),
            self.free
                .iter()
                .map(|f| f.transform.theta(self.values[f.index])),
        )
    }

    /// Every parameter's value at θ.
    pub fn values_at(&self, theta: &DVector<f64>) -> Vec<f64> {
        let mut x = self.values.clone();
        for (f, t) in self.free.iter().zip(theta.iter()) {
            x[f.index] = f.transform.x(*t);
        }
        x
    }

    /// Every parameter's value with the free ones set to `free`.
    pub fn with_free(&self, free: &[f64]) -> Vec<f64> {
        let mut x = self.values.clone();
        for (f, v) in self.free.iter().zip(free) {
            x[f.index] = *v;
        }
        x
    }

    /// The law at parameter values `x`; a value out of the law's range is an error naming the
    /// parameter in the fit file.
    pub fn build(&self, x: &[f64]) -> Result<Box<dyn InterfaceLaw>> {
        self.law.build(x).map_err(|e| {
            let hint = match self.free.iter().find(|f| f.name == e.name) {
                Some(f) if f.transform == Transform::Linear => {
                    "; the fit moved this unbounded parameter out of the law's range: give it bounds \
                     (`min`, `max`) or `log = true`"
                }
                _ => "",
            };
            Error::InvalidParameter {
                path: self.path.clone(),
                key: format!("parameters.{}", e.name),
                value: laws::shown(e.value),
                reason: format!("{}{hint}", e.reason),
            }
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

/// The transform of free parameter `name` starting at `x0`, or why its spec is wrong.
fn transform(name: &str, s: ParameterSpec, x0: f64) -> std::result::Result<Transform, String> {
    if !x0.is_finite() {
        return Err("`initial` must be finite".into());
    }
    let t = match (s.min, s.max, s.log) {
        (_, _, true) if s.min.is_some() || s.max.is_some() => {
            return Err(format!("{name}: give `log = true` or bounds, not both"));
        }
        (None, None, true) if x0 > 0.0 => Transform::Log,
        (None, None, true) => return Err("`log = true` needs a positive `initial`".into()),
        (None, None, false) => Transform::Linear,
        (Some(a), None, _) => Transform::Above(a),
        (None, Some(b), _) => Transform::Below(b),
        (Some(a), Some(b), _) if a < b => Transform::Between(a, b),
        (Some(a), Some(b), _) => return Err(format!("`min` = {a} must be below `max` = {b}")),
    };
    let inside = match t {
        Transform::Above(a) => x0 > a,
        Transform::Below(b) => x0 < b,
        Transform::Between(a, b) => x0 > a && x0 < b,
        _ => true,
    };
    if !inside {
        return Err("`initial` must lie strictly inside `min`..`max`".into());
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transforms_round_trip_and_respect_bounds() {
        for (t, x) in [
            (Transform::Linear, -0.3),
            (Transform::Log, 2e-3),
            (Transform::Above(0.1), 0.5),
            (Transform::Below(1.0), 0.2),
            (Transform::Between(0.0, 2.0), 0.3),
        ] {
            assert!((t.x(t.theta(x)) - x).abs() < 1e-14, "{t:?}");
        }
        let b = Transform::Between(0.0, 2.0);
        assert!(b.x(-40.0) >= 0.0 && b.x(40.0) <= 2.0);
        assert!(Transform::Above(0.1).x(-800.0) >= 0.1);
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
