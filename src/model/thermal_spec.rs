//! The thermal entries of a case as the model takes them: uniform body temperatures,
//! thermal supports and heat sources with their histories.

use super::History;
use super::spec::history;
use crate::config::{Case, Role};
use crate::thermal::ThermalCondition;

/// A uniform temperature change of a body at multiplier 1 (`[[temperature]]`).
#[derive(Clone, Debug, PartialEq)]
pub struct BodyTemperature {
    pub group: String,
    pub change: f64,
    pub factors: History,
}

/// A thermal support on a curve (`[[thermal_support]]`).
#[derive(Clone, Debug, PartialEq)]
pub struct ThermalBoundary {
    pub name: String,
    pub group: String,
    pub condition: ThermalCondition,
    pub factors: History,
}

/// A heat source in a body (`[[heat_source]]`).
#[derive(Clone, Debug, PartialEq)]
pub struct BodyHeatSource {
    pub name: String,
    pub group: String,
    pub power: f64,
    pub factors: History,
}

/// The thermal entries of a case.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ThermalSpec {
    pub temperatures: Vec<BodyTemperature>,
    pub supports: Vec<ThermalBoundary>,
    pub sources: Vec<BodyHeatSource>,
}

/// The thermal entries of `case` with their histories (`[[step]] thermal`, or the global
/// load factor).
pub(super) fn thermal(case: &Case) -> ThermalSpec {
    let factors =
        |name: &str, own: &Option<Vec<f64>>| history(case, Role::Thermal, name, own.as_deref());
    ThermalSpec {
        temperatures: case
            .temperatures
            .iter()
            .map(|t| BodyTemperature {
                group: t.group.clone(),
                change: t.change,
                factors: factors(t.name(), &t.factors),
            })
            .collect(),
        supports: case
            .thermal_supports
            .iter()
            .map(|s| ThermalBoundary {
                name: s.name().to_string(),
                group: s.group.clone(),
                condition: match (s.temperature, s.flux, s.film) {
                    (Some(t), _, _) => ThermalCondition::Temperature(t),
                    (None, Some(q), _) => ThermalCondition::Flux(q),
                    (None, None, Some(f)) => ThermalCondition::Film {
                        h: f.h,
                        ambient: f.ambient,
                    },
                    (None, None, None) => ThermalCondition::Flux(0.0),
                },
                factors: factors(s.name(), &s.factors),
            })
            .collect(),
        sources: case
            .heat_sources
            .iter()
            .map(|h| BodyHeatSource {
                name: h.name().to_string(),
                group: h.group.clone(),
                power: h.power,
                factors: factors(h.name(), &h.factors),
            })
            .collect(),
    }
}
