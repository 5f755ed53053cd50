//! Topology of the zero-thickness 6-node interface elements along a contact: which nodes
//! face each other (Buczkowski & Kleiber (1994), §3.1).
//!
//! Two bodies A and B are joined by quadratic interface elements whose nodes are three nodes
//! on the face of A and three paired nodes on the face of B (Buczkowski & Kleiber (1994),
//! Fig. 1, Eqs. 22–23). The element's geometry and local frame come from side B only:
//! t = ∂x^B/∂ξ / |∂x^B/∂ξ| and n = (−t_y, t_x) (Eqs. 24–25, written there with the slope
//! s = tan θ), and the kinematic variables are the relative displacements
//! u_T = (u^B − u^A)·t, u_N = (u^B − u^A)·n (Eq. 26). This module finds those node pairs in
//! a gmsh mesh and orders them so that the element code can apply the formulas blindly:
//!
//! - the B nodes of an element are one 3-node line of side B, ordered so that body B lies to
//!   the left of b0 → b1; then n = rot90(t) points **into body B**, and u_N > 0 means
//!   opening (closure is −u_N), whatever direction the gmsh curve was drawn in;
//! - a_i is the side-A node paired with b_i, so (u^B − u^A) is taken between paired nodes.
//!
//! Three recipes ([`Pairing`]) cover the ways two faces can be prepared in gmsh:
//!
//! - **Coincident**: two bodies meshed separately (`Geometry.AutoCoherence = 0`), each face
//!   its own physical curve; nodes coincide up to round-off and are paired by coordinates.
//! - **Split**: one conforming mesh with one physical curve between two physical surfaces; the
//!   curve's nodes are duplicated here (what gmsh's `Plugin(Crack)` would do) and body B is
//!   moved onto the copies.
//! - **Ordered**: two faces that do not touch initially (a Hertz-type gap) but carry the same
//!   number of nodes; paired in order along the curves, the initial gap becomes the offset.
//!
//! Everything is checked before anything is changed, so an error leaves the mesh untouched,
//! and every error names the contact pair, the curve and the offending coordinates and gmsh
//! tags. Work is linear in the mesh size (hash maps keyed by node pairs or grid cells), so
//! contacts with ~10⁵ nodes are cheap.

use std::collections::HashMap;

use super::topology::{EdgeIndex, EdgeUse};
use super::{Line3, Mesh, PhysicalGroup};

mod coincident;
mod ordered;
mod split;

use crate::error::{GroupKind, GroupProblem, TopologyProblem};
use crate::{Error, Result};
use coincident::coincident;
use ordered::ordered;
use split::{apply_split, plan_split};

/// Tolerance of the Coincident pairing, relative to [`Mesh::typical_size`].
///
/// gmsh reproduces the coordinates of coincident points of separately meshed surfaces to
/// ~1e-12 relative, far below this; the nodes of one curve are at least half an element
/// apart (end and mid nodes), far above it, even where the contact zone is refined a
/// thousandfold below the median element size. So a pair within the tolerance is certainly
/// meant, and two candidates within it can only be genuinely duplicated nodes.
pub const COINCIDENT_TOLERANCE: f64 = 1e-6;

/// How the two faces of a contact pair are found in the mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum Pairing {
    /// (a) Two physical curves whose nodes coincide (distinct nodes, same coordinates within
    /// [`COINCIDENT_TOLERANCE`] × [`Mesh::typical_size`]), drawn in any direction.
    Coincident { side_a: String, side_b: String },
    /// (b) One physical curve shared by the cells of two bodies (a conforming mesh): its nodes
    /// are duplicated and body B's cells (and B's boundary lines) are moved onto the copies.
    Split {
        curve: String,
        body_a: String,
        body_b: String,
    },
    /// (c) Two curves that are not coincident but have the same number of nodes (Hertz-type
    /// geometry with a small initial gap): paired in order along the curves.
    Ordered { side_a: String, side_b: String },
}

/// Interface elements of one contact pair.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InterfaceTopology {
    /// Per element: [a0, a1, a_mid, b0, b1, b_mid] (line3 order: end, end, middle, as in
    /// gmsh). The B nodes are the nodes of one 3-node line of side B, ordered so that walking
    /// b0 → b1 goes counter-clockwise around body B (body B lies to the LEFT of the direction
    /// b0→b1), so that the normal n = rot90(t) = (−t_y, t_x) of Buczkowski & Kleiber (1994),
    /// Eq. 24, points INTO body B. a_i is the side-A node paired with b_i.
    pub elements: Vec<[u32; 6]>,
    /// Per element and node i (0..3, same order): the initial relative position
    /// x_B,i − x_A,i (zero up to round-off for Coincident/Split; the geometric gap for
    /// Ordered).
    pub offsets: Vec<[[f64; 2]; 3]>,
}

