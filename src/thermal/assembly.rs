//! Assembly of the conduction system: the conductivity matrices and sources of the cells, the
//! films and fluxes of the supports, the joints' conductance matrices, with the joints' points
//! and the supports' line points they share with the heat flows.

use super::{Conduction, JointConductance, JointPoint, ThermalCondition, ThermalSupport};
use crate::contact::InterfaceState;
use crate::element::interface6::interface_point;
use crate::element::kinematics::point_kinematics;
use crate::element::quadrature::{GAUSS3, cell_rule};
use crate::element::set::{ContinuumSet, INTERFACE_POINTS, InterfaceSet};
use crate::element::shape::{cell_shape, line3};

impl Conduction {
    /// The conductivity matrices and source vectors of the conducting cells.
    pub(super) fn add_cells(
        &self,
        continuum: &ContinuumSet,
        multiplier: &impl Fn(usize) -> f64,
        system: &mut System,
    ) {
        let mut power = vec![0.0; self.conductivity.len()];
        for s in &self.sources {
            power[s.body as usize] += s.power * multiplier(s.amplitude);
        }
        system.source_heat = vec![0.0; self.sources.len()];
        for c in &continuum.cells {
            let Some(k) = self.conductivity[c.body as usize] else {
                continue;
            };
            let nn = c.kind.node_count();
            let idx: Vec<usize> = c.nodes[..nn]
                .iter()
                .map(|&n| self.index[n as usize].expect("conducting node") as usize)
                .collect();
            let mut ke = [[0.0; 8]; 8];
            let mut fe = [0.0; 8];
            let mut volume = 0.0;
            for p in cell_rule(c.kind) {
                let pk = point_kinematics(&self.analysis, c.kind, &c.coords, p)
                    .expect("cell Jacobians are checked when the model is built");
                let s = cell_shape(c.kind, p.xi, p.eta);
                let grad = |i: usize| [pk.b[(0, 2 * i)], pk.b[(1, 2 * i + 1)]];
                for (a, (row, f)) in ke.iter_mut().zip(fe.iter_mut()).enumerate().take(nn) {
                    let ga = grad(a);
                    for (b, entry) in row.iter_mut().enumerate().take(nn) {
                        let gb = grad(b);
                        *entry += k * (ga[0] * gb[0] + ga[1] * gb[1]) * pk.dvol;
                    }
                    *f += s.n[a] * power[c.body as usize] * pk.dvol;
                }
                volume += pk.dvol;
            }
            for (s, out) in self.sources.iter().zip(system.source_heat.iter_mut()) {
                if s.body == c.body {
                    *out += s.power * multiplier(s.amplitude) * volume;
                }
            }
            for a in 0..nn {
                system.f[idx[a]] += fe[a];
                for b in 0..nn {
                    system.add(idx[a], idx[b], ke[a][b]);
                }
            }
        }
    }

    /// Films and fluxes of the supports (their heat is summed in `boundary_heat`: the flux
    /// supports' here, the films' after the solve).
    pub(super) fn add_supports(&self, multiplier: &impl Fn(usize) -> f64, system: &mut System) {
        system.boundary_heat = vec![0.0; self.supports.len()];
        for (s, support) in self.supports.iter().enumerate() {
            let m = multiplier(support.amplitude);
            let (h, q) = match support.condition {
                ThermalCondition::Temperature(_) => continue,
                ThermalCondition::Flux(q) => (0.0, q * m),
                ThermalCondition::Film { h, ambient } => (h, h * ambient * m),
            };
            for line in &support.lines {
                let idx = line.map(|n| self.index[n as usize].expect("checked") as usize);
                for (n, da) in self.line_points(line) {
                    for a in 0..3 {
                        system.f[idx[a]] += n[a] * q * da;
                        for b in 0..3 {
                            system.add(idx[a], idx[b], h * n[a] * n[b] * da);
                        }
                    }
                    if h == 0.0 {
                        system.boundary_heat[s] += q * da;
                    }
                }
            }
        }
    }

    /// The joints' conductance matrices.
    pub(super) fn add_joints(
        &self,
        interface: &InterfaceSet,
        states: &[InterfaceState],
        system: &mut System,
    ) {
        let zero = vec![0.0; self.index.len()];
        self.for_joint_points(interface, states, &zero, |at| {
            let idx = at
                .nodes
                .map(|n| self.index[n as usize].expect("checked") as usize);
            let n = at.n;
            let v = [n[0], n[1], n[2], -n[0], -n[1], -n[2]];
            for a in 0..6 {
                for b in 0..6 {
                    let value = at.point.conductance * v[a] * v[b] * at.da;
                    system.add(idx[a], idx[b], value);
                }
            }
        });
    }

