//! Loads: the load histories (amplitudes) and the consistent nodal forces of pressures,
//! tractions and point forces.

use std::collections::HashMap;

use super::{Model, boundary_group};
use crate::config::LoadSpec;
use crate::element::Analysis;
use crate::element::quadrature::GAUSS3;
use crate::element::set::ContinuumSet;
use crate::element::shape::line3;
use crate::mesh::{CellKind, Line3, Mesh};
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

/// Finds, for a boundary line, the model cell it bounds, to orient its outward normal.
pub(super) struct EdgeIndex {
    /// (smaller end node, larger end node) → whether a cell traverses the edge from the
    /// smaller to the larger node counter-clockwise.
    edges: HashMap<(u32, u32), bool>,
}

impl EdgeIndex {
    pub(super) fn new(continuum: &ContinuumSet) -> Self {
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
pub(super) fn add_load(
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
