//! Rigid-body freedom: whether the supports and contact pairs hold every body against the
//! rigid-body motions its stiffness does not resist. In a plane model those are the
//! translations in x and y and the in-plane rotation; in an axisymmetric one only the axial
//! translation (a radial translation strains the hoop direction, and the axis holds a body
//! on it radially), and with twist also the rotation about the axis, u_θ = φ r.
//!
//! A body's rigid motions are the amplitudes q = (t_x, t_y, θ) of u(x) = t + θ ẑ × (x − c) / L
//! (c its centroid, L the model size, so that all columns have one scale); in axisymmetry
//! with twist q = (t_z, φ) of u = t_z ẑ + φ (r / L) θ̂. Every restraint
//! is a linear condition on them: a prescribed displacement component at a node, two bodies
//! sharing a node, and at each node pair of a contact the relative displacement normal to
//! the contact (and along it, in both tangential directions with twist, when the pair holds
//! tangentially). The free motions are the
//! null space of these conditions, found by a singular value decomposition per connected
//! group of bodies. The conditions of each body and of each pair of bodies are first reduced
//! to the triangular factor R of their QR decomposition, which has the same singular values,
//! so the matrices stay tiny whatever the mesh.
//!
//! What a contact holds is decided by the caller ([`Hold`]): as defined (before solving),
//! normal to it always — an initial gap is taken to close under the load, the open
//! regularisation stiffness carries the first iteration — and along it only when its law
//! carries shear (friction with a tangential stiffness); in the diagnosis of a failed step,
//! from the contact states of its last attempt (open: nothing; slipping: normal only).

use nalgebra::{DMatrix, DVector};

use super::Model;
use crate::contact::ContactStatus;
use crate::element::set::{ElementSet, INTERFACE_POINTS};
use crate::element::shape::line3;
use crate::error::FreeBody;

/// How an interface element holds its two faces against each other.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hold {
    /// Not at all (open).
    None,
    /// Normal to the contact only (frictionless, or slipping).
    Normal,
    /// Normal to it and along it (sticking friction).
    Full,
}

/// Singular values below this (relative to the largest, at least 1) are zero: the
/// conditions' entries are O(1), a restraint by two points a distance d apart gives a
/// singular value ≈ d / L, and round-off ≈ 1e-15 √(conditions).
const NULL_TOLERANCE: f64 = 1e-9;

/// A body takes part in a free motion when its amplitudes in the (orthonormal) null space
/// exceed this.
const PARTICIPATION: f64 = 1e-8;

impl Model {
    /// The bodies that supports and contacts, as defined, leave free to move as rigid bodies
    /// (a contact holds normal to it, and along it when its law carries shear).
    pub fn free_bodies(&self) -> Vec<FreeBody> {
        self.free_bodies_with(|e| {
            let pair = &self.interface.pairs[self.interface.elements[e].pair as usize];
            if pair.law.carries_shear() {
                Hold::Full
            } else {
                Hold::Normal
            }
        })
    }

    /// How interface element `e` holds its faces in the contact states `states` (one per
    /// integration point of every interface element): not at all when every point is open,
    /// along the contact too when a point sticks and the law carries shear (and, with
    /// `slip_holds`, when one slips), else normal to it.
    pub fn hold_in(
        &self,
        states: &[crate::contact::InterfaceState],
        e: usize,
        slip_holds: bool,
    ) -> Hold {
        let points = &states[e * INTERFACE_POINTS..(e + 1) * INTERFACE_POINTS];
        let pair = &self.interface.pairs[self.interface.elements[e].pair as usize];
        let holds_along = |s: ContactStatus| {
            s == ContactStatus::Stick || (slip_holds && s == ContactStatus::Slip)
        };
        if points.iter().all(|s| s.status == ContactStatus::Open) {
            Hold::None
        } else if pair.law.carries_shear() && points.iter().any(|s| holds_along(s.status)) {
            Hold::Full
        } else {
            Hold::Normal
        }
    }

