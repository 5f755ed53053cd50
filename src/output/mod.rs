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
pub mod generated;
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

    /// How this grid's cells are divided among `parts` parts (`part[c]`, below `parts`, the
    /// part of cell c): each part's cells in order, its points in the order of first use and
    /// its cells renumbered to them. One pass over the cells and each part's own points, so
    /// the cost is the grid's size however many parts there are. Made once, it divides every
    /// grid with the same cells ([`GridView::part`]): the frames of a run.
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

impl SplitPlan {
    /// The share of the grid's cells that part `k` holds (for the memory a file of it
    /// accounts for).
    pub fn share(&self, k: usize) -> f64 {
        let cells: usize = self.parts.iter().map(|p| p.cells.len()).sum();
        self.parts[k].cells.len() as f64 / cells.max(1) as f64
    }
}

/// What one file holds of a grid: the whole grid, or one part of a [`SplitPlan`] (its
/// points' coordinates and its point and cell arrays' tuples read from the grid's through
/// the plan's indices, its cells the plan's), without a copy of the grid.
#[derive(Clone, Copy, Debug)]
pub struct GridView<'a> {
    pub grid: &'a Grid,
    /// The plan and the part's index in it.
    part: Option<(&'a SplitPlan, usize)>,
}

/// Whether a field's tuples are a grid's points', cells' or neither (field data).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Attachment {
    Points,
    Cells,
    None,
}

impl<'a> GridView<'a> {
    /// The whole `grid`.
    pub fn whole(grid: &'a Grid) -> Self {
        Self { grid, part: None }
    }

    /// Part `k` of `plan`, made by [`Grid::split_plan`] from a grid with the cells of
    /// `grid` ([`Grid::fits`]).
    pub fn part(grid: &'a Grid, plan: &'a SplitPlan, k: usize) -> Self {
        Self {
            grid,
            part: Some((plan, k)),
        }
    }

    /// Whether the grid has the points and cells of the plan the view reads it through.
    pub fn fits(&self) -> bool {
        self.part.is_none_or(|(plan, _)| self.grid.fits(plan))
    }

