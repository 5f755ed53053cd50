//! Interface output: contact fields at the side-B nodes of every pair, ordered along the
//! contact curve, as a VTU grid of quadratic edges, as CSV tables, and as resultant forces.
//!
//! Integration-point values are mapped to the element's nodes by the exact quadratic fit
//! through the three points (for Newton-Cotes the points are the nodes themselves), then
//! averaged over the elements sharing a node.
//!
//! Fretting results ([`FRETTING`]) come from each point's cyclic history
//! ([`PointHistory`](crate::contact::PointHistory)): dissipation, the last completed
//! cycle's dissipation and slip amplitude, the fretting regime, the Ruiz parameters and the
//! wear depths.

use std::collections::HashMap;

use nalgebra::Matrix3;

use crate::contact::{CIRCUMFERENTIAL, ContactStatus, InterfaceState};
use crate::element::Analysis;
use crate::element::interface6::{InterfaceElement, interface_point};
use crate::element::set::INTERFACE_POINTS;
use crate::element::shape::line3;
use crate::mesh::topology::directed_chains;
use crate::model::Model;
use crate::output::csv::CsvTable;
use crate::output::{Field, FieldValues, Grid};
use crate::post::{BodyPoints, nodal_value, thermal};
use crate::solver::state::Solution;

/// Names of the scalar point fields, in the order of [`NodalContact::values`].
pub const FIELDS: [&str; 10] = [
    "contact_normal_stress",
    "contact_pressure",
    "contact_shear_stress",
    "normal_gap",
    "tangential_slip",
    "plastic_slip",
    "signed_plastic_slip",
    "friction_coefficient",
    "normal_stiffness",
    "tangential_stiffness",
];

/// Names of the circumferential point fields of a model with twist, in the order of
/// [`NodalContact::values`] after [`FIELDS`]: the circumferential shear stress p_θ (MPa), the
/// circumferential relative displacement u_θ and the circumferential plastic slip u_θ^p (mm).
/// Each is written beside its meridional partner ([`field_order`]).
pub const TWIST_FIELDS: [&str; 3] = [
    "contact_shear_stress_theta",
    "tangential_slip_theta",
    "signed_plastic_slip_theta",
];

/// Number of values of [`NodalContact::values`]: [`FIELDS`] then [`TWIST_FIELDS`].
const VALUES: usize = FIELDS.len() + TWIST_FIELDS.len();

/// The point fields a grid or table has, as indices into [`NodalContact::values`] in the
/// order of its columns: [`FIELDS`], and with twist each of [`TWIST_FIELDS`] right after its
/// meridional partner.
pub fn field_order(twist: bool) -> &'static [usize] {
    if twist {
        &[0, 1, 2, 10, 3, 4, 11, 5, 6, 12, 7, 8, 9]
    } else {
        &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9]
    }
}

/// The name of value `i` of [`NodalContact::values`].
fn field_name(i: usize) -> &'static str {
    FIELDS
        .get(i)
        .copied()
        .unwrap_or_else(|| TWIST_FIELDS[i - FIELDS.len()])
}

/// Contact results at one side-B node.
#[derive(Clone, Copy, Debug, Default)]
pub struct NodalContact {
    /// In the order of [`FIELDS`]: p_N (paper sign), −p_N, p_T, u_N, u_T, accumulated slip ū,
    /// signed plastic slip u_T^p, μ_F, k_N, k_T; then of [`TWIST_FIELDS`]: p_θ, u_θ, u_θ^p
    /// (zero without twist).
    pub values: [f64; VALUES],
    /// 0 open, 1 stick, 2 slip (the most advanced state among the contributing points).
    pub status: i32,
}

impl NodalContact {
    /// Extrapolation from Gauss points (elements on the axis, or the `gauss` rule) can push
    /// quantities slightly past their physical bounds; they are clamped there: p_N ≤ 0, and
    /// pressure, accumulated slip, friction coefficient and stiffnesses ≥ 0.
    fn clamp_to_physical_range(&mut self) {
        self.values[0] = self.values[0].min(0.0);
        for i in [1, 5, 7, 8, 9] {
            self.values[i] = self.values[i].max(0.0);
        }
    }

