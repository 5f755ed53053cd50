//! Range checks of case-file values beyond what the types enforce: every count bounded
//! (so that no value can drive an absurd allocation or run time), every number finite and
//! physically meaningful, tolerances that cannot accept an unconverged state, names that are
//! safe in file names, and no contact pair defined twice. Material and interface-law
//! parameters are checked where the material and the law are built
//! ([`crate::model::ModelSpec::new`]), the quantities of a study in [`super::quantity`].

use std::collections::BTreeSet;

use super::{AnalysisSpec, Case, ControlKind, Leg, Motion, Role, StepSpec, Target, check_name};
use crate::Result;

/// Most load steps (`[steps] count`, the length of `factors`) and arc-length increments: a
/// run writes files per step, and 10⁵ steps is far beyond any load history that needs
/// resolving.
pub const MAX_STEPS: usize = 100_000;
/// Most Newton iterations per increment.
pub const MAX_ITERATIONS: usize = 10_000;
/// Most cut-backs of a step: 2⁻²⁰ ≈ 10⁻⁶ of a step is already far below any useful increment.
pub const MAX_CUTBACKS: usize = 20;
/// Loosest convergence tolerance: a relative out-of-balance force or correction of more
/// than 1 % is not equilibrium. A tolerance ≥ 1 would accept the unloaded start of an
/// increment (relative residual 1) after zero iterations.
pub const MAX_TOLERANCE: f64 = 1e-2;
/// Upper bound of the late residual tolerance R_p (ten times CalculiX's default 2e-2).
pub const MAX_LATE_TOLERANCE: f64 = 0.2;

impl Case {
    /// The checks of this module, in key order; the first failure is returned.
    pub(super) fn check_ranges(&self) -> Result<()> {
        self.check_mesh_parameters()?;
        if let AnalysisSpec::PlaneStress { thickness } | AnalysisSpec::PlaneStrain { thickness } =
            self.analysis
            && !(thickness.is_finite() && thickness > 0.0)
        {
            return Err(self.invalid(
                "analysis.thickness",
                thickness,
                "must be positive and finite",
            ));
        }
        self.check_names()?;
        self.check_laws()?;
        self.check_hysteresis_points()?;
        self.check_wear()?;
        self.check_steps()?;
        self.check_solver()
    }

    /// `[mesh] parameters`: gmsh hangs on a NaN and its `-setnumber` needs an identifier.
    fn check_mesh_parameters(&self) -> Result<()> {
        for (name, &value) in &self.mesh.parameters {
            let key = format!("mesh.parameters.{name}");
            let identifier = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
                && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
            if !identifier {
                return Err(self.invalid(
                    key,
                    value,
                    "a parameter name must be a gmsh identifier (a letter, then letters, digits \
                     or '_')",
                ));
            }
            if !value.is_finite() {
                return Err(self.invalid(key, value, "must be finite"));
            }
        }
        Ok(())
    }

    /// Every group and pair name (they become parts of file names and CSV headers), and no
    /// pair name used twice (two pairs of one name would overwrite each other's files, and
    /// two identical pairs would double the interface).
    fn check_names(&self) -> Result<()> {
        let mut names: Vec<(String, &str)> = Vec::new();
        for (i, b) in self.bodies.iter().enumerate() {
            names.push((format!("body[{i}].group"), &b.group));
        }
        for (i, s) in self.supports.iter().enumerate() {
            names.push((format!("support[{i}].group"), &s.group));
        }
        for (i, l) in self.loads.iter().enumerate() {
            names.push((format!("load[{i}].group"), &l.group));
        }
        for (i, c) in self.contacts.iter().enumerate() {
            let keys = [
                ("name", &c.name),
                ("side_a", &c.side_a),
                ("side_b", &c.side_b),
                ("curve", &c.curve),
                ("body_a", &c.body_a),
                ("body_b", &c.body_b),
            ];
            for (key, value) in keys {
                if let Some(v) = value {
                    names.push((format!("contact[{i}].{key}"), v));
                }
            }
        }
        for (key, name) in names {
            check_name(name).map_err(|reason| self.invalid(key, format!("{name:?}"), reason))?;
        }
        let mut seen = BTreeSet::new();
        for (i, c) in self.contacts.iter().enumerate() {
            let name = c.name();
            // A derived name ("<side_a>-<side_b>") must also fit in a file name.
            check_name(&name).map_err(|reason| {
                self.invalid(
                    format!("contact[{i}].name"),
                    format!("{name:?}"),
                    format!("{reason} (the name is made from the pair's curves; give `name`)"),
                )
            })?;
            if !seen.insert(name.clone()) {
                return Err(self.invalid(
                    format!("contact[{i}].name"),
                    format!("{name:?}"),
                    "another [[contact]] has this name: every pair needs its own name (two pairs \
                     on the same curves would also double the interface)",
                ));
            }
        }
        Ok(())
    }

