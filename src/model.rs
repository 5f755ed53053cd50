//! The model: a mesh together with bodies and their materials, supports, loads and the
//! degree-of-freedom numbering. Built once from a [`Mesh`] and a [`Case`]; the solver only
//! reads it.
//!
//! Physical groups are referred to by name: bodies are physical surfaces, supports and loads
//! are physical curves or points (see the README's naming convention).

use std::collections::HashMap;

use crate::assembly::{Coloring, DofMap, ElementSet, SparsityPattern};
use crate::case::{Case, LoadSpec, SupportSpec};
use crate::contact::{ContactAlgorithm, InterfaceLaw, InterfaceState};
use crate::element::continuum::{evaluate_cell, min_jacobian};
use crate::element::interface6::{InterfaceElement, InterfaceRule, evaluate_interface};
use crate::element::quadrature::{GAUSS3, MAX_CELL_POINTS};
use crate::element::shape::line3;
use crate::element::{Analysis, ElementMatrix, ElementVector};
use crate::material::{Material, PointState};
use crate::mesh::interface::{InterfaceTopology, insert_interface};
use crate::mesh::{CellKind, Line3, Mesh, PhysicalGroup};
use crate::{Error, Result};

/// A continuum cell of the model with its node coordinates copied in (so assembly reads one
/// contiguous record per element).
#[derive(Clone, Copy, Debug)]
pub struct ContinuumCell {
    pub kind: CellKind,
    pub nodes: [u32; 8],
    pub coords: [[f64; 2]; 8],
    /// Index of the body (into [`Model::bodies`]).
    pub body: u32,
    /// Index of the cell in [`Mesh::cells`].
    pub mesh_cell: u32,
}

/// All continuum cells of the model, with one material per body.
#[derive(Debug)]
pub struct ContinuumSet {
    pub analysis: Analysis,
    pub cells: Vec<ContinuumCell>,
    pub materials: Vec<Box<dyn Material>>,
}

impl ElementSet for ContinuumSet {
    type State = PointState;

    fn len(&self) -> usize {
        self.cells.len()
    }

    fn nodes(&self, e: usize) -> &[u32] {
        let c = &self.cells[e];
        &c.nodes[..c.kind.node_count()]
    }

    fn points_per_element(&self) -> usize {
        MAX_CELL_POINTS
    }

    fn evaluate(
        &self,
        e: usize,
        u: &ElementVector,
        committed: &[PointState],
        trial: &mut [PointState],
        k: Option<&mut ElementMatrix>,
        f: &mut ElementVector,
    ) {
        let c = &self.cells[e];
        evaluate_cell(
            &self.analysis,
            c.kind,
            &c.coords,
            u,
            self.materials[c.body as usize].as_ref(),
            committed,
            trial,
            k,
            f,
        );
    }
}

/// A contact pair: its law, interference and the range of its elements in
/// [`InterfaceSet::elements`].
#[derive(Debug)]
pub struct ContactPair {
    pub name: String,
    pub law: Box<dyn InterfaceLaw>,
    /// Initial interference δ in mm (positive: overlap).
    pub interference: f64,
    pub elements: std::ops::Range<usize>,
}

/// All interface elements of the model, pair after pair.
#[derive(Debug)]
pub struct InterfaceSet {
    pub analysis: Analysis,
    pub elements: Vec<InterfaceElement>,
    pub pairs: Vec<ContactPair>,
    /// Which interface tangent the global iterations use.
    pub algorithm: ContactAlgorithm,
}

/// Integration points per interface element.
pub const INTERFACE_POINTS: usize = 3;

impl ElementSet for InterfaceSet {
    type State = InterfaceState;

    fn len(&self) -> usize {
        self.elements.len()
    }

    fn nodes(&self, e: usize) -> &[u32] {
        &self.elements[e].nodes
    }

    fn points_per_element(&self) -> usize {
        INTERFACE_POINTS
    }

