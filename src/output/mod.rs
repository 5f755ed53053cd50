//! Result output: VTU files ([`vtu`]), the `.pvd` series that lists them ([`pvd`]), CSV
//! tables ([`csv`]), the run's `summary.json` ([`summary`]) and restart record ([`restart`]),
//! and the background thread that writes a run's files in order ([`writer`]).
//!
//! Writers never leave a half-written file behind: each writes to a temporary file in the
//! target folder and renames it into place once it is complete. They also refuse to write
//! non-finite numbers (a NaN in a result file is an error, not data); only `summary.json`
//! writes one, as `null`, since it also describes failed runs.

pub mod append;
pub(crate) mod atomic;
pub mod csv;
pub mod paths;
pub mod pvd;
pub mod restart;
pub mod summary;
pub mod vtm;
pub mod vtu;
pub mod writer;

use crate::mesh::CellKind;

/// An array attached to the points or cells of a [`Grid`], or to the grid as a whole.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// Array name as ParaView shows it (e.g. `displacement`).
    pub name: String,
    /// Components per tuple (1 scalar, 3 vector, 6 symmetric tensor in VTK's order
    /// xx, yy, zz, xy, yz, xz).
    pub components: usize,
    /// Names of the components as ParaView lists them (VTK's `ComponentName` attributes,
    /// e.g. `rr`, `zz`, `θθ`, `rz` for an axisymmetric tensor); empty: VTK's defaults
    /// (`X`, `Y`, `Z`; `XX`, ... for 6 components).
    pub component_names: Vec<String>,
    pub values: FieldValues,
}

impl Field {
    /// A field with `components` values per tuple and VTK's default component names.
    pub fn new(name: &str, components: usize, values: FieldValues) -> Self {
        Self {
            name: name.into(),
            components,
            component_names: Vec::new(),
            values,
        }
    }

    /// A one-component `Float64` field.
    pub fn scalar(name: &str, values: Vec<f64>) -> Self {
        Self::new(name, 1, FieldValues::F64(values))
    }

    /// A symmetric tensor in VTK's component order with the given component names.
    pub fn tensor(name: &str, values: Vec<f64>, component_names: [&str; 6]) -> Self {
        Self {
            component_names: component_names.map(String::from).to_vec(),
            ..Self::new(name, 6, FieldValues::F64(values))
        }
    }

    /// A one-component string array (only in a grid's [`Grid::field_data`]).
    pub fn strings(name: &str, values: Vec<String>) -> Self {
        Self::new(name, 1, FieldValues::Str(values))
    }

    /// Number of values (not tuples).
    pub fn len(&self) -> usize {
        match &self.values {
            FieldValues::F64(v) => v.len(),
            FieldValues::I32(v) => v.len(),
            FieldValues::Str(v) => v.len(),
        }
    }

    /// Whether the field has no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The values of a [`Field`], `components` per point or cell, tuple after tuple.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldValues {
    F64(Vec<f64>),
    I32(Vec<i32>),
    /// Strings (VTK `String` arrays): names in a grid's [`Grid::field_data`].
    Str(Vec<String>),
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
    /// Arrays of the grid as a whole (VTK FieldData, any number of tuples): the step's
    /// `TimeValue`, which ParaView shows as the time, and what the indices of the cell data
    /// name (e.g. `body_names[k]` is body k).
    pub field_data: Vec<Field>,
}

impl Grid {
    /// Appends a cell of VTK type `vtk_type` with the given point indices.
    pub fn push_cell(&mut self, vtk_type: u8, points: impl IntoIterator<Item = u64>) {
        self.connectivity.extend(points);
        self.offsets.push(self.connectivity.len() as u64);
        self.cell_types.push(vtk_type);
    }

