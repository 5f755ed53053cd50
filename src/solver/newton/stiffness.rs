//! A linear bulk's stiffness over all dofs, kept for K·u without a second matrix: the free
//! dofs' block is the Newton system's own matrix (the one the bulk factorisation was made
//! from, which a linear bulk never changes), and only the entries in a prescribed dof's row
//! or column are stored here. At a million unknowns a second all-dof matrix cost 360 MB
//! (values and pattern); these entries are those of the supports' nodes.

use crate::assembly::{DofMap, GlobalSystem, SparsityPattern};

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
}

impl BulkStiffness {
    /// Keeps the entries of `all` (assembled over every dof, numbered by dof) that lie in a
    /// row or column prescribed in `dofs`.
    pub(super) fn new(all: &GlobalSystem, dofs: &DofMap) -> Self {
        let symbolic = all.pattern.symbolic();
        let (cp, ri) = (symbolic.col_ptr(), symbolic.row_idx());
        let n = dofs.dof_count();
        let mut start = Vec::with_capacity(n + 1);
        start.push(0u32);
        let (mut rows, mut values) = (Vec::new(), Vec::new());
        let mut dof_of = vec![0u32; dofs.free_count()];
        for j in 0..n {
            let column = cp[j] as usize..cp[j + 1] as usize;
            let free_column = dofs.equation(j);
            for (&i, &v) in ri[column.clone()].iter().zip(&all.values[column]) {
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
        Self {
            start,
            rows,
            values,
            dof_of,
        }
    }

    /// y = K_c x over all dofs, the free block K_ff having the values `values` over
    /// `pattern` (the free dofs of `dofs`; entries K_c lacks are zero there). Column by
    /// column in dof order, as a product with the whole all-dof matrix would sum, so each
    /// y_i is that product's bit for bit.
    pub(super) fn multiply(
        &self,
        pattern: &SparsityPattern,
        values: &[f64],
        dofs: &DofMap,
        x: &[f64],
        y: &mut [f64],
    ) {
        y.fill(0.0);
        let symbolic = pattern.symbolic();
        let (cp, ri) = (symbolic.col_ptr(), symbolic.row_idx());
        for (j, &xj) in x.iter().enumerate() {
            if xj == 0.0 {
                continue;
            }
            if let Some(eq) = dofs.equation(j) {
                let column = cp[eq] as usize..cp[eq + 1] as usize;
                for (&i, &v) in ri[column.clone()].iter().zip(&values[column]) {
                    y[self.dof_of[i as usize] as usize] += v * xj;
                }
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

    /// A chain of 3-node "elements" over 7 nodes (2 dofs each) with arbitrary values, nodes
    /// 0 and 4 partly held: the split product equals the whole matrix's product bit for bit.
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
        for (k, v) in whole.values.iter_mut().enumerate() {
            *v = (1.0 + k as f64).sqrt().sin() * 1e3;
        }
        // The free pattern couples nodes 1 and 6 too (an interface would), which K_c lacks.
        let far: [u32; 2] = [1, 6];
        let pattern = SparsityPattern::new(node_count, &dofs, cells.chain([&far[..]]));
        let mut free = GlobalSystem::new(pattern, 14);
        free.restrict_from(&whole, &dofs);
        let stiffness = BulkStiffness::new(&whole, &dofs);
        // Prescribed columns: node 0's two (nodes 0–2: 6 rows each), node 4's y (nodes 2–6:
        // 10 rows); prescribed rows in free columns: node 0's two rows in the 4 free columns
        // of nodes 1 and 2, node 4's y row in the 9 other columns of nodes 2–6.
        assert_eq!(stiffness.len(), (6 + 6 + 10) + 2 * 4 + 9);
        let x: Vec<f64> = (0..14).map(|k| (k as f64 * 0.37).cos()).collect();
        let symbolic = whole.pattern.symbolic();
        let mut expected = vec![0.0; 14];
        for (j, &xj) in x.iter().enumerate() {
            for k in symbolic.col_ptr()[j] as usize..symbolic.col_ptr()[j + 1] as usize {
                expected[symbolic.row_idx()[k] as usize] += whole.values[k] * xj;
            }
        }
        let mut y = vec![f64::NAN; 14];
        stiffness.multiply(&free.pattern, &free.values, &dofs, &x, &mut y);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&y), bits(&expected));
    }
}
