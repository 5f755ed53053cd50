//! Result output: VTU files ([`vtu`]), the `.pvd` series that lists them ([`pvd`]), CSV
//! tables ([`csv`]) and the run's `summary.json` ([`summary`]).
//!
//! Writers never leave a half-written file behind: each writes to a temporary file in the
//! target folder and renames it into place once it is complete. They also refuse to write
//! non-finite numbers (a NaN in a result file is an error, not data); only `summary.json`
//! writes one, as `null`, since it also describes failed runs.

pub(crate) mod atomic;
pub mod csv;
pub mod pvd;
pub mod restart;
pub mod summary;
pub mod vtu;

use crate::mesh::CellKind;

/// An array attached to the points or cells of a [`Grid`].
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// Array name as ParaView shows it (e.g. `displacement`).
    pub name: String,
    /// Components per tuple (1 scalar, 3 vector, 6 symmetric tensor in VTK's order
    /// xx, yy, zz, xy, yz, xz).
    pub components: usize,
    pub values: FieldValues,
}

/// The values of a [`Field`], `components` per point or cell, tuple after tuple.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldValues {
    F64(Vec<f64>),
    I32(Vec<i32>),
}

/// An unstructured grid ready to be written: points in the x-y plane (z = 0), cells given
/// by their VTK type and connectivity, and point and cell arrays.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Grid {
    pub points: Vec<[f64; 2]>,
    /// Concatenated point indices of all cells.
    pub connectivity: Vec<u64>,
    /// End offset of each cell in `connectivity` (VTK convention: first cell ends at
    /// `offsets[0]`).
    pub offsets: Vec<u64>,
    /// VTK cell type per cell (21 quadratic edge, 22 quadratic triangle, 23 quadratic quad,
    /// 30 quadratic-linear quad, ...).
    pub cell_types: Vec<u8>,
    pub point_data: Vec<Field>,
    pub cell_data: Vec<Field>,
}

impl Grid {
    /// Appends a cell of VTK type `vtk_type` with the given point indices.
    pub fn push_cell(&mut self, vtk_type: u8, points: impl IntoIterator<Item = u64>) {
        self.connectivity.extend(points);
        self.offsets.push(self.connectivity.len() as u64);
        self.cell_types.push(vtk_type);
    }

    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.cell_types.len()
    }
}

/// VTK cell type of a quadratic body cell (23 quadratic quad, 22 quadratic triangle); VTK's
/// node order of these cells is gmsh's.
pub fn vtk_cell_type(kind: CellKind) -> u8 {
    match kind {
        CellKind::Quad8 => 23,
        CellKind::Tri6 => 22,
    }
}
