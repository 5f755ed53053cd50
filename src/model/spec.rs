//! What a model is built from ([`ModelSpec`]): the case's analysis, bodies with their
//! materials, supports, loads and contact pairs with their laws, converted from the case
//! file's plain data. Every material and interface law is built here, exactly once, and so
//! checked before any mesh exists; [`Model::build`](super::Model::build) consumes the spec.

use super::loads::{History, Schedule, Table, factors_history};
use super::thermal_spec::{ThermalSpec, thermal};
use super::timeline::{StepPlan, Timeline};
use crate::config::wear::{WearLawKind, WearSpec};
use crate::config::{
    AnalysisSpec, Case, ContactAlgorithmKind, ContactSpec, ControlKind, Faces, FormulationKind,
    IntegrationKind, Leg, MaterialSpec, Motion, PairingKind, Role, Steps,
};
use crate::contact::laws;
use crate::contact::wear::{DEFAULT_JUMP_LIMIT, WearLaw, WearModel};
use crate::contact::{ContactAlgorithm, InterfaceLaw};
use crate::element::Analysis;
use crate::element::continuum::Formulation;
use crate::element::interface6::InterfaceRule;
use crate::error::ParameterError;
use crate::material::Material;
use crate::material::cyclic::{CyclicPlasticity, KinematicTerm, Voce};
use crate::material::elastic::LinearElastic;
use crate::material::j2::J2Plasticity;
use crate::mesh::interface::Pairing;
use crate::thermal::JointConductance;
use crate::{Error, Result};

/// The bodies, supports, loads and contact pairs of a case, with built materials and laws.
#[derive(Debug)]
pub struct ModelSpec {
    pub analysis: Analysis,
    pub bodies: Vec<Body>,
    /// Supports in case-file order.
    pub supports: Vec<Prescribed>,
    pub loads: Vec<Load>,
    pub contacts: Vec<Contact>,
    /// The analysis steps and the global load factor (the supports' and loads' own
    /// histories are added when the model is built).
    pub schedule: Schedule,
    /// How the steps are controlled and when a converged increment is implausible.
    pub control: Control,
    /// Uniform body temperatures, thermal supports and heat sources.
    pub thermal: ThermalSpec,
}

/// How the load steps are driven and checked (`[steps]` and the bounds of `[solver]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Control {
    /// Largest nodal displacement increment as a fraction of the model size.
    pub max_displacement_increment: f64,
    /// Largest equivalent strain increment at an integration point.
    pub max_strain_increment: f64,
    /// Collapse when the last converged secant stiffness Δλ/‖Δu‖ is below this fraction of
    /// the first increment's.
    pub collapse_stiffness_ratio: f64,
    /// Most increment solves of a load-controlled run (`[solver] max_solves`).
    pub max_solves: usize,
    /// Whether some body is elasto-plastic.
    pub plastic: bool,
    /// Arc-length control instead of the load factors of the steps.
    pub arc_length: Option<ArcLength>,
}

/// Settings of arc-length control (`[steps] control = "arc_length"`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArcLength {
    /// Load-factor increment of the first increment (sets the arc length).
    pub initial_increment: f64,
    pub max_increments: usize,
    /// Stop once the load factor reaches this.
    pub max_load_factor: f64,
    /// Smallest and largest arc, relative to the first.
    pub min_arc_length: f64,
    pub max_arc_length: f64,
}

impl Default for Control {
    fn default() -> Self {
        let solver = crate::config::SolverSpec::default();
        Self {
            max_displacement_increment: solver.max_displacement_increment,
            max_strain_increment: solver.max_strain_increment,
            collapse_stiffness_ratio: solver.collapse_stiffness_ratio,
            max_solves: solver.max_solves,
            plastic: false,
            arc_length: None,
        }
    }
}

/// A body: a physical surface, its material and its element formulation.
#[derive(Debug)]
pub struct Body {
    pub group: String,
    pub material: Box<dyn Material>,
    pub formulation: Formulation,
    /// Linear thermal expansion coefficient α (1/K).
    pub expansion: f64,
    /// Thermal conductivity (W/(mm·K)); `None`: the body does not conduct.
    pub conductivity: Option<f64>,
}

