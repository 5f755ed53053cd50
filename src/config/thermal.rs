//! Temperature in the case file: uniform body temperatures (`[[temperature]]`), the steady
//! heat conduction's supports (`[[thermal_support]]`) and sources (`[[heat_source]]`), and a
//! contact pair's joint conductance (`[[contact]] conductance`). Plain data with its checks;
//! [`crate::model::ModelSpec`] turns it into the model's thermal part. Temperatures are
//! changes from the stress-free reference (K, or °C: only differences enter); heat in W,
//! lengths in mm, so conductivity is W/(mm·K), fluxes W/mm², conductances W/(mm²·K).
//!
//! Every entry has a `name` (default: its group) that `[[step]]` tables name in `thermal`
//! (`thermal = { hub = 1.0 }`): its value (ΔT, the support's temperature, flux or ambient
//! temperature, the source's power) scales with that history like a load's magnitude; with
//! `[steps]` it follows the global load factor, or its own `factors` (one per step) as a
//! load's. A film's h never scales.

use schemars::JsonSchema;
use serde::Deserialize;

use super::Case;
use crate::Result;

/// A uniform temperature change of a body from the stress-free reference (`[[temperature]]`),
/// at load factor 1. Its thermal strain is α ΔT with the body's `material.expansion`.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TemperatureSpec {
    /// Name the `[[step]]` tables use (default: the group); unique among the thermal entries.
    pub name: Option<String>,
    /// Name of a body (physical surface of a `[[body]]`).
    pub group: String,
    /// Temperature change ΔT in K (or °C).
    pub change: f64,
    /// This entry's own history with `[steps]`: one factor per step (default: the `[steps]`
    /// factors), as a load's `factors`. With `[[step]]` name it in the steps' `thermal`.
    pub factors: Option<Vec<f64>>,
}

/// A boundary condition of the heat conduction on a physical curve (`[[thermal_support]]`):
/// exactly one of `temperature`, `flux` and `film`.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ThermalSupportSpec {
    /// Name the `[[step]]` tables use and `history.csv` shows (default: the group); unique
    /// among the thermal entries.
    pub name: Option<String>,
    /// Name of a physical curve on a conducting body.
    pub group: String,
    /// Prescribed temperature change in K (or °C) from the reference.
    pub temperature: Option<f64>,
    /// Prescribed heat flux in W/mm², positive into the body (as Abaqus' *DFLUX).
    pub flux: Option<f64>,
    /// Convection to an ambient temperature: q = h (T_ambient − T) into the body.
    pub film: Option<FilmSpec>,
    /// This entry's own history with `[steps]`: one factor per step (default: the `[steps]`
    /// factors), as a load's `factors`. With `[[step]]` name it in the steps' `thermal`.
    pub factors: Option<Vec<f64>>,
}

/// A film condition: film coefficient and ambient (sink) temperature.
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FilmSpec {
    /// Film coefficient h in W/(mm²·K), positive. It does not scale with the history.
    pub h: f64,
    /// Ambient temperature change in K (or °C) from the reference (default 0); scales with
    /// the history.
    #[serde(default)]
    pub ambient: f64,
}

/// A uniform volumetric heat source in a body (`[[heat_source]]`).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HeatSourceSpec {
    /// Name the `[[step]]` tables use (default: the group); unique among the thermal entries.
    pub name: Option<String>,
    /// Name of a conducting body.
    pub group: String,
    /// Power per volume in W/mm³.
    pub power: f64,
    /// This entry's own history with `[steps]`: one factor per step (default: the `[steps]`
    /// factors), as a load's `factors`. With `[[step]]` name it in the steps' `thermal`.
    pub factors: Option<Vec<f64>>,
}

/// The joint conductance of a contact pair (`[[contact]] conductance`): a number h in
/// W/(mm²·K), or `{ h0 = ..., exponent = ... }` for the rough joint's h = h0 (|p|/1 MPa)^n,
/// or `{ h = ..., gap = ... }`. Heat crosses closed points with h and open points with the
/// `gap` conductance (default 0: no conduction across an open joint). The flux from side A
/// to side B is h (T_A − T_B).
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum ConductanceSpec {
    /// Constant conductance of closed points, W/(mm²·K).
    Constant(f64),
    /// The table form.
    Table(ConductanceTable),
}

/// The table form of [`ConductanceSpec`]: `h`, or `h0` with `exponent`; optional `gap`.
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConductanceTable {
    /// Constant conductance of closed points, W/(mm²·K).
    pub h: Option<f64>,
    /// Conductance at a contact pressure of 1 MPa, W/(mm²·K).
    pub h0: Option<f64>,
    /// Exponent n of h = h0 (|p|/1 MPa)^n (≥ 0).
    pub exponent: Option<f64>,
    /// Conductance of open points (gas or radiation across the gap), W/(mm²·K); default 0.
    pub gap: Option<f64>,
}

