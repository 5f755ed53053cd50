//! Checks of the `[[step]]` and `[[amplitude]]` load histories (part of
//! [`Case::validate`](super::Case)): every name known and unique, every amplitude a function
//! of step time from 0 to 1, every load continuous from step to step, every cyclic step
//! closing its cycle, counts in range, and nothing of the simple form mixed in.

use std::collections::BTreeSet;

use super::check::MAX_STEPS;
use super::{Case, ControlKind, Leg, Motion, Role, StepSpec, Target, check_name};

/// An entry's case-file key (`load[1]`, `temperature[0]`) and its name.
type NamedEntry = (String, String);
use crate::Result;

/// Two multipliers that must meet (continuity between steps, a cycle that closes): equal up
/// to round-off of the values as written.
fn meets(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0)
}

impl Case {
    /// `[[step]]`, `[[amplitude]]` and the load and support names: every name known and
    /// unique, every amplitude a function of step time from 0 to 1, every load continuous
    /// from step to step, every cyclic step closing its cycle, counts in range, and nothing
    /// of the simple form (`[steps]`, per-load `factors`) mixed in.
    pub(super) fn check_analysis_steps(&self) -> Result<()> {
        if !self.has_analysis_steps() {
            if !self.amplitudes.is_empty() {
                return Err(self.invalid(
                    "amplitude[0]",
                    format!("{:?}", self.amplitudes[0].name),
                    "amplitudes are used by [[step]] tables; this case has no [[step]]",
                ));
            }
            return Ok(());
        }
        self.check_no_factors()?;
        self.check_history_names()?;
        for (j, a) in self.amplitudes.iter().enumerate() {
            self.check_table(&format!("amplitude[{j}]"), &a.time, &a.value)?;
        }
        let wear = self.has_wear();
        let mut increments = 0usize;
        for (i, step) in self.analysis_steps.iter().enumerate() {
            self.check_step_counts(i, step)?;
            increments = increments
                .saturating_add(step.increments.saturating_mul(step.simulated_cycles(wear)));
            if increments > MAX_STEPS {
                return Err(self.invalid(
                    format!("step[{i}].increments"),
                    step.increments,
                    format!(
                        "the steps up to this one simulate {increments} increments (increments × \
                         simulated cycles), at most {MAX_STEPS} are allowed; use fewer \
                         increments or a larger cycles_per_jump"
                    ),
                ));
            }
            self.check_step_targets(i, step)?;
            self.check_cyclic_amplitude(i, step)?;
        }
        self.check_legs()?;
        self.check_every_history_used()
    }