    fn from_state(s: &InterfaceState) -> [f64; VALUES] {
        [
            s.stress[1],
            -s.stress[1],
            s.stress[0],
            s.relative[1],
            s.relative[0],
            s.accumulated_slip,
            s.plastic_slip[0],
            s.friction,
            s.stiffness[1],
            s.stiffness[0],
            s.stress[CIRCUMFERENTIAL],
            s.relative[CIRCUMFERENTIAL],
            s.plastic_slip[1],
        ]
    }
}

/// The side-B nodes of one pair in order along the curve.
#[derive(Clone, Debug)]
struct PairNodes {
    /// Mesh node indices of side B, in curve order (end, mid, end, mid, ...).
    nodes: Vec<u32>,
    /// Arc length at each node.
    arc: Vec<f64>,
    /// Unit tangent of side B at each node (mean over the elements sharing it).
    tangent: Vec<[f64; 2]>,
    /// Body output points of each node and of its side-A partner (for the surface-parallel
    /// stress of either body).
    body_points: Vec<Vec<usize>>,
    /// The side-A node paired with each node.
    partner: Vec<u32>,
}

/// Output of all contact pairs of a model.
#[derive(Clone, Debug)]
pub struct InterfaceOutput {
    pairs: Vec<PairNodes>,
    /// Per pair, per side-B node of the pair: its position in the pair's node list. Per
    /// pair, because pairs meeting at a corner, or one joint split into two groups, share
    /// their end nodes.
    slot: Vec<HashMap<u32, usize>>,
    /// Point-to-node map of each element's rule: node value = Σ_g E[(i, g)] value_g.
    extrapolation: [Matrix3<f64>; 2],
    /// The bodies' output points, whose recovered stresses give σ_T for `ruiz_f3`.
    body_points: BodyPoints,
}

impl InterfaceOutput {
    /// Orders the side-B nodes of every pair along its curve.
    pub fn new(model: &Model) -> Self {
        let mut slot: Vec<HashMap<u32, usize>> = Vec::with_capacity(model.interface.pairs.len());
        let mut pairs = Vec::new();
        for pair in &model.interface.pairs {
            let elements = &model.interface.elements[pair.elements.clone()];
            // Side B's lines, walked b0 → b1; separate pieces are concatenated.
            let lines: Vec<[u32; 3]> = elements
                .iter()
                .map(|e| [e.nodes[3], e.nodes[4], e.nodes[5]])
                .collect();
            let chain: Vec<u32> = directed_chains(&lines)
                .into_iter()
                .flat_map(|c| c.nodes)
                .collect();
            let mut arc = Vec::with_capacity(chain.len());
            let mut s = 0.0;
            for (k, &n) in chain.iter().enumerate() {
                if k > 0 {
                    let (a, b) = (
                        model.mesh.nodes[chain[k - 1] as usize],
                        model.mesh.nodes[n as usize],
                    );
                    s += ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
                }
                arc.push(s);
            }
            slot.push(chain.iter().enumerate().map(|(k, &n)| (n, k)).collect());
            let count = chain.len();
            pairs.push(PairNodes {
                nodes: chain,
                arc,
                tangent: vec![[0.0; 2]; count],
                body_points: vec![Vec::new(); count],
                partner: vec![0; count],
            });
        }
        let body_points = BodyPoints::new(model);
        for element in &model.interface.elements {
            let pair = &mut pairs[element.pair as usize];
            let slot = &slot[element.pair as usize];
            for (k, xi) in [-1.0, 1.0, 0.0].into_iter().enumerate() {
                let at = slot[&element.nodes[3 + k]];
                pair.partner[at] = element.nodes[k];
                let t = interface_point(&model.analysis, &element.b_coords, xi, 1.0).tangent;
                pair.tangent[at] = [pair.tangent[at][0] + t[0], pair.tangent[at][1] + t[1]];
                for node in [element.nodes[k], element.nodes[3 + k]] {
                    for b in 0..model.bodies.len() as u32 {
                        if let Some(p) = body_points.find(b, node)
                            && !pair.body_points[at].contains(&p)
                        {
                            pair.body_points[at].push(p);
                        }
                    }
                }
            }
        }
        // Elements sharing a node follow the curve in one direction, so the sum is not 0.
        for t in pairs.iter_mut().flat_map(|p| p.tangent.iter_mut()) {
            let norm = t[0].hypot(t[1]).max(f64::MIN_POSITIVE);
            *t = [t[0] / norm, t[1] / norm];
        }
        let extrapolation = [
            crate::element::interface6::InterfaceRule::NewtonCotes,
            crate::element::interface6::InterfaceRule::Gauss,
        ]
        .map(|rule| {
            let m = Matrix3::from_fn(|g, i| line3(rule.points()[g].0).0[i]);
            m.try_inverse()
                .expect("three distinct points determine a quadratic")
        });
        Self {
            pairs,
            slot,
            extrapolation,
            body_points,
        }
    }

