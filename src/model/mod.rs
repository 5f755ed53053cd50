//! The model: a mesh together with bodies and their materials, supports, loads and the
//! degree-of-freedom numbering. Built once from a [`Mesh`] and a [`Case`]; the solver only
//! reads it.
//!
//! Physical groups are referred to by name: bodies are physical surfaces, supports and loads
//! are physical curves or points (see the README's naming convention).

mod constraints;
mod loads;

pub use constraints::{AXIS_SUPPORT, Support};
pub use loads::Schedule;

use crate::assembly::{Coloring, DofMap, SparsityPattern};
use crate::config::Case;
use crate::element::Analysis;
use crate::element::continuum::min_jacobian;
use crate::element::interface6::{InterfaceElement, InterfaceRule};
use crate::element::set::{ContactPair, ContinuumCell, ContinuumSet, ElementSet, InterfaceSet};
use crate::material::Material;
use crate::mesh::interface::{InterfaceTopology, insert_interface};
use crate::mesh::{CellKind, Mesh, PhysicalGroup};
use crate::{Error, Result};
use constraints::{axis_support, support_nodes};
use loads::{EdgeIndex, add_load};

/// Everything the solver needs, built from a mesh and a case.
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
    /// Supports in case-file order, then the automatic axis support ("axis": u_r = 0 on r = 0) in
    /// axisymmetry.
    pub supports: Vec<Support>,
    /// Prescribed dofs: (dof, value at factor 1, amplitude in [`Model::schedule`]).
    pub prescribed: Vec<(usize, f64, usize)>,
    /// External nodal forces: (dof, force at factor 1, amplitude).
    pub nodal_loads: Vec<(usize, f64, usize)>,
    /// Load histories.
    pub schedule: Schedule,
    pub dofs: DofMap,
    pub pattern: SparsityPattern,
}

