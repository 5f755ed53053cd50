//! The checks of a read case ([`Case::validate`]) beyond what the types enforce: keys that
//! go together or exclude each other, every count bounded (so that no value can drive an
//! absurd allocation or run time), every number finite and physically meaningful, tolerances
//! that cannot accept an unconverged state, names that are safe in file names, and no contact
//! pair defined twice. The load histories are checked in [`super::step_checks`], a contact's
//! wear in [`super::wear`], the quantities of a study in [`super::quantity`]. Material and
//! interface-law parameters are checked where the material and the law are built
//! ([`crate::model::ModelSpec::new`]).

use std::collections::BTreeSet;
use std::path::Path;

use super::{AnalysisSpec, Case, MAX_KINEMATIC_TERMS, check_name};
use crate::{Error, Result};

/// Most load steps (`[steps] count`, the length of `factors`) and arc-length increments: a
/// run writes files per step, and 10⁵ steps is far beyond any load history that needs
/// resolving.
pub const MAX_STEPS: usize = 100_000;
/// Most Newton iterations per increment.
pub const MAX_ITERATIONS: usize = 10_000;
/// Most cut-backs of a step: 2⁻²⁰ ≈ 10⁻⁶ of a step is already far below any useful increment.
pub const MAX_CUTBACKS: usize = 20;
/// Most interface iterations within a Newton iteration: each costs a dense LU of the
/// interface system, and a law whose statuses have not settled in 100 is left to the Newton
/// iterations.
pub const MAX_INTERFACE_ITERATIONS: usize = 100;
/// Loosest convergence tolerance: a relative out-of-balance force or correction of more
/// than 1 % is not equilibrium. A tolerance ≥ 1 would accept the unloaded start of an
/// increment (relative residual 1) after zero iterations.
pub const MAX_TOLERANCE: f64 = 1e-2;
/// Upper bound of the late residual tolerance R_p (ten times CalculiX's default 2e-2).
pub const MAX_LATE_TOLERANCE: f64 = 0.2;

/// Why a key of the circumferential direction is refused without twist.
const NEEDS_TWIST: &str = "the circumferential direction exists only in an axisymmetric \
     analysis with twist: set [analysis] type = \"axisymmetric\", twist = true";

/// `[analysis]` on the raw table, before the typed parse (whose messages would only say
/// "unknown field"): an axisymmetric analysis has no `thickness`, and `twist` belongs to
/// axisymmetric analyses only. `path` names the case file.
pub(super) fn check_analysis_table(text: &str, path: &Path) -> Result<()> {
    // A file that is no TOML is reported by the typed parse.
    let Ok(table) = toml::from_str::<toml::Table>(text) else {
        return Ok(());
    };
    let Some(analysis) = table.get("analysis").and_then(toml::Value::as_table) else {
        return Ok(());
    };
    let case_error = |message: String| Error::Case {
        path: path.to_path_buf(),
        message,
    };
    let kind = analysis.get("type").and_then(toml::Value::as_str);
    if kind == Some("axisymmetric") {
        return match analysis
            .keys()
            .find(|k| !["type", "twist"].contains(&k.as_str()))
        {
            Some(key) if key == "thickness" => Err(case_error(
                "[analysis]: `thickness` is not used in axisymmetric analyses (forces and \
                 reactions are totals over the full ring); remove it"
                    .into(),
            )),
            Some(key) => Err(case_error(format!(
                "[analysis]: unknown key `{key}` (an axisymmetric analysis has only `type` and \
                 `twist`)"
            ))),
            None => Ok(()),
        };
    }
    match (kind, analysis.get("twist")) {
        (Some(kind), Some(twist)) => Err(Error::InvalidParameter {
            path: path.to_path_buf(),
            key: "analysis.twist".into(),
            value: twist.to_string(),
            reason: format!(
                "twist (the circumferential displacement u_θ) needs type = \"axisymmetric\"; \
                 a {kind} analysis has no axis to twist about"
            ),
        }),
        _ => Ok(()),
    }
}

impl Case {
    /// Every check of a read case, in key order; the first failure is returned.
    pub(super) fn validate(&self) -> Result<()> {
        self.check_mesh()?;
        self.check_analysis()?;
        self.check_bodies()?;
        self.check_supports()?;
        self.check_loads()?;
        self.check_contacts()?;
        self.check_steps()?;
        self.check_analysis_steps()?;
        self.check_factors()?;
        self.check_solver()?;
        self.check_names()?;
        self.check_laws()?;
        self.check_hysteresis_points()?;
        self.check_wear()?;
        self.check_thermal()?;
        self.check_quantities()
    }

