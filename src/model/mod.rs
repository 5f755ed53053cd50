//! The model: a mesh together with bodies and their materials, supports, loads, contact
//! interfaces and the degree-of-freedom numbering. Built once from a [`Mesh`] and a
//! [`ModelSpec`] (which [`ModelSpec::new`] makes from a case file); the solver only reads it.
//!
//! Physical groups are referred to by name: bodies are physical surfaces, supports and loads
//! are physical curves or points (see docs/guide/meshes.md).

mod constraints;
mod loads;
mod penalty;
mod rigid;
mod spec;
mod thermal;
mod thermal_spec;
pub mod timeline;

pub use constraints::{AXIS_SUPPORT, Support};
pub use loads::{History, Schedule, Table};
pub use penalty::{PENALTY_FACTOR, PenaltyDefault};
pub use rigid::Hold;
pub use spec::{
    ArcLength, Body, Circumferential, Contact, Control, LineLoad, Load, LoadKind, ModelSpec,
    PairLaw, Prescribed, load_factors,
};
pub use thermal::{Thermal, UniformTemperature};
pub use thermal_spec::{BodyHeatSource, BodyTemperature, ThermalBoundary, ThermalSpec};

use crate::assembly::{Coloring, DofMap, ElementNodes, SparsityPattern};
use crate::contact::laws::{self, LawDescriptor};
use crate::element::Analysis;
use crate::element::interface6::{
    InterfaceElement, InterfaceRule, chord_length, surface_compliance,
};
use crate::element::kinematics::min_jacobian;
use crate::element::set::{ContactPair, ContinuumCell, ContinuumSet, ElementSet, InterfaceSet};
use crate::error::{GroupKind, GroupProblem, TopologyProblem};
use crate::mesh::interface::{InterfaceTopology, insert_interface};
use crate::mesh::topology::model_size;
use crate::mesh::{Mesh, PhysicalGroup};
use crate::{Error, Result};
use constraints::{Constraints, prescribe};
use loads::nodal_loads;

/// Everything the solver needs, built from a mesh and a [`ModelSpec`].
#[derive(Debug)]
pub struct Model {
    pub mesh: Mesh,
    pub analysis: Analysis,
    /// Body names (physical surface names), indexed by [`ContinuumCell::body`].
    pub bodies: Vec<String>,
    pub continuum: ContinuumSet,
    pub continuum_coloring: Coloring,
    /// Interface elements of the contact pairs.
    pub interface: InterfaceSet,
    pub interface_coloring: Coloring,
    /// The penalty stiffnesses the contact pairs' laws got by default, pair by pair.
    pub penalty_defaults: Vec<PenaltyDefault>,
    /// Supports in case-file order, then the automatic axis support ("axis": u_r = 0 on r = 0) in
    /// axisymmetry.
    pub supports: Vec<Support>,
    /// Prescribed dofs: (dof, value at factor 1, amplitude in [`Model::schedule`]).
    pub prescribed: Vec<(usize, f64, usize)>,
    /// External nodal forces: (dof, force at factor 1, amplitude).
    pub nodal_loads: Vec<(usize, f64, usize)>,
    /// Load histories.
    pub schedule: Schedule,
    /// How the steps are driven and checked.
    pub control: Control,
    /// Uniform body temperatures and the heat conduction.
    pub thermal: Thermal,
    /// Size of the model (bounding-box diagonal) in mm.
    pub size: f64,
    pub dofs: DofMap,
    pub pattern: SparsityPattern,
}

