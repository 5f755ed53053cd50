//! Range checks of case-file values beyond what the types enforce: every count bounded
//! (so that no value can drive an absurd allocation or run time), every number finite and
//! physically meaningful, tolerances that cannot accept an unconverged state, names that are
//! safe in file names, and no contact pair defined twice. Material and interface-law
//! parameters are checked where the material and the law are built
//! ([`crate::model::ModelSpec::new`]), the quantities of a study in [`super::quantity`].

use std::collections::BTreeSet;

use super::{AnalysisSpec, Case, LawSpec, check_name};
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

    /// The rough-joint law's tangential stiffness k_T = p^S / R (paper, Eq. 3) only matters
    /// with friction: R and S are required when `mu_m > 0` and unused (a warning if given)
    /// when `mu_m = 0`.
    fn check_laws(&self) -> Result<()> {
        for (i, c) in self.contacts.iter().enumerate() {
            let LawSpec::RoughJoint { mu_m, r, s, .. } = c.law else {
                continue;
            };
            if mu_m == 0.0 {
                if r.is_some() || s.is_some() {
                    tracing::warn!(
                        "{}: contact[{i}] ('{}'): R and S are not used when mu_m = 0 (no friction)",
                        self.path.display(),
                        c.name()
                    );
                }
                continue;
            }
            for (key, value) in [("R", r), ("S", s)] {
                if value.is_none() {
                    return Err(self.invalid(
                        format!("contact[{i}].law.{key}"),
                        "(missing)",
                        format!(
                            "the rough-joint law needs R and S (k_T = p^S / R) when mu_m = {mu_m} \
                             (contact '{}')",
                            c.name()
                        ),
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