/// Prescribed displacement components on the nodes of a physical curve or point, at load
/// factor 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Prescribed {
    /// The user's name (`name`, else the group): in history columns, summary keys, the log.
    pub name: String,
    pub group: String,
    /// (u_x, u_y); `None` leaves the component free.
    pub values: [Option<f64>; 2],
    /// The circumferential component (with twist); `None` leaves u_θ free.
    pub circumferential: Option<Circumferential>,
    /// The support's history: the global factor, or its own (`factors` of `[steps]`, its
    /// `[[step]]` tables).
    pub factors: History,
}

/// What a support prescribes in the circumferential direction (axisymmetry with twist).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Circumferential {
    /// u_θ in mm at every node (`utheta`).
    Displacement(f64),
    /// A rigid rotation φ about the axis in radians (`rotation`): u_θ = φ r.
    Rotation(f64),
}

impl Circumferential {
    /// The value given: u_θ (mm) or φ (radians).
    pub fn value(self) -> f64 {
        match self {
            Circumferential::Displacement(v) | Circumferential::Rotation(v) => v,
        }
    }

    /// u_θ at radius `r`.
    pub fn at(self, r: f64) -> f64 {
        match self {
            Circumferential::Displacement(v) => v,
            Circumferential::Rotation(phi) => phi * r,
        }
    }
}

/// A load at load factor 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Load {
    pub group: String,
    pub kind: LoadKind,
    /// The load's history: the global factor, or its own (`factors` of `[steps]`, its
    /// `[[step]]` tables).
    pub factors: History,
}

/// What a load applies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LoadKind {
    /// A distributed load on the lines of a physical curve.
    Line(LineLoad),
    /// A force (F_x, F_y, and with twist F_θ; 0 otherwise) in N at each node of a physical
    /// point group.
    Point([f64; 3]),
}

/// A distributed load on a curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LineLoad {
    /// Normal pressure in MPa, positive pushing into the body.
    Pressure(f64),
    /// Traction vector (t_x, t_y, t_θ) in MPa (t_θ = 0 without twist).
    Traction([f64; 3]),
    /// Torque about the axis in N·mm: a circumferential traction ∝ r whose moment is this.
    Torque(f64),
}

/// A contact pair: how its faces are found, the integration rule, the initial interference,
/// the interface law and the wear of its surfaces.
#[derive(Debug)]
pub struct Contact {
    pub name: String,
    pub pairing: Pairing,
    pub rule: InterfaceRule,
    pub interference: f64,
    pub law: PairLaw,
    pub wear: Option<WearModel>,
    /// The joint's heat conductance (`None`: no heat crosses it).
    pub conductance: Option<JointConductance>,
}

/// The interface law of a contact pair: built, or, when the case leaves a penalty stiffness
/// to its default (which depends on the mesh), checked and built when the model is
/// (`model::penalty`).
#[derive(Debug)]
pub enum PairLaw {
    Built(Box<dyn InterfaceLaw>),
    /// The law's table entry and its values, NaN at the penalty stiffnesses to default.
    Defaulted {
        law: &'static laws::LawDescriptor,
        values: Vec<f64>,
    },
}

