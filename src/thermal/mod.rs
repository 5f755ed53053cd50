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
//! takes the later one's value. The system is solved by sparse Cholesky (faer).

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};

use crate::contact::{ContactStatus, InterfaceState};
use crate::element::Analysis;
use crate::element::continuum::point_kinematics;
use crate::element::interface6::interface_point;
use crate::element::quadrature::{GAUSS3, cell_rule};
use crate::element::set::{ContinuumSet, INTERFACE_POINTS, InterfaceSet, TemperatureField};
use crate::element::shape::{cell_shape, line3, node_coordinates};
use crate::{Error, Result};

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
    /// Per conduction index, its equation among the free ones.
    equation: Vec<Option<u32>>,
    free: usize,
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
        let mut free = 0;
        let equation = fixed
            .iter()
            .map(|f| {
                f.is_none().then(|| {
                    free += 1;
                    (free - 1) as u32
                })
            })
            .collect();
        Self {
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
            equation,
            free,
        }
    }

    /// Whether the conduction depends on the contact states (some joint conducts).
    pub fn is_coupled(&self) -> bool {
        self.joints.iter().any(Option::is_some)
    }

    /// Whether mesh node `n` carries a temperature.
    pub fn conducts(&self, n: u32) -> bool {
        self.index[n as usize].is_some()
    }

    /// The steady temperature with the supports' and sources' values scaled by
    /// `multiplier(amplitude)`, the joints conducting according to the interface `states`.
    pub fn solve(
        &self,
        continuum: &ContinuumSet,
        interface: &InterfaceSet,
        states: &[InterfaceState],
        multiplier: impl Fn(usize) -> f64,
    ) -> Result<HeatSolution> {
        let mut system = System::new(self.nodes.len());
        self.add_cells(continuum, &multiplier, &mut system);
        self.add_supports(&multiplier, &mut system);
        self.add_joints(interface, states, &mut system);
        self.check_anchored(continuum, &system)?;
        let mut t = vec![0.0; self.nodes.len()];
        for (i, f) in self.fixed.iter().enumerate() {
            if let Some(s) = f {
                let support = &self.supports[*s as usize];
                if let ThermalCondition::Temperature(v) = support.condition {
                    t[i] = v * multiplier(support.amplitude);
                }
            }
        }
        self.solve_free(&system, &mut t)?;
        // The heat a temperature support lets in is its nodes' reaction K T − f.
        let mut reaction: Vec<f64> = system.f.iter().map(|f| -f).collect();
        for &(i, j, v) in &system.entries {
            reaction[i as usize] += v * t[j as usize];
        }
        let mut supports = system.boundary_heat;
        for (i, f) in self.fixed.iter().enumerate() {
            if let Some(s) = f {
                supports[*s as usize] += reaction[i];
            }
        }
        // The joints' heat from the solved temperatures.
        let mut nodal = vec![0.0; self.index.len()];
        for (i, &n) in self.nodes.iter().enumerate() {
            nodal[n as usize] = t[i];
        }
        let mut joints = vec![0.0; self.joints.len()];
        self.for_joint_points(interface, states, &nodal, |at| {
            joints[at.pair] += at.point.flux * at.da;
        });
        Ok(HeatSolution {
            nodal,
            supports: supports
                .iter()
                .zip(&self.supports)
                .map(|(q, s)| match s.condition {
                    ThermalCondition::Film { h, ambient } => {
                        q + self.film_heat(s, h, ambient * multiplier(s.amplitude), &t)
                    }
                    _ => *q,
                })
                .collect(),
            sources: system.source_heat,
            joints,
        })
    }

    /// The conductivity matrices and source vectors of the conducting cells.
    fn add_cells(
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
    fn add_supports(&self, multiplier: &impl Fn(usize) -> f64, system: &mut System) {
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
    fn add_joints(&self, interface: &InterfaceSet, states: &[InterfaceState], system: &mut System) {
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
    fn film_heat(&self, support: &ThermalSupport, h: f64, ambient: f64, t: &[f64]) -> f64 {
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
    fn line_points(&self, line: &[u32; 3]) -> [([f64; 3], f64); 3] {
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

    /// Refuses a system with a conducting region whose temperature nothing fixes: every
    /// group of nodes linked by cells and conducting joints needs a temperature support or a
    /// film (the matrix would be singular).
    fn check_anchored(&self, continuum: &ContinuumSet, system: &System) -> Result<()> {
        let mut parent: Vec<u32> = (0..self.nodes.len() as u32).collect();
        fn root(parent: &mut [u32], mut i: u32) -> u32 {
            while parent[i as usize] != i {
                parent[i as usize] = parent[parent[i as usize] as usize];
                i = parent[i as usize];
            }
            i
        }
        for &(i, j, _) in &system.entries {
            let (a, b) = (root(&mut parent, i), root(&mut parent, j));
            parent[a as usize] = b;
        }
        let mut anchored = vec![false; self.nodes.len()];
        let film_nodes = self
            .supports
            .iter()
            .filter(|s| matches!(s.condition, ThermalCondition::Film { .. }))
            .flat_map(|s| s.lines.iter().flatten());
        let held = film_nodes.filter_map(|&n| self.index[n as usize]);
        let fixed = (0..self.nodes.len() as u32).filter(|&i| self.fixed[i as usize].is_some());
        for i in held.chain(fixed).collect::<Vec<_>>() {
            let r = root(&mut parent, i);
            anchored[r as usize] = true;
        }
        for c in &continuum.cells {
            let Some(i) = self.index[c.nodes[0] as usize] else {
                continue;
            };
            if self.conductivity[c.body as usize].is_some()
                && !anchored[root(&mut parent, i) as usize]
            {
                return Err(Error::Conduction(format!(
                    "nothing fixes the temperature of body '{}' near ({:.4}, {:.4}): give it a \
                     [[thermal_support]] with `temperature` or `film`, or connect it to one \
                     through a contact's `conductance` (a joint conducts only where it is \
                     closed, unless it has a `gap` conductance)",
                    self.body_names[c.body as usize], c.coords[0][0], c.coords[0][1]
                )));
            }
        }
        Ok(())
    }

    /// Solves for the free temperatures in `t` (conduction indices; the fixed ones given).
    fn solve_free(&self, system: &System, t: &mut [f64]) -> Result<()> {
        if self.free == 0 {
            return Ok(());
        }
        let mut rhs = vec![0.0; self.free];
        let mut triplets = Vec::with_capacity(system.entries.len());
        for &(i, j, v) in &system.entries {
            let (Some(ei), ej) = (self.equation[i as usize], self.equation[j as usize]) else {
                continue;
            };
            match ej {
                Some(ej) if ei >= ej => {
                    triplets.push(Triplet::new(ei as usize, ej as usize, v));
                }
                Some(_) => {}
                None => rhs[ei as usize] -= v * t[j as usize],
            }
        }
        for (i, e) in self.equation.iter().enumerate() {
            if let Some(e) = e {
                rhs[*e as usize] += system.f[i];
            }
        }
        let matrix =
            SparseColMat::<usize, f64>::try_new_from_triplets(self.free, self.free, &triplets)
                .map_err(|e| {
                    Error::Conduction(format!("cannot build the conductivity matrix: {e:?}"))
                })?;
        let llt = matrix.sp_cholesky(Side::Lower).map_err(|e| {
            Error::Conduction(format!(
                "the conductivity matrix is not positive definite ({e:?}): does every \
                 conducting body have a temperature support or a film, directly or through a \
                 closed joint?"
            ))
        })?;
        let mut x = Mat::from_fn(self.free, 1, |i, _| rhs[i]);
        llt.solve_in_place(x.as_mut());
        for (i, e) in self.equation.iter().enumerate() {
            if let Some(e) = e {
                t[i] = x[(*e as usize, 0)];
            }
        }
        if t.iter().any(|v| !v.is_finite()) {
            return Err(Error::Conduction(
                "the temperature is not finite: the conductivity matrix is singular".into(),
            ));
        }
        Ok(())
    }

    /// The heat flux −k ∇T (W/mm²) at every mesh node: the average over the conducting cells
    /// holding it of the cell's gradient at the node (0 elsewhere).
    pub fn nodal_flux(&self, continuum: &ContinuumSet, nodal: &[f64]) -> Vec<[f64; 2]> {
        let mut sum = vec![[0.0; 2]; nodal.len()];
        let mut count = vec![0u32; nodal.len()];
        for c in &continuum.cells {
            let Some(k) = self.conductivity[c.body as usize] else {
                continue;
            };
            let nn = c.kind.node_count();
            for (a, &(xi, eta)) in node_coordinates(c.kind).iter().enumerate() {
                let p = crate::element::quadrature::QuadPoint {
                    xi,
                    eta,
                    weight: 1.0,
                };
                let Ok(pk) = point_kinematics(&self.analysis, c.kind, &c.coords, &p) else {
                    continue;
                };
                let mut g = [0.0; 2];
                for i in 0..nn {
                    let t = nodal[c.nodes[i] as usize];
                    g[0] += pk.b[(0, 2 * i)] * t;
                    g[1] += pk.b[(1, 2 * i + 1)] * t;
                }
                let n = c.nodes[a] as usize;
                sum[n][0] -= k * g[0];
                sum[n][1] -= k * g[1];
                count[n] += 1;
            }
        }
        for (s, &c) in sum.iter_mut().zip(&count) {
            if c > 0 {
                s[0] /= c as f64;
                s[1] /= c as f64;
            }
        }
        sum
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
struct System {
    entries: Vec<(u32, u32, f64)>,
    f: Vec<f64>,
    boundary_heat: Vec<f64>,
    source_heat: Vec<f64>,
}

impl System {
    fn new(n: usize) -> Self {
        Self {
            entries: Vec::new(),
            f: vec![0.0; n],
            boundary_heat: Vec::new(),
            source_heat: Vec::new(),
        }
    }

    fn add(&mut self, i: usize, j: usize, v: f64) {
        if v != 0.0 {
            self.entries.push((i as u32, j as u32, v));
        }
    }
}