    /// Nodal contact results of every pair (in curve order).
    pub fn nodal(&self, model: &Model, states: &[InterfaceState]) -> Vec<Vec<NodalContact>> {
        let mut out: Vec<Vec<NodalContact>> = self
            .pairs
            .iter()
            .map(|p| vec![NodalContact::default(); p.nodes.len()])
            .collect();
        let mut count: Vec<Vec<u32>> = self.pairs.iter().map(|p| vec![0; p.nodes.len()]).collect();
        for (e, element) in model.interface.elements.iter().enumerate() {
            let p = element.pair as usize;
            let points = &states[e * INTERFACE_POINTS..(e + 1) * INTERFACE_POINTS];
            let ex = &self.extrapolation[element.rule as usize];
            let values: Vec<[f64; VALUES]> = points.iter().map(NodalContact::from_state).collect();
            for i in 0..3 {
                let k = self.slot[p][&element.nodes[3 + i]];
                let target = &mut out[p][k];
                for (f, v) in target.values.iter_mut().enumerate() {
                    *v += (0..3).map(|g| ex[(i, g)] * values[g][f]).sum::<f64>();
                }
                let nearest = nearest_point(element, i);
                target.status = target.status.max(points[nearest].status as i32);
                count[p][k] += 1;
            }
        }
        for (pair, counts) in out.iter_mut().zip(&count) {
            for (n, &c) in pair.iter_mut().zip(counts) {
                n.values.iter_mut().for_each(|v| *v /= c.max(1) as f64);
                n.clamp_to_physical_range();
            }
        }
        out
    }

    /// The mesh nodes of the interface grid's points: side B of every pair in curve order,
    /// pair after pair.
    pub fn nodes(&self) -> Vec<u32> {
        self.pairs
            .iter()
            .flat_map(|p| p.nodes.iter().copied())
            .collect()
    }

    /// Index of the first grid point of each pair.
    fn offsets(&self) -> Vec<usize> {
        self.pairs
            .iter()
            .scan(0, |acc, p| {
                let start = *acc;
                *acc += p.nodes.len();
                Some(start)
            })
            .collect()
    }

    /// The grid point of side-B node `k` (0, 1, 2: b0, b1, mid) of `element`.
    fn grid_point(&self, offsets: &[usize], element: &InterfaceElement, k: usize) -> usize {
        let pair = element.pair as usize;
        offsets[pair] + self.slot[pair][&element.nodes[3 + k]]
    }