impl InterfaceTopology {
    /// Number of interface elements.
    pub fn len(&self) -> usize {
        self.elements.len()
    }

    /// True when there are no elements.
    pub fn is_empty(&self) -> bool {
        self.elements.is_empty()
    }
}

/// Builds the interface topology of contact pair `name` (used in error messages) for
/// `pairing`, modifying the mesh for `Split` (new nodes appended to `mesh.nodes` and
/// `mesh.node_tags` with fresh tags above the current maximum; B cells and B boundary lines
/// re-pointed to the copies). `bodies` are the names of the physical surfaces that are bodies
/// in the case: every contact curve must be an edge of cells of these bodies.
///
/// Elements follow the order of side B's lines (Coincident, Split) or the order along the
/// curves (Ordered). On error the mesh is unchanged. The function does not panic on bad
/// input (inconsistent hand-made meshes included).
pub fn insert_interface(
    mesh: &mut Mesh,
    pairing: &Pairing,
    name: &str,
    bodies: &[&str],
) -> Result<InterfaceTopology> {
    let ctx = Ctx { mesh: &*mesh, name };
    ctx.check_indices()?;
    let body_of = ctx.bodies(bodies)?;
    match pairing {
        Pairing::Coincident { side_a, side_b } => {
            let sides = ctx.sides(side_a, side_b, &body_of)?;
            coincident(&ctx, &sides)
        }
        Pairing::Ordered { side_a, side_b } => {
            let sides = ctx.sides(side_a, side_b, &body_of)?;
            ordered(&ctx, &sides)
        }
        Pairing::Split {
            curve,
            body_a,
            body_b,
        } => {
            let plan = plan_split(&ctx, curve, body_a, body_b, bodies)?;
            Ok(apply_split(mesh, plan))
        }
    }
}

// ------------------------------------------------------------------------------------------
// Shared machinery: messages, cell edges, curve sides.
// ------------------------------------------------------------------------------------------

/// The mesh and the pair name, for lookups and error messages.
struct Ctx<'m> {
    mesh: &'m Mesh,
    name: &'m str,
}