    fn split_part(&self) -> Option<&'a SplitPart> {
        self.part.map(|(plan, k)| &plan.parts[k])
    }

    /// The cells (connectivity, offsets, types) the view holds, numbered to its points.
    pub fn topology(&self) -> &'a Grid {
        self.split_part().map_or(self.grid, |p| &p.topology)
    }

    pub fn point_count(&self) -> usize {
        self.split_part()
            .map_or(self.grid.points.len(), |p| p.points.len())
    }

    pub fn cell_count(&self) -> usize {
        self.topology().cell_count()
    }

    /// The tuples of `values` (`n` components each, attached as `at`) the view holds, in
    /// its order: each call of `each` gets one tuple.
    pub fn for_each_tuple<T>(
        &self,
        values: &'a [T],
        n: usize,
        at: Attachment,
        mut each: impl FnMut(&'a [T]),
    ) {
        let indices = match (self.split_part(), at) {
            (Some(p), Attachment::Points) => &p.points,
            (Some(p), Attachment::Cells) => &p.cells,
            _ => return values.chunks_exact(n).for_each(each),
        };
        for &i in indices {
            each(&values[i as usize * n..(i as usize + 1) * n]);
        }
    }

    /// The number of tuples of a field attached as `at` with `len` values of `n` components.
    pub fn tuple_count(&self, len: usize, n: usize, at: Attachment) -> usize {
        match at {
            Attachment::Points => self.point_count(),
            Attachment::Cells => self.cell_count(),
            Attachment::None => len / n.max(1),
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

    /// `n` quadratic edges (VTK 21) along x, each sharing its last point with the next: edge
    /// k is (2k, 2k + 2, 2k + 1), point i at (i, 0).
    fn chain_of_edges(n: u64) -> Grid {
        let mut grid = Grid {
            points: (0..2 * n + 1).map(|i| [i as f64, 0.0]).collect(),
            ..Grid::default()
        };
        for k in 0..n {
            grid.push_cell(21, [2 * k, 2 * k + 2, 2 * k + 1]);
        }
        grid
    }

    /// Three edges in two parts, point 4 shared by both: each part's file gets
    /// its own cells and points in order of first use, and its arrays' tuples, read from
    /// the whole grid through the plan.
    #[test]
    fn a_part_holds_its_cells_points_and_arrays() {
        let mut grid = chain_of_edges(3);
        grid.point_data = vec![Field::new(
            "u",
            2,
            FieldValues::F64((0..14).map(f64::from).collect()),
        )];
        grid.cell_data = vec![Field::new("pair", 1, FieldValues::I32(vec![0, 1, 0]))];
        grid.field_data = vec![Field::strings("pair_names", vec!["a".into(), "b".into()])];
        let plan = grid.split_plan(&[0, 1, 0], 2);
        assert_eq!([plan.share(0), plan.share(1)], [2.0 / 3.0, 1.0 / 3.0]);
        let dir = tempfile::tempdir().unwrap();
        let written = |grid: &Grid, k: usize| {
            let path = dir.path().join(format!("part_{k}.vtu"));
            vtu::write_vtu_with(&path, GridView::part(grid, &plan, k), &mut Vec::new()).unwrap();
            vtu::read_vtu(&path).unwrap()
        };
        let [a, b] = [written(&grid, 0), written(&grid, 1)];
        assert_eq!(a.connectivity, [0, 1, 2, 3, 4, 5]);
        assert_eq!(a.offsets, [3, 6]);
        let xs = |g: &Grid| g.points.iter().map(|p| p[0]).collect::<Vec<_>>();
        assert_eq!(xs(&a), [0.0, 2.0, 1.0, 4.0, 6.0, 5.0]);
        assert_eq!(b.connectivity, [0, 1, 2]);
        assert_eq!(xs(&b), [2.0, 4.0, 3.0]);
        assert_eq!(
            b.point_data[0].values,
            FieldValues::F64(vec![4.0, 5.0, 8.0, 9.0, 6.0, 7.0])
        );
        assert_eq!(a.cell_data[0].values, FieldValues::I32(vec![0, 0]));
        assert_eq!(b.cell_data[0].values, FieldValues::I32(vec![1]));
        assert_eq!(a.field_data, grid.field_data);
        assert_eq!(a.cell_types, [21, 21]);
        // The plan made from this frame's grid divides the next frame's (the same cells,
        // other coordinates and values): part 1 holds its points' new values.
        let mut next = grid.clone();
        next.points.iter_mut().for_each(|p| p[1] = 1.0 + p[0]);
        next.point_data[0].values = FieldValues::F64((0..14).map(|i| f64::from(i) * 0.5).collect());
        assert!(next.fits(&plan));
        assert!(!Grid::default().fits(&plan));
        let path = dir.path().join("unfit.vtu");
        let empty = Grid::default();
        let other = GridView::part(&empty, &plan, 0);
        let err = vtu::write_vtu_with(&path, other, &mut Vec::new()).unwrap_err();
        assert!(err.to_string().contains("division into files"), "{err}");
        assert!(!path.exists());
        let b = written(&next, 1);
        assert_eq!(b.points, [[2.0, 3.0], [4.0, 5.0], [3.0, 4.0]]);
        assert_eq!(
            b.point_data[0].values,
            FieldValues::F64(vec![2.0, 2.5, 4.0, 4.5, 3.0, 3.5])
        );
        // The whole grid's file is the grid.
        let path = dir.path().join("whole.vtu");
        vtu::write_vtu(&path, &next).unwrap();
        assert_eq!(vtu::read_vtu(&path).unwrap(), next);
    }

    /// A non-finite value is named by its index in the part's file, and a value outside the
    /// part does not stop it.
    #[test]
    fn a_part_names_a_bad_value_by_its_index_in_the_file() {
        let mut grid = chain_of_edges(2);
        let mut values: Vec<f64> = (0..5).map(f64::from).collect();
        values[0] = f64::NAN;
        grid.point_data = vec![Field::scalar("p", values)];
        let plan = grid.split_plan(&[0, 1], 2);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("part.vtu");
        vtu::write_vtu_with(&path, GridView::part(&grid, &plan, 1), &mut Vec::new()).unwrap();
        grid.point_data[0].values = FieldValues::F64(vec![0.0, 1.0, 2.0, f64::INFINITY, 4.0]);
        let err = vtu::write_vtu_with(&path, GridView::part(&grid, &plan, 1), &mut Vec::new())
            .unwrap_err()
            .to_string();
        // Part 1's points are 2, 4, 3: the grid's point 3 is the file's point 2.
        assert!(
            err.contains("`p`") && err.contains("(point 2, component 0)"),
            "{err}"
        );
    }
}
