//! Load histories of the case file: analysis steps in sequence (`[[step]]`), named
//! piecewise-linear amplitudes (`[[amplitude]]`), and what every load and support does in
//! every step. Plain data; [`crate::model::Schedule`] turns it into the amplitudes the solver
//! evaluates, and [`super::check`] checks it.
//!
//! A load or support named in a step follows a number (a linear ramp from its value at the end
//! of the previous step to this value), a named amplitude or an inline amplitude; one not
//! named keeps its value from the end of the previous step (0 before it is first named). In a
//! cyclic step (`cycles > 1`) the amplitudes are repeated once per cycle.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::Deserialize;

use super::Case;

/// A named piecewise-linear amplitude (`[[amplitude]]`).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AmplitudeSpec {
    /// Name the steps refer to; unique among amplitudes.
    pub name: String,
    /// Step time (fraction of the step, or of one cycle in a cyclic step): strictly
    /// increasing from 0 to 1.
    pub time: Vec<f64>,
    /// Multiplier of the load's magnitude at each time (any sign).
    pub value: Vec<f64>,
}

/// An amplitude given in a step itself: `{ time = [...], value = [...] }`.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InlineAmplitude {
    /// Step time, strictly increasing from 0 to 1.
    pub time: Vec<f64>,
    /// Multiplier of the load's magnitude at each time.
    pub value: Vec<f64>,
}

/// What a load or support does in a step (`loads = { name = ... }`).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum Target {
    /// Ramp linearly from the value at the end of the previous step to this multiplier.
    Ramp(f64),
    /// Follow the named `[[amplitude]]`.
    Named(String),
    /// Follow this amplitude.
    Table(InlineAmplitude),
}

/// One analysis step (`[[step]]`).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StepSpec {
    /// Name used in output (default `step-<n>`, n 1-based); unique.
    pub name: Option<String>,
    /// Output increments of the step, per cycle in a cyclic step (default 1).
    #[serde(default = "one")]
    pub increments: usize,
    /// Load cycles: the step's amplitudes are repeated this many times (default 1).
    #[serde(default = "one")]
    pub cycles: usize,
    /// Cycle jumping: one simulated cycle stands for this many cycles (default
    /// ceil(cycles / 20) when a contact has wear, else 1).
    pub cycles_per_jump: Option<usize>,
    /// Loads by name: a number (ramp target), an amplitude name, or an inline amplitude.
    #[serde(default)]
    pub loads: BTreeMap<String, Target>,
    /// Supports by name, as `loads`.
    #[serde(default)]
    pub supports: BTreeMap<String, Target>,
    /// `[[temperature]]`, `[[thermal_support]]` and `[[heat_source]]` entries by name, as
    /// `loads` (their ΔT, temperature, flux, ambient temperature or power scales).
    #[serde(default)]
    pub thermal: BTreeMap<String, Target>,
}

fn one() -> usize {
    1
}

/// Simulated cycles when wear jumps cycles by default: a cyclic step is simulated in about
/// this many cycles.
pub const DEFAULT_JUMPS: usize = 20;

impl StepSpec {
    /// The step's name; `index` is 0-based.
    pub fn name(&self, index: usize) -> String {
        self.name
            .clone()
            .unwrap_or_else(|| format!("step-{}", index + 1))
    }

    /// The step's table of `role` (`loads`, `supports`, `thermal`).
    pub fn table(&self, role: Role) -> &BTreeMap<String, Target> {
        match role {
            Role::Load => &self.loads,
            Role::Support => &self.supports,
            Role::Thermal => &self.thermal,
        }
    }

    /// Whether the step repeats its amplitudes.
    pub fn is_cyclic(&self) -> bool {
        self.cycles > 1
    }

    /// Cycles one simulated cycle stands for: the given value, else ceil(cycles / 20) when
    /// some contact wears (a cyclic step is then simulated in about 20 cycles), else 1.
    pub fn cycles_per_jump(&self, wear: bool) -> usize {
        match self.cycles_per_jump {
            Some(n) => n,
            None if wear => self.cycles.div_ceil(DEFAULT_JUMPS).max(1),
            None => 1,
        }
    }

    /// Simulated cycles: the first on its own, then one per `cycles_per_jump` of the rest,
    /// the last standing for the remainder.
    pub fn simulated_cycles(&self, wear: bool) -> usize {
        1 + self
            .cycles
            .saturating_sub(1)
            .div_ceil(self.cycles_per_jump(wear).max(1))
    }
}

/// Whether a history belongs to a load or a support.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Load,
    Support,
    /// A temperature, thermal support or heat source.
    Thermal,
}

impl Role {
    /// The key of the role's table in a step (`loads`, `supports`).
    pub fn key(self) -> &'static str {
        match self {
            Role::Load => "loads",
            Role::Support => "supports",
            Role::Thermal => "thermal",
        }
    }

    /// The case-file tables of the role's entries, for messages.
    pub fn entries(self) -> &'static str {
        match self {
            Role::Load => "[[load]]",
            Role::Support => "[[support]]",
            Role::Thermal => "[[temperature]], [[thermal_support]] or [[heat_source]]",
        }
    }

    /// The role's name in column headers (`load`, `support`, `thermal`).
    pub fn name(self) -> &'static str {
        match self {
            Role::Load => "load",
            Role::Support => "support",
            Role::Thermal => "thermal",
        }
    }
}