impl Model {
    /// Builds the model of `spec` on `mesh`: the contact interfaces (which may split the
    /// mesh), the bodies' elements, the supports, the loads, and the numbering.
    pub fn build(mut mesh: Mesh, spec: ModelSpec) -> Result<Self> {
        let ModelSpec {
            analysis,
            bodies,
            supports,
            loads,
            contacts,
            mut schedule,
            control,
            thermal,
        } = spec;
        let conductivity: Vec<Option<f64>> = bodies.iter().map(|b| b.conductivity).collect();
        let joints = contacts.iter().map(|c| c.conductance).collect();
        // Interfaces first: splitting a conforming curve re-points body B's cells.
        let topologies = insert_interfaces(&mut mesh, &bodies, &contacts)?;
        let (bodies, continuum) = build_continuum(&mesh, analysis, bodies)?;
        let owners = node_bodies(&continuum, mesh.nodes.len());
        let in_body: Vec<bool> = owners.iter().map(Option::is_some).collect();
        let scale = model_scale(&mesh);
        let surfaces = BodySurfaces {
            owners: &owners,
            continuum: &continuum,
        };
        let (interface, penalty_defaults) =
            build_interface(&mesh, analysis, contacts, topologies, &surfaces, scale)?;
        let Constraints {
            supports,
            prescribed,
        } = prescribe(&mesh, analysis, &supports, &in_body, scale, &mut schedule)?;
        let nodal_loads =
            nodal_loads(&mesh, analysis, &continuum, &loads, &in_body, &mut schedule)?;
        let inputs = thermal::ThermalInputs {
            mesh: &mesh,
            bodies: &bodies,
            continuum: &continuum,
            interface: &interface,
            conductivity,
            joints,
        };
        let thermal = thermal::build(inputs, thermal, &mut schedule)?;
        let Numbering {
            dofs,
            pattern,
            continuum_coloring,
            interface_coloring,
        } = numbering(analysis, &prescribed, &in_body, &continuum, &interface)?;
        let model = Self {
            mesh,
            analysis,
            bodies,
            continuum,
            continuum_coloring,
            interface,
            interface_coloring,
            penalty_defaults,
            supports,
            prescribed,
            nodal_loads,
            schedule,
            control,
            thermal,
            size: scale,
            dofs,
            pattern,
        };
        model.check_planned_solves()?;
        // Before any solve: a free rigid-body motion makes every stiffness matrix singular.
        let free = model.free_bodies();
        if !free.is_empty() {
            return Err(Error::RigidBodyMotion { bodies: free });
        }
        Ok(model)
    }
}

impl Model {
    /// Whether the continuum's integration-point states are a function of the displacements
    /// alone: every body linear elastic (no plastic strain, no internal variables) and no
    /// temperature field (a coupled run evaluates its states with the temperatures of the
    /// exchange before the last). A restart record then leaves them out, and a resumed run
    /// evaluates them again at the record's displacements, to the same bits.
    pub fn states_follow_displacements(&self) -> bool {
        self.continuum.is_linear() && !self.has_temperature()
    }

    /// Refuses a load-controlled run whose output increments and amplitude breakpoints alone
    /// need more increment solves than `[solver] max_solves`, naming the step that passes it.
    fn check_planned_solves(&self) -> Result<()> {
        if self.control.arc_length.is_some() {
            return Ok(());
        }
        let limit = self.control.max_solves;
        let timeline = self.schedule.timeline();
        let mut count = 0usize;
        for (plan, solves) in timeline.steps().iter().zip(self.schedule.planned_solves()) {
            count = count.saturating_add(solves);
            if count > limit {
                let start = plan.first as f64;
                return Err(Error::TooManySolves {
                    at: Box::new(self.schedule.load_point(start, start + 1.0)),
                    count,
                    limit,
                    planned: true,
                });
            }
        }
        Ok(())
    }
}

/// The interface topology of every contact pair, in order (splitting the mesh where a pair
/// asks for it).
fn insert_interfaces(
    mesh: &mut Mesh,
    bodies: &[Body],
    contacts: &[Contact],
) -> Result<Vec<InterfaceTopology>> {
    let names: Vec<&str> = bodies.iter().map(|b| b.group.as_str()).collect();
    let topologies = contacts
        .iter()
        .map(|c| insert_interface(mesh, &c.pairing, &c.name, &names))
        .collect::<Result<Vec<_>>>()?;
    check_faces_used_once(mesh, contacts, &topologies)?;
    Ok(topologies)
}

