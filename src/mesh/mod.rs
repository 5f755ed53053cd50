//! The mesh: the raw gmsh mesh ([`Mesh`]) as read from an MSH 4.1 file ([`msh`]) or made
//! by gmsh ([`gmsh`]), its topology helpers ([`topology`]) and the contact interfaces cut
//! into it ([`interface`]).
//!
//! The mesh is pure geometry and topology plus gmsh's physical groups; it knows nothing of
//! materials or loads. [`crate::model`] turns a mesh and a case file into a model.
//!
//! Node order inside cells is gmsh's, which is also VTK's:
//! - quad8 (gmsh type 16, VTK 23): corners 0..4 counter-clockwise, then mid-side nodes
//!   4 (edge 0–1), 5 (1–2), 6 (2–3), 7 (3–0);
//! - tri6 (gmsh type 9, VTK 22): corners 0..3, then mid-side nodes 3 (0–1), 4 (1–2), 5 (2–0);
//! - line3 (gmsh type 8, VTK 21): end nodes 0, 1, then the mid node 2.

pub mod cache;
pub mod gmsh;
pub mod interface;
pub mod msh;
pub mod topology;

use std::path::PathBuf;

use crate::Error;
use crate::error::{GroupKind, GroupProblem};

/// Kind of a quadratic surface cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CellKind {
    /// 8-node serendipity quadrilateral.
    Quad8,
    /// 6-node triangle.
    Tri6,
}

impl CellKind {
    /// Number of nodes of the cell.
    pub fn node_count(self) -> usize {
        match self {
            CellKind::Quad8 => 8,
            CellKind::Tri6 => 6,
        }
    }

    /// Number of corner nodes (the first nodes of a cell in gmsh order); the mid-side nodes
    /// follow, one per corner edge.
    pub fn corner_count(self) -> usize {
        match self {
            CellKind::Quad8 => 4,
            CellKind::Tri6 => 3,
        }
    }
}

/// A quadratic surface cell. `nodes[..kind.node_count()]` are valid (0-based node indices).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    pub kind: CellKind,
    pub nodes: [u32; 8],
    /// gmsh surface entity the cell belongs to.
    pub entity: i32,
    /// gmsh element tag (for error messages).
    pub tag: u64,
}

impl Cell {
    /// The valid node indices of the cell.
    pub fn nodes(&self) -> &[u32] {
        &self.nodes[..self.kind.node_count()]
    }
}

/// A 3-node boundary line: end nodes `nodes[0]`, `nodes[1]`, mid node `nodes[2]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line3 {
    pub nodes: [u32; 3],
    /// gmsh curve entity the line belongs to.
    pub entity: i32,
    pub tag: u64,
}

/// A point element (gmsh type 15).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointElement {
    pub node: u32,
    /// gmsh point entity.
    pub entity: i32,
    pub tag: u64,
}

/// A gmsh physical group: a name given to a set of entities of one dimension.
#[derive(Clone, Debug, PartialEq)]
pub struct PhysicalGroup {
    /// 0 point, 1 curve, 2 surface.
    pub dim: u8,
    pub tag: i32,
    /// From `$PhysicalNames`; groups without a name are called `"<dim>:<tag>"`.
    pub name: String,
    /// Entity tags (of dimension `dim`) in the group.
    pub entities: Vec<i32>,
}

impl PhysicalGroup {
    /// The kind of group its dimension makes it (dimension 3 counts as a surface: it is
    /// never what a 2D case asks for).
    pub fn kind(&self) -> GroupKind {
        match self.dim {
            0 => GroupKind::Point,
            1 => GroupKind::Curve,
            _ => GroupKind::Surface,
        }
    }
}

/// A 2D quadratic mesh as read from gmsh (z coordinates dropped).
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// File the mesh was read from (for error messages).
    pub path: PathBuf,
    /// Node coordinates (x, y), or (r, z) in axisymmetry.
    pub nodes: Vec<[f64; 2]>,
    /// gmsh tag of each node (for error messages and output).
    pub node_tags: Vec<u64>,
    /// Quadratic surface cells, all counter-clockwise after reading.
    pub cells: Vec<Cell>,
    /// 3-node boundary lines.
    pub lines: Vec<Line3>,
    /// Point elements.
    pub points: Vec<PointElement>,
    pub groups: Vec<PhysicalGroup>,
    /// Number of cells whose node order the reader reversed to make them counter-clockwise.
    pub reoriented_cells: usize,
    /// Nodes made by splitting a contact curve (see [`interface`]'s Split recipe) → the node
    /// each copies, so that a later split of a curve sharing an end node with an earlier one
    /// recognises body B's copy there.
    pub split_copies: std::collections::HashMap<u32, u32>,
}