    /// The parameters of every contact's law are finite numbers (their bounds, and the rules
    /// that tie them together, are checked where the law is built).
    fn check_laws(&self) -> Result<()> {
        for (i, c) in self.contacts.iter().enumerate() {
            let law = &c.law;
            let given = law.law.parameters.iter().zip(&law.values);
            if let Some((p, v)) = given
                .filter_map(|(p, v)| Some((p, (*v)?)))
                .find(|(_, v)| !v.is_finite())
            {
                return Err(self.invalid(
                    format!("contact[{i}].law.{}", p.key),
                    v,
                    format!("must be finite (contact '{}')", c.name()),
                ));
            }
        }
        Ok(())
    }

    /// The points whose local loops a contact traces have finite coordinates (whether they
    /// lie on the contact is checked against the mesh, when the run starts).
    fn check_hysteresis_points(&self) -> Result<()> {
        for (i, c) in self.contacts.iter().enumerate() {
            for (k, point) in c.hysteresis_points.iter().enumerate() {
                if !point.iter().all(|v| v.is_finite()) {
                    return Err(self.invalid(
                        format!("contact[{i}].hysteresis_points[{k}]"),
                        format!("{point:?}"),
                        "the coordinates (x, y) of a point on the contact must be finite numbers (mm)",
                    ));
                }
            }
        }
        Ok(())
    }

    /// In axisymmetric analyses `[analysis]` has no other key than `type` (serde ignores the
    /// keys of a unit variant, so they are checked on the raw table).
    pub(super) fn check_analysis_keys(&self, text: &str) -> Result<()> {
        if !self.analysis.is_axisymmetric() {
            return Ok(());
        }
        let table: toml::Table = toml::from_str(text).map_err(|e| self.error(e.to_string()))?;
        let extra = table
            .get("analysis")
            .and_then(toml::Value::as_table)
            .and_then(|t| t.keys().find(|k| k.as_str() != "type"));
        match extra {
            Some(key) if key == "thickness" => Err(self.error(
                "[analysis]: `thickness` is not used in axisymmetric analyses (forces and \
                 reactions are totals over the full ring); remove it",
            )),
            Some(key) => Err(self.error(format!(
                "[analysis]: unknown key `{key}` (an axisymmetric analysis has only `type`)"
            ))),
            None => Ok(()),
        }
    }

    /// `[steps]`: bounded counts.
    fn check_steps(&self) -> Result<()> {
        let steps = &self.steps;
        let counts = [
            ("steps.count", steps.count),
            ("steps.factors", steps.factors.as_ref().map(Vec::len)),
            ("steps.max_increments", steps.max_increments),
        ];
        for (key, count) in counts {
            if let Some(n) = count.filter(|&n| n > MAX_STEPS) {
                return Err(self.invalid(
                    key,
                    n,
                    format!("at most {MAX_STEPS} steps (increments) are allowed"),
                ));
            }
        }
        Ok(())
    }