    fn evaluate(
        &self,
        e: usize,
        u: &ElementVector,
        committed: &[InterfaceState],
        trial: &mut [InterfaceState],
        k: Option<&mut ElementMatrix>,
        f: &mut ElementVector,
    ) {
        let element = &self.elements[e];
        let pair = &self.pairs[element.pair as usize];
        evaluate_interface(
            &self.analysis,
            element,
            pair.interference,
            pair.law.as_ref(),
            self.algorithm,
            u,
            committed,
            trial,
            k,
            f,
        );
    }
}

/// The interface elements seen as the difference between their elastic-tangent matrix and
/// their consistent one, K_elastic − K_consistent. Added to the consistent global tangent it
/// gives the tangent with the elastic contact matrix (paper conclusion 3): symmetric positive
/// definite, used as the preconditioner of unsymmetric solves. Internal forces are zero.
#[derive(Debug)]
pub struct ElasticContactCorrection<'a>(pub &'a InterfaceSet);

impl ElementSet for ElasticContactCorrection<'_> {
    type State = InterfaceState;

    fn len(&self) -> usize {
        self.0.len()
    }

    fn nodes(&self, e: usize) -> &[u32] {
        self.0.nodes(e)
    }

    fn points_per_element(&self) -> usize {
        INTERFACE_POINTS
    }

    fn evaluate(
        &self,
        e: usize,
        u: &ElementVector,
        committed: &[InterfaceState],
        trial: &mut [InterfaceState],
        k: Option<&mut ElementMatrix>,
        f: &mut ElementVector,
    ) {
        let Some(k) = k else { return };
        let set = self.0;
        let element = &set.elements[e];
        let pair = &set.pairs[element.pair as usize];
        let law = pair.law.as_ref();
        let mut consistent = ElementMatrix::zeros();
        let mut elastic = ElementMatrix::zeros();
        let mut scratch = ElementVector::zeros();
        let analysis = &set.analysis;
        evaluate_interface(
            analysis,
            element,
            pair.interference,
            law,
            set.algorithm,
            u,
            committed,
            trial,
            Some(&mut consistent),
            &mut scratch,
        );
        evaluate_interface(
            analysis,
            element,
            pair.interference,
            law,
            ContactAlgorithm::ElasticContact,
            u,
            committed,
            trial,
            Some(&mut elastic),
            &mut scratch,
        );
        *k += elastic - consistent;
        f.fill(0.0);
    }
}

/// A named set of prescribed dofs whose reaction force is reported.
#[derive(Clone, Debug)]
pub struct Support {
    pub name: String,
    /// Global dofs (2·node + component) this support prescribes.
    pub dofs: Vec<usize>,
}

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

/// Load histories ("amplitudes"): amplitude 0 is the case's `[steps]` schedule, and every
/// support or load with its own `factors` adds one. An amplitude is piecewise linear in the
/// pseudo-time τ ∈ [0, steps]: 0 at τ = 0 and `factors[j − 1]` at τ = j, so that a step cut
/// back into sub-increments moves every load along its own straight line.
#[derive(Clone, Debug)]
pub struct Schedule {
    amplitudes: Vec<Vec<f64>>,
}

impl Schedule {
    /// Schedule with the global factors only.
    pub fn new(factors: Vec<f64>) -> Self {
        Self {
            amplitudes: vec![factors],
        }
    }

    /// Adds an amplitude (or returns 0, the global one, for `None`).
    fn add(&mut self, factors: &Option<Vec<f64>>) -> usize {
        match factors {
            Some(f) => {
                self.amplitudes.push(f.clone());
                self.amplitudes.len() - 1
            }
            None => 0,
        }
    }

    /// Number of steps.
    pub fn steps(&self) -> usize {
        self.amplitudes[0].len()
    }

    /// The global load factor at the end of step `step` (1-based).
    pub fn load_factor(&self, step: usize) -> f64 {
        self.amplitudes[0][step - 1]
    }

