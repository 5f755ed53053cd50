//! An unsymmetric bulk (a yielding body with a non-associated or otherwise unsymmetric
//! tangent): LU of K_BB and S_c = K_II − K_IB K_BB⁻¹ K_BI by blocks of right-hand sides, for
//! [`super::CondensedSolver`].

use faer::reborrow::ReborrowMut;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Mat, MatMut, Par};

use crate::solver::linear::SparseLu;
use crate::{Error, Result};

use super::{CondensedSolver, SCHUR_BLOCK};

/// The structures of [`CondensedSolver::factor_bulk_unsymmetric`]: the bulk block K_BB (in
/// elimination order) and its LU, the couplings K_BI, K_IB and the block K_II as positions in
/// the continuum's value array, and the values factored last (for the change test).
pub(super) struct UnsymmetricBulk {
    /// The continuum pattern (of the values compared by the change test).
    pattern: SymbolicSparseColMat<u32>,
    bulk: SymbolicSparseColMat<u32>,
    bulk_values: Vec<f64>,
    bulk_source: Vec<u32>,
    lu: SparseLu,
    /// K_BI by interface column: `bi_ptr[k]..bi_ptr[k + 1]` index `bi_rows` (bulk positions)
    /// and `bi_source`.
    bi_ptr: Vec<usize>,
    bi_rows: Vec<u32>,
    bi_source: Vec<u32>,
    /// K_IB and K_II entries: (interface row, bulk position or interface column, position).
    ib: Vec<(u32, u32, u32)>,
    ii: Vec<(u32, u32, u32)>,
    factored_values: Vec<f64>,
    /// Right-hand sides of the S_c formation (n_B × [`SCHUR_BLOCK`]), also the bulk
    /// substitution's buffer of solves.
    block: Mat<f64>,
}

impl UnsymmetricBulk {
    /// The first half of a solve: x_I ← x_I − K_IB K_BB⁻¹ x_B (x_B itself is left as it is,
    /// for [`Self::back_substitute`]).
    pub(super) fn eliminate_bulk(&mut self, x_b: &[f64], x_i: &mut [f64]) {
        let mut z = self.block.as_mut().subcols_mut(0, 1);
        z.rb_mut()
            .col_mut(0)
            .copy_from(faer::ColRef::from_slice(x_b));
        self.lu.solve_in_place(z.rb_mut(), Par::Seq);
        for &(i, b, p) in &self.ib {
            x_i[i as usize] -= self.factored_values[p as usize] * z[(b as usize, 0)];
        }
    }

    /// The second half: x_B ← K_BB⁻¹ (x_B − K_BI x_I).
    pub(super) fn back_substitute(&mut self, x_b: &mut [f64], x_i: &[f64]) {
        let values = &self.factored_values;
        for (k, &xk) in x_i.iter().enumerate() {
            let range = self.bi_ptr[k]..self.bi_ptr[k + 1];
            for (&row, &p) in self.bi_rows[range.clone()]
                .iter()
                .zip(&self.bi_source[range])
            {
                x_b[row as usize] -= values[p as usize] * xk;
            }
        }
        let n_bulk = x_b.len();
        self.lu.solve_in_place(
            MatMut::from_column_major_slice_mut(x_b, n_bulk, 1),
            Par::Seq,
        );
    }
}

impl CondensedSolver {
    /// [`Self::change_from_factored`] over both triangles, against the last matrix factored
    /// by [`Self::factor_bulk_unsymmetric`].
    pub(super) fn change_from_factored_lu(&self, values: &[f64]) -> f64 {
        let u = self.unsymmetric.as_ref().expect("LU made");
        let factored = &u.factored_values;
        let scale = |eq: usize| self.inverse_scale[self.position[eq] as usize];
        let (col_ptr, row_idx) = (u.pattern.col_ptr(), u.pattern.row_idx());
        let mut largest = 0.0f64;
        for col in 0..self.n {
            for k in col_ptr[col] as usize..col_ptr[col + 1] as usize {
                let difference = (values[k] - factored[k]).abs();
                if difference == 0.0 {
                    continue;
                }
                let relative = difference * scale(row_idx[k] as usize) * scale(col);
                if !relative.is_finite() {
                    return f64::INFINITY;
                }
                largest = largest.max(relative);
            }
        }
        largest
    }