    /// `[mesh]`: a file or a script, a positive size, and parameters that gmsh takes (it
    /// hangs on a NaN and its `-setnumber` needs an identifier).
    fn check_mesh(&self) -> Result<()> {
        match (&self.mesh.file, &self.mesh.geo) {
            (Some(_), Some(_)) => {
                return Err(self.error("[mesh]: give either `file` or `geo`, not both"));
            }
            (None, None) => {
                return Err(
                    self.error("[mesh]: give `file` (an .msh file) or `geo` (a gmsh script)")
                );
            }
            _ => {}
        }
        if !self.mesh.size.is_finite() || self.mesh.size <= 0.0 {
            return Err(self.invalid("mesh.size", self.mesh.size, "must be positive and finite"));
        }
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

    /// `[analysis] thickness`: positive and finite.
    fn check_analysis(&self) -> Result<()> {
        let (AnalysisSpec::PlaneStress { thickness } | AnalysisSpec::PlaneStrain { thickness }) =
            self.analysis
        else {
            return Ok(());
        };
        if thickness.is_nan() || thickness <= 0.0 {
            return Err(self.invalid("analysis.thickness", thickness, "must be positive"));
        }
        if thickness.is_infinite() {
            return Err(self.invalid(
                "analysis.thickness",
                thickness,
                "must be positive and finite",
            ));
        }
        Ok(())
    }

    /// At least one `[[body]]`; hardening only with a yield stress.
    fn check_bodies(&self) -> Result<()> {
        if self.bodies.is_empty() {
            return Err(
                self.error("no [[body]]: name at least one physical surface and its material")
            );
        }
        for (i, b) in self.bodies.iter().enumerate() {
            if let (None, Some(h)) = (b.material.yield_stress, b.material.hardening) {
                return Err(self.invalid(
                    format!("body[{i}].material.hardening"),
                    h,
                    format!("`hardening` needs a `yield_stress` (body '{}')", b.group),
                ));
            }
            self.check_cyclic_hardening(i, b)?;
        }
        Ok(())
    }

    /// `kinematic` and `isotropic` of body `i`: only with a yield stress, one to five
    /// backstresses, each C > 0 and gamma ≥ 0, Voce b ≥ 0 and Q > −yield_stress (the
    /// material checks the rest when it is built).
    fn check_cyclic_hardening(&self, i: usize, b: &super::BodySpec) -> Result<()> {
        let m = &b.material;
        let key = |k: &str| format!("body[{i}].material.{k}");
        if m.yield_stress.is_none() && m.has_cyclic_hardening() {
            let name = if m.kinematic.is_some() {
                "kinematic"
            } else {
                "isotropic"
            };
            return Err(self.invalid(
                key(name),
                "(given)",
                format!("`{name}` needs a `yield_stress` (body '{}')", b.group),
            ));
        }
        if let Some(sy) = m.yield_stress.filter(|sy| !(sy.is_finite() && *sy > 0.0)) {
            // before the bounds below that depend on it (Q > −yield_stress)
            return Err(self.invalid(
                key("yield_stress"),
                sy,
                format!(
                    "the yield stress (MPa) must be positive and finite (body '{}')",
                    b.group
                ),
            ));
        }
        if let Some(terms) = m.kinematic.as_ref().map(|k| k.as_slice()) {
            // (a longer list is refused when the case is read)
            if terms.is_empty() {
                return Err(self.invalid(
                    key("kinematic"),
                    "[]",
                    format!(
                        "give 1 to {MAX_KINEMATIC_TERMS} backstresses {{ C, gamma }} (body '{}')",
                        b.group
                    ),
                ));
            }
            for (k, t) in terms.iter().enumerate() {
                if !(t.c.is_finite() && t.c > 0.0) {
                    return Err(self.invalid(
                        key(&format!("kinematic[{k}].C")),
                        t.c,
                        "the kinematic hardening modulus C (MPa) must be positive and finite",
                    ));
                }
                if !(t.gamma.is_finite() && t.gamma >= 0.0) {
                    return Err(self.invalid(
                        key(&format!("kinematic[{k}].gamma")),
                        t.gamma,
                        "the recovery rate gamma must be finite and non-negative (0: Prager)",
                    ));
                }
            }
        }
        if let Some(v) = m.isotropic {
            if !(v.b.is_finite() && v.b >= 0.0) {
                return Err(self.invalid(
                    key("isotropic.b"),
                    v.b,
                    "the Voce rate b must be finite and non-negative",
                ));
            }
            let sy = m.yield_stress.unwrap_or(0.0);
            if !(v.q.is_finite() && v.q > -sy) {
                return Err(self.invalid(
                    key("isotropic.Q"),
                    v.q,
                    format!("the Voce saturation Q (MPa) must be finite and greater than -yield_stress = {}", -sy),
                ));
            }
        }
        Ok(())
    }

    /// Every `[[support]]` prescribes a component, with a finite value; `utheta` and
    /// `rotation` only with twist, and not both.
    fn check_supports(&self) -> Result<()> {
        let twist = self.analysis.has_twist();
        for (i, s) in self.supports.iter().enumerate() {
            let values = [
                ("ux", s.ux),
                ("uy", s.uy),
                ("utheta", s.utheta),
                ("rotation", s.rotation),
            ];
            if values.iter().all(|(_, v)| v.is_none()) {
                let keys = if twist {
                    "ux, uy, utheta or rotation"
                } else {
                    "ux and/or uy"
                };
                return Err(self.error(format!("[[support]] '{}': give {keys}", s.group)));
            }
            for (key, value) in values {
                if let Some(v) = value.filter(|v| !v.is_finite()) {
                    return Err(self.invalid(format!("support[{i}].{key}"), v, "must be finite"));
                }
            }
            for (key, value) in &values[2..] {
                if let Some(v) = value.filter(|_| !twist) {
                    return Err(self.invalid(format!("support[{i}].{key}"), v, NEEDS_TWIST));
                }
            }
            if let (Some(_), Some(phi)) = (s.utheta, s.rotation) {
                return Err(self.invalid(
                    format!("support[{i}].rotation"),
                    phi,
                    format!(
                        "support '{}' gives both `utheta` and `rotation`, which both prescribe \
                         u_θ: give one",
                        s.name()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Every `[[load]]` is one finite pressure, traction, force or torque; a torque and a
    /// traction of three components only with twist.
    fn check_loads(&self) -> Result<()> {
        let twist = self.analysis.has_twist();
        for (i, l) in self.loads.iter().enumerate() {
            let given = [
                l.pressure.is_some(),
                l.traction.is_some(),
                l.force.is_some(),
                l.torque.is_some(),
            ]
            .iter()
            .filter(|&&b| b)
            .count();
            if given != 1 {
                let keys = if twist {
                    "pressure, traction, force, torque"
                } else {
                    "pressure, traction, force"
                };
                return Err(self.error(format!(
                    "[[load]] '{}': give exactly one of {keys}",
                    l.group
                )));
            }
            if let Some(t) = &l.traction {
                self.check_components(i, "traction", t, ("t_x, t_y", "t_r, t_z, t_θ"))?;
            }
            if let Some(f) = &l.force {
                self.check_components(i, "force", f, ("F_x, F_y", "F_r, F_z, F_θ"))?;
            }
            if let Some(t) = l.torque.filter(|_| !twist) {
                return Err(self.invalid(format!("load[{i}].torque"), t, NEEDS_TWIST));
            }
            let values = [
                ("pressure", l.pressure.map(|p| vec![p])),
                ("traction", l.traction.clone()),
                ("force", l.force.clone()),
                ("torque", l.torque.map(|t| vec![t])),
            ];
            for (key, value) in values {
                if let Some(v) = value.filter(|v| v.iter().any(|x| !x.is_finite())) {
                    let shown = if v.len() == 1 {
                        v[0].to_string()
                    } else {
                        format!("{v:?}")
                    };
                    return Err(self.invalid(format!("load[{i}].{key}"), shown, "must be finite"));
                }
            }
        }
        Ok(())
    }

    /// A load vector `key` of `[[load]]` number `i` has two components, or three with twist
    /// (`names`: the components' names in each case, for the message).
    fn check_components(
        &self,
        i: usize,
        key: &str,
        v: &[f64],
        (plane, twisted): (&str, &str),
    ) -> Result<()> {
        let path = format!("load[{i}].{key}");
        match v.len() {
            2 => Ok(()),
            3 if self.analysis.has_twist() => Ok(()),
            3 => Err(self.invalid(
                path,
                format!("{v:?}"),
                format!(
                    "a third (circumferential) {key} component needs an axisymmetric analysis \
                     with twist: set [analysis] type = \"axisymmetric\", twist = true, or give \
                     ({plane})"
                ),
            )),
            n => Err(self.invalid(
                path,
                format!("{v:?}"),
                format!(
                    "a {key} has two components ({plane}), or with twist three ({twisted}); \
                     got {n}"
                ),
            )),
        }
    }

    /// Every `[[contact]]` gives its faces one way, and a finite interference.
    fn check_contacts(&self) -> Result<()> {
        for (i, c) in self.contacts.iter().enumerate() {
            if c.faces().is_none() {
                return Err(self.error(format!(
                    "[[contact]] '{}': give either side_a and side_b (with optional pairing), or curve, body_a \
                     and body_b",
                    c.name()
                )));
            }
            if !c.interference.is_finite() {
                return Err(self.invalid(
                    format!("contact[{i}].interference"),
                    c.interference,
                    "must be finite",
                ));
            }
        }
        Ok(())
    }

    /// Per-load `factors` of the `[steps]` form: one finite value per step.
    fn check_factors(&self) -> Result<()> {
        let steps = self.steps.len();
        let own = self.supports.iter().map(|s| &s.factors).enumerate();
        let own = own
            .map(|(i, f)| (format!("support[{i}].factors"), f))
            .chain(
                self.loads
                    .iter()
                    .enumerate()
                    .map(|(i, l)| (format!("load[{i}].factors"), &l.factors)),
            );
        for (key, factors) in own {
            if let Some(f) = factors
                && (f.len() != steps || f.iter().any(|x| !x.is_finite()))
            {
                return Err(self.invalid(
                    key,
                    format!("{f:?}"),
                    format!("needs one finite value per step ({steps}), got {}", f.len()),
                ));
            }
        }
        Ok(())
    }

    /// `[[quantity]]`: each one valid for this case, no name twice.
    fn check_quantities(&self) -> Result<()> {
        let mut names = BTreeSet::new();
        for q in &self.quantities {
            q.check(self).map_err(|m| self.error(m))?;
            if !names.insert(&q.name) {
                return Err(self.error(format!("[[quantity]] '{}' is defined twice", q.name)));
            }
        }
        Ok(())
    }

    /// Every group and pair name (they become parts of file names and CSV headers), no
    /// physical surface in two bodies, and no pair name used twice (two pairs of one name would overwrite each other's files, and
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
        let mut bodies = BTreeSet::new();
        for (i, b) in self.bodies.iter().enumerate() {
            if !bodies.insert(&b.group) {
                return Err(self.invalid(
                    format!("body[{i}].group"),
                    format!("{:?}", b.group),
                    "another [[body]] has this physical surface: give each surface one body \
                     (and one material)",
                ));
            }
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

    /// `[steps]`: `count` or `factors`, finite factors, bounded counts.
    fn check_steps(&self) -> Result<()> {
        let steps = &self.steps;
        match (&steps.factors, steps.count) {
            (Some(_), Some(_)) => {
                return Err(self.error("[steps]: give either `count` or `factors`, not both"));
            }
            (Some(f), None) if f.is_empty() => {
                return Err(self.invalid("steps.factors", "[]", "must not be empty"));
            }
            (Some(f), None) if f.iter().any(|x| !x.is_finite()) => {
                return Err(self.invalid("steps.factors", format!("{f:?}"), "must be finite"));
            }
            (None, Some(0)) => return Err(self.invalid("steps.count", 0, "must be at least 1")),
            _ => {}
        }
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

    /// `[solver]`: positive and bounded iteration and cut-back counts, tolerances in
    /// (0, 1 %] and the linear one not above the residual one.
    fn check_solver(&self) -> Result<()> {
        let s = &self.solver;
        if s.max_iterations == 0 {
            return Err(self.invalid("solver.max_iterations", 0, "must be positive"));
        }
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
        if s.interface_iterations > MAX_INTERFACE_ITERATIONS {
            return Err(self.invalid(
                "solver.interface_iterations",
                s.interface_iterations,
                format!("at most {MAX_INTERFACE_ITERATIONS} (0 turns them off)"),
            ));
        }
        if s.max_solves == 0 {
            return Err(self.invalid("solver.max_solves", 0, "must be positive"));
        }
        let tolerances = [
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
        ];
        let positive = [
            ("solver.late_residual_tolerance", s.late_residual_tolerance),
            ("solver.average_force", s.average_force.unwrap_or(1.0)),
        ];
        for (key, value) in tolerances.into_iter().chain(positive) {
            if !(value.is_finite() && value > 0.0) {
                return Err(self.invalid(key, value, "must be positive and finite"));
            }
        }
        if s.linear_residual_tolerance > s.residual_tolerance {
            return Err(self.invalid(
                "solver.linear_residual_tolerance",
                s.linear_residual_tolerance,
                format!(
                    "must not exceed residual_tolerance ({}): a linear increment is accepted \
                     without the correction check",
                    s.residual_tolerance
                ),
            ));
        }
        for (key, value) in tolerances {
            if value > MAX_TOLERANCE {
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
