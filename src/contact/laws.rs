//! The table of interface laws: for each law its case-file name, its parameters (key, unit,
//! default, bound, documentation) and how it is built from their values. It is the one place
//! these are declared; the case file ([`crate::config`]: reading `law = { type = ..., ... }`
//! and `asperity schema`), model building and `asperity fit` all read it.
//!
//! A law's values travel as `&[f64]` in the order of its parameters, NaN standing for an
//! optional parameter that is not given (the case file's reader rejects a given NaN).

use std::sync::LazyLock;

use serde::Deserialize;

use super::InterfaceLaw;
use super::{linear, rough};
use crate::error::ParameterError;

/// Every interface law, in the order `asperity schema` lists them.
pub static LAWS: [&LawDescriptor; 2] = [&linear::LAW, &rough::LAW];

/// A law built from its parameters, or the first parameter that is wrong.
pub type Built = Result<Box<dyn InterfaceLaw>, ParameterError>;

/// An interface law as the case file and `asperity fit` know it.
#[derive(Debug)]
pub struct LawDescriptor {
    /// The case file's `type` (`law = { type = "rough_joint", ... }`) and the fit file's `law`.
    pub name: &'static str,
    /// What the law is, for `asperity schema`.
    pub doc: &'static str,
    pub parameters: &'static [ParameterDescriptor],
    /// The law at values in the order of `parameters` (NaN: an optional one not given); checks
    /// the bounds and the rules that tie parameters together.
    pub build: fn(&[f64]) -> Built,
    /// Why some given parameters have no effect at these values, if they have none (a
    /// warning for the user).
    pub unused: fn(&[f64]) -> Option<&'static str>,
}

/// One parameter of an interface law.
#[derive(Clone, Copy, Debug)]
pub struct ParameterDescriptor {
    /// The key in `law = { ... }` and in a fit file's `[parameters]`.
    pub key: &'static str,
    /// Unit (mm, MPa), empty for a number without one; shown with the bound in messages.
    pub unit: &'static str,
    pub default: ParameterDefault,
    pub bound: Bound,
    /// What the parameter is, for `asperity schema`.
    pub doc: &'static str,
}

/// Whether a parameter must be given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParameterDefault {
    /// It must be given.
    Required,
    /// This value when not given.
    Value(f64),
    /// It may be left out (NaN among the values); the law says what that means.
    Optional,
    /// A penalty stiffness (MPa/mm) that may be left out: model building then sets it from
    /// the pair's bodies and mesh (`crate::model`'s penalty default, 10 E*/h), which a law at
    /// a material point does not have. NaN among the values until then.
    Penalty,
}

/// The values a parameter may take (all of them finite).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bound {
    /// x > 0.
    Positive,
    /// x ≥ 0.
    NonNegative,
    /// 0 < x ≤ 1.
    Fraction,
}

impl Bound {
    /// Whether `x` lies within the bound.
    pub fn contains(self, x: f64) -> bool {
        x.is_finite()
            && match self {
                Bound::Positive => x > 0.0,
                Bound::NonNegative => x >= 0.0,
                Bound::Fraction => x > 0.0 && x <= 1.0,
            }
    }

    /// The message of a value out of the bound.
    fn reason(self) -> &'static str {
        match self {
            Bound::Positive => "must be positive",
            Bound::NonNegative => "must be zero or positive",
            Bound::Fraction => "must lie in (0, 1]",
        }
    }

    /// The bound as JSON-schema keywords: (lower, whether exclusive), upper.
    pub fn limits(self) -> ((f64, bool), Option<f64>) {
        match self {
            Bound::Positive => ((0.0, true), None),
            Bound::NonNegative => ((0.0, false), None),
            Bound::Fraction => ((0.0, true), Some(1.0)),
        }
    }
}

impl ParameterDescriptor {
    /// The value of a parameter not given: its default, NaN for an optional one, `None` for a
    /// required one.
    pub fn default_value(&self) -> Option<f64> {
        match self.default {
            ParameterDefault::Required => None,
            ParameterDefault::Value(v) => Some(v),
            ParameterDefault::Optional | ParameterDefault::Penalty => Some(f64::NAN),
        }
    }
}

impl LawDescriptor {
    /// The law at `values` (in the order of [`Self::parameters`]; NaN: an optional one not
    /// given). The error names the parameter.
    pub fn build(&self, values: &[f64]) -> Built {
        debug_assert_eq!(values.len(), self.parameters.len(), "{}", self.name);
        (self.build)(values)
    }

