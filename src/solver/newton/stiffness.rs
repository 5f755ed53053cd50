//! A linear bulk's stiffness over all dofs, kept for K·u without a second matrix: the free
//! dofs' block is the Newton system's own matrix (the one the bulk factorisation was made
//! from, which a linear bulk never changes), and only the entries in a prescribed dof's row
//! or column are stored here. At a million unknowns a second all-dof matrix cost 360 MB
//! (values and pattern); these entries are those of the supports' nodes, assembled with the
//! free block in its one element loop from the cells at the supports alone
//! ([`crate::assembly::PrescribedCouplings`]; at 3.8 M unknowns an all-dof pattern and
//! matrix assembled only to be copied from cost 3 s and 1.4 GB of fresh pages).
//!
//! K_c is symmetric (a linear bulk is elastic), so a column of the free block is also its row:
//! each y_j is one column's dot product with x, the columns split between the cores with
//! no two writing the same y_j. Every y_j is summed in one order whatever the number of
//! threads, so the product has the same bits on any of them. (Element matrices are
//! symmetric up to rounding only, so this is K_cᵀ u, equal to K_c u within rounding.)

use faer::sparse::SparseColMatRef;

use crate::assembly::{DofMap, SparsityPattern, symmetric_product};

/// The entries of the bulk stiffness K_c (over all dofs) in a prescribed row or column, by
/// column, and the dof of each equation.
#[derive(Debug)]
pub(super) struct BulkStiffness {
    /// Column (dof) j's entries are `rows[start[j]..start[j + 1]]` (dofs) and `values[..]`.
    start: Vec<u32>,
    rows: Vec<u32>,
    values: Vec<f64>,
    /// The dof of each equation.
    dof_of: Vec<u32>,
    /// Workspaces over the free equations: x gathered, the free block's product.
    x_free: Vec<f64>,
    y_free: Vec<f64>,
}

impl BulkStiffness {
    /// Keeps the entries of `all` (a matrix over every dof, numbered by dof, holding at least
    /// K_c's entries in prescribed rows and columns) that lie in a row or column prescribed
    /// in `dofs`.
    pub(super) fn new(all: SparseColMatRef<'_, u32, f64>, dofs: &DofMap) -> Self {
        let (cp, ri, all_values) = (all.col_ptr(), all.row_idx(), all.val());
        let n = dofs.dof_count();
        let mut start = Vec::with_capacity(n + 1);
        start.push(0u32);
        let (mut rows, mut values) = (Vec::new(), Vec::new());
        let mut dof_of = vec![0u32; dofs.free_count()];
        for j in 0..n {
            let column = cp[j] as usize..cp[j + 1] as usize;
            let free_column = dofs.equation(j);
            for (&i, &v) in ri[column.clone()].iter().zip(&all_values[column]) {
                if free_column.is_none() || dofs.equation(i as usize).is_none() {
                    rows.push(i);
                    values.push(v);
                }
            }
            if let Some(eq) = free_column {
                dof_of[eq] = j as u32;
            }
            start.push(rows.len() as u32);
        }
        let free = dof_of.len();
        Self {
            start,
            rows,
            values,
            dof_of,
            x_free: vec![0.0; free],
            y_free: vec![0.0; free],
        }
    }

    /// y = K_c x over all dofs, the free block K_ff having the values `values` over
    /// `pattern` (the free dofs of `dofs`; entries K_c lacks are zero there). Free rows: the free
    /// block's columns read as rows, in parallel (see the module's note); then the stored
    /// prescribed rows and columns, column by column in dof order.
    pub(super) fn multiply(
        &mut self,
        pattern: &SparsityPattern,
        values: &[f64],
        dofs: &DofMap,
        x: &[f64],
        y: &mut [f64],
    ) {
        dofs.gather_free(x, &mut self.x_free);
        symmetric_product(pattern, values, &self.x_free, &mut self.y_free);
        y.fill(0.0);
        for (&yf, &dof) in self.y_free.iter().zip(&self.dof_of) {
            y[dof as usize] = yf;
        }
        for (j, &xj) in x.iter().enumerate() {
            if xj == 0.0 {
                continue;
            }
            let column = self.start[j] as usize..self.start[j + 1] as usize;
            for (&i, &v) in self.rows[column.clone()].iter().zip(&self.values[column]) {
                y[i as usize] += v * xj;
            }
        }
    }