impl ModelSpec {
    /// Converts a (checked) case, building each body's material and each pair's law. A
    /// parameter out of its range is an [`Error::InvalidParameter`] naming its key in the
    /// case (`body[0].material.nu`, `contact[1].law.friction`).
    pub fn new(case: &Case) -> Result<Self> {
        let invalid = |prefix: &str, owner: &str, e: ParameterError| {
            case.invalid(
                format!("{prefix}.{}", e.name),
                e.value,
                format!("{} ({owner})", e.reason),
            )
        };
        let bodies =
            case.bodies
                .iter()
                .enumerate()
                .map(|(i, b)| {
                    let material = build_material(&b.material).map_err(|e| {
                        invalid(
                            &format!("body[{i}].material"),
                            &format!("body '{}'", b.group),
                            e,
                        )
                    })?;
                    let analysis: Analysis = case.analysis.into();
                    let requested = b.formulation.map(|f| match f {
                        FormulationKind::Full => Formulation::Full,
                        FormulationKind::Bbar => Formulation::Bbar,
                    });
                    let plastic = b.material.yield_stress.is_some();
                    let formulation =
                        Formulation::for_body(requested, &analysis, plastic, b.material.nu)
                            .map_err(|reason| {
                                let value = requested.map_or("default", Formulation::name);
                                case.invalid(
                                    format!("body[{i}].formulation"),
                                    format!("\"{value}\""),
                                    format!("{reason} (body '{}')", b.group),
                                )
                            })?;
                    Ok(Body {
                        group: b.group.clone(),
                        material,
                        formulation,
                        expansion: b.material.expansion.unwrap_or(0.0),
                        conductivity: b.conductivity,
                    })
                })
                .collect::<Result<_>>()?;
        let contacts = case
            .contacts
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let name = c.name();
                let law = build_law(case, i, c)?;
                let pairing = c.faces().map(pairing).ok_or_else(|| Error::Case {
                    path: case.path.clone(),
                    message: format!("[[contact]] '{name}': the faces are not given"),
                })?;
                Ok(Contact {
                    name,
                    pairing,
                    rule: c.integration.into(),
                    interference: c.interference,
                    law,
                    wear: c.wear.as_ref().map(wear_model),
                    conductance: c.conductance.and_then(|h| h.conductance().ok()).map(|h| {
                        JointConductance {
                            h0: h.h0,
                            exponent: h.exponent,
                            gap: h.gap,
                        }
                    }),
                })
            })
            .collect::<Result<_>>()?;
        let supports: Vec<Prescribed> = case
            .supports
            .iter()
            .map(|s| Prescribed {
                name: s.name().to_string(),
                group: s.group.clone(),
                values: [s.ux, s.uy],
                circumferential: match (s.utheta, s.rotation) {
                    (Some(u), _) => Some(Circumferential::Displacement(u)),
                    (None, Some(phi)) => Some(Circumferential::Rotation(phi)),
                    (None, None) => None,
                },
                factors: history(case, Role::Support, s.name(), s.factors.as_deref()),
            })
            .collect();
        let loads: Vec<Load> = case
            .loads
            .iter()
            .map(|l| {
                // Two or three components (checked when the case was read).
                let three = |t: &[f64]| [t[0], t[1], t.get(2).copied().unwrap_or(0.0)];
                let traction = l.traction.as_deref().map(three);
                let force = l.force.as_deref().map(three);
                let kind = match (l.pressure, traction, force, l.torque) {
                    (Some(p), ..) => LoadKind::Line(LineLoad::Pressure(p)),
                    (None, Some(t), ..) => LoadKind::Line(LineLoad::Traction(t)),
                    (None, None, Some(f), _) => LoadKind::Point(f),
                    (None, None, None, Some(t)) => LoadKind::Line(LineLoad::Torque(t)),
                    (None, None, None, None) => {
                        return Err(Error::Case {
                            path: case.path.clone(),
                            message: format!("[[load]] '{}': no load is given", l.group),
                        });
                    }
                };
                Ok(Load {
                    group: l.group.clone(),
                    kind,
                    factors: history(case, Role::Load, l.name(), l.factors.as_deref()),
                })
            })
            .collect::<Result<_>>()?;
        let solver = &case.solver;
        for (key, value) in [
            (
                "max_displacement_increment",
                solver.max_displacement_increment,
            ),
            ("max_strain_increment", solver.max_strain_increment),
            ("collapse_stiffness_ratio", solver.collapse_stiffness_ratio),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(case.invalid(
                    format!("solver.{key}"),
                    value,
                    "must be positive and finite",
                ));
            }
        }
        let control = Control {
            max_displacement_increment: solver.max_displacement_increment,
            max_strain_increment: solver.max_strain_increment,
            collapse_stiffness_ratio: solver.collapse_stiffness_ratio,
            max_solves: solver.max_solves,
            plastic: case
                .bodies
                .iter()
                .any(|b| b.material.yield_stress.is_some()),
            arc_length: arc_length(case, &supports)?,
        };
        Ok(Self {
            analysis: case.analysis.into(),
            bodies,
            supports,
            loads,
            contacts,
            schedule: schedule(case),
            control,
            thermal: thermal(case),
        })
    }
}

/// The analysis steps of `case` with the global load factor: the `[steps]` factors, or the
/// `[[step]]` steps (cycles per jump defaulting by whether a contact wears).
fn schedule(case: &Case) -> Schedule {
    if !case.has_analysis_steps() {
        return Schedule::new(load_factors(&case.steps));
    }
    let wear = case.has_wear();
    let steps =
        case.analysis_steps.iter().enumerate().map(|(i, s)| {
            StepPlan::new(s.name(i), s.increments, s.cycles, s.cycles_per_jump(wear))
        });
    Schedule::with_steps(Timeline::new(steps.collect()))
}

