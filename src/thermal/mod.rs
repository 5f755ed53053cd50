//! Steady heat conduction on the bodies' quadratic mesh (Abaqus' steady *HEAT TRANSFER):
//! −∇·(k ∇T) = Q in the conducting bodies, with prescribed temperatures, fluxes and films on
//! curves, and heat crossing the contact pairs' joints with a conductance that may depend on
//! the contact pressure (*GAP CONDUCTANCE; the rough joint's h = h0 (|p|/1 MPa)^n).
//!
//! Galerkin on the same quad8/tri6 cells and rules as the mechanics (dV = t dA or 2πr dA, so
//! heat flows are totals over the full circle in axisymmetry, like forces):
//! K = ∫ ∇Nᵀ k ∇N dV + ∫ h N Nᵀ dA (films) + ∫ h [N_A; −N_B][N_A; −N_B]ᵀ dA (joints),
//! f = ∫ N Q dV + ∫ N q dA + ∫ N h T_∞ dA. The joints use their interface elements' points
//! and weights (lumped with the default Newton-Cotes rule) and each point's contact state:
//! a closed point conducts with h(p), an open one with the gap conductance. Temperatures
//! are changes from the stress-free reference; a node held by two temperature supports
//! takes the later one's value. The system is solved by [`crate::solver::conduction`]: the
//! cells' and films' part, which depends on neither the time nor the contact, factored once
//! per run, the joints' part in a small dense system at every solve.
//!
//! `assembly` gives the system's parts (the constant matrix, the load, the joints' entries),
//! `flows` sums the heat flows of solved temperatures, `fixed` checks that every conducting
//! region's temperature is held (and finds the regions open joints cut off in a solve), and
//! `flux` recovers the nodal heat flux.

mod assembly;
mod fixed;
mod flows;
mod flux;

pub use assembly::{HeatLoad, JointAt};
pub use fixed::CellRegions;

use assembly::SourceBody;

use crate::contact::{ContactStatus, InterfaceState};
use crate::element::Analysis;
use crate::element::set::{ContinuumSet, InterfaceSet, TemperatureField};

/// A boundary condition of the conduction on a curve (values at multiplier 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ThermalCondition {
    /// Prescribed temperature change.
    Temperature(f64),
    /// Heat flux in W/mm², positive into the body.
    Flux(f64),
    /// Convection q = h (T_ambient − T) into the body; only the ambient scales.
    Film { h: f64, ambient: f64 },
}

/// A thermal support: its condition on the lines of a curve.
#[derive(Clone, Debug, PartialEq)]
pub struct ThermalSupport {
    pub name: String,
    pub condition: ThermalCondition,
    /// Amplitude of the model's schedule that scales the condition's value.
    pub amplitude: usize,
    /// Its lines' nodes (end, end, middle), all on conducting bodies.
    pub lines: Vec<[u32; 3]>,
}

/// A uniform volumetric heat source in a body.
#[derive(Clone, Debug, PartialEq)]
pub struct HeatSource {
    pub name: String,
    pub body: u32,
    /// W/mm³ at multiplier 1.
    pub power: f64,
    pub amplitude: usize,
}

/// Unit of contact pressure of the rough joint's conductance law.
pub const REFERENCE_PRESSURE: f64 = 1.0;

/// The heat conductance of a joint: h0 (|p|/1 MPa)^exponent at closed points (exponent 0:
/// a constant), `gap` at open ones; W/(mm²·K).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointConductance {
    pub h0: f64,
    pub exponent: f64,
    pub gap: f64,
}

impl JointConductance {
    /// The conductance at an interface point in `state`.
    pub fn at(&self, state: &InterfaceState) -> f64 {
        if state.status == ContactStatus::Open {
            return self.gap;
        }
        if self.exponent == 0.0 {
            return self.h0;
        }
        self.h0 * (state.stress[1].abs() / REFERENCE_PRESSURE).powf(self.exponent)
    }
}

/// The conduction problem of a model, built once: which nodes carry a temperature, which are
/// prescribed, and the supports, sources and joints.
#[derive(Clone, Debug)]
pub struct Conduction {
    pub analysis: Analysis,
    /// Conductivity k (W/(mm·K)) of each body; `None`: the body does not conduct.
    pub conductivity: Vec<Option<f64>>,
    pub supports: Vec<ThermalSupport>,
    pub sources: Vec<HeatSource>,
    /// Per contact pair, its conductance (`None`: no heat crosses it).
    pub joints: Vec<Option<JointConductance>>,
    /// Conduction index of every mesh node (`None`: in no conducting body).
    index: Vec<Option<u32>>,
    /// Coordinates of every mesh node.
    coords: Vec<[f64; 2]>,
    /// Body names, for messages.
    body_names: Vec<String>,
    /// Mesh node of every conduction index.
    nodes: Vec<u32>,
    /// Per conduction index, the temperature support that holds it.
    fixed: Vec<Option<u32>>,
    /// ∫ N dV and the volume of each body with a heat source.
    source_bodies: Vec<Option<SourceBody>>,
}