    /// The bodies free to move as rigid bodies when interface element `e` holds as
    /// `hold(e)` says, in body order.
    pub fn free_bodies_with(&self, hold: impl Fn(usize) -> Hold) -> Vec<FreeBody> {
        let modes = Modes::new(self);
        let mut blocks = Blocks::default();
        let node_bodies = self.node_bodies();
        let x = |n: usize| self.mesh.nodes[n];
        let dofs = self.analysis.dofs_per_node();
        let unit = |c: usize| [c == 0, c == 1, c == 2].map(f64::from);
        for &(dof, _, _) in &self.prescribed {
            let (n, c) = (dof / dofs, dof % dofs);
            for &b in &node_bodies[n] {
                blocks.add(&modes, (b, x(n), unit(c)), None);
            }
        }
        for (n, bodies) in node_bodies.iter().enumerate() {
            for &other in bodies.iter().skip(1) {
                for c in 0..dofs {
                    blocks.add(&modes, (bodies[0], x(n), unit(c)), Some((other, x(n))));
                }
            }
        }
        for (e, element) in self.interface.elements.iter().enumerate() {
            let hold = hold(e);
            if hold == Hold::None {
                continue;
            }
            for (i, xi) in [-1.0, 1.0, 0.0].into_iter().enumerate() {
                let (a, b) = (element.nodes[i] as usize, element.nodes[i + 3] as usize);
                let (Some(&body_a), Some(&body_b)) =
                    (node_bodies[a].first(), node_bodies[b].first())
                else {
                    continue;
                };
                let (_, dn) = line3(xi);
                let mut t = [0.0; 2];
                for (j, c) in element.b_coords.iter().enumerate() {
                    t[0] += dn[j] * c[0];
                    t[1] += dn[j] * c[1];
                }
                let length = t[0].hypot(t[1]);
                if length == 0.0 {
                    continue;
                }
                let t = [t[0] / length, t[1] / length, 0.0];
                let normal = [-t[1], t[0], 0.0];
                // Friction holds in both tangential directions (isotropic).
                let circumferential = [0.0, 0.0, 1.0];
                let directions: &[[f64; 3]] = match hold {
                    Hold::Full if dofs == 3 => &[normal, t, circumferential],
                    Hold::Full => &[normal, t],
                    _ => &[normal],
                };
                for &d in directions {
                    blocks.add(&modes, (body_b, x(b), d), Some((body_a, x(a))));
                }
            }
        }
        let mut free = Vec::new();
        for group in blocks.groups(self.bodies.len()) {
            free.extend(free_in_group(self, &modes, &blocks, &group));
        }
        free.sort_by_key(|(b, _)| *b);
        free.into_iter().map(|(_, f)| f).collect()
    }

    /// The bodies each node belongs to (two or more where bodies share nodes).
    pub fn node_bodies(&self) -> Vec<Vec<usize>> {
        let mut bodies = vec![Vec::new(); self.mesh.nodes.len()];
        for (e, cell) in self.continuum.cells.iter().enumerate() {
            for &n in self.continuum.nodes(e) {
                let list: &mut Vec<usize> = &mut bodies[n as usize];
                if !list.contains(&(cell.body as usize)) {
                    list.push(cell.body as usize);
                }
            }
        }
        bodies
    }
}

/// The rigid motions of the bodies: their number per body, centroids and the length scale.
struct Modes {
    /// 3 in a plane model (t_x, t_y, θ), 1 in an axisymmetric one (t_z), 2 with twist
    /// (t_z, φ).
    per_body: usize,
    centroids: Vec<[f64; 2]>,
    scale: f64,
}

impl Modes {
    fn new(model: &Model) -> Self {
        let mut sums = vec![([0.0; 2], 0usize); model.bodies.len()];
        for cell in &model.continuum.cells {
            let (sum, count) = &mut sums[cell.body as usize];
            for c in &cell.coords[..cell.kind.corner_count()] {
                sum[0] += c[0];
                sum[1] += c[1];
                *count += 1;
            }
        }
        Self {
            per_body: match model.analysis {
                a if a.has_twist() => 2,
                a if a.is_axisymmetric() => 1,
                _ => 3,
            },
            centroids: sums
                .iter()
                .map(|(s, n)| {
                    let n = (*n).max(1) as f64;
                    [s[0] / n, s[1] / n]
                })
                .collect(),
            scale: model.size,
        }
    }