/// The history of the support or load `name`: its own `[steps]` factors if given, else the
/// global factor; with `[[step]]` a table per step, from its motions through the steps (the
/// global, zero, amplitude for a support that no step names: it holds its zero value).
pub(super) fn history(case: &Case, role: Role, name: &str, factors: Option<&[f64]>) -> History {
    let column = format!("factor_{}_{name}", role.name());
    if !case.has_analysis_steps() {
        return factors.map_or(History::Global, |f| factors_history(column, f));
    }
    let legs = case.legs(role, name);
    if legs.iter().all(|l| l.motion == Motion::Hold) {
        return History::Global;
    }
    let tables = case
        .analysis_steps
        .iter()
        .zip(&legs)
        .map(|(step, leg)| leg_table(leg, step.increments))
        .collect();
    History::Own { column, tables }
}

/// The table of one motion over a step (or cycle) of `increments` output increments: local
/// time u = step time × increments.
fn leg_table(leg: &Leg, increments: usize) -> Table {
    match leg.motion {
        Motion::Hold | Motion::Table(None) => Table::constant(leg.start, increments),
        Motion::Ramp(to) => Table::ramp(leg.start, to, increments),
        Motion::Table(Some((time, value))) => {
            let n = increments as f64;
            Table::new(time.iter().map(|t| t * n).collect(), value.to_vec())
        }
    }
}

/// The arc-length settings of `[steps]`, checked, when `control = "arc_length"`: the loads
/// must all follow the global load factor and no support may prescribe a non-zero value.
fn arc_length(case: &Case, supports: &[Prescribed]) -> Result<Option<ArcLength>> {
    let steps = &case.steps;
    if steps.control != ControlKind::ArcLength {
        return Ok(None);
    }
    let control = "steps.control";
    if let Some(s) = supports.iter().find(|s| {
        let theta = s.circumferential.map(Circumferential::value);
        s.values.iter().chain([&theta]).flatten().any(|&v| v != 0.0)
    }) {
        return Err(case.invalid(
            control,
            "\"arc_length\"",
            format!(
                "arc-length control drives forces and pressures only; support '{}' prescribes \
                 a non-zero displacement (use load control, or a force instead)",
                s.name
            ),
        ));
    }
    if let Some(l) = case.loads.iter().find(|l| l.factors.is_some()) {
        return Err(case.invalid(
            control,
            "\"arc_length\"",
            format!(
                "under arc-length control every load follows the one load factor λ; load on '{}' \
                 has its own factors",
                l.group
            ),
        ));
    }
    let arc = ArcLength {
        initial_increment: steps.initial_increment.unwrap_or(0.1),
        max_increments: steps.max_increments.unwrap_or(100),
        max_load_factor: steps.max_load_factor.unwrap_or(1.0),
        min_arc_length: steps.min_arc_length.unwrap_or(1e-4),
        max_arc_length: steps.max_arc_length.unwrap_or(10.0),
    };
    for (key, value) in [
        ("initial_increment", arc.initial_increment),
        ("max_load_factor", arc.max_load_factor),
        ("min_arc_length", arc.min_arc_length),
        ("max_arc_length", arc.max_arc_length),
        ("max_increments", arc.max_increments as f64),
    ] {
        if !(value > 0.0 && value.is_finite()) {
            return Err(case.invalid(format!("steps.{key}"), value, "must be positive and finite"));
        }
    }
    if arc.min_arc_length > 1.0 || arc.max_arc_length < 1.0 {
        return Err(case.invalid(
            "steps.min_arc_length",
            arc.min_arc_length,
            format!(
                "need min_arc_length ≤ 1 ≤ max_arc_length (relative to the first arc; \
                 max_arc_length = {})",
                arc.max_arc_length
            ),
        ));
    }
    Ok(Some(arc))
}

