//! The model's temperatures: uniform body temperature changes (`[[temperature]]`) and the
//! steady heat conduction ([`crate::thermal::Conduction`]) with its supports, sources and
//! joints, built from a [`ThermalSpec`]; and the temperature field at a pseudo-time that
//! drives the bodies' thermal strains.

use super::thermal_spec::{BodyHeatSource, ThermalBoundary, ThermalSpec};
use super::{Model, Schedule};
use crate::element::set::{ContinuumSet, InterfaceSet, TemperatureField};
use crate::error::{GroupKind, GroupProblem};
use crate::mesh::Mesh;
use crate::thermal::{Conduction, HeatSolution, HeatSource, JointConductance, ThermalSupport};
use crate::{Error, Result};

/// A uniform temperature change of a body: (body, ΔT at multiplier 1, amplitude).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UniformTemperature {
    pub body: u32,
    pub change: f64,
    pub amplitude: usize,
}

/// The thermal part of a model.
#[derive(Clone, Debug, Default)]
pub struct Thermal {
    pub uniform: Vec<UniformTemperature>,
    /// The conduction problem, when some body conducts.
    pub conduction: Option<Conduction>,
}

/// What [`build`] needs of the model under construction.
pub(super) struct ThermalInputs<'a> {
    pub mesh: &'a Mesh,
    pub bodies: &'a [String],
    pub continuum: &'a ContinuumSet,
    pub interface: &'a InterfaceSet,
    pub conductivity: Vec<Option<f64>>,
    pub joints: Vec<Option<JointConductance>>,
}

/// The thermal part of a model from `spec`, adding its histories to `schedule`.
pub(super) fn build(
    inputs: ThermalInputs,
    spec: ThermalSpec,
    schedule: &mut Schedule,
) -> Result<Thermal> {
    let ThermalInputs {
        mesh,
        bodies,
        continuum,
        interface,
        conductivity,
        joints,
    } = inputs;
    let body = |group: &str| bodies.iter().position(|b| b == group).map(|b| b as u32);
    let uniform = spec
        .temperatures
        .iter()
        .map(|t| UniformTemperature {
            body: body(&t.group).expect("checked with the case"),
            change: t.change,
            amplitude: schedule.add(&t.factors),
        })
        .collect();
    if conductivity.iter().all(Option::is_none) {
        return Ok(Thermal {
            uniform,
            conduction: None,
        });
    }
    let supports = spec
        .supports
        .into_iter()
        .map(|s| support(mesh, s, schedule))
        .collect::<Result<Vec<_>>>()?;
    let sources = spec
        .sources
        .into_iter()
        .map(
            |BodyHeatSource {
                 name,
                 group,
                 power,
                 factors,
             }| HeatSource {
                name,
                body: body(&group).expect("checked with the case"),
                power,
                amplitude: schedule.add(&factors),
            },
        )
        .collect();
    let conduction = Conduction::new(
        continuum,
        &mesh.nodes,
        bodies,
        conductivity,
        supports,
        sources,
        joints,
    );
    check_on_conducting(&conduction, interface)?;
    conduction.check_held(continuum, interface)?;
    Ok(Thermal {
        uniform,
        conduction: Some(conduction),
    })
}

/// A thermal support's lines: a physical curve of the mesh.
fn support(mesh: &Mesh, s: ThermalBoundary, schedule: &mut Schedule) -> Result<ThermalSupport> {
    let role = "thermal support";
    let group = match (mesh.group(1, &s.group), mesh.group(0, &s.group)) {
        (Some(g), _) => g,
        (None, Some(g)) => {
            let problem = GroupProblem::WrongKind {
                found: g.kind(),
                purpose: "a thermal support (temperature, flux or film on a curve)",
            };
            return Err(mesh.group_error(role, &s.group, GroupKind::Curve, problem));
        }
        (None, None) => return Err(mesh.missing_group(role, &s.group, GroupKind::Curve)),
    };
    let lines: Vec<[u32; 3]> = mesh.lines_in(group).map(|l| l.nodes).collect();
    if lines.is_empty() {
        let problem = GroupProblem::Empty;
        return Err(mesh.group_error(role, &s.group, GroupKind::Curve, problem));
    }
    Ok(ThermalSupport {
        name: s.name,
        condition: s.condition,
        amplitude: schedule.add(&s.factors),
        lines,
    })
}

/// Every thermal support's nodes and every conducting joint's nodes lie on conducting
/// bodies.
fn check_on_conducting(conduction: &Conduction, interface: &InterfaceSet) -> Result<()> {
    for s in &conduction.supports {
        if let Some(&n) = s.lines.iter().flatten().find(|&&n| !conduction.conducts(n)) {
            return Err(Error::ThermalModel(format!(
                "thermal support '{}': node {} is on no body with `conductivity` (a thermal \
                 support needs a curve on the boundary of a conducting body)",
                s.name,
                n + 1
            )));
        }
    }
    for e in &interface.elements {
        if conduction.joints[e.pair as usize].is_some()
            && e.nodes.iter().any(|&n| !conduction.conducts(n))
        {
            let pair = &interface.pairs[e.pair as usize].name;
            return Err(Error::ThermalModel(format!(
                "contact '{pair}' has a `conductance`, but a body on one of its sides has no \
                 `conductivity`: heat can cross a joint only between conducting bodies"
            )));
        }
    }
    Ok(())
}

impl Model {
    /// Whether the model has temperatures (uniform or conducted).
    pub fn has_temperature(&self) -> bool {
        !self.thermal.uniform.is_empty() || self.thermal.conduction.is_some()
    }

    /// Whether the conduction depends on the contact pressures (staggered coupling).
    pub fn is_thermally_coupled(&self) -> bool {
        self.thermal
            .conduction
            .as_ref()
            .is_some_and(Conduction::is_coupled)
    }

    /// The temperature field at pseudo-time `time`: the uniform changes of the bodies with a
    /// `[[temperature]]` (0 for the other non-conducting ones), the conduction's `heat` in
    /// the conducting ones. Empty without temperatures.
    pub fn temperature_field(&self, time: f64, heat: Option<&HeatSolution>) -> TemperatureField {
        if !self.has_temperature() {
            return TemperatureField::default();
        }
        let conducting = |b: usize| {
            self.thermal
                .conduction
                .as_ref()
                .is_some_and(|c| c.conductivity[b].is_some())
        };
        let mut bodies: Vec<Option<f64>> = (0..self.bodies.len())
            .map(|b| (!conducting(b)).then_some(0.0))
            .collect();
        for t in &self.thermal.uniform {
            bodies[t.body as usize] = Some(t.change * self.schedule.value(t.amplitude, time));
        }
        TemperatureField {
            bodies,
            nodal: heat.map(|h| h.nodal.clone()).unwrap_or_default(),
        }
    }
}
