//! Sparse symmetric positive-definite solves with faer's supernodal Cholesky.
//!
//! The fill-reducing ordering and symbolic factorisation are computed once per sparsity
//! pattern ([`CholeskySolver::new`]); every Newton iteration then only refactors numerically
//! into the same factor storage with the same workspace ([`CholeskySolver::factorize`]).
//! faer's high-level API would allocate a fresh workspace on every call (about 1.3 GB at a
//! million unknowns, see DESIGN.md), so the low-level API is used with a buffer kept here.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::{Conj, MatMut, Par, Side};

use crate::assembly::SparsityPattern;
use crate::{Error, Result};

/// Cholesky factorisation of matrices sharing one sparsity pattern.
pub struct CholeskySolver {
    symbolic: SymbolicCholesky<u32>,
    factor: Vec<f64>,
    workspace: MemBuffer,
    par: Par,
    factorized: bool,
}

impl std::fmt::Debug for CholeskySolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CholeskySolver")
            .field("n", &self.symbolic.nrows())
            .field("factor_nnz", &self.factor.len())
            .finish()
    }
}

impl CholeskySolver {
    /// Orders (AMD) and symbolically factors the lower triangle of `pattern`, and allocates
    /// the factor and the workspace for numeric factorisation and solves.
    pub fn new(pattern: &SparsityPattern) -> Result<Self> {
        let symbolic = factorize_symbolic_cholesky(
            pattern.symbolic().as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .map_err(|e| Error::Linear(format!("symbolic Cholesky factorisation failed: {e:?}")))?;
        let par = Par::rayon(0);
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, par),
        ]);
        let workspace = MemBuffer::try_new(req)
            .map_err(|_| Error::Linear("out of memory for the factorisation workspace".into()))?;
        let factor = vec![0.0; symbolic.len_val()];
        Ok(Self {
            symbolic,
            factor,
            workspace,
            par,
            factorized: false,
        })
    }

    /// Number of stored entries of the Cholesky factor (a measure of fill-in).
    pub fn factor_nnz(&self) -> usize {
        self.factor.len()
    }

    /// Numeric factorisation of `matrix` (lower triangle read), reusing storage. Fails with a
    /// clear message if the matrix is not positive definite, which for a linear-elastic model
    /// means a body is not held against rigid-body motion.
    pub fn factorize(&mut self, matrix: SparseColMatRef<'_, u32, f64>) -> Result<()> {
        self.factorized = false;
        let stack = MemStack::new(&mut self.workspace);
        self.symbolic
            .factorize_numeric_llt(
                &mut self.factor,
                matrix,
                Side::Lower,
                LltRegularization::default(),
                self.par,
                stack,
                Default::default(),
            )
            .map_err(|_| {
                Error::Linear(
                    "the stiffness matrix is not positive definite: a body is not supported against rigid-body \
                     motion (check the supports), or the tangent lost definiteness"
                        .into(),
                )
            })?;
        self.factorized = true;
        Ok(())
    }

    /// Solves `A x = rhs` in place with the last factorisation.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) {
        assert!(self.factorized, "solve before factorize");
        let n = rhs.len();
        let stack = MemStack::new(&mut self.workspace);
        let rhs = MatMut::from_column_major_slice_mut(rhs, n, 1);
        LltRef::new(&self.symbolic, &self.factor).solve_in_place_with_conj(
            Conj::No,
            rhs,
            self.par,
            stack,
        );
    }
}