/// The constitutive model of a body: linear elastic, J2 plasticity with linear isotropic
/// hardening when a yield stress is given, and with combined (kinematic and Voce) hardening
/// when `kinematic` or `isotropic` is given too.
fn build_material(spec: &MaterialSpec) -> std::result::Result<Box<dyn Material>, ParameterError> {
    let elastic = LinearElastic::new(spec.e, spec.nu)?;
    let hardening = spec.hardening.unwrap_or(0.0);
    Ok(match spec.yield_stress {
        None => Box::new(elastic),
        Some(sy) if spec.has_cyclic_hardening() => {
            let kinematic: Vec<KinematicTerm> = (spec.kinematic.iter().flat_map(|k| k.as_slice()))
                .map(|t| KinematicTerm {
                    c: t.c,
                    gamma: t.gamma,
                })
                .collect();
            let voce = spec
                .isotropic
                .map(|v| Voce { q: v.q, b: v.b })
                .unwrap_or_default();
            Box::new(CyclicPlasticity::new(
                elastic, sy, hardening, voce, &kinematic,
            )?)
        }
        Some(sy) => Box::new(J2Plasticity::new(elastic, sy, hardening)?),
    })
}

/// The wear model of a pair (checked by the case validation).
fn wear_model(spec: &WearSpec) -> WearModel {
    WearModel {
        law: match spec.model {
            WearLawKind::Archard => WearLaw::Archard,
            WearLawKind::Energy => WearLaw::Energy,
        },
        coefficients: spec.coefficients(),
        max_depth: spec.max_depth,
        jump_limit: spec.jump_limit.unwrap_or(DEFAULT_JUMP_LIMIT),
    }
}

/// The interface law of contact `i` of `case`, from the table of laws; a parameter given to
/// no effect is a warning, a wrong one an [`Error::InvalidParameter`] naming its key. A law
/// whose penalty stiffnesses default is checked with a stand-in for them (any value in their
/// bound) and built with the model.
fn build_law(case: &Case, i: usize, contact: &ContactSpec) -> Result<PairLaw> {
    let (law, values) = (contact.law.law, contact.law.numbers());
    if let Some(note) = (law.unused)(&values) {
        tracing::warn!(
            "{}: contact[{i}] ('{}'): {note}",
            case.path.display(),
            contact.name()
        );
    }
    let defaulted = law.defaults_penalty(&values);
    let checked = if defaulted {
        law.build(&law.with_penalty(&values, 1.0))
    } else {
        law.build(&values)
    };
    let built = checked.map_err(|e| {
        case.invalid(
            format!("contact[{i}].law.{}", e.name),
            laws::shown(e.value),
            format!("{} (contact '{}')", e.reason, contact.name()),
        )
    })?;
    Ok(if defaulted {
        PairLaw::Defaulted { law, values }
    } else {
        PairLaw::Built(built)
    })
}

/// The pairing recipe of a pair's faces.
fn pairing(faces: Faces) -> Pairing {
    match faces {
        Faces::Sides {
            side_a,
            side_b,
            pairing: PairingKind::Coincident,
        } => Pairing::Coincident {
            side_a: side_a.into(),
            side_b: side_b.into(),
        },
        Faces::Sides {
            side_a,
            side_b,
            pairing: PairingKind::Ordered,
        } => Pairing::Ordered {
            side_a: side_a.into(),
            side_b: side_b.into(),
        },
        Faces::Split {
            curve,
            body_a,
            body_b,
        } => Pairing::Split {
            curve: curve.into(),
            body_a: body_a.into(),
            body_b: body_b.into(),
        },
    }
}

/// The global load factor at the end of each step: the given factors, or `count` equal
/// steps from 1/count to 1.
pub fn load_factors(steps: &Steps) -> Vec<f64> {
    match (&steps.factors, steps.count) {
        (Some(f), _) => f.clone(),
        (None, Some(n)) => (1..=n).map(|i| i as f64 / n as f64).collect(),
        (None, None) => vec![1.0],
    }
}

impl From<AnalysisSpec> for Analysis {
    fn from(spec: AnalysisSpec) -> Self {
        match spec {
            AnalysisSpec::PlaneStress { thickness } => Analysis::PlaneStress { thickness },
            AnalysisSpec::PlaneStrain { thickness } => Analysis::PlaneStrain { thickness },
            AnalysisSpec::Axisymmetric { twist: false } => Analysis::Axisymmetric,
            AnalysisSpec::Axisymmetric { twist: true } => Analysis::AxisymmetricTwist,
        }
    }
}

impl From<IntegrationKind> for InterfaceRule {
    fn from(kind: IntegrationKind) -> Self {
        match kind {
            IntegrationKind::NewtonCotes => InterfaceRule::NewtonCotes,
            IntegrationKind::Gauss => InterfaceRule::Gauss,
        }
    }
}