    /// Bytes of memory its arrays hold (points, cells and the values of its fields).
    pub fn heap_bytes(&self) -> usize {
        let fields = self.point_data.iter().chain(&self.cell_data);
        let values: usize = fields
            .map(|f| match &f.values {
                FieldValues::F64(v) => v.len() * size_of::<f64>(),
                FieldValues::I32(v) => v.len() * size_of::<i32>(),
                FieldValues::Str(v) => v.iter().map(String::len).sum(),
            })
            .sum();
        self.points.len() * size_of::<[f64; 2]>()
            + (self.connectivity.len() + self.offsets.len()) * size_of::<u64>()
            + self.cell_types.len()
            + values
    }

    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.cell_types.len()
    }

    /// The grids of the parts of this grid's cells, `part[c]` (below `parts`) the part of cell
    /// c: each holds its cells in order, their points renumbered in the order of first use,
    /// the point and cell arrays restricted to them and the field data unchanged. One pass
    /// over the cells and each part's own points, so the cost is the grid's size however many
    /// parts there are.
    pub fn split(&self, part: &[u32], parts: usize) -> Vec<Grid> {
        self.split_by(&self.split_plan(part, parts))
    }

    /// How [`Self::split`] divides this grid's cells among `parts` parts (`part[c]` the part
    /// of cell c): each part's cells, its points and its cells renumbered. Made once, it
    /// splits every grid with the same cells ([`Self::split_by`]): the frames of a run.
    pub fn split_plan(&self, part: &[u32], parts: usize) -> SplitPlan {
        debug_assert_eq!(part.len(), self.cell_count());
        let mut cells = vec![Vec::new(); parts];
        for (c, &p) in part.iter().enumerate() {
            cells[p as usize].push(c as u32);
        }
        // The part that numbered each point last, and the point's index in it.
        let mut owner = vec![usize::MAX; self.points.len()];
        let mut local = vec![0u64; self.points.len()];
        let mut plan = Vec::with_capacity(parts);
        for (k, cells) in cells.into_iter().enumerate() {
            let mut points = Vec::new();
            let mut topology = Grid::default();
            for c in cells.iter().map(|&c| c as usize) {
                let start = if c == 0 {
                    0
                } else {
                    self.offsets[c - 1] as usize
                };
                let cell = &self.connectivity[start..self.offsets[c] as usize];
                let renumbered = cell.iter().map(|&p| {
                    let p = p as usize;
                    if owner[p] != k {
                        owner[p] = k;
                        local[p] = points.len() as u64;
                        points.push(p as u32);
                    }
                    local[p]
                });
                topology.push_cell(self.cell_types[c], renumbered);
            }
            plan.push(SplitPart {
                cells,
                points,
                topology,
            });
        }
        SplitPlan {
            points: self.points.len(),
            parts: plan,
        }
    }

    /// The grids of the parts of `plan` (made by [`Self::split_plan`] from a grid with the
    /// same cells): each part's cells as the plan numbers them, this grid's point
    /// coordinates and arrays restricted to the part, on all threads.
    pub fn split_by(&self, plan: &SplitPlan) -> Vec<Grid> {
        use rayon::prelude::*;
        debug_assert_eq!(plan.points, self.points.len());
        plan.parts
            .par_iter()
            .map(|part| Grid {
                points: (part.points.par_iter())
                    .map(|&p| self.points[p as usize])
                    .collect(),
                connectivity: part.topology.connectivity.clone(),
                offsets: part.topology.offsets.clone(),
                cell_types: part.topology.cell_types.clone(),
                point_data: (self.point_data.par_iter())
                    .map(|f| f.select(&part.points))
                    .collect(),
                cell_data: (self.cell_data.par_iter())
                    .map(|f| f.select(&part.cells))
                    .collect(),
                field_data: self.field_data.clone(),
            })
            .collect()
    }

    /// Whether `plan` was made for a grid of this one's size (its cells are taken to be the
    /// same: a run's frames share them).
    pub fn fits(&self, plan: &SplitPlan) -> bool {
        plan.points == self.points.len()
            && plan.parts.iter().map(|p| p.cells.len()).sum::<usize>() == self.cell_count()
    }
}

/// How a grid's cells are divided among parts ([`Grid::split_plan`]).
#[derive(Clone, Debug)]
pub struct SplitPlan {
    /// Points of the grid it was made for.
    points: usize,
    parts: Vec<SplitPart>,
}

/// A part of a [`SplitPlan`]: its cells and points (indices into the whole grid's), and its
/// cells with their points renumbered in the part (no coordinates, no arrays).
#[derive(Clone, Debug)]
struct SplitPart {
    cells: Vec<u32>,
    points: Vec<u32>,
    topology: Grid,
}

impl Field {
    /// The field at the tuples `indices`, in that order.
    fn select(&self, indices: &[u32]) -> Field {
        let n = self.components;
        fn pick<T: Clone>(values: &[T], indices: &[u32], n: usize) -> Vec<T> {
            indices
                .iter()
                .flat_map(|&i| values[i as usize * n..(i as usize + 1) * n].iter().cloned())
                .collect()
        }
        let values = match &self.values {
            FieldValues::F64(v) => FieldValues::F64(pick(v, indices, n)),
            FieldValues::I32(v) => FieldValues::I32(pick(v, indices, n)),
            FieldValues::Str(v) => FieldValues::Str(pick(v, indices, n)),
        };
        Field {
            name: self.name.clone(),
            components: n,
            component_names: self.component_names.clone(),
            values,
        }
    }
}

