//! Assembly of the conduction system: its constant part (the cells' conductivity matrices,
//! the films' h N Nᵀ), the load of the sources, fluxes and films, and the joints'
//! conductance matrices, with the joints' points and the supports' line points they share
//! with the heat flows.

use super::{Conduction, JointConductance, JointPoint, ThermalCondition, ThermalSupport};
use crate::contact::InterfaceState;
use crate::element::interface6::interface_point;
use crate::element::kinematics::point_kinematics;
use crate::element::quadrature::{GAUSS3, cell_rule};
use crate::element::set::{ContinuumCell, ContinuumSet, INTERFACE_POINTS, InterfaceSet};
use crate::element::shape::{cell_shape, line3};

impl Conduction {
    /// Calls `add(i, j, value)` for the entries of the constant part of the conduction
    /// matrix (conduction indices; an entry may come several times, to be summed): the
    /// conducting cells' ∫ ∇Nᵀ k ∇N dV and the films' ∫ h N Nᵀ dA. Neither depends on the
    /// time or the contact, so it is assembled once per model.
    pub fn constant_entries(&self, continuum: &ContinuumSet, mut add: impl FnMut(u32, u32, f64)) {
        for c in &continuum.cells {
            let Some(k) = self.conductivity[c.body as usize] else {
                continue;
            };
            let nn = c.kind.node_count();
            let idx = self.cell_indices(c);
            let mut ke = [[0.0; 8]; 8];
            for p in cell_rule(c.kind) {
                let pk = point_kinematics(&self.analysis, c.kind, &c.coords, p)
                    .expect("cell Jacobians are checked when the model is built");
                let grad = |i: usize| [pk.b[(0, 2 * i)], pk.b[(1, 2 * i + 1)]];
                for (a, row) in ke.iter_mut().enumerate().take(nn) {
                    let ga = grad(a);
                    for (b, entry) in row.iter_mut().enumerate().take(nn) {
                        let gb = grad(b);
                        *entry += k * (ga[0] * gb[0] + ga[1] * gb[1]) * pk.dvol;
                    }
                }
            }
            for a in 0..nn {
                for b in 0..nn {
                    add(idx[a], idx[b], ke[a][b]);
                }
            }
        }
        for support in &self.supports {
            let ThermalCondition::Film { h, .. } = support.condition else {
                continue;
            };
            for line in &support.lines {
                let idx = self.line_indices(line);
                for (n, da) in self.line_points(line) {
                    for a in 0..3 {
                        for b in 0..3 {
                            add(idx[a], idx[b], h * n[a] * n[b] * da);
                        }
                    }
                }
            }
        }
    }

    /// The heat load with the supports' and sources' values scaled by
    /// `multiplier(amplitude)`: f = ∫ N Q dV + ∫ N q dA + ∫ N h T_∞ dA over the conduction
    /// indices, with the heat of each source and flux support.
    pub fn load(&self, multiplier: &impl Fn(usize) -> f64) -> HeatLoad {
        let mut f = vec![0.0; self.nodes.len()];
        let source_heat = self
            .sources
            .iter()
            .map(|s| {
                let power = s.power * multiplier(s.amplitude);
                let body = &self.source_bodies[s.body as usize];
                let body = body.as_ref().expect("made for every body with a source");
                for (fi, &w) in f.iter_mut().zip(&body.shape) {
                    *fi += power * w;
                }
                power * body.volume
            })
            .collect();
        let mut boundary_heat = vec![0.0; self.supports.len()];
        for (s, support) in self.supports.iter().enumerate() {
            let m = multiplier(support.amplitude);
            let q = match support.condition {
                ThermalCondition::Temperature(_) => continue,
                ThermalCondition::Flux(q) => q * m,
                ThermalCondition::Film { h, ambient } => h * ambient * m,
            };
            for line in &support.lines {
                let idx = self.line_indices(line);
                for (n, da) in self.line_points(line) {
                    for a in 0..3 {
                        f[idx[a] as usize] += n[a] * q * da;
                    }
                    if let ThermalCondition::Flux(_) = support.condition {
                        boundary_heat[s] += q * da;
                    }
                }
            }
        }
        HeatLoad {
            f,
            boundary_heat,
            source_heat,
        }
    }