/// A checked joint conductance: h of closed points as h0 (|p|/1 MPa)^n (n = 0 for a
/// constant), and the gap conductance of open points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductance {
    pub h0: f64,
    pub exponent: f64,
    pub gap: f64,
}

impl ConductanceSpec {
    /// The conductance, or what is wrong: (the key's part below `conductance` as written,
    /// such as `.h0`, or empty for the conductance as a whole; the value shown; the reason).
    pub fn conductance(&self) -> std::result::Result<Conductance, (String, String, String)> {
        let (h_key, h0, exponent, gap) = match *self {
            ConductanceSpec::Constant(h) => ("", h, 0.0, 0.0),
            ConductanceSpec::Table(t) => match (t.h, t.h0, t.exponent) {
                (Some(h), None, None) => (".h", h, 0.0, t.gap.unwrap_or(0.0)),
                (None, Some(h0), Some(n)) => (".h0", h0, n, t.gap.unwrap_or(0.0)),
                _ => {
                    return Err((
                        String::new(),
                        "{…}".into(),
                        "give either `h` or both `h0` and `exponent`".into(),
                    ));
                }
            },
        };
        for (key, value) in [(h_key, h0), (".exponent", exponent), (".gap", gap)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err((
                    key.into(),
                    value.to_string(),
                    "must be finite and ≥ 0".into(),
                ));
            }
        }
        if h0 == 0.0 && gap == 0.0 {
            return Err((
                h_key.into(),
                h0.to_string(),
                "a joint without conductance (h and gap both 0) carries no heat: omit \
                 `conductance`"
                    .into(),
            ));
        }
        Ok(Conductance { h0, exponent, gap })
    }
}

impl TemperatureSpec {
    /// The entry's name: `name`, else its group.
    pub fn name(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.group)
    }
}

impl ThermalSupportSpec {
    /// The entry's name: `name`, else its group.
    pub fn name(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.group)
    }

    /// The value its history scales: temperature, flux or ambient temperature.
    pub fn value(&self) -> f64 {
        self.temperature
            .or(self.flux)
            .or(self.film.map(|f| f.ambient))
            .unwrap_or(0.0)
    }
}

impl HeatSourceSpec {
    /// The entry's name: `name`, else its group.
    pub fn name(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.group)
    }
}

impl Case {
    /// The thermal entries' names and the values their histories scale, in case order:
    /// temperatures, thermal supports, heat sources (the `[[step]] thermal` names).
    pub fn thermal_names(&self) -> impl Iterator<Item = (&str, f64)> {
        let t = self.temperatures.iter().map(|t| (t.name(), t.change));
        let s = self.thermal_supports.iter().map(|s| (s.name(), s.value()));
        let h = self.heat_sources.iter().map(|h| (h.name(), h.power));
        t.chain(s).chain(h)
    }

    /// The thermal entries' case-file keys (`temperature[0]`, `thermal_support[1]`,
    /// `heat_source[0]`), in the order of [`Case::thermal_names`].
    pub fn thermal_keys(&self) -> impl Iterator<Item = String> {
        let t = (0..self.temperatures.len()).map(|i| format!("temperature[{i}]"));
        let s = (0..self.thermal_supports.len()).map(|i| format!("thermal_support[{i}]"));
        let h = (0..self.heat_sources.len()).map(|i| format!("heat_source[{i}]"));
        t.chain(s).chain(h)
    }

    /// The thermal entries' own `[steps]` factors with their case-file keys, in the order of
    /// [`Case::thermal_names`].
    fn thermal_factors(&self) -> impl Iterator<Item = (String, Option<&Vec<f64>>)> {
        let t = self.temperatures.iter().enumerate();
        let t = t.map(|(i, t)| (format!("temperature[{i}].factors"), t.factors.as_ref()));
        let s = self.thermal_supports.iter().enumerate();
        let s = s.map(|(i, s)| (format!("thermal_support[{i}].factors"), s.factors.as_ref()));
        let h = self.heat_sources.iter().enumerate();
        let h = h.map(|(i, h)| (format!("heat_source[{i}].factors"), h.factors.as_ref()));
        t.chain(s).chain(h)
    }

    /// Own `factors` of the thermal entries: one finite value per `[steps]` step, and none
    /// with `[[step]]` (whose `thermal` tables give the histories).
    fn check_thermal_factors(&self) -> Result<()> {
        let steps = self.steps.len();
        for (key, factors) in self.thermal_factors() {
            let Some(f) = factors else { continue };
            if self.has_analysis_steps() {
                return Err(self.invalid(
                    key,
                    format!("{f:?}"),
                    "per-entry factors belong to [steps]; with [[step]] give the history in \
                     the steps' `thermal` tables",
                ));
            }
            if f.len() != steps || f.iter().any(|x| !x.is_finite()) {
                return Err(self.invalid(
                    key,
                    format!("{f:?}"),
                    format!("needs one finite value per step ({steps}), got {}", f.len()),
                ));
            }
        }
        Ok(())
    }

