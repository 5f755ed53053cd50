//! Sparse symmetric positive-definite solves with faer's supernodal Cholesky.
//!
//! The fill-reducing ordering and symbolic factorisation are computed once per sparsity
//! pattern, by the first [`CholeskySolver::factorize`] (not by [`CholeskySolver::new`]: a
//! contact model solved by the condensed solver never factors the whole pattern, and at a
//! million unknowns the unused analysis cost seconds and the factor storage hundreds of
//! megabytes); every later factorisation only refactors numerically into the same factor
//! storage with the same workspace.
//! faer's high-level API would allocate a fresh workspace on every call (about 1.3 GB at a
//! million unknowns, measured), so the low-level API is used with a buffer kept here.
//!
//! Friction makes the tangent unsymmetric (Buczkowski & Kleiber (1994), Eq. 21). faer's
//! sparse LU fills badly on FE matrices (its ordering needed 4.3 GB at 200k unknowns,
//! measured), so the unsymmetric path keeps the Cholesky machinery: it factors a symmetric
//! positive-definite approximation of the tangent with the same symbolic factorisation and
//! uses it as the preconditioner of BiCGSTAB on the true tangent. The approximation is the
//! tangent with the elastic contact matrix (Buczkowski & Kleiber (1994), conclusion 3); the
//! symmetric part ½(K + Kᵀ) would not do, since at a slipping point it is indefinite. The
//! two differ only at slipping interface points, so few Krylov iterations are needed.
//!
//! Every workspace is kept between calls: the numeric factorisation, the solves and BiCGSTAB
//! allocate nothing once the first unsymmetric solve has sized the Krylov workspace.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::matrix_free::bicgstab::{BicgParams, bicgstab, bicgstab_scratch};
use faer::matrix_free::{IdentityPrecond, InitialGuessStatus, LinOp, Precond};
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Mat, MatMut, MatRef, Par, Side};

use crate::assembly::SparsityPattern;
use crate::{Error, Result};

/// Cholesky factorisation of matrices sharing one sparsity pattern.
pub struct CholeskySolver {
    /// Size of the pattern the solver was made for.
    n: usize,
    /// Symbolic factorisation, factor storage and workspace, made by the first factorisation.
    analysis: Option<Analysis>,
    /// BiCGSTAB's workspace, made by the first unsymmetric solve: runs whose tangent stays
    /// symmetric (no slipping point) never pay for it.
    krylov: Option<KrylovWorkspace>,
    par: Par,
    factorized: bool,
    symbolic_seconds: f64,
}

/// The pattern-dependent part of the solver: ordering and symbolic factorisation, the numeric
/// factor's storage and the workspace of factorisations and solves.
struct Analysis {
    symbolic: SymbolicCholesky<u32>,
    factor: Vec<f64>,
    workspace: MemBuffer,
}

impl Analysis {
    /// Orders (AMD) and symbolically factors the lower triangle of `pattern`, and allocates
    /// the factor and the workspace for numeric factorisation and solves.
    fn new(pattern: SymbolicSparseColMatRef<'_, u32>, par: Par) -> Result<Self> {
        let symbolic = factorize_symbolic_cholesky(
            pattern,
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .map_err(|e| Error::Linear(format!("symbolic Cholesky factorisation failed: {e:?}")))?;
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
        })
    }
}

/// Scratch memory of BiCGSTAB (sized for its requirement `req`) and its solution vector.
struct KrylovWorkspace {
    req: StackReq,
    buffer: MemBuffer,
    x: Mat<f64>,
}

impl std::fmt::Debug for CholeskySolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CholeskySolver")
            .field("n", &self.n)
            .field("factor_nnz", &self.factor_nnz())
            .finish()
    }
}

impl CholeskySolver {
    /// A solver for matrices with the pattern `pattern`. The ordering, the symbolic
    /// factorisation and the storage are made by the first [`Self::factorize`].
    pub fn new(pattern: &SparsityPattern) -> Result<Self> {
        Ok(Self {
            n: pattern.size(),
            analysis: None,
            krylov: None,
            par: Par::rayon(0),
            factorized: false,
            symbolic_seconds: 0.0,
        })
    }

    /// Seconds the ordering, symbolic factorisation and allocation took (0 before the first
    /// factorisation, which makes them).
    pub fn symbolic_seconds(&self) -> f64 {
        self.symbolic_seconds
    }

    /// Number of stored entries of the Cholesky factor (a measure of fill-in; 0 before the
    /// first factorisation).
    pub fn factor_nnz(&self) -> usize {
        self.analysis.as_ref().map_or(0, |a| a.factor.len())
    }