impl Ctx<'_> {
    /// An [`Error::Topology`] of this pair.
    fn err(&self, problem: TopologyProblem, message: impl std::fmt::Display) -> Error {
        self.err_at(problem, None, None, message)
    }

    /// An [`Error::Topology`] of this pair at mesh node `node` (index) and line element
    /// `element` (gmsh tag).
    fn err_at(
        &self,
        problem: TopologyProblem,
        node: Option<u32>,
        element: Option<u64>,
        message: impl std::fmt::Display,
    ) -> Error {
        Error::Topology {
            pair: self.name.to_string(),
            problem,
            node: node.map(|i| self.mesh.node_tags[i as usize]),
            element,
            message: message.to_string(),
        }
    }

    /// The role of a group of this pair in errors: "contact 'p': side A curve".
    fn role(&self, role: &str) -> String {
        format!("contact '{}': {role}", self.name)
    }

    /// "node 12 at (1, 0.5)".
    fn node(&self, i: u32) -> String {
        let p = self.mesh.nodes[i as usize];
        format!(
            "node {} at ({}, {})",
            self.mesh.node_tags[i as usize], p[0], p[1]
        )
    }

    /// "line element 7 from (0, 1) to (0.25, 1)".
    fn line(&self, line: &Line3) -> String {
        let (p, q) = (
            self.mesh.nodes[line.nodes[0] as usize],
            self.mesh.nodes[line.nodes[1] as usize],
        );
        format!(
            "line element {} from ({}, {}) to ({}, {})",
            line.tag, p[0], p[1], q[0], q[1]
        )
    }

    /// All node references in range and one tag per node, so that indexing cannot panic
    /// (the reader guarantees this; hand-made meshes might not).
    fn check_indices(&self) -> Result<()> {
        let invalid = TopologyProblem::InvalidMesh;
        let n = self.mesh.nodes.len();
        if self.mesh.node_tags.len() != n {
            return Err(self.err(
                invalid,
                format!(
                    "the mesh has {n} nodes but {} node tags",
                    self.mesh.node_tags.len()
                ),
            ));
        }
        let bad = |nodes: &[u32]| nodes.iter().any(|&i| i as usize >= n);
        if let Some(c) = self.mesh.cells.iter().find(|c| bad(c.nodes())) {
            return Err(self.err(
                invalid,
                format!(
                    "element {} references a node index beyond the {n} nodes of the mesh",
                    c.tag
                ),
            ));
        }
        if let Some(l) = self.mesh.lines.iter().find(|l| bad(&l.nodes)) {
            return Err(self.err_at(
                invalid,
                None,
                Some(l.tag),
                format!(
                    "line element {} references a node index beyond the {n} nodes of the mesh",
                    l.tag
                ),
            ));
        }
        Ok(())
    }

    /// Maps each surface entity of the case's bodies to the body's index in `bodies`.
    fn bodies(&self, bodies: &[&str]) -> Result<HashMap<i32, usize>> {
        if bodies.is_empty() {
            return Err(self.err(
                TopologyProblem::NoBodies,
                "the case defines no bodies for the contact to join",
            ));
        }
        let mut body_of = HashMap::new();
        for (b, &body) in bodies.iter().enumerate() {
            let group = self.surface(body)?;
            for &e in &group.entities {
                body_of.entry(e).or_insert(b);
            }
        }
        Ok(body_of)
    }

    fn surface(&self, name: &str) -> Result<&PhysicalGroup> {
        self.mesh.group(2, name).ok_or_else(|| {
            self.mesh
                .missing_group(self.role("body"), name, GroupKind::Surface)
        })
    }

    /// The lines of curve group `curve` (side `role`); error if the group is missing or empty.
    fn curve_lines(&self, curve: &str, role: &str) -> Result<(&PhysicalGroup, Vec<Line3>)> {
        let role = self.role(&format!("{role} curve"));
        let group = self
            .mesh
            .group(1, curve)
            .ok_or_else(|| self.mesh.missing_group(&role, curve, GroupKind::Curve))?;
        let lines: Vec<Line3> = self.mesh.lines_in(group).copied().collect();
        if lines.is_empty() {
            let empty = GroupProblem::Empty;
            return Err(self.mesh.group_error(role, curve, GroupKind::Curve, empty));
        }
        Ok((group, lines))
    }

    /// An index of the corner edges of the cells of `body_of`'s bodies whose both ends are
    /// end nodes of `lines`.
    fn edges<'l>(
        &self,
        body_of: &HashMap<i32, usize>,
        lines: impl Iterator<Item = &'l Line3>,
    ) -> EdgeIndex {
        let mut wanted = vec![false; self.mesh.nodes.len()];
        for l in lines {
            wanted[l.nodes[0] as usize] = true;
            wanted[l.nodes[1] as usize] = true;
        }
        let cells = self.mesh.cells.iter().enumerate();
        EdgeIndex::new(
            cells.filter_map(|(i, c)| body_of.get(&c.entity).map(|&b| (i, b, c.kind, &c.nodes))),
            &wanted,
        )
    }

    /// Both sides of a Coincident or Ordered pair, with their owner cells checked.
    fn sides(&self, side_a: &str, side_b: &str, body_of: &HashMap<i32, usize>) -> Result<Sides> {
        let (_, a_lines) = self.curve_lines(side_a, "side A")?;
        let (_, b_lines) = self.curve_lines(side_b, "side B")?;
        let split_hint = format!(
            "use the Split recipe instead (in the case file: curve = \"{side_a}\", body_a = \
             ..., body_b = ...)"
        );
        if side_a == side_b {
            return Err(self.err(
                TopologyProblem::SameCurve,
                format!(
                    "side A and side B are the same curve '{side_a}'; for a curve between two \
                     bodies of one conforming mesh {split_hint}"
                ),
            ));
        }
        let a_nodes = unique_nodes(&a_lines);
        let b_nodes = unique_nodes(&b_lines);
        let mut on_a = vec![false; self.mesh.nodes.len()];
        for &i in &a_nodes {
            on_a[i as usize] = true;
        }
        if let Some(&shared) = b_nodes.iter().find(|&&i| on_a[i as usize]) {
            return Err(self.err_at(
                TopologyProblem::SharedNodes,
                Some(shared),
                None,
                format!(
                    "{} is on both side A curve '{side_a}' and side B curve '{side_b}': the two \
                     faces share nodes, i.e. the mesh is conforming there; {split_hint}",
                    self.node(shared)
                ),
            ));
        }
        let edges = self.edges(body_of, a_lines.iter().chain(&b_lines));
        // Side A's owners only need to exist (the elements are oriented by side B).
        self.owners(&edges, &a_lines, side_a, "side A")?;
        let b_owner = self.owners(&edges, &b_lines, side_b, "side B")?;
        Ok(Sides {
            a_name: side_a.to_string(),
            b_name: side_b.to_string(),
            a_lines,
            b_lines,
            a_nodes,
            b_nodes,
            edges,
            b_owner,
        })
    }

    /// The one body cell whose edge each line is.
    fn owners(
        &self,
        edges: &EdgeIndex,
        lines: &[Line3],
        curve: &str,
        role: &str,
    ) -> Result<Vec<EdgeUse>> {
        lines
            .iter()
            .map(|l| {
                let uses = edges.find(l.nodes[0], l.nodes[1], l.nodes[2]);
                match uses.as_slice() {
                    [one] => Ok(*one),
                    [] => Err(self.err_at(
                        TopologyProblem::NoOwner,
                        None,
                        Some(l.tag),
                        format!(
                            "{role} curve '{curve}' belongs to no body ({} is an edge of no \
                             element of the bodies)",
                            self.line(l)
                        ),
                    )),
                    [first, second, ..] => Err(self.err_at(
                        TopologyProblem::Interior,
                        None,
                        Some(l.tag),
                        format!(
                            "{role} curve '{curve}' runs inside the bodies, not on a face ({} is \
                             shared by elements {} and {}); for a curve between two bodies of \
                             one conforming mesh use the Split recipe",
                            self.line(l),
                            self.mesh.cells[first.cell].tag,
                            self.mesh.cells[second.cell].tag
                        ),
                    )),
                }
            })
            .collect()
    }

    /// Orients one element by the cell that owns its B line (`b_owner`, whose walk goes
    /// counter-clockwise around body B) and checks that the paired A nodes form a face edge
    /// of a body cell lying on the other side. `a` and `b` are paired node by node in line
    /// order (end, end, middle).
    fn element(
        &self,
        edges: &EdgeIndex,
        mut a: [u32; 3],
        mut b: [u32; 3],
        b_owner: &EdgeUse,
        b_line: &Line3,
    ) -> Result<([u32; 6], [[f64; 2]; 3])> {
        if b_owner.from != b[0] {
            a.swap(0, 1);
            b.swap(0, 1);
        }
        let a_uses = edges.find(a[0], a[1], a[2]);
        if a_uses.is_empty() {
            return Err(self.err_at(
                TopologyProblem::Mismatch,
                Some(a[0]),
                Some(b_line.tag),
                format!(
                    "the side A nodes paired with side B {} ({}, {}, {}) are not the end and mid \
                     nodes of one element edge of a body: the two curves are discretised \
                     differently; mesh both faces with the same points (e.g. Transfinite Curve)",
                    self.line(b_line),
                    self.node(a[0]),
                    self.node(a[1]),
                    self.node(a[2])
                ),
            ));
        }
        // Both cells counter-clockwise: across a face their walks along the edge are opposite.
        // The same direction means both bodies lie on the same side, i.e. they overlap.
        if a_uses.iter().any(|u| u.from == a[0]) {
            return Err(self.err_at(
                TopologyProblem::Overlap,
                None,
                Some(b_line.tag),
                format!(
                    "bodies A and B lie on the same side of the contact at side B {} (element {} \
                     of side A and element {} of side B): the bodies overlap",
                    self.line(b_line),
                    self.mesh.cells[a_uses[0].cell].tag,
                    self.mesh.cells[b_owner.cell].tag
                ),
            ));
        }
        let x = |i: u32| self.mesh.nodes[i as usize];
        let offsets = std::array::from_fn(|k| [x(b[k])[0] - x(a[k])[0], x(b[k])[1] - x(a[k])[1]]);
        Ok(([a[0], a[1], a[2], b[0], b[1], b[2]], offsets))
    }
}

