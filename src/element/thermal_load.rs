//! The thermal load of linear bodies as a linear operator of the nodal temperature changes.
//!
//! A linear body's internal force under a temperature field is f = K u − G ΔT (the thermal
//! strain α ΔT m is interpolated from the nodal ΔT by the shape functions and subtracted
//! from the strain before the material sees it: [`thermal_load_matrix`]). With K assembled
//! and factored once, a new temperature field (each increment of a prescribed one, each
//! exchange of a thermally coupled one) then costs one small product per cell instead of an
//! element loop.

use std::collections::TryReserveError;

use rayon::prelude::*;

use super::MAX_ELEMENT_NODES;
use super::continuum::thermal_load_matrix;
use super::set::{ContinuumSet, TemperatureField};

/// Cells per task when the matrices are made (any split gives the same matrices).
const CELLS_PER_TASK: usize = 1024;

/// The thermal load matrices G of the cells of the expanding bodies (α ≠ 0) of a continuum
/// whose materials are linear.
#[derive(Debug)]
pub struct ThermalLoad {
    /// The cells (indices into [`ContinuumSet::cells`]).
    cells: Vec<u32>,
    /// Their G, one after the other, row-major: `rows` rows (the element vector's dofs) of
    /// [`MAX_ELEMENT_NODES`] columns.
    matrices: Vec<f64>,
    rows: usize,
}

impl ThermalLoad {
    /// The thermal load of `set`'s expanding bodies (`None` when no body expands); every
    /// material must be linear ([`ContinuumSet::is_linear`]). Fails only when the matrices'
    /// memory cannot be had.
    pub fn new(set: &ContinuumSet) -> Result<Option<Self>, TryReserveError> {
        let expands = |e: &u32| set.expansions[set.cells[*e as usize].body as usize] != 0.0;
        let cells: Vec<u32> = (0..set.cells.len() as u32).filter(expands).collect();
        if cells.is_empty() {
            return Ok(None);
        }
        let rows = MAX_ELEMENT_NODES * set.analysis.dofs_per_node();
        let size = rows * MAX_ELEMENT_NODES;
        let mut matrices = Vec::new();
        matrices.try_reserve_exact(cells.len() * size)?;
        matrices.resize(cells.len() * size, 0.0);
        matrices
            .par_chunks_mut(size)
            .zip(cells.par_iter())
            .with_min_len(CELLS_PER_TASK)
            .for_each(|(m, &e)| {
                let c = &set.cells[e as usize];
                let body = c.body as usize;
                let g = thermal_load_matrix(
                    &set.analysis,
                    c.kind,
                    &c.coords,
                    set.formulations[body],
                    set.materials[body].as_ref(),
                    set.expansions[body],
                );
                for (r, row) in m.chunks_exact_mut(MAX_ELEMENT_NODES).enumerate() {
                    for (j, v) in row.iter_mut().enumerate() {
                        *v = g[(r, j)];
                    }
                }
            });
        Ok(Some(Self {
            cells,
            matrices,
            rows,
        }))
    }

    /// The nodal forces G ΔT of the temperature changes `field` over all dofs (node-major,
    /// `set`'s dofs per node) into `out` (overwritten): what the thermal strains take off
    /// K u. One pass in cell order, on one thread: the same sums on any number of threads.
    pub fn force(&self, set: &ContinuumSet, field: &TemperatureField, out: &mut [f64]) {
        out.fill(0.0);
        let d = set.analysis.dofs_per_node();
        let size = self.rows * MAX_ELEMENT_NODES;
        for (&e, g) in self.cells.iter().zip(self.matrices.chunks_exact(size)) {
            let cell = &set.cells[e as usize];
            let Some(dt) = field.cell(cell) else {
                continue;
            };
            let rows = g.chunks_exact(MAX_ELEMENT_NODES);
            let dofs = cell.nodes[..cell.kind.node_count()]
                .iter()
                .flat_map(|&node| (0..d).map(move |c| d * node as usize + c));
            for (dof, row) in dofs.zip(rows) {
                out[dof] += row.iter().zip(&dt).map(|(a, b)| a * b).sum::<f64>();
            }
        }
    }

    /// Bytes of the matrices.
    pub fn memory_bytes(&self) -> usize {
        self.matrices.len() * std::mem::size_of::<f64>() + self.cells.len() * 4
    }
}