/// Component names of a symmetric tensor in VTK's order (xx, yy, zz, xy, yz, xz): in
/// axisymmetry x is r, y is z and the out-of-plane direction is the hoop direction θ.
pub fn tensor_component_names(axisymmetric: bool) -> [&'static str; 6] {
    if axisymmetric {
        ["rr", "zz", "θθ", "rz", "zθ", "rθ"]
    } else {
        ["xx", "yy", "zz", "xy", "yz", "xz"]
    }
}

/// A stress-like Voigt vector (xx, yy, xy, zz, xθ, yθ) in VTK's symmetric-tensor order
/// (xx, yy, zz, xy, yz, xz), its shear components times `shear` (1 for tensor components,
/// ½ for a strain's engineering shear). In axisymmetry x, y, z are r, z, θ, so yz is zθ and
/// xz is rθ ([`tensor_component_names`]); both are zero without twist.
pub fn vtk_tensor(v: &crate::material::Voigt, shear: f64) -> [f64; 6] {
    use crate::material::{R_THETA, Z_THETA, ZZ};
    [
        v[0],
        v[1],
        v[ZZ],
        shear * v[2],
        shear * v[Z_THETA],
        shear * v[R_THETA],
    ]
}

/// VTK cell type of a quadratic body cell (23 quadratic quad, 22 quadratic triangle); VTK's
/// node order of these cells is gmsh's.
pub fn vtk_cell_type(kind: CellKind) -> u8 {
    match kind {
        CellKind::Quad8 => 23,
        CellKind::Tri6 => 22,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three edges (VTK 21) in two parts, point 4 shared by both: each part
    /// gets its own cells and points in order of first use, and its arrays' tuples.
    #[test]
    fn split_gives_each_part_its_cells_points_and_arrays() {
        let mut grid = Grid {
            points: (0..7).map(|i| [i as f64, 0.0]).collect(),
            ..Grid::default()
        };
        grid.push_cell(21, [0, 2, 1]);
        grid.push_cell(21, [2, 4, 3]);
        grid.push_cell(21, [4, 6, 5]);
        grid.point_data = vec![Field::new(
            "u",
            2,
            FieldValues::F64((0..14).map(f64::from).collect()),
        )];
        grid.cell_data = vec![Field::new("pair", 1, FieldValues::I32(vec![0, 1, 0]))];
        grid.field_data = vec![Field::strings("pair_names", vec!["a".into(), "b".into()])];
        let parts = grid.split(&[0, 1, 0], 2);
        assert_eq!(parts.len(), 2);
        let [a, b] = [&parts[0], &parts[1]];
        assert_eq!(a.connectivity, [0, 1, 2, 3, 4, 5]);
        assert_eq!(a.offsets, [3, 6]);
        let xs = |g: &Grid| g.points.iter().map(|p| p[0]).collect::<Vec<_>>();
        assert_eq!(xs(a), [0.0, 2.0, 1.0, 4.0, 6.0, 5.0]);
        assert_eq!(b.connectivity, [0, 1, 2]);
        assert_eq!(xs(b), [2.0, 4.0, 3.0]);
        assert_eq!(
            b.point_data[0].values,
            FieldValues::F64(vec![4.0, 5.0, 8.0, 9.0, 6.0, 7.0])
        );
        assert_eq!(a.cell_data[0].values, FieldValues::I32(vec![0, 0]));
        assert_eq!(b.cell_data[0].values, FieldValues::I32(vec![1]));
        assert_eq!(a.field_data, grid.field_data);
        assert_eq!(a.cell_types, [21, 21]);
        // The plan made from this frame's grid splits the next frame's (the same cells, other
        // coordinates and values) as a fresh split of it does.
        let plan = grid.split_plan(&[0, 1, 0], 2);
        let mut next = grid.clone();
        next.points.iter_mut().for_each(|p| p[1] = 1.0 + p[0]);
        next.point_data[0].values = FieldValues::F64((0..14).map(|i| f64::from(i) * 0.5).collect());
        assert!(next.fits(&plan));
        assert_eq!(next.split_by(&plan), next.split(&[0, 1, 0], 2));
        assert!(!Grid::default().fits(&plan));
    }
}