impl Model {
    /// Builds the model of `case` on `mesh`.
    pub fn build(mut mesh: Mesh, case: &Case) -> Result<Self> {
        let analysis = case.analysis;
        // Interfaces first: splitting a conforming curve re-points body B's cells.
        let body_names: Vec<&str> = case.bodies.iter().map(|b| b.group.as_str()).collect();
        let mut topologies = Vec::new();
        for spec in &case.contacts {
            let pairing = spec.pairing().map_err(Error::Model)?;
            topologies.push(insert_interface(
                &mut mesh,
                &pairing,
                &spec.name(),
                &body_names,
            )?);
        }
        let (bodies, continuum) = build_continuum(&mesh, case)?;
        let node_count = mesh.nodes.len();
        let mut in_body = vec![false; node_count];
        for c in &continuum.cells {
            for &n in &c.nodes[..c.kind.node_count()] {
                in_body[n as usize] = true;
            }
        }
        let scale = model_scale(&mesh);
        let interface = build_interface(&mesh, case, topologies, scale)?;

        let factors = case.steps.factors().map_err(Error::Model)?;
        let mut schedule = Schedule::new(factors);
        // Per dof: (value, amplitude, index of the support that set it).
        let mut prescribed: Vec<Option<(f64, usize, usize)>> = vec![None; 2 * node_count];
        let mut supports = Vec::new();
        for (i, spec) in case.supports.iter().enumerate() {
            let amplitude = schedule.add(&spec.factors);
            let nodes = support_nodes(&mesh, spec, &in_body)?;
            let mut dofs = Vec::new();
            for n in nodes {
                for (c, value) in [spec.ux, spec.uy].into_iter().enumerate() {
                    let Some(value) = value else { continue };
                    let dof = 2 * n as usize + c;
                    match prescribed[dof] {
                        Some((v, k, j))
                            if (v != 0.0 || value != 0.0)
                                && (k != amplitude
                                    || (v - value).abs() > 1e-12 * v.abs().max(value.abs())) =>
                        {
                            return Err(Error::Model(format!(
                                "supports '{}' and '{}' prescribe different {} displacement histories ({v} and \
                                 {value} at factor 1) at node {} ({:?})",
                                case.supports[j].group,
                                spec.group,
                                ["x", "y"][c],
                                mesh.node_tags[n as usize],
                                mesh.nodes[n as usize]
                            )));
                        }
                        Some(_) => {}
                        None => {
                            prescribed[dof] = Some((value, amplitude, i));
                            dofs.push(dof);
                        }
                    }
                }
            }
            supports.push(Support {
                name: spec.group.clone(),
                dofs,
            });
        }
        if analysis.is_axisymmetric() {
            supports.push(axis_support(
                &mesh,
                &in_body,
                scale,
                &mut prescribed,
                supports.len(),
            )?);
        }
        // Nodes outside every body carry no stiffness: hold them so the system stays regular.
        let mut fixed: Vec<bool> = prescribed.iter().map(Option::is_some).collect();
        for (n, &used) in in_body.iter().enumerate() {
            if !used {
                fixed[2 * n] = true;
                fixed[2 * n + 1] = true;
            }
        }
        let prescribed = prescribed
            .iter()
            .enumerate()
            .filter_map(|(d, p)| p.map(|(v, k, _)| (d, v, k)))
            .collect();

        let mut nodal_loads = Vec::new();
        let mut load = vec![0.0; 2 * node_count];
        let edges = EdgeIndex::new(&continuum);
        for spec in &case.loads {
            load.fill(0.0);
            add_load(&mesh, &analysis, &edges, spec, &in_body, &mut load)?;
            let amplitude = schedule.add(&spec.factors);
            nodal_loads.extend(
                load.iter()
                    .enumerate()
                    .filter(|(_, f)| **f != 0.0)
                    .map(|(d, f)| (d, *f, amplitude)),
            );
        }

        let dofs = DofMap::new(&fixed);
        if dofs.free_count() == 0 {
            return Err(Error::Model(
                "every degree of freedom is prescribed: nothing to solve".into(),
            ));
        }
        let connectivity = (0..continuum.len())
            .map(|e| continuum.nodes(e))
            .chain((0..interface.len()).map(|e| interface.nodes(e)));
        let pattern = SparsityPattern::new(node_count, &dofs, connectivity);
        let continuum_coloring = Coloring::new(&continuum, node_count);
        let interface_coloring = Coloring::new(&interface, node_count);
        Ok(Self {
            mesh,
            analysis,
            bodies,
            continuum,
            continuum_coloring,
            interface,
            interface_coloring,
            supports,
            prescribed,
            nodal_loads,
            schedule,
            dofs,
            pattern,
        })
    }
}

/// The interface elements of all contact pairs.
///
/// Axis (paper §3.3.1): with Newton-Cotes integration a point on the axis r = 0 has zero
/// area, so the pair on the axis would carry no stiffness. The paper moves the first
/// interface element off the axis; the equivalent used here integrates every element that
/// touches the axis with 3-point Gauss instead, whose points lie off the axis: the axis pair
/// is then coupled to its neighbours with positive stiffness (∫ N₀² 2πr ds > 0), and the rest
/// of the interface keeps the lumped rule.
fn build_interface(
    mesh: &Mesh,
    case: &Case,
    topologies: Vec<InterfaceTopology>,
    scale: f64,
) -> Result<InterfaceSet> {
    let mut elements = Vec::new();
    let mut pairs = Vec::new();
    for (p, (spec, topology)) in case.contacts.iter().zip(topologies).enumerate() {
        let name = spec.name();
        let law = spec
            .law
            .build()
            .map_err(|m| Error::Model(format!("contact '{name}': {m}")))?;
        let start = elements.len();
        for (nodes, offsets) in topology.elements.iter().zip(&topology.offsets) {
            let b_coords = [3, 4, 5].map(|i| mesh.nodes[nodes[i] as usize]);
            let on_axis = case.analysis.is_axisymmetric()
                && b_coords.iter().any(|x| x[0].abs() <= 1e-9 * scale);
            let rule = if on_axis {
                InterfaceRule::Gauss
            } else {
                spec.integration
            };
            elements.push(InterfaceElement {
                nodes: *nodes,
                b_coords,
                offsets: *offsets,
                pair: p as u32,
                rule,
            });
        }
        if elements.len() == start {
            return Err(Error::Model(format!(
                "contact '{name}': no interface elements were found"
            )));
        }
        tracing::info!(
            "contact '{name}': {} interface elements, {}",
            elements.len() - start,
            law.describe()
        );
        pairs.push(ContactPair {
            name,
            law,
            interference: spec.interference,
            elements: start..elements.len(),
        });
    }
    Ok(InterfaceSet {
        analysis: case.analysis,
        elements,
        pairs,
    })
}