    /// `[solver]`: bounded iteration and cut-back counts, tolerances in (0, 1 %].
    fn check_solver(&self) -> Result<()> {
        let s = &self.solver;
        if s.max_iterations > MAX_ITERATIONS {
            return Err(self.invalid(
                "solver.max_iterations",
                s.max_iterations,
                format!("at most {MAX_ITERATIONS}"),
            ));
        }
        if s.max_cutbacks > MAX_CUTBACKS {
            return Err(self.invalid(
                "solver.max_cutbacks",
                s.max_cutbacks,
                format!(
                    "at most {MAX_CUTBACKS} (a step cut back {MAX_CUTBACKS} times is 2^-{MAX_CUTBACKS} \
                     of its size)"
                ),
            ));
        }
        for (key, value) in [
            ("solver.force_tolerance", s.force_tolerance),
            ("solver.displacement_tolerance", s.displacement_tolerance),
            ("solver.residual_tolerance", s.residual_tolerance),
            ("solver.correction_tolerance", s.correction_tolerance),
            ("solver.zero_flux", s.zero_flux),
            (
                "solver.zero_flux_correction_tolerance",
                s.zero_flux_correction_tolerance,
            ),
            (
                "solver.linear_residual_tolerance",
                s.linear_residual_tolerance,
            ),
        ] {
            if !(value > 0.0 && value <= MAX_TOLERANCE) {
                return Err(self.invalid(
                    key,
                    value,
                    format!(
                        "must lie in (0, {MAX_TOLERANCE}]: a larger relative tolerance would \
                         accept a state out of equilibrium"
                    ),
                ));
            }
        }
        // R_p is the looser residual bound of slowly converging increments (CalculiX: 2e-2).
        if !(s.late_residual_tolerance > 0.0 && s.late_residual_tolerance <= MAX_LATE_TOLERANCE) {
            return Err(self.invalid(
                "solver.late_residual_tolerance",
                s.late_residual_tolerance,
                format!(
                    "must lie in (0, {MAX_LATE_TOLERANCE}]: a larger residual would accept a \
                     state out of equilibrium"
                ),
            ));
        }
        let ratio = s.collapse_stiffness_ratio;
        if !(ratio > 0.0 && ratio < 1.0) {
            return Err(self.invalid(
                "solver.collapse_stiffness_ratio",
                ratio,
                "must lie in (0, 1)",
            ));
        }
        Ok(())
    }
}

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

    /// Load, support, amplitude and step names: safe, and unique within their kind.
    fn check_history_names(&self) -> Result<()> {
        let loads = self.loads.iter().map(|l| l.name());
        let supports = self.supports.iter().map(|s| s.name());
        let amplitudes = self.amplitudes.iter().map(|a| a.name.as_str());
        let steps = (0..self.analysis_steps.len()).map(|i| self.analysis_steps[i].name(i));
        let kinds: [(&str, Vec<String>); 4] = [
            ("load", loads.map(String::from).collect()),
            ("support", supports.map(String::from).collect()),
            ("amplitude", amplitudes.map(String::from).collect()),
            ("step", steps.collect()),
        ];
        for (kind, names) in kinds {
            let mut seen = BTreeSet::new();
            for (i, name) in names.iter().enumerate() {
                let key = format!("{kind}[{i}].name");
                check_name(name)
                    .map_err(|reason| self.invalid(&key, format!("{name:?}"), reason))?;
                if !seen.insert(name) {
                    return Err(self.invalid(
                        key,
                        format!("{name:?}"),
                        format!(
                            "another [[{kind}]] has this name (a load's or support's name \
                             defaults to its group: give `name`)"
                        ),
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
        targets.into_iter().any(|t| !matches!(t, Target::Ramp(_)))
    }

    /// The `loads` and `supports` tables of step `i`: known names and amplitudes, finite
    /// ramps, valid inline tables.
    fn check_step_targets(&self, i: usize, step: &StepSpec) -> Result<()> {
        for role in [Role::Load, Role::Support] {
            let (table, known): (_, Vec<&str>) = match role {
                Role::Load => (&step.loads, self.loads.iter().map(|l| l.name()).collect()),
                Role::Support => (
                    &step.supports,
                    self.supports.iter().map(|s| s.name()).collect(),
                ),
            };
            for (name, target) in table {
                let key = format!("step[{i}].{}.{name}", role.key());
                if !known.contains(&name.as_str()) {
                    return Err(self.invalid(
                        key,
                        format!("{name:?}"),
                        format!(
                            "no [[{}]] has this name (known: {})",
                            role.name(),
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
            };
            let named = self.analysis_steps.iter().any(|s| match role {
                Role::Load => s.loads.contains_key(name),
                Role::Support => s.supports.contains_key(name),
            });
            if nonzero && !named {
                return Err(self.invalid(
                    format!("{}[{i}]", role.name()),
                    format!("{name:?}"),
                    format!(
                        "this {} is named in no [[step]], so it would never be applied: name it \
                         in a step's `{}` table",
                        role.name(),
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