    /// Value of amplitude `k` at pseudo-time `time`.
    pub fn value(&self, k: usize, time: f64) -> f64 {
        let a = &self.amplitudes[k];
        let knot = |j: usize| if j == 0 { 0.0 } else { a[j - 1] };
        let time = time.clamp(0.0, a.len() as f64);
        let j = (time.ceil() as usize).max(1);
        let theta = time - (j - 1) as f64;
        knot(j - 1) + theta * (knot(j) - knot(j - 1))
    }
}

impl Model {
    /// Sets the prescribed components of `u` to their values at pseudo-time `time`.
    pub fn apply_prescribed(&self, time: f64, u: &mut [f64]) {
        for &(dof, value, k) in &self.prescribed {
            u[dof] = value * self.schedule.value(k, time);
        }
    }

    /// External nodal forces over all dofs at pseudo-time `time`.
    pub fn external_force(&self, time: f64, f: &mut [f64]) {
        f.fill(0.0);
        for &(dof, value, k) in &self.nodal_loads {
            f[dof] += value * self.schedule.value(k, time);
        }
    }
}

/// Name of the automatic support of axisymmetric models.
pub const AXIS_SUPPORT: &str = "axis";

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
        algorithm: case.solver.contact_algorithm,
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
fn boundary_group<'m>(mesh: &'m Mesh, name: &str, what: &str) -> Result<&'m PhysicalGroup> {
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

fn support_nodes(mesh: &Mesh, spec: &SupportSpec, in_body: &[bool]) -> Result<Vec<u32>> {
    let group = boundary_group(mesh, &spec.group, "support")?;
    let mut nodes: Vec<u32> = if group.dim == 1 {
        mesh.lines_in(group).flat_map(|l| l.nodes).collect()
    } else {
        mesh.points_in(group).collect()
    };
    nodes.sort_unstable();
    nodes.dedup();
    if nodes.is_empty() {
        return Err(Error::Model(format!(
            "support '{}': the group has no elements",
            spec.group
        )));
    }
    if let Some(&n) = nodes.iter().find(|&&n| !in_body[n as usize]) {
        return Err(Error::Model(format!(
            "support '{}': node {} at {:?} belongs to no body",
            spec.group, mesh.node_tags[n as usize], mesh.nodes[n as usize]
        )));
    }
    Ok(nodes)
}

/// In axisymmetry nodes on the axis (r = 0 within a relative tolerance) have u_r = 0; nodes
/// at negative r are an input error.
fn axis_support(
    mesh: &Mesh,
    in_body: &[bool],
    scale: f64,
    prescribed: &mut [Option<(f64, usize, usize)>],
    index: usize,
) -> Result<Support> {
    let tol = 1e-9 * scale;
    let mut dofs = Vec::new();
    for (n, p) in mesh.nodes.iter().enumerate().filter(|&(n, _)| in_body[n]) {
        if p[0] < -tol {
            return Err(Error::Model(format!(
                "axisymmetric model: node {} lies at negative radius r = {} (the axis is x = r = 0)",
                mesh.node_tags[n], p[0]
            )));
        }
        if p[0] <= tol {
            let dof = 2 * n;
            if let Some((v, _, _)) = prescribed[dof] {
                if v != 0.0 {
                    return Err(Error::Model(format!(
                        "node {} on the axis has a prescribed radial displacement {v}; it must be 0",
                        mesh.node_tags[n]
                    )));
                }
            } else {
                prescribed[dof] = Some((0.0, 0, index));
                dofs.push(dof);
            }
        }
    }
    Ok(Support {
        name: AXIS_SUPPORT.into(),
        dofs,
    })
}

/// Finds, for a boundary line, the model cell it bounds, to orient its outward normal.
struct EdgeIndex {
    /// (smaller end node, larger end node) → whether a cell traverses the edge from the
    /// smaller to the larger node counter-clockwise.
    edges: HashMap<(u32, u32), bool>,
}