    /// Per-load `factors` belong to the `[steps]` form.
    fn check_no_factors(&self) -> Result<()> {
        fn given<'a>(
            role: &str,
            mut factors: impl Iterator<Item = &'a Option<Vec<f64>>>,
        ) -> Option<(String, &'a Vec<f64>)> {
            factors
                .by_ref()
                .enumerate()
                .find_map(|(i, f)| Some((format!("{role}[{i}].factors"), f.as_ref()?)))
        }
        let supports = given("support", self.supports.iter().map(|s| &s.factors));
        let loads = || given("load", self.loads.iter().map(|l| &l.factors));
        if let Some((key, f)) = supports.or_else(loads) {
            return Err(self.invalid(
                key,
                format!("{f:?}"),
                "per-load factors belong to [steps]; with [[step]] give the history in the \
                 steps' `loads` and `supports` tables",
            ));
        }
        Ok(())
    }

    /// Load, support, thermal-entry, amplitude and step names (each with its entry's key, e.g.
    /// `load[1]`): safe, and unique within their kind (the thermal entries — temperatures,
    /// thermal supports, heat sources — together: they share a step's `thermal` table).
    fn check_history_names(&self) -> Result<()> {
        let keyed = |kind: &str, names: Vec<String>| -> Vec<NamedEntry> {
            let keys = (0..names.len()).map(|i| format!("{kind}[{i}]"));
            keys.zip(names).collect()
        };
        let loads = keyed(
            "load",
            self.loads.iter().map(|l| l.name().to_string()).collect(),
        );
        let supports = self.supports.iter().map(|s| s.name().to_string()).collect();
        let amplitudes = self.amplitudes.iter().map(|a| a.name.clone()).collect();
        let steps = (0..self.analysis_steps.len())
            .map(|i| self.analysis_steps[i].name(i))
            .collect();
        let thermal: Vec<NamedEntry> = self
            .thermal_keys()
            .zip(self.thermal_names().map(|(name, _)| name.to_string()))
            .collect();
        // Names that default to the entry's group get a hint to give `name`.
        let defaulted = " (a name defaults to the entry's group: give `name`)";
        let kinds = [
            ("[[load]]", loads, defaulted),
            ("[[support]]", keyed("support", supports), defaulted),
            (Role::Thermal.entries(), thermal, defaulted),
            ("[[amplitude]]", keyed("amplitude", amplitudes), ""),
            ("[[step]]", keyed("step", steps), ""),
        ];
        for (table, entries, hint) in kinds {
            let mut seen = BTreeSet::new();
            for (entry, name) in &entries {
                let key = format!("{entry}.name");
                check_name(name)
                    .map_err(|reason| self.invalid(&key, format!("{name:?}"), reason))?;
                if !seen.insert(name) {
                    return Err(self.invalid(
                        key,
                        format!("{name:?}"),
                        format!("another entry of {table} has this name{hint}"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// An amplitude table at `key`: as many values as times, all finite, times strictly
    /// increasing from 0 to 1.
    fn check_table(&self, key: &str, time: &[f64], value: &[f64]) -> Result<()> {
        if value.len() != time.len() {
            return Err(self.invalid(
                format!("{key}.value"),
                format!("{value:?}"),
                format!(
                    "needs one value per time ({}), got {}",
                    time.len(),
                    value.len()
                ),
            ));
        }
        if value.iter().any(|v| !v.is_finite()) {
            return Err(self.invalid(
                format!("{key}.value"),
                format!("{value:?}"),
                "must be finite",
            ));
        }
        let increasing = time.windows(2).all(|w| w[0] < w[1]);
        if !increasing || time.iter().any(|t| !t.is_finite()) {
            return Err(self.invalid(
                format!("{key}.time"),
                format!("{time:?}"),
                "must be finite and strictly increasing",
            ));
        }
        if time.first() != Some(&0.0) || time.last() != Some(&1.0) {
            return Err(self.invalid(
                format!("{key}.time"),
                format!("{time:?}"),
                "must run from 0 to 1 (step time: the fraction of the step, or of one cycle)",
            ));
        }
        Ok(())
    }

    /// `increments`, `cycles` and `cycles_per_jump` of step `i`.
    fn check_step_counts(&self, i: usize, step: &StepSpec) -> Result<()> {
        for (key, value) in [("increments", step.increments), ("cycles", step.cycles)] {
            if value < 1 {
                return Err(self.invalid(format!("step[{i}].{key}"), value, "must be at least 1"));
            }
        }
        if let Some(n) = step.cycles_per_jump
            && (n < 1 || n > step.cycles)
        {
            return Err(self.invalid(
                format!("step[{i}].cycles_per_jump"),
                n,
                format!("must lie in [1, cycles = {}]", step.cycles),
            ));
        }
        Ok(())
    }

    /// A cyclic step `i` repeats its amplitudes: it needs one (checked after its targets,
    /// so that a target naming no load is named as such).
    fn check_cyclic_amplitude(&self, i: usize, step: &StepSpec) -> Result<()> {
        if step.is_cyclic() && !self.step_has_amplitude(step) {
            return Err(self.invalid(
                format!("step[{i}].cycles"),
                step.cycles,
                "a cyclic step repeats its amplitudes, and this one has none: let a load or \
                 support follow an amplitude (a name or { time = [...], value = [...] })",
            ));
        }
        Ok(())
    }

    /// Whether a load or support of `step` follows an amplitude.
    fn step_has_amplitude(&self, step: &StepSpec) -> bool {
        let targets = step.loads.values().chain(step.supports.values());
        let targets = targets.chain(step.thermal.values());
        targets.into_iter().any(|t| !matches!(t, Target::Ramp(_)))
    }

    /// The `loads` and `supports` tables of step `i`: known names and amplitudes, finite
    /// ramps, valid inline tables.
    fn check_step_targets(&self, i: usize, step: &StepSpec) -> Result<()> {
        for role in [Role::Load, Role::Support, Role::Thermal] {
            let table = step.table(role);
            let known: Vec<&str> = self
                .history_names()
                .filter(|(r, _, _)| *r == role)
                .map(|(_, _, name)| name)
                .collect();
            for (name, target) in table {
                let key = format!("step[{i}].{}.{name}", role.key());
                if !known.contains(&name.as_str()) {
                    return Err(self.invalid(
                        key,
                        format!("{name:?}"),
                        format!(
                            "no {} has this name (known: {})",
                            role.entries(),
                            known.join(", ")
                        ),
                    ));
                }
                self.check_target(&key, target)?;
            }
        }
        Ok(())
    }

    /// Every load's and support's motion from step to step ([`Self::check_leg`]).
    fn check_legs(&self) -> Result<()> {
        for (role, _, name) in self.history_names() {
            let steps = self.analysis_steps.iter().enumerate();
            for ((i, step), leg) in steps.zip(self.legs(role, name)) {
                let key = format!("step[{i}].{}.{name}", role.key());
                self.check_leg(&key, step, &leg)?;
            }
        }
        Ok(())
    }

    /// One target on its own: a finite ramp, a known amplitude, a valid inline table.
    fn check_target(&self, key: &str, target: &Target) -> Result<()> {
        match target {
            Target::Ramp(v) if !v.is_finite() => Err(self.invalid(key, v, "must be finite")),
            Target::Ramp(_) => Ok(()),
            Target::Named(a) if self.amplitude(a).is_none() => Err(self.invalid(
                key,
                format!("{a:?}"),
                format!(
                    "no [[amplitude]] has this name (known: {})",
                    self.amplitudes
                        .iter()
                        .map(|a| a.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )),
            Target::Named(_) => Ok(()),
            Target::Table(t) => self.check_table(key, &t.time, &t.value),
        }
    }

    /// The motion of one load or support in a step against where it stands: an amplitude
    /// starts at the value the previous step ended with; in a cyclic step a ramp cannot
    /// repeat (unless it holds the value) and an amplitude must end where it starts.
    fn check_leg(&self, key: &str, step: &StepSpec, leg: &Leg) -> Result<()> {
        match leg.motion {
            Motion::Ramp(v) if step.is_cyclic() && !meets(v, leg.start) => Err(self.invalid(
                key,
                v,
                format!(
                    "a number ramps once and cannot repeat in a cyclic step (cycles = {}); the \
                     value at the end of the previous step is {}: follow an amplitude instead",
                    step.cycles, leg.start
                ),
            )),
            Motion::Table(Some((_, value))) => {
                let (first, last) = (value[0], value[value.len() - 1]);
                if !meets(first, leg.start) {
                    return Err(self.invalid(
                        key,
                        first,
                        format!(
                            "the amplitude starts at {first}, but the value at the end of the \
                             previous step is {} (a load cannot jump between steps)",
                            leg.start
                        ),
                    ));
                }
                if step.is_cyclic() && !meets(first, last) {
                    return Err(self.invalid(
                        key,
                        last,
                        format!(
                            "in a cyclic step (cycles = {}) the amplitude must end where it \
                             starts ({first}), it ends at {last}",
                            step.cycles
                        ),
                    ));
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// Every load, and every support with a non-zero value, is named in some step (otherwise
    /// it would stay at zero: a forgotten load).
    fn check_every_history_used(&self) -> Result<()> {
        for (role, i, name) in self.history_names() {
            let nonzero = match role {
                Role::Load => true,
                Role::Support => self.supports[i].is_nonzero(),
                Role::Thermal => self.thermal_names().nth(i).is_some_and(|(_, v)| v != 0.0),
            };
            let named = self
                .analysis_steps
                .iter()
                .any(|s| s.table(role).contains_key(name));
            if nonzero && !named {
                return Err(self.invalid(
                    format!("{}[{i}]", role.name()),
                    format!("{name:?}"),
                    format!(
                        "this {} entry is named in no [[step]], so it would never be applied: \
                         name it in a step's `{}` table",
                        role.entries(),
                        role.key()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// `[steps]` and `[[step]]` are two forms of one history: the raw table tells whether
    /// `[steps]` was written (its defaults are indistinguishable from an absent table).
    pub(super) fn check_history_form(&self, text: &str) -> Result<()> {
        if !self.has_analysis_steps() {
            return Ok(());
        }
        let table: toml::Table = toml::from_str(text).map_err(|e| self.error(e.to_string()))?;
        if !table.contains_key("steps") {
            return Ok(());
        }
        if self.steps.control == ControlKind::ArcLength {
            return Err(self.invalid(
                "steps.control",
                "\"arc_length\"",
                "arc-length control finds its own load factor and cannot follow [[step]] \
                 histories; use [steps] alone",
            ));
        }
        Err(self.invalid(
            "steps",
            "[steps]",
            "give either [steps] (the simple form) or [[step]] (analysis steps), not both",
        ))
    }
}