    /// ∫ N dV over the conduction indices and the volume of every body that has a heat
    /// source (`None` for the others): a source's load is its power times these.
    pub(super) fn source_bodies(&self, continuum: &ContinuumSet) -> Vec<Option<SourceBody>> {
        let mut bodies: Vec<Option<SourceBody>> = vec![None; self.conductivity.len()];
        for s in &self.sources {
            bodies[s.body as usize] = Some(SourceBody {
                shape: vec![0.0; self.nodes.len()],
                volume: 0.0,
            });
        }
        for c in &continuum.cells {
            let Some(body) = bodies[c.body as usize].as_mut() else {
                continue;
            };
            let idx = self.cell_indices(c);
            for p in cell_rule(c.kind) {
                let pk = point_kinematics(&self.analysis, c.kind, &c.coords, p)
                    .expect("cell Jacobians are checked when the model is built");
                let s = cell_shape(c.kind, p.xi, p.eta);
                for (a, &i) in idx.iter().enumerate().take(c.kind.node_count()) {
                    body.shape[i as usize] += s.n[a] * pk.dvol;
                }
                body.volume += pk.dvol;
            }
        }
        bodies
    }

    /// Calls `add(i, j, value)` for the entries of the joints' conductance matrices
    /// ∫ h [N_A; −N_B][N_A; −N_B]ᵀ dA in the contact `states` (conduction indices; zero
    /// entries left out, so that every entry is a link heat can cross).
    pub fn joint_entries(
        &self,
        interface: &InterfaceSet,
        states: &[InterfaceState],
        mut add: impl FnMut(u32, u32, f64),
    ) {
        let zero = vec![0.0; self.index.len()];
        self.for_joint_points(interface, states, &zero, |at| {
            if at.point.conductance == 0.0 {
                return;
            }
            let idx = at.nodes.map(|n| self.index[n as usize].expect("checked"));
            let n = at.n;
            let v = [n[0], n[1], n[2], -n[0], -n[1], -n[2]];
            for a in 0..6 {
                for b in 0..6 {
                    let value = at.point.conductance * v[a] * v[b] * at.da;
                    if value != 0.0 {
                        add(idx[a], idx[b], value);
                    }
                }
            }
        });
    }

    /// The conduction indices of a conducting cell's nodes (the first `node_count`).
    fn cell_indices(&self, c: &ContinuumCell) -> [u32; 8] {
        let mut idx = [0; 8];
        for (i, &n) in idx.iter_mut().zip(&c.nodes[..c.kind.node_count()]) {
            *i = self.index[n as usize].expect("conducting node");
        }
        idx
    }

    /// The conduction indices of a support line's nodes.
    fn line_indices(&self, line: &[u32; 3]) -> [u32; 3] {
        line.map(|n| self.index[n as usize].expect("checked"))
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
            let idx = self.line_indices(line);
            for (n, da) in self.line_points(line) {
                let temperature: f64 = (0..3).map(|a| n[a] * t[idx[a] as usize]).sum();
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

/// The heat load of a solve ([`Conduction::load`]).
#[derive(Clone, Debug, PartialEq)]
pub struct HeatLoad {
    /// f over the conduction indices.
    pub f: Vec<f64>,
    /// Heat entering through each thermal support's flux (0 for the others: a temperature
    /// support's is its reaction, a film's follows from the temperatures).
    pub boundary_heat: Vec<f64>,
    /// Heat each source generates.
    pub source_heat: Vec<f64>,
}

/// A body with a heat source: ∫ N dV over the conduction indices, and its volume.
#[derive(Clone, Debug)]
pub(super) struct SourceBody {
    pub(super) shape: Vec<f64>,
    pub(super) volume: f64,
}