/// Refuses a face (the three nodes of a boundary line) that two interface elements join —
/// two `[[contact]]` pairs on the same curves, or overlapping ones: each would add its own
/// interface stiffness and stress on the same surface, counting the joint twice.
fn check_faces_used_once(
    mesh: &Mesh,
    contacts: &[Contact],
    topologies: &[InterfaceTopology],
) -> Result<()> {
    let mut owner: std::collections::HashMap<[u32; 3], usize> = std::collections::HashMap::new();
    for (pair, topology) in topologies.iter().enumerate() {
        for element in &topology.elements {
            for face in [&element[..3], &element[3..]] {
                let mut key = [face[0], face[1], face[2]];
                key.sort_unstable();
                match owner.insert(key, pair) {
                    Some(other) if other != pair => {
                        let [p, q] = [face[0], face[1]].map(|n| mesh.nodes[n as usize]);
                        return Err(Error::Topology {
                            pair: contacts[pair].name.clone(),
                            problem: TopologyProblem::SharedFace,
                            node: Some(mesh.node_tags[face[0] as usize]),
                            element: None,
                            message: format!(
                                "its face from ({}, {}) to ({}, {}) is also a face of contact \
                                 '{}': two pairs on one surface would count the joint twice; \
                                 give each surface to one [[contact]]",
                                p[0], p[1], q[0], q[1], contacts[other].name
                            ),
                        });
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(())
}

/// The body whose cells hold each node (None: the node is in no body).
fn node_bodies(continuum: &ContinuumSet, node_count: usize) -> Vec<Option<u32>> {
    let mut owners = vec![None; node_count];
    for c in &continuum.cells {
        for &n in &c.nodes[..c.kind.node_count()] {
            owners[n as usize] = Some(c.body);
        }
    }
    owners
}

/// The bodies behind the interface faces: which body holds a node, and its material.
struct BodySurfaces<'a> {
    owners: &'a [Option<u32>],
    continuum: &'a ContinuumSet,
}

impl BodySurfaces<'_> {
    /// Surface modulus E / (1 − ν²) (E in plane stress) of the body holding `node`;
    /// infinite (a rigid face) for a node in no body.
    fn modulus(&self, node: u32) -> f64 {
        let plane_stress = self.continuum.analysis.is_plane_stress();
        self.owners[node as usize].map_or(f64::INFINITY, |b| {
            let material = &self.continuum.materials[b as usize];
            material.elastic().surface_modulus(plane_stress)
        })
    }

    /// Compliance of the two bodies' surfaces at interface element `nodes` with B-side
    /// coordinates `b_coords`: the shortest pressure wave its quadratic faces resolve
    /// alternates from node to node (spacing ℓ/2), wavelength ℓ = the element's length.
    fn compliance(&self, nodes: &[u32; 6], b_coords: &[[f64; 2]; 3]) -> f64 {
        let moduli = [self.modulus(nodes[0]), self.modulus(nodes[3])];
        surface_compliance(moduli, chord_length(b_coords))
    }
}

/// The degree-of-freedom numbering and what depends on it.
struct Numbering {
    dofs: DofMap,
    pattern: SparsityPattern,
    continuum_coloring: Coloring,
    interface_coloring: Coloring,
}

/// Numbers the free dofs (nodes outside every body carry no stiffness and are held, so the
/// system stays regular) and makes the sparsity pattern and element colourings.
fn numbering(
    analysis: Analysis,
    prescribed: &[(usize, f64, usize)],
    in_body: &[bool],
    continuum: &ContinuumSet,
    interface: &InterfaceSet,
) -> Result<Numbering> {
    let node_count = in_body.len();
    let d = analysis.dofs_per_node();
    let mut fixed = vec![false; d * node_count];
    for &(dof, _, _) in prescribed {
        fixed[dof] = true;
    }
    for (n, &used) in in_body.iter().enumerate() {
        if !used {
            fixed[d * n..d * (n + 1)].fill(true);
        }
    }
    let dofs = DofMap::new(&fixed);
    if dofs.free_count() == 0 {
        return Err(Error::NothingToSolve);
    }
    let connectivity = continuum_connectivity(continuum)
        .chain((0..interface.len()).map(|e| interface.nodes(e).into()));
    let pattern = SparsityPattern::new(node_count, &dofs, connectivity);
    Ok(Numbering {
        pattern,
        continuum_coloring: Coloring::new(continuum, node_count),
        interface_coloring: Coloring::new(interface, node_count),
        dofs,
    })
}

/// Each continuum cell's nodes, with whether its matrix may couple twist, for a sparsity
/// pattern ([`SparsityPattern::new`]).
pub fn continuum_connectivity(
    continuum: &ContinuumSet,
) -> impl Iterator<Item = ElementNodes<'_>> + '_ {
    (0..continuum.len()).map(|e| ElementNodes {
        nodes: continuum.nodes(e),
        couples_twist: continuum.couples_twist(e),
    })
}

/// The interface elements of all contact pairs.
///
/// Axis (Buczkowski & Kleiber (1994), §3.3.1): with Newton-Cotes integration a point on the
/// axis r = 0 has zero area, so the pair on the axis would carry no stiffness. They move the first
/// interface element off the axis; the equivalent used here integrates every element that
/// touches the axis with 3-point Gauss instead, whose points lie off the axis: the axis pair
/// is then coupled to its neighbours with positive stiffness (∫ N₀² 2πr ds > 0), and the rest
/// of the interface keeps the lumped rule.
fn build_interface(
    mesh: &Mesh,
    analysis: Analysis,
    contacts: Vec<Contact>,
    topologies: Vec<InterfaceTopology>,
    surfaces: &BodySurfaces,
    scale: f64,
) -> Result<(InterfaceSet, Vec<PenaltyDefault>)> {
    let mut elements = Vec::new();
    let mut pairs = Vec::new();
    let mut defaults = Vec::new();
    for (p, (contact, topology)) in contacts.into_iter().zip(topologies).enumerate() {
        let Contact {
            name,
            rule,
            interference,
            law,
            wear,
            ..
        } = contact;
        let start = elements.len();
        for (nodes, offsets) in topology.elements.iter().zip(&topology.offsets) {
            let b_coords = [3, 4, 5].map(|i| mesh.nodes[nodes[i] as usize]);
            let on_axis =
                analysis.is_axisymmetric() && b_coords.iter().any(|x| x[0].abs() <= 1e-9 * scale);
            elements.push(InterfaceElement {
                nodes: *nodes,
                b_coords,
                offsets: *offsets,
                pair: p as u32,
                rule: if on_axis { InterfaceRule::Gauss } else { rule },
                body_compliance: surfaces.compliance(nodes, &b_coords),
            });
        }
        if elements.len() == start {
            return Err(Error::Topology {
                pair: name,
                problem: TopologyProblem::NoElements,
                node: None,
                element: None,
                message: "no interface elements were found".into(),
            });
        }
        let law = match law {
            PairLaw::Built(law) => law,
            PairLaw::Defaulted { law, values } => {
                let default = penalty_default(&name, law, &values, &elements[start..], surfaces)?;
                tracing::info!("{}", default.describe());
                let built = law.build(&law.with_penalty(&values, default.stiffness));
                defaults.push(default);
                // Checked with a stand-in stiffness by `ModelSpec::new`; the default is in
                // the same bound.
                built.map_err(|e| Error::InvalidParameter {
                    path: std::path::PathBuf::new(),
                    key: format!("contact '{name}' law.{}", e.name),
                    value: laws::shown(e.value),
                    reason: e.reason,
                })?
            }
        };
        let pair = ContactPair {
            name,
            law,
            wear,
            interference,
            elements: start..elements.len(),
        };
        tracing::info!(
            "contact '{}': {} interface elements, {}",
            pair.name,
            pair.elements.len(),
            pair.describe()
        );
        pairs.push(pair);
    }
    let set = InterfaceSet {
        analysis,
        elements,
        pairs,
    };
    Ok((set, defaults))
}

/// The default penalty stiffness of pair `name` (law `law` at `values`) on its `elements`.
fn penalty_default(
    name: &str,
    law: &LawDescriptor,
    values: &[f64],
    elements: &[InterfaceElement],
    surfaces: &BodySurfaces,
) -> Result<PenaltyDefault> {
    let moduli = elements.iter().map(|e| {
        let sides = [surfaces.modulus(e.nodes[0]), surfaces.modulus(e.nodes[3])];
        (sides, chord_length(&e.b_coords))
    });
    let parameters = law.defaulted_penalties(values);
    PenaltyDefault::new(name, parameters, moduli).ok_or_else(|| Error::Topology {
        pair: name.to_string(),
        problem: TopologyProblem::NoOwner,
        node: None,
        element: None,
        message: "no body behind either face to default the penalty stiffness from".into(),
    })
}

/// Largest coordinate extent of the mesh (for relative tolerances), never zero.
fn model_scale(mesh: &Mesh) -> f64 {
    model_size(&mesh.nodes).max(f64::MIN_POSITIVE)
}

/// The physical curve or point called `name` (a name used for both is ambiguous).
fn boundary_group<'m>(mesh: &'m Mesh, name: &str, role: &str) -> Result<&'m PhysicalGroup> {
    match (mesh.group(1, name), mesh.group(0, name)) {
        (Some(g), None) | (None, Some(g)) => Ok(g),
        (Some(_), Some(_)) => {
            Err(mesh.group_error(role, name, GroupKind::CurveOrPoint, GroupProblem::Ambiguous))
        }
        (None, None) => Err(mesh.missing_group(role, name, GroupKind::CurveOrPoint)),
    }
}

/// The continuum elements of the bodies, with their materials, and the body names. Checks
/// that the bodies' surfaces exist, do not overlap, and hold only elements with a positive
/// Jacobian.
fn build_continuum(
    mesh: &Mesh,
    analysis: Analysis,
    bodies: Vec<Body>,
) -> Result<(Vec<String>, ContinuumSet)> {
    let mut owner: Vec<Option<u32>> = vec![None; mesh.cells.len()];
    let mut names: Vec<String> = Vec::new();
    let mut materials = Vec::new();
    let mut formulations = Vec::new();
    let mut expansions = Vec::new();
    let mut cells = Vec::new();
    for (
        b,
        Body {
            group: name,
            material,
            formulation,
            expansion,
            ..
        },
    ) in bodies.into_iter().enumerate()
    {
        let group = mesh
            .group(2, &name)
            .ok_or_else(|| mesh.missing_group("body", &name, GroupKind::Surface))?;
        let before = cells.len();
        for (i, cell) in mesh.cells_in(group) {
            if let Some(other) = owner[i] {
                return Err(Error::OverlappingBodies {
                    element: cell.tag,
                    first: names[other as usize].clone(),
                    second: name,
                });
            }
            owner[i] = Some(b as u32);
            let coords = mesh.cell_coords(cell);
            let det = min_jacobian(cell.kind, &coords);
            if det.is_nan() || det <= 0.0 {
                return Err(Error::DistortedElement {
                    element: cell.tag,
                    body: name,
                    jacobian: det,
                    corners: coords[..cell.kind.corner_count()].to_vec(),
                });
            }
            cells.push(ContinuumCell {
                kind: cell.kind,
                nodes: cell.nodes,
                coords,
                body: b as u32,
                mesh_cell: i as u32,
            });
        }
        if cells.len() == before {
            let problem = GroupProblem::Empty;
            return Err(mesh.group_error("body", &name, GroupKind::Surface, problem));
        }
        tracing::info!(
            "body '{name}': {}, {} formulation",
            material.describe(),
            formulation.name()
        );
        names.push(name);
        materials.push(material);
        formulations.push(formulation);
        expansions.push(expansion);
    }
    for g in mesh
        .groups
        .iter()
        .filter(|g| g.dim == 2 && !names.contains(&g.name))
    {
        tracing::warn!(
            "physical surface '{}' is not a body in the case file; its elements are ignored",
            g.name
        );
    }
    Ok((
        names,
        ContinuumSet {
            analysis,
            cells,
            materials,
            formulations,
            expansions,
        },
    ))
}