    /// Contact force vectors at the side-B nodes, in grid order, like Abaqus' CNORMF and
    /// CSHEARF: the consistent nodal forces that body A exerts on body B through the normal
    /// and the shear stress, f_i = −∫ N_i p_N n dA and −∫ N_i p_T t dA (N) with the element's
    /// own rule (in axisymmetry totals over the circle); and the circumferential force
    /// −∫ N_i p_θ dA (N, a scalar per node: the magnitude of the ring of circumferential
    /// forces, zero without twist). Summed over a pair the first two are its resultant
    /// `force_on_b` ([`resultants`]).
    pub fn nodal_forces(&self, model: &Model, states: &[InterfaceState]) -> [Vec<f64>; 3] {
        let offsets = self.offsets();
        let n = offsets
            .last()
            .map_or(0, |&o| o + self.pairs.last().map_or(0, |p| p.nodes.len()));
        let mut forces = [vec![0.0; 3 * n], vec![0.0; 3 * n], vec![0.0; n]];
        for (e, element) in model.interface.elements.iter().enumerate() {
            for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
                let p = interface_point(&model.analysis, &element.b_coords, xi, w);
                let [pt, pn, ptheta] = states[e * INTERFACE_POINTS + g].stress;
                for k in 0..3 {
                    let node = self.grid_point(&offsets, element, k);
                    let at = 3 * node;
                    for c in 0..2 {
                        forces[0][at + c] -= p.n[k] * pn * p.normal[c] * p.da;
                        forces[1][at + c] -= p.n[k] * pt * p.tangent[c] * p.da;
                    }
                    forces[2][node] -= p.n[k] * ptheta * p.da;
                }
            }
        }
        forces
    }

    /// Interface grid: one quadratic edge (VTK 21) per element at the side-B positions; point
    /// data: the fields of [`field_order`] (with twist also [`TWIST_FIELDS`]),
    /// `contact_status`, and the contact force vectors `contact_normal_force` and
    /// `contact_shear_force` ([`Self::nodal_forces`]), with twist then the scalar
    /// `contact_shear_force_theta`; cell data `pair`; field data `pair_names` (`pair` k is
    /// `pair_names[k]`).
    pub fn grid(&self, model: &Model, states: &[InterfaceState]) -> Grid {
        let nodal = self.nodal(model, states);
        let offsets = self.offsets();
        let mut grid = Grid::default();
        for p in &self.pairs {
            grid.points
                .extend(p.nodes.iter().map(|&n| model.mesh.nodes[n as usize]));
        }
        for element in &model.interface.elements {
            grid.push_cell(
                21,
                [0, 1, 2].map(|k| self.grid_point(&offsets, element, k) as u64),
            );
        }
        let all: Vec<&NodalContact> = nodal.iter().flatten().collect();
        let twist = model.analysis.has_twist();
        for &f in field_order(twist) {
            let values = all.iter().map(|n| n.values[f]).collect();
            grid.point_data.push(Field {
                name: field_name(f).into(),
                components: 1,
                component_names: Vec::new(),
                values: FieldValues::F64(values),
            });
        }
        grid.point_data.push(Field {
            name: "contact_status".into(),
            components: 1,
            component_names: Vec::new(),
            values: FieldValues::I32(all.iter().map(|n| n.status).collect()),
        });
        let [normal, shear, shear_theta] = self.nodal_forces(model, states);
        grid.point_data.extend([
            Field::new("contact_normal_force", 3, FieldValues::F64(normal)),
            Field::new("contact_shear_force", 3, FieldValues::F64(shear)),
        ]);
        if twist {
            grid.point_data
                .push(Field::scalar("contact_shear_force_theta", shear_theta));
        }
        let names = model.interface.pairs.iter().map(|p| p.name.clone());
        grid.field_data
            .push(Field::strings("pair_names", names.collect()));
        grid.cell_data.push(Field {
            name: "pair".into(),
            components: 1,
            component_names: Vec::new(),
            values: FieldValues::I32(
                model
                    .interface
                    .elements
                    .iter()
                    .map(|e| e.pair as i32)
                    .collect(),
            ),
        });
        grid
    }

    /// One table per pair along the curve: arc length, position, the fields
    /// ([`field_order`]) and the status.
    pub fn tables(&self, model: &Model, states: &[InterfaceState]) -> Vec<CsvTable> {
        let nodal = self.nodal(model, states);
        let order = field_order(model.analysis.has_twist());
        let mut columns: Vec<String> = ["arc_length", "x", "y"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        columns.extend(order.iter().map(|&f| field_name(f).to_string()));
        columns.push("contact_status".into());
        self.pairs
            .iter()
            .zip(&nodal)
            .map(|(p, values)| CsvTable {
                columns: columns.clone(),
                rows: p
                    .nodes
                    .iter()
                    .zip(&p.arc)
                    .zip(values)
                    .map(|((&n, &s), v)| {
                        let x = model.mesh.nodes[n as usize];
                        let mut row = vec![s, x[0], x[1]];
                        row.extend(order.iter().map(|&f| v.values[f]));
                        row.push(v.status as f64);
                        row
                    })
                    .collect(),
            })
            .collect()
    }
}

/// The integration point of `element` nearest to its side-B node `i` (0, 1, 2: b0, b1, mid):
/// whose status (or regime) the node shows.
fn nearest_point(element: &InterfaceElement, i: usize) -> usize {
    let xi = [-1.0, 1.0, 0.0][i];
    let points = element.rule.points();
    (0..3)
        .min_by(|&a, &b| {
            (points[a].0 - xi)
                .abs()
                .total_cmp(&(points[b].0 - xi).abs())
        })
        .expect("three points")
}