    /// Stored entries (those in a prescribed row or column).
    pub(super) fn len(&self) -> usize {
        self.values.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::GlobalSystem;

    /// A chain of 3-node "elements" over 7 nodes (2 dofs each) with arbitrary symmetric
    /// values, nodes 0 and 4 partly held: the split product (the free block's columns as
    /// rows, the prescribed rows and columns) equals the whole matrix's product to rounding.
    #[test]
    fn the_split_product_is_the_all_dof_product() {
        let elements: [[u32; 3]; 3] = [[0, 1, 2], [2, 3, 4], [4, 5, 6]];
        let node_count = 7;
        let mut fixed = vec![false; 2 * node_count];
        fixed[0] = true; // node 0, x
        fixed[1] = true; // node 0, y
        fixed[9] = true; // node 4, y
        let dofs = DofMap::new(&fixed);
        let all = DofMap::new(&vec![false; fixed.len()]);
        let cells = elements.iter().map(|e| &e[..]);
        let mut whole =
            GlobalSystem::new(SparsityPattern::new(node_count, &all, cells.clone()), 14);
        let symbolic = whole.pattern.symbolic().clone();
        for j in 0..14 {
            for k in symbolic.col_ptr()[j] as usize..symbolic.col_ptr()[j + 1] as usize {
                let i = symbolic.row_idx()[k] as usize;
                let (a, b) = (i.min(j), i.max(j));
                whole.values[k] = (1.0 + (14 * a + b) as f64).sqrt().sin() * 1e3;
            }
        }
        // The free pattern couples nodes 1 and 6 too (an interface would), which K_c lacks.
        let far: [u32; 2] = [1, 6];
        let pattern = SparsityPattern::new(node_count, &dofs, cells.chain([&far[..]]));
        // The free block: K_c's values between free dofs, zero at the far coupling.
        let mut free = GlobalSystem::new(pattern, 14);
        let dof_of: Vec<usize> = (0..14).filter(|&k| !fixed[k]).collect();
        let free_symbolic = free.pattern.symbolic().clone();
        for eq in 0..dof_of.len() {
            let column =
                free_symbolic.col_ptr()[eq] as usize..free_symbolic.col_ptr()[eq + 1] as usize;
            for k in column {
                let (i, j) = (dof_of[free_symbolic.row_idx()[k] as usize], dof_of[eq]);
                let in_whole = symbolic.row_idx()
                    [symbolic.col_ptr()[j] as usize..symbolic.col_ptr()[j + 1] as usize]
                    .iter()
                    .position(|&r| r as usize == i);
                free.values[k] =
                    in_whole.map_or(0.0, |p| whole.values[symbolic.col_ptr()[j] as usize + p]);
            }
        }
        let mut stiffness = BulkStiffness::new(whole.matrix(), &dofs);
        // Prescribed columns: node 0's two (nodes 0–2: 6 rows each), node 4's y (nodes 2–6:
        // 10 rows); prescribed rows in free columns: node 0's two rows in the 4 free columns
        // of nodes 1 and 2, node 4's y row in the 9 other columns of nodes 2–6.
        assert_eq!(stiffness.len(), (6 + 6 + 10) + 2 * 4 + 9);
        let x: Vec<f64> = (0..14).map(|k| (k as f64 * 0.37).cos()).collect();
        let mut expected = vec![0.0; 14];
        for (j, &xj) in x.iter().enumerate() {
            for k in symbolic.col_ptr()[j] as usize..symbolic.col_ptr()[j + 1] as usize {
                expected[symbolic.row_idx()[k] as usize] += whole.values[k] * xj;
            }
        }
        let mut y = vec![f64::NAN; 14];
        stiffness.multiply(&free.pattern, &free.values, &dofs, &x, &mut y);
        // Summed in another order: equal within a few roundings of the largest term (entries
        // up to 1e3, x up to 1, at most 10 terms a row).
        for (a, b) in y.iter().zip(&expected) {
            assert!((a - b).abs() <= 1e4 * f64::EPSILON, "{a} against {b}");
        }
    }
}