    /// Numeric factorisation of `matrix` (lower triangle read), reusing storage. Fails with a
    /// clear message if the matrix is not positive definite, which for a linear-elastic model
    /// means a body is not held against rigid-body motion.
    pub fn factorize(&mut self, matrix: SparseColMatRef<'_, u32, f64>) -> Result<()> {
        self.factorized = false;
        if matrix.nrows() != self.n || matrix.ncols() != self.n {
            return Err(Error::Linear(format!(
                "a {}×{} matrix given to the Cholesky solver of {} unknowns",
                matrix.nrows(),
                matrix.ncols(),
                self.n
            )));
        }
        if self.analysis.is_none() {
            let t = std::time::Instant::now();
            self.analysis = Some(Analysis::new(matrix.symbolic(), self.par)?);
            self.symbolic_seconds = t.elapsed().as_secs_f64();
        }
        let Analysis {
            symbolic,
            factor,
            workspace,
        } = self.analysis.as_mut().expect("made above");
        let stack = MemStack::new(workspace);
        symbolic
            .factorize_numeric_llt(
                factor,
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
                     motion (check the supports), or the tangent lost definiteness (in a plastic model: a plastic \
                     collapse mechanism, the load exceeding the limit load)"
                        .into(),
                )
            })?;
        self.factorized = true;
        Ok(())
    }

    /// Solves `A x = rhs` in place for an unsymmetric `matrix` (full pattern stored): factors
    /// the symmetric positive-definite `preconditioner` (same pattern) and runs BiCGSTAB on
    /// `matrix` preconditioned by it, to the relative residual `tolerance`. Returns the number
    /// of Krylov iterations.
    pub fn solve_unsymmetric(
        &mut self,
        matrix: SparseColMatRef<'_, u32, f64>,
        preconditioner: SparseColMatRef<'_, u32, f64>,
        rhs: &mut [f64],
        tolerance: f64,
    ) -> Result<usize> {
        self.factorize(preconditioner)?;
        let n = rhs.len();
        let analysis = self.analysis.as_ref().expect("factorised above");
        let precond = CholeskyPreconditioner {
            llt: LltRef::new(&analysis.symbolic, &analysis.factor),
            n,
        };
        let identity = IdentityPrecond { dim: n };
        let req = bicgstab_scratch(identity, precond, matrix, 1, self.par);
        // The requirement depends only on the pattern, so this allocates once per solver.
        if self
            .krylov
            .as_ref()
            .is_none_or(|k| k.req != req || k.x.nrows() != n)
        {
            let buffer = MemBuffer::try_new(req)
                .map_err(|_| Error::Linear("out of memory for the Krylov workspace".into()))?;
            let x = Mat::<f64>::zeros(n, 1);
            self.krylov = Some(KrylovWorkspace { req, buffer, x });
        }
        let KrylovWorkspace { buffer, x, .. } = self.krylov.as_mut().expect("made above");
        x.fill(0.0);
        let b = MatRef::from_column_major_slice(rhs, n, 1);
        let params = BicgParams {
            // `Zero` would be right, but faer 0.24's BiCGSTAB then leaves its residual vector
            // uninitialised; with `MaybeNonZero` it computes r = b − A·0 itself.
            initial_guess: InitialGuessStatus::MaybeNonZero,
            abs_tolerance: 0.0,
            rel_tolerance: tolerance,
            max_iters: 1000,
            ..Default::default()
        };
        let info = bicgstab(
            x.as_mut(),
            identity,
            precond,
            matrix,
            b,
            params,
            |_| {},
            self.par,
            MemStack::new(buffer),
        )
        .map_err(|e| {
            Error::Linear(format!(
                "BiCGSTAB on the unsymmetric tangent did not converge: {e:?}"
            ))
        })?;
        rhs.copy_from_slice(x.col(0).try_as_col_major().expect("contiguous").as_slice());
        Ok(info.iter_count)
    }

    /// Solves `A x = rhs` in place with the last factorisation.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) {
        assert!(self.factorized, "solve before factorize");
        let n = rhs.len();
        let Analysis {
            symbolic,
            factor,
            workspace,
        } = self.analysis.as_mut().expect("factorised");
        let stack = MemStack::new(workspace);
        let rhs = MatMut::from_column_major_slice_mut(rhs, n, 1);
        LltRef::new(symbolic, factor).solve_in_place_with_conj(Conj::No, rhs, self.par, stack);
    }
}

/// A Cholesky factor applied as a preconditioner.
#[derive(Clone, Copy, Debug)]
struct CholeskyPreconditioner<'a> {
    llt: LltRef<'a, u32, f64>,
    n: usize,
}

impl LinOp<f64> for CholeskyPreconditioner<'_> {
    fn apply_scratch(&self, rhs_ncols: usize, par: Par) -> StackReq {
        self.llt
            .symbolic()
            .solve_in_place_scratch::<f64>(rhs_ncols, par)
    }

    fn nrows(&self) -> usize {
        self.n
    }

    fn ncols(&self) -> usize {
        self.n
    }

    fn apply(
        &self,
        mut out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        par: Par,
        stack: &mut MemStack,
    ) {
        out.copy_from(rhs);
        self.llt.solve_in_place_with_conj(Conj::No, out, par, stack);
    }

    fn conj_apply(
        &self,
        out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        par: Par,
        stack: &mut MemStack,
    ) {
        self.apply(out, rhs, par, stack);
    }
}

impl Precond<f64> for CholeskyPreconditioner<'_> {}