/// Names of the fretting point fields (interface CSV columns after `contact_status`, VTU
/// point data), in the order of [`InterfaceOutput::fretting`]'s values: accumulated
/// dissipation ∫ p_T du_T^p (N/mm), its last completed cycle's part, slip amplitude of that
/// cycle (mm), regime (0 stick, 1 partial slip, 2 gross slip), the Ruiz parameters F2 = τ_max
/// δ (N/mm) and F3 = max(σ_T, 0) F2 (N²/mm³), and the wear depths h_A, h_B, h_A + h_B (mm).
pub const FRETTING: [&str; 9] = [
    "dissipation",
    "cycle_dissipation",
    "slip_amplitude",
    "regime",
    "ruiz_f2",
    "ruiz_f3",
    "wear_a",
    "wear_b",
    "wear_depth",
];

/// Index of `regime` and of `ruiz_f2`, `ruiz_f3` in [`FRETTING`].
const REGIME: usize = 3;
const F2: usize = 4;
const F3: usize = 5;

/// The fretting regime of each pair's points in the last completed cycle (Vingsbo &
/// Söderberg, Wear 126 (1988) 131, fretting maps): 0 stick (no slip in the cycle), 1 partial
/// slip (slipped, while some closed point of the pair stuck through the cycle), 2 gross slip
/// (slipped, and no closed point of the pair stuck).
pub fn regimes(model: &Model, states: &[InterfaceState]) -> Vec<u8> {
    let mut sticks = vec![false; model.interface.pairs.len()];
    for (e, element) in model.interface.elements.iter().enumerate() {
        let points = &states[e * INTERFACE_POINTS..(e + 1) * INTERFACE_POINTS];
        sticks[element.pair as usize] |= points
            .iter()
            .any(|s| s.status != ContactStatus::Open && s.history.last_cycle_slip_amplitude == 0.0);
    }
    states
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let pair = model.interface.elements[k / INTERFACE_POINTS].pair as usize;
            match (s.history.last_cycle_slip_amplitude > 0.0, sticks[pair]) {
                (false, _) => 0,
                (true, true) => 1,
                (true, false) => 2,
            }
        })
        .collect()
}

/// The fretting values of a point in [`FRETTING`] order, `ruiz_f3` (which needs the bodies'
/// stress) zero.
fn point_fretting(s: &InterfaceState, regime: u8) -> [f64; 9] {
    let h = &s.history;
    [
        h.dissipation,
        h.last_cycle_dissipation,
        h.last_cycle_slip_amplitude,
        f64::from(regime),
        h.last_cycle_max_shear * h.last_cycle_slip_amplitude,
        0.0,
        h.wear[0],
        h.wear[1],
        h.depth(),
    ]
}

impl InterfaceOutput {
    /// The fretting values ([`FRETTING`]) at the side-B nodes of every pair (in curve order):
    /// extrapolated like [`Self::nodal`] (and clamped at 0, where extrapolation can
    /// undershoot), the regime of the nearest point (the most advanced of the elements
    /// sharing the node), and `ruiz_f3` from the larger surface-parallel normal stress
    /// σ_T = t·σ·t of the two bodies at the node, recovered from the bodies' integration
    /// points (Ruiz, Boddington & Chen, Exp. Mech. 24 (1984) 208; Nowell & Hills, Wear 136
    /// (1990) 329).
    pub fn fretting(&self, model: &Model, solution: &Solution) -> Vec<Vec<[f64; 9]>> {
        let states = &solution.interface_committed;
        let regime = regimes(model, states);
        let mut out: Vec<Vec<[f64; 9]>> = self
            .pairs
            .iter()
            .map(|p| vec![[0.0; 9]; p.nodes.len()])
            .collect();
        let mut count: Vec<Vec<u32>> = self.pairs.iter().map(|p| vec![0; p.nodes.len()]).collect();
        for (e, element) in model.interface.elements.iter().enumerate() {
            let p = element.pair as usize;
            let at = e * INTERFACE_POINTS;
            let values: [[f64; 9]; 3] =
                std::array::from_fn(|g| point_fretting(&states[at + g], regime[at + g]));
            let ex = &self.extrapolation[element.rule as usize];
            for i in 0..3 {
                let k = self.slot[p][&element.nodes[3 + i]];
                let target = &mut out[p][k];
                for (f, v) in target.iter_mut().enumerate() {
                    if f != REGIME {
                        *v += (0..3).map(|g| ex[(i, g)] * values[g][f]).sum::<f64>();
                    }
                }
                target[REGIME] = target[REGIME].max(values[nearest_point(element, i)][REGIME]);
                count[p][k] += 1;
            }
        }
        for (pair, counts) in out.iter_mut().zip(&count) {
            for (node, &c) in pair.iter_mut().zip(counts) {
                for (f, v) in node.iter_mut().enumerate() {
                    if f != REGIME {
                        *v = (*v / c.max(1) as f64).max(0.0);
                    }
                }
            }
        }
        // F3 needs the stress recovery only once a cycle has slipped somewhere.
        if out.iter().flatten().any(|v| v[F2] > 0.0) {
            let states = solution.point_states();
            for (pair, values) in self.pairs.iter().zip(&mut out) {
                for ((v, t), points) in values.iter_mut().zip(&pair.tangent).zip(&pair.body_points)
                {
                    let sigma_t = points
                        .iter()
                        .map(|&b| {
                            let s = nodal_value(model, &self.body_points, states, b).stress;
                            t[0] * t[0] * s[0] + t[1] * t[1] * s[1] + 2.0 * t[0] * t[1] * s[2]
                        })
                        .fold(0.0, f64::max);
                    v[F3] = sigma_t * v[F2];
                }
            }
        }
        out
    }