    /// The displacement along `d` (x, y and the circumferential component) at `x` of each
    /// rigid motion of `body` at unit amplitude.
    fn along(&self, body: usize, x: [f64; 2], d: [f64; 3]) -> [f64; 3] {
        match self.per_body {
            1 => return [d[1], 0.0, 0.0],
            2 => return [d[1], d[2] * x[0] / self.scale, 0.0],
            _ => {}
        }
        let c = self.centroids[body];
        let rotation = (-(x[1] - c[1]) * d[0] + (x[0] - c[0]) * d[1]) / self.scale;
        [d[0], d[1], rotation]
    }
}

/// The conditions of each body (`(b, b)`) and each pair of bodies (`(b, c)`, b < c), as rows
/// over their rigid motions (b's, then c's), reduced as they come.
#[derive(Default)]
struct Blocks {
    rows: std::collections::BTreeMap<(usize, usize), Vec<Vec<f64>>>,
}

/// Rows gathered before a block is reduced to its triangular factor.
const REDUCE_AT: usize = 64;

impl Blocks {
    /// The condition "the displacement along `d` of body `b` at `x` (minus that of body
    /// `other` at its point, when given) is zero".
    fn add(
        &mut self,
        modes: &Modes,
        (b, x, d): (usize, [f64; 2], [f64; 3]),
        other: Option<(usize, [f64; 2])>,
    ) {
        let m = modes.per_body;
        let own = modes.along(b, x, d);
        let (key, row) = match other {
            None => ((b, b), own[..m].to_vec()),
            Some((c, y)) => {
                let theirs = modes.along(c, y, d);
                if c == b {
                    let row = (0..m).map(|k| own[k] - theirs[k]).collect();
                    ((b, b), row)
                } else {
                    let (first, second, sign) = if b < c {
                        (own, theirs, 1.0)
                    } else {
                        (theirs, own, -1.0)
                    };
                    let row = first[..m]
                        .iter()
                        .map(|v| sign * v)
                        .chain(second[..m].iter().map(|v| -sign * v))
                        .collect();
                    ((b.min(c), b.max(c)), row)
                }
            }
        };
        if row.iter().all(|&v| v == 0.0) {
            return;
        }
        let rows = self.rows.entry(key).or_default();
        rows.push(row);
        if rows.len() >= REDUCE_AT {
            *rows = reduce(rows);
        }
    }

    /// Connected groups of bodies (joined by a condition between two of them), each sorted.
    fn groups(&self, bodies: usize) -> Vec<Vec<usize>> {
        let mut parent: Vec<usize> = (0..bodies).collect();
        fn root(parent: &mut [usize], mut b: usize) -> usize {
            while parent[b] != b {
                parent[b] = parent[parent[b]];
                b = parent[b];
            }
            b
        }
        for &(b, c) in self.rows.keys() {
            let (rb, rc) = (root(&mut parent, b), root(&mut parent, c));
            parent[rb.max(rc)] = rb.min(rc);
        }
        let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for b in 0..bodies {
            groups.entry(root(&mut parent, b)).or_default().push(b);
        }
        groups.into_values().collect()
    }
}

/// The rows of R in the QR decomposition of `rows`: as many rows as columns at most, the
/// same singular values and right singular vectors.
fn reduce(rows: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let columns = rows[0].len();
    let data: Vec<f64> = rows.iter().flatten().copied().collect();
    let r = DMatrix::from_row_slice(rows.len(), columns, &data).qr().r();
    r.row_iter()
        .map(|row| row.iter().copied().collect())
        .collect()
}