    /// Whether some body conducts heat (`conductivity`).
    pub fn has_conduction(&self) -> bool {
        self.bodies.iter().any(|b| b.conductivity.is_some())
    }

    /// `expansion`, `conductivity`, `[[temperature]]`, `[[thermal_support]]`,
    /// `[[heat_source]]` and `conductance`: finite values in range, known conducting bodies,
    /// exactly one condition per thermal support, and no body both given a uniform temperature
    /// and conducting.
    pub(super) fn check_thermal(&self) -> Result<()> {
        self.check_thermal_factors()?;
        for (i, b) in self.bodies.iter().enumerate() {
            if let Some(a) = b.material.expansion.filter(|a| !a.is_finite()) {
                return Err(self.invalid(
                    format!("body[{i}].material.expansion"),
                    a,
                    format!("must be finite (body '{}')", b.group),
                ));
            }
            if let Some(k) = b.conductivity.filter(|k| !(k.is_finite() && *k > 0.0)) {
                return Err(self.invalid(
                    format!("body[{i}].conductivity"),
                    k,
                    format!("must be positive and finite (body '{}')", b.group),
                ));
            }
        }
        let body = |group: &str| self.bodies.iter().find(|b| b.group == group);
        for (i, t) in self.temperatures.iter().enumerate() {
            let key = format!("temperature[{i}]");
            if !t.change.is_finite() {
                return Err(self.invalid(format!("{key}.change"), t.change, "must be finite"));
            }
            match body(&t.group) {
                None => {
                    return Err(self.invalid(
                        format!("{key}.group"),
                        format!("{:?}", t.group),
                        "is no [[body]]: a uniform temperature belongs to a body",
                    ));
                }
                Some(b) if b.conductivity.is_some() => {
                    return Err(self.invalid(
                        format!("{key}.group"),
                        format!("{:?}", t.group),
                        "this body conducts heat (`conductivity`), so its temperature comes \
                         from the conduction solve: remove the [[temperature]] entry or the \
                         conductivity",
                    ));
                }
                Some(_) => {}
            }
            if let Some(j) = self.temperatures[..i]
                .iter()
                .position(|o| o.group == t.group)
            {
                return Err(self.invalid(
                    format!("{key}.group"),
                    format!("{:?}", t.group),
                    format!("temperature[{j}] gives this body a temperature already"),
                ));
            }
        }
        let thermal = !self.temperatures.is_empty() || self.has_conduction();
        if thermal && self.steps.control == super::ControlKind::ArcLength {
            return Err(self.invalid(
                "steps.control",
                "\"arc_length\"",
                "arc-length control drives forces and pressures only; temperatures \
                 ([[temperature]], conduction) need load control",
            ));
        }
        let thermal_entries = !self.thermal_supports.is_empty() || !self.heat_sources.is_empty();
        if thermal_entries && !self.has_conduction() {
            return Err(self.error(
                "[[thermal_support]] and [[heat_source]] need a conducting body: give a \
                 [[body]] `conductivity` (W/(mm·K))",
            ));
        }
        for (i, s) in self.thermal_supports.iter().enumerate() {
            let key = format!("thermal_support[{i}]");
            let given = [s.temperature.is_some(), s.flux.is_some(), s.film.is_some()];
            if given.iter().filter(|g| **g).count() != 1 {
                return Err(self.error(format!(
                    "[[thermal_support]] '{}': give exactly one of `temperature`, `flux` and \
                     `film`",
                    s.name()
                )));
            }
            let values = [
                ("temperature", s.temperature),
                ("flux", s.flux),
                ("film.ambient", s.film.map(|f| f.ambient)),
            ];
            for (k, v) in values {
                if let Some(v) = v.filter(|v| !v.is_finite()) {
                    return Err(self.invalid(format!("{key}.{k}"), v, "must be finite"));
                }
            }
            if let Some(h) = s.film.map(|f| f.h).filter(|h| !(h.is_finite() && *h > 0.0)) {
                return Err(self.invalid(
                    format!("{key}.film.h"),
                    h,
                    "must be positive and finite",
                ));
            }
        }
        for (i, h) in self.heat_sources.iter().enumerate() {
            let key = format!("heat_source[{i}]");
            if !h.power.is_finite() {
                return Err(self.invalid(format!("{key}.power"), h.power, "must be finite"));
            }
            if body(&h.group).is_none_or(|b| b.conductivity.is_none()) {
                return Err(self.invalid(
                    format!("{key}.group"),
                    format!("{:?}", h.group),
                    "is no [[body]] with `conductivity`: a heat source belongs to a \
                     conducting body",
                ));
            }
        }
        for (i, c) in self.contacts.iter().enumerate() {
            let Some(spec) = &c.conductance else { continue };
            if !self.has_conduction() {
                return Err(self.invalid(
                    format!("contact[{i}].conductance"),
                    "…",
                    "a joint conductance needs conducting bodies: give the [[body]] \
                     `conductivity`",
                ));
            }
            spec.conductance().map_err(|(key, value, reason)| {
                self.invalid(
                    format!("contact[{i}].conductance{key}"),
                    value,
                    format!("{reason} (contact '{}')", c.name()),
                )
            })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::Error;
    use crate::config::Case;
    use std::path::Path;

    const BASE: &str = r#"
        [mesh]
        file = "m.msh"
        [analysis]
        type = "plane_strain"
        [[body]]
        group = "hub"
        material = { E = 210000.0, nu = 0.3, expansion = 1.2e-5 }
        [[body]]
        group = "shaft"
        conductivity = 0.05
        material = { E = 210000.0, nu = 0.3 }
    "#;

    fn error(extra: &str) -> String {
        let text = format!("{BASE}{extra}");
        match Case::from_toml(&text, Path::new("c.toml")) {
            Err(e @ (Error::Case { .. } | Error::InvalidParameter { .. })) => e.to_string(),
            other => panic!("expected a case error for {extra}, got {other:?}"),
        }
    }

    #[test]
    fn thermal_entries_parse() {
        let text = format!(
            "{BASE}[[temperature]]\ngroup = \"hub\"\nchange = 200.0\n\
             [[thermal_support]]\ngroup = \"out\"\nfilm = {{ h = 1e-5, ambient = 20.0 }}\n\
             [[heat_source]]\ngroup = \"shaft\"\npower = 1e-3\n"
        );
        let c = Case::from_toml(&text, Path::new("c.toml")).unwrap();
        assert_eq!(c.temperatures[0].change, 200.0);
        assert_eq!(c.thermal_supports[0].value(), 20.0);
        assert_eq!(c.bodies[0].material.expansion, Some(1.2e-5));
        assert!(c.has_conduction());
    }

    #[test]
    fn bad_thermal_input_is_named() {
        for (extra, expected) in [
            (
                "[[temperature]]\ngroup = \"shaft\"\nchange = 1.0\n",
                "conducts heat",
            ),
            (
                "[[temperature]]\ngroup = \"nothing\"\nchange = 1.0\n",
                "temperature[0].group",
            ),
            (
                "[[thermal_support]]\ngroup = \"c\"\ntemperature = 1.0\nflux = 2.0\n",
                "exactly one of",
            ),
            (
                "[[thermal_support]]\ngroup = \"c\"\nfilm = { h = -1.0 }\n",
                "thermal_support[0].film.h",
            ),
            (
                "[[heat_source]]\ngroup = \"hub\"\npower = 1.0\n",
                "heat_source[0].group",
            ),
        ] {
            let message = error(extra);
            assert!(message.contains(expected), "{extra}: {message}");
        }
    }

    #[test]
    fn conductance_forms() {
        use super::{ConductanceSpec, ConductanceTable};
        let table = |h, h0, exponent, gap| {
            ConductanceSpec::Table(ConductanceTable {
                h,
                h0,
                exponent,
                gap,
            })
        };
        let c = ConductanceSpec::Constant(0.1).conductance().unwrap();
        assert_eq!((c.h0, c.exponent, c.gap), (0.1, 0.0, 0.0));
        let c = table(None, Some(0.2), Some(0.7), Some(1e-4))
            .conductance()
            .unwrap();
        assert_eq!((c.h0, c.exponent, c.gap), (0.2, 0.7, 1e-4));
        assert!(
            table(Some(0.1), Some(0.2), None, None)
                .conductance()
                .is_err()
        );
        // Each error names the key as written below `conductance` (empty for the number).
        let key = |spec: ConductanceSpec| spec.conductance().unwrap_err().0;
        assert_eq!(key(table(Some(0.1), Some(0.2), None, None)), "");
        assert_eq!(key(table(None, Some(0.2), Some(-1.0), None)), ".exponent");
        assert_eq!(key(table(Some(-1.0), None, None, None)), ".h");
        assert_eq!(key(table(None, Some(-1.0), Some(1.0), None)), ".h0");
        assert_eq!(key(table(Some(1.0), None, None, Some(f64::NAN))), ".gap");
        assert_eq!(key(ConductanceSpec::Constant(-1.0)), "");
        assert_eq!(key(ConductanceSpec::Constant(0.0)), "");
    }
}
