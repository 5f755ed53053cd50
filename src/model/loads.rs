//! Loads: the load histories (amplitudes) and the consistent nodal forces of pressures,
//! tractions and point forces.

use super::{LineLoad, Load, LoadKind, Model, boundary_group};
use crate::element::Analysis;
use crate::element::quadrature::GAUSS3;
use crate::element::set::ContinuumSet;
use crate::element::shape::line3;
use crate::error::{GroupKind, GroupProblem, MeshEntity};
use crate::mesh::Mesh;
use crate::mesh::topology::EdgeIndex;
use crate::{Error, Result};

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
    pub(super) fn add(&mut self, factors: &Option<Vec<f64>>) -> usize {
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

/// The external nodal forces of the loads at load factor 1: (dof, force, amplitude), load
/// after load (adding their own histories to `schedule`, in order).
pub(super) fn nodal_loads(
    mesh: &Mesh,
    analysis: Analysis,
    continuum: &ContinuumSet,
    specs: &[Load],
    in_body: &[bool],
    schedule: &mut Schedule,
) -> Result<Vec<(usize, f64, usize)>> {
    // The edges of the body cells that may carry a line load orient its outward normal.
    let mut wanted = vec![false; mesh.nodes.len()];
    for group in specs.iter().filter_map(|l| mesh.group(1, &l.group)) {
        for line in mesh.lines_in(group) {
            wanted[line.nodes[0] as usize] = true;
            wanted[line.nodes[1] as usize] = true;
        }
    }
    let cells = continuum.cells.iter().enumerate();
    let edges = EdgeIndex::new(
        cells.map(|(i, c)| (i, c.body as usize, c.kind, &c.nodes)),
        &wanted,
    );
    let mut nodal_loads = Vec::new();
    let mut load = vec![0.0; 2 * mesh.nodes.len()];
    for spec in specs {
        load.fill(0.0);
        add_load(mesh, analysis, &edges, spec, in_body, &mut load)?;
        let amplitude = schedule.add(&spec.factors);
        nodal_loads.extend(
            load.iter()
                .enumerate()
                .filter(|(_, f)| **f != 0.0)
                .map(|(d, f)| (d, *f, amplitude)),
        );
    }
    Ok(nodal_loads)
}

/// Adds the consistent nodal forces of a load at load factor 1.
fn add_load(
    mesh: &Mesh,
    analysis: Analysis,
    edges: &EdgeIndex,
    spec: &Load,
    in_body: &[bool],
    load: &mut [f64],
) -> Result<()> {
    let group = boundary_group(mesh, &spec.group, "load")?;
    let wrong_kind = |expected, purpose| {
        let found = group.kind();
        let problem = GroupProblem::WrongKind { found, purpose };
        mesh.group_error("load", &spec.group, expected, problem)
    };
    let line_load = match spec.kind {
        LoadKind::Point(force) => {
            if group.dim != 0 {
                return Err(wrong_kind(GroupKind::Point, "a force"));
            }
            for n in mesh.points_in(group) {
                if !in_body[n as usize] {
                    return Err(Error::NotOnBody {
                        role: "load",
                        group: spec.group.clone(),
                        entity: MeshEntity::Node(mesh.node_tags[n as usize]),
                        position: mesh.nodes[n as usize],
                    });
                }
                load[2 * n as usize] += force[0];
                load[2 * n as usize + 1] += force[1];
            }
            return Ok(());
        }
        LoadKind::Line(line_load) => line_load,
    };
    if group.dim != 1 {
        return Err(wrong_kind(GroupKind::Curve, "a pressure or traction"));
    }
    let mut count = 0;
    for line in mesh.lines_in(group) {
        let nodes = edges.oriented(line).ok_or_else(|| Error::NotOnBody {
            role: "load",
            group: spec.group.clone(),
            entity: MeshEntity::Element(line.tag),
            position: mesh.nodes[line.nodes[0] as usize],
        })?;
        add_line_load(mesh, analysis, nodes, line_load, load);
        count += 1;
    }
    if count == 0 {
        let problem = GroupProblem::Empty;
        return Err(mesh.group_error("load", &spec.group, GroupKind::Curve, problem));
    }
    Ok(())
}

/// Consistent nodal forces f_i = ∫ N_i t dA on one line, with dA = (thickness or 2πr) ds,
/// integrated by 3-point Gauss (exact for a pressure on a curved quadratic edge in
/// axisymmetry: degree 5).
fn add_line_load(
    mesh: &Mesh,
    analysis: Analysis,
    nodes: [u32; 3],
    line_load: LineLoad,
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
        let t = match line_load {
            LineLoad::Pressure(p) => [-p * dy, p * dx],
            LineLoad::Traction([tx, ty]) => {
                let ds = (dx * dx + dy * dy).sqrt();
                [tx * ds, ty * ds]
            }
        };
        let m = w * analysis.measure(px);
        for i in 0..3 {
            load[2 * nodes[i] as usize] += n[i] * t[0] * m;
            load[2 * nodes[i] as usize + 1] += n[i] * t[1] * m;
        }
    }
}