/// The free bodies of one connected group, with their index.
fn free_in_group(
    model: &Model,
    modes: &Modes,
    blocks: &Blocks,
    group: &[usize],
) -> Vec<(usize, FreeBody)> {
    let m = modes.per_body;
    let n = m * group.len();
    let offset = |b: usize| m * group.binary_search(&b).expect("a body of the group");
    let mut rows: Vec<DVector<f64>> = Vec::new();
    for (&(b, c), block) in blocks.rows.iter().filter(|((b, _), _)| group.contains(b)) {
        for row in block {
            let mut full = DVector::zeros(n);
            for k in 0..m {
                full[offset(b) + k] = row[k];
                if c != b {
                    full[offset(c) + k] = row[m + k];
                }
            }
            rows.push(full);
        }
    }
    let mut matrix = DMatrix::zeros(rows.len().max(n), n);
    for (i, row) in rows.iter().enumerate() {
        matrix.row_mut(i).copy_from(&row.transpose());
    }
    let svd = matrix.svd(false, true);
    let v_t = svd.v_t.expect("right singular vectors were asked for");
    let largest = svd.singular_values.max().max(1.0);
    let null: Vec<usize> = (0..n)
        .filter(|&i| svd.singular_values[i] <= NULL_TOLERANCE * largest)
        .collect();
    if null.is_empty() {
        return Vec::new();
    }
    // Orthonormal basis of the free motions, one per column.
    let basis = DMatrix::from_fn(n, null.len(), |i, j| v_t[(null[j], i)]);
    group
        .iter()
        .filter_map(|&b| {
            let motions = basis.rows(offset(b), m).into_owned();
            (motions.norm() > PARTICIPATION).then(|| (b, describe(model, modes, b, &motions)))
        })
        .collect()
}

/// How body `b` can move, from its rows `motions` of an orthonormal basis of the free
/// motions (independent of the basis): the directions it can translate in without
/// rotating, whether it can rotate, and about which point when it cannot also translate.
fn describe(model: &Model, modes: &Modes, b: usize, motions: &DMatrix<f64>) -> FreeBody {
    let body = model.bodies[b].clone();
    if modes.per_body < 3 {
        // Axisymmetry: the axial translation t_z, and with twist the turn φ about the axis.
        let free = |k: usize| k < modes.per_body && motions.row(k).norm() > PARTICIPATION;
        return FreeBody {
            body,
            translations: if free(0) { vec![[0.0, 1.0]] } else { vec![] },
            rotates: false,
            twists: free(1),
            centre: None,
        };
    }
    let k = motions.ncols();
    let rotation = motions.row(2).transpose();
    let rotates = rotation.norm() > PARTICIPATION;
    let translation = motions.rows(0, 2).into_owned();
    // The combinations that do not rotate the body: the complement of `rotation`.
    let translation = if rotates {
        let r = &rotation / rotation.norm();
        translation * (DMatrix::identity(k, k) - &r * r.transpose())
    } else {
        translation
    };
    let svd = translation.svd(true, false);
    let u = svd.u.expect("left singular vectors were asked for");
    let directions: Vec<[f64; 2]> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] > PARTICIPATION)
        .map(|i| {
            let d = [u[(0, i)], u[(1, i)]];
            // The sign that makes the larger component positive.
            let sign = if d[0].abs() >= d[1].abs() { d[0] } else { d[1] }.signum();
            // Round-off of an axis direction is no direction of its own.
            d.map(|c| if c.abs() < 1e-9 { 0.0 } else { sign * c })
        })
        .collect();
    let translations = if directions.len() >= 2 {
        vec![[1.0, 0.0], [0.0, 1.0]]
    } else {
        directions
    };
    // With no translation free, the rotation is about one point: where u = t + θ ẑ × (x − c)/L
    // vanishes for the motion with θ = 1.
    let centre = (rotates && translations.is_empty()).then(|| {
        let a = &rotation / rotation.norm_squared();
        let t = motions.rows(0, 2) * a;
        let c = modes.centroids[b];
        [c[0] - t[1] * modes.scale, c[1] + t[0] * modes.scale]
    });
    FreeBody {
        body,
        translations,
        rotates,
        twists: false,
        centre,
    }
}