/// The two faces of a Coincident or Ordered pair.
struct Sides {
    a_name: String,
    b_name: String,
    a_lines: Vec<Line3>,
    b_lines: Vec<Line3>,
    /// Distinct nodes of each side, sorted.
    a_nodes: Vec<u32>,
    b_nodes: Vec<u32>,
    edges: EdgeIndex,
    /// Owner cell of each B line (same order as `b_lines`).
    b_owner: Vec<EdgeUse>,
}

/// Distinct nodes of `lines`, sorted.
fn unique_nodes(lines: &[Line3]) -> Vec<u32> {
    let mut nodes: Vec<u32> = lines.iter().flat_map(|l| l.nodes).collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

#[cfg(test)]
mod tests {
    use super::ordered::chain;
    use super::*;
    use crate::mesh::{Cell, CellKind};

    /// A hand-made mesh: quad8 cells from corner coordinates, with nodes shared only within a
    /// "scope" (one scope per separately meshed body).
    #[derive(Default)]
    struct Builder {
        mesh: Mesh,
        index: HashMap<(usize, i64, i64), u32>,
    }

    impl Builder {
        fn node(&mut self, scope: usize, p: [f64; 2]) -> u32 {
            let k = (
                scope,
                (p[0] * 1e6).round() as i64,
                (p[1] * 1e6).round() as i64,
            );
            if let Some(&i) = self.index.get(&k) {
                return i;
            }
            let i = self.mesh.nodes.len() as u32;
            self.mesh.nodes.push(p);
            self.mesh.node_tags.push(100 + i as u64);
            self.index.insert(k, i);
            i
        }

        /// Counter-clockwise axis-parallel quad [x0,x1]×[y0,y1].
        fn quad(&mut self, scope: usize, entity: i32, x0: f64, x1: f64, y0: f64, y1: f64) {
            let c = [[x0, y0], [x1, y0], [x1, y1], [x0, y1]];
            let mut nodes = [0; 8];
            for k in 0..4 {
                nodes[k] = self.node(scope, c[k]);
                let (p, q) = (c[k], c[(k + 1) % 4]);
                nodes[4 + k] = self.node(scope, [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0]);
            }
            let tag = self.mesh.cells.len() as u64 + 1;
            self.mesh.cells.push(Cell {
                kind: CellKind::Quad8,
                nodes,
                entity,
                tag,
            });
        }

        /// Straight line3 from p to q in `scope`, on curve entity `entity`.
        fn line(&mut self, scope: usize, entity: i32, p: [f64; 2], q: [f64; 2]) {
            let m = [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
            let nodes = [
                self.node(scope, p),
                self.node(scope, q),
                self.node(scope, m),
            ];
            let tag = 1000 + self.mesh.lines.len() as u64;
            self.mesh.lines.push(Line3 { nodes, entity, tag });
        }

        fn group(&mut self, dim: u8, tag: i32, name: &str, entities: &[i32]) {
            self.mesh.groups.push(PhysicalGroup {
                dim,
                tag,
                name: name.into(),
                entities: entities.to_vec(),
            });
        }
    }

    /// Lower body [0,2]×[0,1] as two quads (entity 1), upper body [0,2]×[1,2] (entity 2) as
    /// two quads in its own scope; curve 11 = lower top (drawn right to left), curve 12 =
    /// upper bottom (left to right).
    fn two_blocks() -> Builder {
        let mut b = Builder::default();
        b.quad(0, 1, 0.0, 1.0, 0.0, 1.0);
        b.quad(0, 1, 1.0, 2.0, 0.0, 1.0);
        b.quad(1, 2, 0.0, 1.0, 1.0, 2.0);
        b.quad(1, 2, 1.0, 2.0, 1.0, 2.0);
        b.line(0, 11, [2.0, 1.0], [1.0, 1.0]);
        b.line(0, 11, [1.0, 1.0], [0.0, 1.0]);
        b.line(1, 12, [0.0, 1.0], [1.0, 1.0]);
        b.line(1, 12, [1.0, 1.0], [2.0, 1.0]);
        b.group(2, 1, "lower", &[1]);
        b.group(2, 2, "upper", &[2]);
        b.group(1, 11, "top", &[11]);
        b.group(1, 12, "bottom", &[12]);
        b
    }

    fn coincident(a: &str, b: &str) -> Pairing {
        Pairing::Coincident {
            side_a: a.into(),
            side_b: b.into(),
        }
    }

    /// The problem, node and line element of a topology error of pair "p".
    fn topology(e: Error) -> (TopologyProblem, Option<u64>, Option<u64>) {
        match e {
            Error::Topology {
                pair,
                problem,
                node,
                element,
                ..
            } if pair == "p" => (problem, node, element),
            other => panic!("expected a topology error of pair 'p', got {other}"),
        }
    }

    /// The topology error of a call that must fail.
    fn error(
        mesh: &mut Mesh,
        pairing: &Pairing,
        bodies: &[&str],
    ) -> (TopologyProblem, Option<u64>, Option<u64>) {
        match insert_interface(mesh, pairing, "p", bodies) {
            Ok(t) => panic!("expected an error, got {t:?}"),
            Err(e) => topology(e),
        }
    }

    /// Coordinates of the node with gmsh tag `tag`.
    fn at(mesh: &Mesh, tag: Option<u64>) -> [f64; 2] {
        let i = mesh.node_tags.iter().position(|&t| Some(t) == tag);
        mesh.nodes[i.expect("a node tag of the mesh")]
    }

    #[test]
    fn coincident_blocks_are_oriented_into_b() {
        let mut mesh = two_blocks().mesh;
        let t = insert_interface(
            &mut mesh,
            &coincident("top", "bottom"),
            "p",
            &["lower", "upper"],
        )
        .unwrap();
        assert_eq!(t.len(), 2);
        for (e, o) in t.elements.iter().zip(&t.offsets) {
            let (b0, b1) = (mesh.nodes[e[3] as usize], mesh.nodes[e[4] as usize]);
            // Body B is above y = 1: B is left of b0 → b1 means walking in +x.
            assert!(b1[0] > b0[0], "{e:?}");
            for i in 0..3 {
                assert_ne!(e[i], e[i + 3]);
                assert_eq!(mesh.nodes[e[i] as usize], mesh.nodes[e[i + 3] as usize]);
                assert_eq!(o[i], [0.0, 0.0]);
            }
        }
        // Swapping the roles flips the walk: the lower body is then B.
        let t = insert_interface(
            &mut mesh,
            &coincident("bottom", "top"),
            "p",
            &["lower", "upper"],
        )
        .unwrap();
        for e in &t.elements {
            assert!(mesh.nodes[e[4] as usize][0] < mesh.nodes[e[3] as usize][0]);
        }
    }

    #[test]
    fn ambiguous_candidates_are_reported() {
        // Lower body made of two separately meshed halves: two A nodes at (1, 1).
        let mut b = Builder::default();
        b.quad(0, 1, 0.0, 1.0, 0.0, 1.0);
        b.quad(2, 1, 1.0, 2.0, 0.0, 1.0);
        b.quad(1, 2, 0.0, 2.0, 1.0, 2.0);
        b.line(0, 11, [1.0, 1.0], [0.0, 1.0]);
        b.line(2, 11, [2.0, 1.0], [1.0, 1.0]);
        b.line(1, 12, [0.0, 1.0], [2.0, 1.0]);
        b.group(2, 1, "lower", &[1]);
        b.group(2, 2, "upper", &[2]);
        b.group(1, 11, "top", &[11]);
        b.group(1, 12, "bottom", &[12]);
        let mut mesh = b.mesh;
        let (problem, node, _) =
            error(&mut mesh, &coincident("top", "bottom"), &["lower", "upper"]);
        assert_eq!(problem, TopologyProblem::Ambiguous);
        assert_eq!(at(&mesh, node), [1.0, 1.0]);
    }

    #[test]
    fn differently_discretised_faces_with_equal_node_sets_are_rejected() {
        // Upper body: one quad whose bottom edge is split at x = 1 as end node, but whose
        // line3 "mid" node is the node at x = 2 (a topologically inconsistent face).
        let mut b = Builder::default();
        b.quad(0, 1, 0.0, 2.0, 0.0, 1.0);
        b.line(0, 11, [2.0, 1.0], [0.0, 1.0]);
        b.group(2, 1, "lower", &[1]);
        b.group(2, 2, "upper", &[2]);
        b.group(1, 11, "top", &[11]);
        b.group(1, 12, "bottom", &[12]);
        b.quad(1, 2, 0.0, 2.0, 1.0, 2.0);
        let cell = b.mesh.cells[1];
        let (corner1, mid0) = (cell.nodes[1], cell.nodes[4]); // (2,1) and (1,1)
        let cell = &mut b.mesh.cells[1];
        cell.nodes[1] = mid0;
        cell.nodes[4] = corner1;
        b.mesh.lines.push(Line3 {
            nodes: [cell.nodes[0], mid0, corner1],
            entity: 12,
            tag: 77,
        });
        let mut mesh = b.mesh;
        let e = error(&mut mesh, &coincident("top", "bottom"), &["lower", "upper"]);
        assert_eq!((e.0, e.2), (TopologyProblem::Mismatch, Some(77)));
    }

    #[test]
    fn chains_and_their_errors() {
        let mut b = two_blocks();
        // A third line on "top" from (1,1) up to (1,1.5): a branch.
        b.line(0, 11, [1.0, 1.0], [1.0, 1.5]);
        let mesh = b.mesh;
        let ctx = Ctx {
            mesh: &mesh,
            name: "p",
        };
        let group = mesh.group(1, "top").unwrap();
        let lines: Vec<Line3> = mesh.lines_in(group).copied().collect();
        let e = chain(&ctx, &lines, "top", "side A").err().unwrap();
        let (problem, node, _) = topology(e);
        assert_eq!(problem, TopologyProblem::Branch);
        assert_eq!(at(&mesh, node), [1.0, 1.0]);
        let c = chain(&ctx, &lines[..2], "top", "side A").unwrap();
        assert_eq!(c.nodes.len(), 5);
        let xs: Vec<f64> = c.nodes.iter().map(|&n| mesh.nodes[n as usize][0]).collect();
        assert!(xs == [0.0, 0.5, 1.0, 1.5, 2.0] || xs == [2.0, 1.5, 1.0, 0.5, 0.0]);
        // Two disjoint pieces.
        let pieces = [lines[0], mesh.lines[2]];
        let e = chain(&ctx, &pieces, "top", "side A").err().unwrap();
        assert_eq!(topology(e).0, TopologyProblem::Disconnected);
    }

    #[test]
    fn split_two_blocks_of_one_mesh() {
        let mut b = Builder::default();
        b.quad(0, 1, 0.0, 1.0, 0.0, 1.0);
        b.quad(0, 2, 0.0, 1.0, 1.0, 2.0);
        b.line(0, 11, [1.0, 1.0], [0.0, 1.0]);
        b.line(0, 13, [1.0, 1.0], [1.0, 2.0]); // right side of the upper block
        b.line(0, 14, [1.0, 0.0], [1.0, 1.0]); // right side of the lower block
        b.group(2, 1, "lower", &[1]);
        b.group(2, 2, "upper", &[2]);
        b.group(1, 11, "cut", &[11]);
        b.group(1, 13, "upper_right", &[13]);
        b.group(1, 14, "lower_right", &[14]);
        let mut mesh = b.mesh;
        let before = mesh.nodes.len();
        let pairing = Pairing::Split {
            curve: "cut".into(),
            body_a: "lower".into(),
            body_b: "upper".into(),
        };
        let t = insert_interface(&mut mesh, &pairing, "p", &["lower", "upper"]).unwrap();
        assert_eq!(mesh.nodes.len(), before + 3);
        assert_eq!(mesh.node_tags.len(), before + 3);
        let e = t.elements[0];
        // B above: b0 → b1 walks in +x.
        assert_eq!(mesh.nodes[e[3] as usize], [0.0, 1.0]);
        assert_eq!(mesh.nodes[e[4] as usize], [1.0, 1.0]);
        assert!(e[3..].iter().all(|&n| n as usize >= before));
        assert!(e[..3].iter().all(|&n| (n as usize) < before));
        let (lower, upper) = (mesh.cells[0], mesh.cells[1]);
        assert!(lower.nodes().iter().all(|n| !upper.nodes().contains(n)));
        assert!(mesh.lines[1].nodes.iter().any(|&n| n as usize >= before));
        assert!(mesh.lines[2].nodes.iter().all(|&n| (n as usize) < before));
        assert!(mesh.lines[0].nodes.iter().all(|&n| (n as usize) < before));
        // Splitting again: the curve is already split, and the mesh is left unchanged.
        let copy = mesh.clone();
        let e = error(&mut mesh, &pairing, &["lower", "upper"]);
        assert_eq!(e.0, TopologyProblem::AlreadySplit);
        assert_eq!(mesh.nodes, copy.nodes);
        assert_eq!(mesh.cells, copy.cells);
    }

    /// One joint y = 1 in two curves that share the node (1, 1), each split by its own pair:
    /// both pairs join A's node there to the same copy of B, made once, and B's cells use
    /// copies only.
    #[test]
    fn split_two_curves_sharing_an_end_node() {
        let mut b = Builder::default();
        b.quad(0, 1, 0.0, 1.0, 0.0, 1.0);
        b.quad(0, 1, 1.0, 2.0, 0.0, 1.0);
        b.quad(0, 2, 0.0, 1.0, 1.0, 2.0);
        b.quad(0, 2, 1.0, 2.0, 1.0, 2.0);
        b.line(0, 11, [0.0, 1.0], [1.0, 1.0]);
        b.line(0, 12, [1.0, 1.0], [2.0, 1.0]);
        b.group(2, 1, "lower", &[1]);
        b.group(2, 2, "upper", &[2]);
        b.group(1, 11, "left", &[11]);
        b.group(1, 12, "right", &[12]);
        let mut mesh = b.mesh;
        let before = mesh.nodes.len();
        let mut sides = Vec::new();
        for curve in ["left", "right"] {
            let pairing = Pairing::Split {
                curve: curve.into(),
                body_a: "lower".into(),
                body_b: "upper".into(),
            };
            let t = insert_interface(&mut mesh, &pairing, curve, &["lower", "upper"]).unwrap();
            assert_eq!(t.len(), 1);
            sides.push(t.elements[0]);
        }
        // Three copies for the first curve, two more (mid and far end) for the second.
        assert_eq!(mesh.nodes.len(), before + 5);
        let at = |e: [u32; 6], x: [f64; 2]| {
            let k = (3..6).find(|&k| mesh.nodes[e[k] as usize] == x).unwrap();
            (e[k - 3], e[k])
        };
        let (left, right) = (at(sides[0], [1.0, 1.0]), at(sides[1], [1.0, 1.0]));
        assert_eq!(left, right, "one node pair at the shared node");
        assert!((left.0 as usize) < before && left.1 as usize >= before);
        for cell in &mesh.cells[2..] {
            for &n in cell.nodes() {
                assert!(
                    mesh.nodes[n as usize][1] > 1.0 || n as usize >= before,
                    "an upper cell keeps an original node on the joint"
                );
            }
        }
    }

    /// ~10⁵ nodes per face (50 000 quads on each side): pairing must stay linear in time.
    #[test]
    fn long_contact_scales() {
        let n = 50_000;
        let mut b = Builder::default();
        for i in 0..n {
            let x0 = i as f64;
            b.quad(0, 1, x0, x0 + 1.0, 0.0, 1.0);
            b.quad(1, 2, x0, x0 + 1.0, 1.0, 2.0);
            b.line(0, 11, [x0 + 1.0, 1.0], [x0, 1.0]);
            b.line(1, 12, [x0, 1.0], [x0 + 1.0, 1.0]);
        }
        b.group(2, 1, "lower", &[1]);
        b.group(2, 2, "upper", &[2]);
        b.group(1, 11, "top", &[11]);
        b.group(1, 12, "bottom", &[12]);
        let mut mesh = b.mesh;
        let start = std::time::Instant::now();
        for pairing in [
            coincident("top", "bottom"),
            Pairing::Ordered {
                side_a: "top".into(),
                side_b: "bottom".into(),
            },
        ] {
            let t = insert_interface(&mut mesh, &pairing, "p", &["lower", "upper"]).unwrap();
            assert_eq!(t.len(), n);
            assert!(t.offsets.iter().flatten().all(|o| *o == [0.0, 0.0]));
        }
        // Generous bound (debug build): a quadratic search would take minutes.
        assert!(
            start.elapsed().as_secs_f64() < 20.0,
            "{:?}",
            start.elapsed()
        );
    }

    #[test]
    fn bad_meshes_do_not_panic() {
        let mut mesh = two_blocks().mesh;
        mesh.lines[0].nodes[2] = 10_000;
        let e = error(&mut mesh, &coincident("top", "bottom"), &["lower", "upper"]);
        assert_eq!(e, (TopologyProblem::InvalidMesh, None, Some(1000)));
        let mut mesh = two_blocks().mesh;
        mesh.node_tags.pop();
        let e = error(&mut mesh, &coincident("top", "bottom"), &["lower", "upper"]);
        assert_eq!(e.0, TopologyProblem::InvalidMesh);
        let mut mesh = Mesh::default();
        let e = error(&mut mesh, &coincident("top", "bottom"), &[]);
        assert_eq!(e.0, TopologyProblem::NoBodies);
        let mut mesh = two_blocks().mesh;
        let e = error(&mut mesh, &coincident("top", "top"), &["lower", "upper"]);
        assert_eq!(e.0, TopologyProblem::SameCurve);
    }
}