    /// Calls `f` for every point of every conducting joint, with its conductance, jump and
    /// flux in the temperature `nodal` (mesh nodes).
    pub fn for_joint_points(
        &self,
        interface: &InterfaceSet,
        states: &[InterfaceState],
        nodal: &[f64],
        mut f: impl FnMut(JointAt),
    ) {
        for (e, element) in interface.elements.iter().enumerate() {
            let Some(h) = self.joints[element.pair as usize] else {
                continue;
            };
            for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
                let p = interface_point(&self.analysis, &element.b_coords, xi, w);
                let slot = e * INTERFACE_POINTS + g;
                f(JointAt {
                    pair: element.pair as usize,
                    slot,
                    nodes: element.nodes,
                    n: p.n,
                    da: p.da,
                    point: joint_point(&h, &states[slot], &element.nodes, &p.n, nodal),
                });
            }
        }
    }

    /// The heat a film takes into the body at temperature `t` (conduction indices):
    /// ∫ h (T_∞ − T) dA.
    pub(super) fn film_heat(
        &self,
        support: &ThermalSupport,
        h: f64,
        ambient: f64,
        t: &[f64],
    ) -> f64 {
        let mut heat = 0.0;
        for line in &support.lines {
            let idx = line.map(|n| self.index[n as usize].expect("checked") as usize);
            for (n, da) in self.line_points(line) {
                let temperature: f64 = (0..3).map(|a| n[a] * t[idx[a]]).sum();
                heat += h * (ambient - temperature) * da;
            }
        }
        heat
    }

    /// Shape values and area weights (ds × thickness or 2πr) of a line's 3 Gauss points.
    pub(super) fn line_points(&self, line: &[u32; 3]) -> [([f64; 3], f64); 3] {
        let x = line.map(|n| self.coords[n as usize]);
        GAUSS3.map(|(xi, w)| {
            let (n, dn) = line3(xi);
            let (mut r, mut dx, mut dy) = (0.0, 0.0, 0.0);
            for i in 0..3 {
                r += n[i] * x[i][0];
                dx += dn[i] * x[i][0];
                dy += dn[i] * x[i][1];
            }
            (n, w * dx.hypot(dy) * self.analysis.measure(r))
        })
    }
}

/// A joint point's transfer with conductance law `h` in `state`, for the element's nodes
/// [a0, a1, a_mid, b0, b1, b_mid] with shape values `n` at the point.
fn joint_point(
    h: &JointConductance,
    state: &InterfaceState,
    nodes: &[u32; 6],
    n: &[f64; 3],
    nodal: &[f64],
) -> JointPoint {
    let conductance = h.at(state);
    let jump: f64 = (0..3)
        .map(|i| n[i] * (nodal[nodes[i] as usize] - nodal[nodes[i + 3] as usize]))
        .sum();
    JointPoint {
        conductance,
        jump,
        flux: conductance * jump,
    }
}

/// A point of a conducting joint ([`Conduction::for_joint_points`]).
#[derive(Clone, Copy, Debug)]
pub struct JointAt {
    /// Contact pair.
    pub pair: usize,
    /// Index of the point's interface state.
    pub slot: usize,
    /// The element's nodes [a0, a1, a_mid, b0, b1, b_mid] and shape values at the point.
    pub nodes: [u32; 6],
    pub n: [f64; 3],
    /// Area weight (ds × thickness or 2πr).
    pub da: f64,
    pub point: JointPoint,
}

/// The assembled conduction system over the conduction indices (entries summed by the
/// solver's triplet conversion).
pub(super) struct System {
    pub(super) entries: Vec<(u32, u32, f64)>,
    pub(super) f: Vec<f64>,
    pub(super) boundary_heat: Vec<f64>,
    pub(super) source_heat: Vec<f64>,
}

impl System {
    pub(super) fn new(n: usize) -> Self {
        Self {
            entries: Vec::new(),
            f: vec![0.0; n],
            boundary_heat: Vec::new(),
            source_heat: Vec::new(),
        }
    }

    pub(super) fn add(&mut self, i: usize, j: usize, v: f64) {
        if v != 0.0 {
            self.entries.push((i as u32, j as u32, v));
        }
    }
}