impl Mesh {
    /// The coordinates of `cell`'s nodes, in its node order (zero beyond its node count).
    pub fn cell_coords(&self, cell: &Cell) -> [[f64; 2]; 8] {
        let mut coords = [[0.0; 2]; 8];
        for (c, &n) in coords.iter_mut().zip(cell.nodes()) {
            *c = self.nodes[n as usize];
        }
        coords
    }

    /// The physical group of dimension `dim` called `name`.
    pub fn group(&self, dim: u8, name: &str) -> Option<&PhysicalGroup> {
        self.groups.iter().find(|g| g.dim == dim && g.name == name)
    }

    /// Comma-separated names of the physical groups of dimension `dim` ("none" if there are
    /// none), for error messages that list the alternatives.
    pub fn group_names(&self, dim: u8) -> String {
        let names: Vec<&str> = self
            .groups
            .iter()
            .filter(|g| g.dim == dim)
            .map(|g| g.name.as_str())
            .collect();
        if names.is_empty() {
            "none".into()
        } else {
            names.join(", ")
        }
    }

    /// An [`Error::Group`]: the group `name`, used by `role` ("body", "support", "contact 'p':
    /// side A curve", ...), is not as `expected` because of `problem`.
    pub fn group_error(
        &self,
        role: impl Into<String>,
        name: &str,
        expected: GroupKind,
        problem: GroupProblem,
    ) -> Error {
        Error::Group {
            mesh: self.path.clone(),
            role: role.into(),
            name: name.into(),
            expected,
            problem,
        }
    }

    /// An [`Error::Group`] for the missing group `name`, listing the groups of the expected
    /// kind (e.g. "surfaces: lower, upper").
    pub fn missing_group(&self, role: impl Into<String>, name: &str, expected: GroupKind) -> Error {
        let list = |dim, kind| format!("{kind}: {}", self.group_names(dim));
        let available = match expected {
            GroupKind::Surface => list(2, "surfaces"),
            GroupKind::Curve => list(1, "curves"),
            GroupKind::Point => list(0, "points"),
            GroupKind::CurveOrPoint => format!("{}; {}", list(1, "curves"), list(0, "points")),
        };
        self.group_error(role, name, expected, GroupProblem::Missing { available })
    }

    /// Cells in the surface group `group`.
    pub fn cells_in<'a>(
        &'a self,
        group: &'a PhysicalGroup,
    ) -> impl Iterator<Item = (usize, &'a Cell)> + 'a {
        self.cells
            .iter()
            .enumerate()
            .filter(move |(_, c)| group.dim == 2 && group.entities.contains(&c.entity))
    }

    /// Lines in the curve group `group`.
    pub fn lines_in<'a>(
        &'a self,
        group: &'a PhysicalGroup,
    ) -> impl Iterator<Item = &'a Line3> + 'a {
        self.lines
            .iter()
            .filter(move |l| group.dim == 1 && group.entities.contains(&l.entity))
    }

    /// Nodes of the points in the point group `group`.
    pub fn points_in<'a>(&'a self, group: &'a PhysicalGroup) -> impl Iterator<Item = u32> + 'a {
        self.points
            .iter()
            .filter(move |p| group.dim == 0 && group.entities.contains(&p.entity))
            .map(|p| p.node)
    }

    /// A typical element size: the median over cells of the longest corner-to-corner distance.
    /// Used to make geometric tolerances relative.
    pub fn typical_size(&self) -> f64 {
        let mut sizes: Vec<f64> = self
            .cells
            .iter()
            .map(|c| {
                topology::cell_edges(c.kind, &c.nodes)
                    .map(|(a, b, _)| {
                        let (a, b) = (self.nodes[a as usize], self.nodes[b as usize]);
                        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
                    })
                    .fold(0.0, f64::max)
            })
            .collect();
        if sizes.is_empty() {
            return 0.0;
        }
        let mid = sizes.len() / 2;
        *sizes.select_nth_unstable_by(mid, f64::total_cmp).1
    }
}