/// The steady temperature and the heat flows of one solve (W; totals over 2π in
/// axisymmetry, per thickness in plane problems).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HeatSolution {
    /// Temperature change of every mesh node (0 outside the conducting bodies).
    pub nodal: Vec<f64>,
    /// Heat entering the bodies through each thermal support.
    pub supports: Vec<f64>,
    /// Heat each source generates.
    pub sources: Vec<f64>,
    /// Heat crossing each contact pair from side A to side B.
    pub joints: Vec<f64>,
}

/// The temperatures of a solution: the field that drives the thermal strains and the
/// conduction it came from (recomputed from the model at every increment, so no part of a
/// restart record).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ThermalState {
    pub field: TemperatureField,
    pub heat: Option<HeatSolution>,
    /// Conduction–mechanics exchanges of the last increment (staggered coupling).
    pub exchanges: usize,
}

/// One joint point's heat transfer: conductance, jump T_A − T_B and flux h (T_A − T_B) from A
/// to B.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointPoint {
    pub conductance: f64,
    pub jump: f64,
    pub flux: f64,
}

impl Conduction {
    /// The problem on `continuum`'s conducting bodies (`conductivity`) and the contact
    /// pairs' `joints`, on the mesh nodes at `coords`. The supports' lines must lie on conducting bodies
    /// (checked by the model).
    pub fn new(
        continuum: &ContinuumSet,
        coords: &[[f64; 2]],
        body_names: &[String],
        conductivity: Vec<Option<f64>>,
        supports: Vec<ThermalSupport>,
        sources: Vec<HeatSource>,
        joints: Vec<Option<JointConductance>>,
    ) -> Self {
        let mut index = vec![None; coords.len()];
        let mut nodes = Vec::new();
        for c in &continuum.cells {
            if conductivity[c.body as usize].is_none() {
                continue;
            }
            for &n in &c.nodes[..c.kind.node_count()] {
                if index[n as usize].is_none() {
                    index[n as usize] = Some(nodes.len() as u32);
                    nodes.push(n);
                }
            }
        }
        let mut fixed = vec![None; nodes.len()];
        for (s, support) in supports.iter().enumerate() {
            if let ThermalCondition::Temperature(_) = support.condition {
                for n in support.lines.iter().flatten() {
                    if let Some(i) = index[*n as usize] {
                        fixed[i as usize] = Some(s as u32);
                    }
                }
            }
        }
        let mut conduction = Self {
            analysis: continuum.analysis,
            conductivity,
            supports,
            sources,
            joints,
            index,
            coords: coords.to_vec(),
            body_names: body_names.to_vec(),
            nodes,
            fixed,
            source_bodies: Vec::new(),
        };
        conduction.source_bodies = conduction.source_bodies(continuum);
        conduction
    }

    /// Number of nodes carrying a temperature (the conduction indices 0..size).
    pub fn size(&self) -> usize {
        self.nodes.len()
    }

    /// Per conduction index, whether a temperature support prescribes it.
    pub fn prescribed(&self) -> Vec<bool> {
        self.fixed.iter().map(Option::is_some).collect()
    }

    /// Sets the prescribed temperatures of `t` (conduction indices), the supports' values
    /// scaled by `multiplier(amplitude)`; a node held by two supports takes the later one's.
    pub fn set_prescribed(&self, multiplier: &impl Fn(usize) -> f64, t: &mut [f64]) {
        for (ti, f) in t.iter_mut().zip(&self.fixed) {
            if let Some(s) = f {
                let support = &self.supports[*s as usize];
                if let ThermalCondition::Temperature(v) = support.condition {
                    *ti = v * multiplier(support.amplitude);
                }
            }
        }
    }

    /// The conduction indices of the nodes of every conducting cell and of every conducting
    /// joint's interface element (each list its element's), the couplings of the
    /// conduction matrix.
    pub fn element_nodes(
        &self,
        continuum: &ContinuumSet,
        interface: &InterfaceSet,
    ) -> Vec<Vec<u32>> {
        let cells = continuum
            .cells
            .iter()
            .filter(|c| self.conductivity[c.body as usize].is_some())
            .map(|c| c.nodes[..c.kind.node_count()].to_vec());
        let joints = interface
            .elements
            .iter()
            .filter(|e| self.joints[e.pair as usize].is_some())
            .map(|e| e.nodes.to_vec());
        cells
            .chain(joints)
            .map(|nodes| {
                let index = |n: u32| self.index[n as usize].expect("conducting node");
                nodes.into_iter().map(index).collect()
            })
            .collect()
    }

    /// The conduction indices of the nodes of the conducting joints' interface elements.
    pub fn joint_indices(&self, interface: &InterfaceSet) -> Vec<u32> {
        let conducting = interface
            .elements
            .iter()
            .filter(|e| self.joints[e.pair as usize].is_some());
        let nodes = conducting.flat_map(|e| e.nodes);
        nodes
            .map(|n| self.index[n as usize].expect("checked"))
            .collect()
    }

    /// Whether the conduction depends on the contact states (some joint conducts).
    pub fn is_coupled(&self) -> bool {
        self.joints.iter().any(Option::is_some)
    }

    /// Whether mesh node `n` carries a temperature.
    pub fn conducts(&self, n: u32) -> bool {
        self.index[n as usize].is_some()
    }
}