/// What a load or support does in one step, with the value it starts the step from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Leg<'c> {
    /// Multiplier at the end of the previous step (0 before the first step).
    pub start: f64,
    pub motion: Motion<'c>,
}

/// The motion of a multiplier within a step (or one cycle of it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion<'c> {
    /// Not named in the step: keeps its value.
    Hold,
    /// Linear from the start value to this one.
    Ramp(f64),
    /// Piecewise linear through (time, value); `None` for an amplitude name the case does
    /// not define (an error of the checked case).
    Table(Option<(&'c [f64], &'c [f64])>),
}

impl Motion<'_> {
    /// Multiplier at the end of the step (or cycle).
    pub fn end(&self, start: f64) -> f64 {
        match self {
            Motion::Hold => start,
            Motion::Ramp(v) => *v,
            Motion::Table(Some((_, value))) => value.last().copied().unwrap_or(start),
            Motion::Table(None) => start,
        }
    }
}

impl Case {
    /// Whether some contact pair wears (cycle jumping then defaults to about 20 simulated
    /// cycles per cyclic step).
    pub fn has_wear(&self) -> bool {
        self.contacts.iter().any(|c| c.wear.is_some())
    }

    /// Whether the case describes its history by `[[step]]` (else by `[steps]`).
    pub fn has_analysis_steps(&self) -> bool {
        !self.analysis_steps.is_empty()
    }

    /// The output frames of a load-controlled run (the step numbers of its files): the
    /// `[steps]` count, or with `[[step]]` the increments of every simulated cycle.
    pub fn frames(&self) -> usize {
        if !self.has_analysis_steps() {
            return self.steps.len();
        }
        let wear = self.has_wear();
        let frames = self.analysis_steps.iter();
        frames
            .map(|s| s.increments.saturating_mul(s.simulated_cycles(wear)))
            .sum()
    }

    /// The amplitude called `name`.
    pub fn amplitude(&self, name: &str) -> Option<&AmplitudeSpec> {
        self.amplitudes.iter().find(|a| a.name == name)
    }

    /// The motion of the load or support called `name` through every `[[step]]`, in order.
    pub fn legs(&self, role: Role, name: &str) -> Vec<Leg<'_>> {
        let mut start = 0.0;
        self.analysis_steps
            .iter()
            .map(|step| {
                let table = step.table(role);
                let motion = match table.get(name) {
                    None => Motion::Hold,
                    Some(Target::Ramp(v)) => Motion::Ramp(*v),
                    Some(Target::Named(a)) => Motion::Table(
                        self.amplitude(a)
                            .map(|a| (a.time.as_slice(), a.value.as_slice())),
                    ),
                    Some(Target::Table(t)) => {
                        Motion::Table(Some((t.time.as_slice(), t.value.as_slice())))
                    }
                };
                let leg = Leg { start, motion };
                start = motion.end(start);
                leg
            })
            .collect()
    }

    /// The supports', loads' and thermal entries' names with their role and index (case-file
    /// order; the thermal entries' as [`Case::thermal_names`]): supports first (the order of
    /// the per-load columns of `history.csv`).
    pub fn history_names(&self) -> impl Iterator<Item = (Role, usize, &str)> {
        let supports = self.supports.iter().enumerate();
        let loads = self.loads.iter().enumerate();
        let thermal = self.thermal_names().enumerate();
        supports
            .map(|(i, s)| (Role::Support, i, s.name()))
            .chain(loads.map(|(i, l)| (Role::Load, i, l.name())))
            .chain(thermal.map(|(i, (name, _))| (Role::Thermal, i, name)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn case(history: &str) -> Case {
        let text = format!(
            "[mesh]\nfile = \"m.msh\"\n[analysis]\ntype = \"plane_strain\"\n\
             [[body]]\ngroup = \"b\"\nmaterial = {{ E = 1.0, nu = 0.3 }}\n\
             [[load]]\nname = \"p\"\ngroup = \"top\"\npressure = 1.0\n{history}"
        );
        Case::from_toml(&text, Path::new("case.toml")).unwrap()
    }

    #[test]
    fn frames_count_the_increments_of_every_simulated_cycle() {
        assert_eq!(case("[steps]\ncount = 7\n").frames(), 7);
        let steps = "[[amplitude]]\nname = \"c\"\ntime = [0.0, 0.5, 1.0]\nvalue = [1.0, 0.0, 1.0]\n\
                     [[step]]\nincrements = 3\nloads = { p = 1.0 }\n\
                     [[step]]\ncycles = 10\nincrements = 4\ncycles_per_jump = 3\nloads = { p = \"c\" }\n";
        // 3 + 4 × (1 + ceil(9 / 3)) = 3 + 16.
        assert_eq!(case(steps).frames(), 19);
    }
}