    /// The wear-depth profile of pair `pair` along its side A: per node (in curve order) the
    /// arc length along side A, the side-A position and the nodal depths h_A, h_B and
    /// h_A + h_B.
    pub fn wear_profile(&self, model: &Model, solution: &Solution, pair: usize) -> Vec<[f64; 6]> {
        let fretting = self.fretting(model, solution);
        let nodes = &self.pairs[pair];
        let mut s = 0.0;
        let mut last: Option<[f64; 2]> = None;
        nodes
            .partner
            .iter()
            .zip(&fretting[pair])
            .map(|(&a, v)| {
                let x = model.mesh.nodes[a as usize];
                if let Some(l) = last {
                    s += (x[0] - l[0]).hypot(x[1] - l[1]);
                }
                last = Some(x);
                [s, x[0], x[1], v[6], v[7], v[8]]
            })
            .collect()
    }

    /// [`Self::tables`] with the fretting columns ([`FRETTING`]) appended: the contact CSV
    /// files of a run.
    pub fn fretting_tables(&self, model: &Model, solution: &Solution) -> Vec<CsvTable> {
        let mut tables = self.tables(model, &solution.interface_committed);
        let fretting = self.fretting(model, solution);
        for (table, values) in tables.iter_mut().zip(&fretting) {
            table.columns.extend(FRETTING.iter().map(|s| s.to_string()));
            for (row, v) in table.rows.iter_mut().zip(values) {
                row.extend(v);
            }
        }
        if let Some(heat) = thermal::joint_values(model, solution) {
            for ((k, table), p) in tables.iter_mut().enumerate().zip(&self.pairs) {
                table
                    .columns
                    .extend(thermal::JOINT_FIELDS.iter().map(|s| s.to_string()));
                for (row, &n) in table.rows.iter_mut().zip(&p.nodes) {
                    row.extend(heat.get(k, n));
                }
            }
        }
        tables
    }

    /// The (pair, side-B node) of every grid point and table row, in order.
    fn pair_nodes(&self) -> impl Iterator<Item = (usize, u32)> + '_ {
        let pairs = self.pairs.iter().enumerate();
        pairs.flat_map(|(k, p)| p.nodes.iter().map(move |&n| (k, n)))
    }

    /// Adds the joints' heat transfer ([`thermal::JOINT_FIELDS`]) to the interface `grid`
    /// when some pair conducts heat.
    pub fn add_joint_heat(&self, grid: &mut Grid, model: &Model, solution: &Solution) {
        let Some(values) = thermal::joint_values(model, solution) else {
            return;
        };
        for (f, name) in thermal::JOINT_FIELDS.iter().enumerate() {
            let column = self.pair_nodes().map(|(p, n)| values.get(p, n)[f]);
            grid.point_data.push(Field::scalar(name, column.collect()));
        }
    }

    /// Adds the fretting point data ([`FRETTING`]; `regime` as integers) to the interface
    /// `grid` of [`Self::grid`].
    pub fn add_fretting(&self, grid: &mut Grid, model: &Model, solution: &Solution) {
        let fretting = self.fretting(model, solution);
        let all: Vec<&[f64; 9]> = fretting.iter().flatten().collect();
        for (f, name) in FRETTING.iter().enumerate() {
            let values = all.iter().map(|v| v[f]);
            let values = if f == REGIME {
                FieldValues::I32(values.map(|r| r as i32).collect())
            } else {
                FieldValues::F64(values.collect())
            };
            grid.point_data.push(Field::new(name, 1, values));
        }
    }
}