/// Largest coordinate extent of the mesh (for relative tolerances).
fn model_scale(mesh: &Mesh) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &mesh.nodes {
        for c in 0..2 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    (hi[0] - lo[0]).max(hi[1] - lo[1]).max(f64::MIN_POSITIVE)
}

/// The physical curve or point called `name` (a name used for both is ambiguous).
pub(super) fn boundary_group<'m>(
    mesh: &'m Mesh,
    name: &str,
    what: &str,
) -> Result<&'m PhysicalGroup> {
    match (mesh.group(1, name), mesh.group(0, name)) {
        (Some(g), None) | (None, Some(g)) => Ok(g),
        (Some(_), Some(_)) => Err(Error::Model(format!(
            "{what} '{name}': the name is used by a physical curve and a physical point in {}; rename one",
            mesh.path.display()
        ))),
        (None, None) => Err(Error::Model(format!(
            "{what} '{name}': no physical curve or point of that name in {} (curves: {}; points: {})",
            mesh.path.display(),
            mesh.group_names(1),
            mesh.group_names(0)
        ))),
    }
}

fn build_continuum(mesh: &Mesh, case: &Case) -> Result<(Vec<String>, ContinuumSet)> {
    let mut owner: Vec<Option<u32>> = vec![None; mesh.cells.len()];
    let mut bodies = Vec::new();
    let mut materials: Vec<Box<dyn Material>> = Vec::new();
    let mut cells = Vec::new();
    for (b, spec) in case.bodies.iter().enumerate() {
        let group = mesh.group(2, &spec.group).ok_or_else(|| {
            Error::Model(format!(
                "body '{}': no physical surface of that name in {} (surfaces: {})",
                spec.group,
                mesh.path.display(),
                mesh.group_names(2)
            ))
        })?;
        let material = spec
            .material
            .build()
            .map_err(|m| Error::Model(format!("body '{}': {m}", spec.group)))?;
        let before = cells.len();
        for (i, cell) in mesh.cells_in(group) {
            if let Some(other) = owner[i] {
                return Err(Error::Model(format!(
                    "element {} belongs to bodies '{}' and '{}': physical surfaces of bodies must not overlap",
                    cell.tag, case.bodies[other as usize].group, spec.group
                )));
            }
            owner[i] = Some(b as u32);
            let mut coords = [[0.0; 2]; 8];
            for (k, &n) in cell.nodes().iter().enumerate() {
                coords[k] = mesh.nodes[n as usize];
            }
            let det = min_jacobian(cell.kind, &coords);
            if det.is_nan() || det <= 0.0 {
                return Err(Error::Model(format!(
                    "element {} of body '{}' is distorted or degenerate (Jacobian determinant {det:.3e} ≤ 0; corners \
                     {:?}); check mid-side nodes and the mesh quality",
                    cell.tag,
                    spec.group,
                    &coords[..if cell.kind == CellKind::Quad8 { 4 } else { 3 }]
                )));
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
            return Err(Error::Model(format!(
                "body '{}': the physical surface has no elements",
                spec.group
            )));
        }
        bodies.push(spec.group.clone());
        tracing::info!("body '{}': {}", spec.group, material.describe());
        materials.push(material);
    }
    for g in mesh
        .groups
        .iter()
        .filter(|g| g.dim == 2 && !bodies.contains(&g.name))
    {
        tracing::warn!(
            "physical surface '{}' is not a body in the case file; its elements are ignored",
            g.name
        );
    }
    Ok((
        bodies,
        ContinuumSet {
            analysis: case.analysis,
            cells,
            materials,
        },
    ))
}