impl From<ContactAlgorithmKind> for ContactAlgorithm {
    fn from(kind: ContactAlgorithmKind) -> Self {
        match kind {
            ContactAlgorithmKind::Newton => ContactAlgorithm::Newton,
            ContactAlgorithmKind::TwoStep => ContactAlgorithm::TwoStep,
            ContactAlgorithmKind::ElasticContact => ContactAlgorithm::ElasticContact,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::tests::MINIMAL as CASE;
    use std::path::Path;

    fn spec(text: &str) -> Result<ModelSpec> {
        ModelSpec::new(&Case::from_toml(text, Path::new("c.toml"))?)
    }

    #[test]
    fn step_counts_make_uniform_factors() {
        let s = Steps {
            count: Some(4),
            factors: None,
            ..Steps::default()
        };
        assert_eq!(load_factors(&s), vec![0.25, 0.5, 0.75, 1.0]);
        let schedule = spec(CASE).unwrap().schedule;
        assert_eq!((schedule.steps(), schedule.load_factor(1)), (1, 1.0));
    }

    #[test]
    fn a_bad_material_parameter_names_its_key_and_body() {
        let Err(Error::InvalidParameter {
            path,
            key,
            value,
            reason,
        }) = spec(&CASE.replace("E = 210000.0", "E = -1.0"))
        else {
            panic!("expected an invalid parameter")
        };
        assert_eq!(
            (path.as_path(), key.as_str(), value.as_str()),
            (Path::new("c.toml"), "body[0].material.E", "-1")
        );
        assert!(reason.contains("'plate'"), "{reason}");
    }

    /// The case file's limit on backstresses is the material's.
    #[test]
    fn backstress_limits_agree() {
        assert_eq!(
            crate::config::MAX_KINEMATIC_TERMS,
            crate::material::cyclic::MAX_KINEMATIC_TERMS
        );
    }

    /// The cyclic hardening keys build the combined-hardening material; a bad value, or the
    /// keys without a yield stress, is an error naming the key.
    #[test]
    fn cyclic_hardening_keys_build_and_name_bad_values() {
        let with = |keys: &str| {
            CASE.replace(
                "material = { E = 210000.0, nu = 0.3 }",
                &format!("material = {{ E = 210000.0, nu = 0.3, {keys} }}"),
            )
        };
        let built = spec(&with(
            "yield_stress = 250.0, kinematic = [{ C = 1e4, gamma = 50.0 }, { C = 1e3, gamma = 0.0 }], \
             isotropic = { Q = 50.0, b = 5.0 }",
        ))
        .unwrap();
        let m = &built.bodies[0].material;
        assert_eq!(m.internal_variables(), 2 * crate::material::VOIGT_LEN);
        assert!(
            m.describe()
                .contains("backstress 2: C = 1000 MPa, gamma = 0")
        );
        for (keys, expected) in [
            (
                "kinematic = [{ C = 1e4, gamma = 50.0 }]",
                "body[0].material.kinematic",
            ),
            (
                "yield_stress = 250.0, kinematic = []",
                "body[0].material.kinematic",
            ),
            (
                "yield_stress = 250.0, kinematic = [{ C = 1e4, gamma = 1.0 }, { C = -1.0, gamma = 0.0 }]",
                "body[0].material.kinematic[1].C",
            ),
            (
                "yield_stress = 250.0, kinematic = [{ C = 1e4, gamma = -1.0 }]",
                "body[0].material.kinematic[0].gamma",
            ),
            (
                "yield_stress = 250.0, isotropic = { Q = -300.0, b = 1.0 }",
                "body[0].material.isotropic.Q",
            ),
            (
                "isotropic = { Q = 30.0, b = 1.0 }",
                "body[0].material.isotropic",
            ),
        ] {
            let Err(Error::InvalidParameter { key, .. }) = spec(&with(keys)) else {
                panic!("{keys}: expected an invalid parameter")
            };
            assert_eq!(key, expected, "{keys}");
        }
    }

    #[test]
    fn a_bad_law_parameter_names_its_key() {
        let text = format!(
            "{CASE}[[contact]]\nside_a = \"a\"\nside_b = \"b\"\nlaw = {{ type = \"linear_coulomb\", \
             normal_stiffness = 1.0, tangential_stiffness = 1.0, friction = -0.1 }}\n"
        );
        let Err(Error::InvalidParameter { key, .. }) = spec(&text) else {
            panic!("expected an invalid parameter")
        };
        assert_eq!(key, "contact[0].law.friction");
    }
}