/// The extent of a pair's contact at a step, from its integration points (each stands for
/// its weight of the curve): lengths along side B in mm, whatever the analysis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactExtent {
    /// Area in contact (stick or slip), mm²: length × thickness in a plane analysis, ∫ 2πr dl
    /// in axisymmetry.
    pub area: f64,
    /// Length of side B that sticks, slips, or is open (they add up to the pair's length).
    pub stick_length: f64,
    pub slip_length: f64,
    pub open_length: f64,
    /// Largest accumulated slip ū over the pair's points (mm).
    pub max_slip: f64,
}

/// The [`ContactExtent`] of each pair (for `history.csv` and the `stick_zone` quantity).
pub fn contact_extent(model: &Model, states: &[InterfaceState]) -> Vec<ContactExtent> {
    // A unit thickness turns the area weight into the length weight, also on the axis.
    let unit = Analysis::PlaneStrain { thickness: 1.0 };
    let mut out = vec![ContactExtent::default(); model.interface.pairs.len()];
    for (e, element) in model.interface.elements.iter().enumerate() {
        let x = &mut out[element.pair as usize];
        for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
            let state = &states[e * INTERFACE_POINTS + g];
            let dl = interface_point(&unit, &element.b_coords, xi, w).da;
            match state.status {
                ContactStatus::Open => x.open_length += dl,
                ContactStatus::Stick => x.stick_length += dl,
                ContactStatus::Slip => x.slip_length += dl,
            }
            if state.status != ContactStatus::Open {
                x.area += interface_point(&model.analysis, &element.b_coords, xi, w).da;
            }
            x.max_slip = x.max_slip.max(state.accumulated_slip);
        }
    }
    out
}

/// Resultants of each pair: [Σ p_N dA, Σ p_T dA, F_x, F_y], where (F_x, F_y) is the force
/// body A exerts on body B, −Σ (p_T t + p_N n) dA (in axisymmetry totals over the circle).
pub fn resultants(model: &Model, states: &[InterfaceState]) -> Vec<[f64; 4]> {
    let mut out = vec![[0.0; 4]; model.interface.pairs.len()];
    for (e, element) in model.interface.elements.iter().enumerate() {
        let r = &mut out[element.pair as usize];
        for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
            let p = interface_point(&model.analysis, &element.b_coords, xi, w);
            let [pt, pn, _] = states[e * INTERFACE_POINTS + g].stress;
            r[0] += pn * p.da;
            r[1] += pt * p.da;
            for c in 0..2 {
                r[2 + c] -= (pt * p.tangent[c] + pn * p.normal[c]) * p.da;
            }
        }
    }
    out
}

/// The torque (N·mm) about the axis that body A exerts on body B through each pair's
/// circumferential shear: −∫ p_θ r dA, r the radius of the point (side B) and dA the area
/// weight, which in axisymmetry already holds the 2πr of the circle, so the integral is over
/// the whole surface of revolution. Signed like the components of [`resultants`]' force on B
/// (positive in the sense of increasing θ, anticlockwise seen from +z); zero without twist.
pub fn torques(model: &Model, states: &[InterfaceState]) -> Vec<f64> {
    let mut out = vec![0.0; model.interface.pairs.len()];
    for (e, element) in model.interface.elements.iter().enumerate() {
        for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
            let p = interface_point(&model.analysis, &element.b_coords, xi, w);
            let shear = states[e * INTERFACE_POINTS + g].stress[CIRCUMFERENTIAL];
            out[element.pair as usize] -= shear * p.x[0] * p.da;
        }
    }
    out
}