impl EdgeIndex {
    fn new(continuum: &ContinuumSet) -> Self {
        let mut edges = HashMap::new();
        for c in &continuum.cells {
            let corners = if c.kind == CellKind::Quad8 { 4 } else { 3 };
            for i in 0..corners {
                let (a, b) = (c.nodes[i], c.nodes[(i + 1) % corners]);
                edges.insert((a.min(b), a.max(b)), a < b);
            }
        }
        Self { edges }
    }

    /// The line's nodes ordered so the body lies to the left (counter-clockwise boundary
    /// traversal), or `None` if no body cell has this edge.
    fn oriented(&self, line: &Line3) -> Option<[u32; 3]> {
        let [a, b, m] = line.nodes;
        let forward = *self.edges.get(&(a.min(b), a.max(b)))?;
        Some(if forward == (a < b) {
            [a, b, m]
        } else {
            [b, a, m]
        })
    }
}

/// Adds the consistent nodal forces of a load at load factor 1.
fn add_load(
    mesh: &Mesh,
    analysis: &Analysis,
    edges: &EdgeIndex,
    spec: &LoadSpec,
    in_body: &[bool],
    load: &mut [f64],
) -> Result<()> {
    let group = boundary_group(mesh, &spec.group, "load")?;
    if let Some(force) = spec.force {
        if group.dim != 0 {
            return Err(Error::Model(format!(
                "load '{}': a force needs a physical point group",
                spec.group
            )));
        }
        for n in mesh.points_in(group) {
            if !in_body[n as usize] {
                return Err(Error::Model(format!(
                    "load '{}': point node {} belongs to no body",
                    spec.group, mesh.node_tags[n as usize]
                )));
            }
            load[2 * n as usize] += force[0];
            load[2 * n as usize + 1] += force[1];
        }
        return Ok(());
    }
    if group.dim != 1 {
        return Err(Error::Model(format!(
            "load '{}': pressure and traction need a physical curve",
            spec.group
        )));
    }
    let mut count = 0;
    for line in mesh.lines_in(group) {
        let nodes = edges.oriented(line).ok_or_else(|| {
            let p = mesh.nodes[line.nodes[0] as usize];
            Error::Model(format!(
                "load '{}': boundary element {} (from {p:?}) is not an edge of any body's element",
                spec.group, line.tag
            ))
        })?;
        add_line_load(mesh, analysis, nodes, spec, load);
        count += 1;
    }
    if count == 0 {
        return Err(Error::Model(format!(
            "load '{}': the curve group has no elements",
            spec.group
        )));
    }
    Ok(())
}

/// Consistent nodal forces f_i = ∫ N_i t dA on one line, with dA = (thickness or 2πr) ds,
/// integrated by 3-point Gauss (exact for a pressure on a curved quadratic edge in
/// axisymmetry: degree 5).
fn add_line_load(
    mesh: &Mesh,
    analysis: &Analysis,
    nodes: [u32; 3],
    spec: &LoadSpec,
    load: &mut [f64],
) {
    let x: Vec<[f64; 2]> = nodes.iter().map(|&n| mesh.nodes[n as usize]).collect();
    for &(xi, w) in &GAUSS3 {
        let (n, dn) = line3(xi);
        let (mut px, mut dx, mut dy) = (0.0, 0.0, 0.0);
        for i in 0..3 {
            px += n[i] * x[i][0];
            dx += dn[i] * x[i][0];
            dy += dn[i] * x[i][1];
        }
        // Tangent (dx, dy) runs counter-clockwise around the body, so (dy, −dx) is the
        // outward normal scaled by ds/dξ.
        let t = match (spec.pressure, spec.traction) {
            (Some(p), _) => [-p * dy, p * dx],
            (None, Some([tx, ty])) => {
                let ds = (dx * dx + dy * dy).sqrt();
                [tx * ds, ty * ds]
            }
            (None, None) => unreachable!("validated: a line load has pressure or traction"),
        };
        let m = w * analysis.measure(px);
        for i in 0..3 {
            load[2 * nodes[i] as usize] += n[i] * t[0] * m;
            load[2 * nodes[i] as usize + 1] += n[i] * t[1] * m;
        }
    }
}