    /// Whether `values` leave a penalty stiffness to its default (NaN at a
    /// [`ParameterDefault::Penalty`] parameter).
    pub fn defaults_penalty(&self, values: &[f64]) -> bool {
        self.parameters
            .iter()
            .zip(values)
            .any(|(p, x)| p.default == ParameterDefault::Penalty && x.is_nan())
    }

    /// The keys of the penalty stiffnesses `values` leave to their default.
    pub fn defaulted_penalties(&self, values: &[f64]) -> Vec<&'static str> {
        let parameters = self.parameters.iter().zip(values);
        parameters
            .filter(|(p, x)| p.default == ParameterDefault::Penalty && x.is_nan())
            .map(|(p, _)| p.key)
            .collect()
    }

    /// `values` with every penalty stiffness left to its default set to `stiffness`.
    pub fn with_penalty(&self, values: &[f64], stiffness: f64) -> Vec<f64> {
        let parameters = self.parameters.iter().zip(values);
        parameters
            .map(|(p, &x)| match p.default {
                ParameterDefault::Penalty if x.is_nan() => stiffness,
                _ => x,
            })
            .collect()
    }

    /// The index of parameter `key`.
    pub fn index(&self, key: &str) -> Option<usize> {
        self.parameters.iter().position(|p| p.key == key)
    }
}

/// The law called `name`.
pub fn find(name: &str) -> Option<&'static LawDescriptor> {
    LAWS.iter().copied().find(|l| l.name == name)
}

/// The names of every law.
fn names() -> &'static [&'static str] {
    static NAMES: LazyLock<Vec<&'static str>> =
        LazyLock::new(|| LAWS.iter().map(|l| l.name).collect());
    &NAMES
}

/// Checks `values` against the bounds of `parameters` (in order; NaN: an optional parameter
/// not given): the first value out of its bound is the error. Every law's constructor calls
/// this, so a law cannot be built outside the bounds of its table.
pub fn check(parameters: &[ParameterDescriptor], values: &[f64]) -> Result<(), ParameterError> {
    for (p, &x) in parameters.iter().zip(values) {
        if x.is_nan() && p.default == ParameterDefault::Optional {
            continue;
        }
        if !p.bound.contains(x) {
            let reason = match p.unit {
                "" => p.bound.reason().to_string(),
                unit => format!("{} ({unit})", p.bound.reason()),
            };
            return Err(ParameterError::new(p.key, x, reason));
        }
    }
    Ok(())
}

/// How a law parameter's value shows in a message: NaN is one not given.
pub fn shown(value: f64) -> String {
    if value.is_nan() {
        return "(missing)".into();
    }
    // f64's Display writes 1e-300 (or the smallest positive double, a range's bound) in
    // full: hundreds of digits, which messages write in exponent form.
    crate::error::shorten_numbers(&value.to_string())
}

/// A law by its name (`"rough_joint"`); an unknown name lists the known ones.
impl<'de> Deserialize<'de> for &'static LawDescriptor {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        find(&name).ok_or_else(|| serde::de::Error::unknown_variant(&name, names()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_law_is_found_by_its_name_and_builds_from_its_defaults() {
        for law in LAWS {
            assert!(std::ptr::eq(find(law.name).unwrap(), law));
            // Every parameter given, at its default or at a value inside every bound (0.5).
            let values: Vec<f64> = law
                .parameters
                .iter()
                .map(|p| match p.default {
                    ParameterDefault::Value(v) => v,
                    _ => 0.5,
                })
                .collect();
            assert!(law.build(&values).is_ok(), "{}", law.name);
        }
        assert!(find("coulomb").is_none());
    }

    #[test]
    fn a_value_out_of_its_bound_names_key_bound_and_unit() {
        let p = [ParameterDescriptor {
            key: "k",
            unit: "MPa/mm",
            default: ParameterDefault::Required,
            bound: Bound::Positive,
            doc: "",
        }];
        let e = check(&p, &[0.0]).unwrap_err();
        assert_eq!(
            (e.name, e.reason.as_str()),
            ("k", "must be positive (MPa/mm)")
        );
        // NaN is not "not given" for a required parameter.
        assert!(check(&p, &[f64::NAN]).is_err());
        assert!(Bound::Fraction.contains(1.0) && !Bound::Fraction.contains(0.0));
    }
}