    /// [`Self::factor_bulk`] for an unsymmetric continuum matrix (both triangles read): LU
    /// of K_BB and S_c = K_II − K_IB K_BB⁻¹ K_BI (module docs). The factorisation is kept
    /// under the same rule as [`Self::factor_bulk`]'s, for a matrix last factored by this
    /// method. Returns whether it factored.
    pub fn factor_bulk_unsymmetric(
        &mut self,
        continuum: SparseColMatRef<'_, u32, f64>,
    ) -> Result<bool> {
        if self.unsymmetric.is_none() {
            self.unsymmetric = Some(Box::new(self.unsymmetric_structures(continuum.symbolic())?));
        }
        self.varying_known = false;
        if self.keeps_factor(continuum, true)? {
            return Ok(false);
        }
        self.factored_varying_known = false;
        self.factored = false;
        self.interface_factored = false;
        self.lu_bulk = true;
        let values = continuum.val();
        for (d, &slot) in self.inverse_scale.iter_mut().zip(&self.diagonal) {
            *d = values[self.source[slot as usize] as usize]
                .abs()
                .sqrt()
                .recip();
        }
        let u = self.unsymmetric.as_deref_mut().expect("made above");
        u.factored_values.copy_from_slice(values);
        for (v, &p) in u.bulk_values.iter_mut().zip(&u.bulk_source) {
            *v = values[p as usize];
        }
        u.lu
            .factorize(SparseColMatRef::new(u.bulk.as_ref(), &u.bulk_values), self.par)
            .map_err(|_| {
                Error::Linear(
                    "the bodies' stiffness with the interface unknowns held is singular: a body is neither \
                     supported nor in contact, or the bulk tangent lost definiteness"
                        .into(),
                )
            })?;
        let n_i = self.interface.len();
        if self.schur.nrows() != n_i {
            self.schur = Mat::zeros(n_i, n_i);
        }
        let schur = &mut self.schur;
        schur.fill(0.0);
        for &(i, j, p) in &u.ii {
            schur[(i as usize, j as usize)] += values[p as usize];
        }
        for first in (0..n_i).step_by(SCHUR_BLOCK) {
            let width = SCHUR_BLOCK.min(n_i - first);
            let mut y = u.block.as_mut().subcols_mut(0, width);
            y.fill(0.0);
            for c in 0..width {
                let range = u.bi_ptr[first + c]..u.bi_ptr[first + c + 1];
                for (&row, &p) in u.bi_rows[range.clone()].iter().zip(&u.bi_source[range]) {
                    y[(row as usize, c)] = values[p as usize];
                }
            }
            u.lu.solve_in_place(y.rb_mut(), self.par);
            for &(i, b, p) in &u.ib {
                let v = values[p as usize];
                for c in 0..width {
                    schur[(i as usize, first + c)] -= v * y[(b as usize, c)];
                }
            }
        }
        self.shift.fill(0.0);
        self.dense.analyse(self.schur.as_ref());
        self.factored = true;
        self.factorizations += 1;
        Ok(true)
    }

    /// The structures of the LU path for the continuum pattern `pattern` (the one given to
    /// [`Self::new`]).
    fn unsymmetric_structures(
        &self,
        pattern: SymbolicSparseColMatRef<'_, u32>,
    ) -> Result<UnsymmetricBulk> {
        let (n_bulk, n_i) = (self.n_bulk, self.interface.len());
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        let entries = |j: usize| (cp[j] as usize..cp[j + 1] as usize).map(|p| (ri[p] as usize, p));
        // K_BB in elimination order, columns sorted.
        let mut col_ptr = Vec::with_capacity(n_bulk + 1);
        col_ptr.push(0u32);
        let (mut rows, mut bulk_source) = (Vec::new(), Vec::new());
        let mut column: Vec<(u32, u32)> = Vec::new();
        for &old in &self.order[..n_bulk] {
            column.clear();
            column.extend(
                entries(old as usize)
                    .map(|(i, p)| (self.position[i], p as u32))
                    .filter(|&(row, _)| (row as usize) < n_bulk),
            );
            column.sort_unstable();
            rows.extend(column.iter().map(|&(row, _)| row));
            bulk_source.extend(column.iter().map(|&(_, p)| p));
            col_ptr.push(rows.len() as u32);
        }
        let bulk = SymbolicSparseColMat::new_checked(n_bulk, n_bulk, col_ptr, None, rows);
        let lu = SparseLu::new(bulk.as_ref(), SCHUR_BLOCK, self.par)?;
        let mut bi_ptr = vec![0usize];
        let (mut bi_rows, mut bi_source, mut ii) = (Vec::new(), Vec::new(), Vec::new());
        for (k, &eq) in self.interface.iter().enumerate() {
            for (i, p) in entries(eq) {
                match self.local_index(i) {
                    Some(ki) => ii.push((ki as u32, k as u32, p as u32)),
                    None => {
                        bi_rows.push(self.position[i]);
                        bi_source.push(p as u32);
                    }
                }
            }
            bi_ptr.push(bi_rows.len());
        }
        let mut ib = Vec::new();
        for &old in &self.order[..n_bulk] {
            for (i, p) in entries(old as usize) {
                if let Some(ki) = self.local_index(i) {
                    ib.push((ki as u32, self.position[old as usize], p as u32));
                }
            }
        }
        Ok(UnsymmetricBulk {
            bulk_values: vec![0.0; bulk_source.len()],
            bulk,
            bulk_source,
            lu,
            bi_ptr,
            bi_rows,
            bi_source,
            ib,
            ii,
            factored_values: vec![0.0; ri.len()],
            block: Mat::zeros(n_bulk, SCHUR_BLOCK.min(n_i).max(1)),
            pattern: pattern.to_owned().map_err(|e| {
                crate::solver::faer_error(e, "a copy of the bulk pattern", n_bulk + n_i)
            })?,
        })
    }
}
