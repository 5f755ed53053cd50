//! Sparse solves of the bodies' tangent: faer's supernodal Cholesky for symmetric positive-
//! definite matrices, faer's supernodal LU for an unsymmetric bulk.
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
//! # An unsymmetric bulk
//! Kinematic hardening with dynamic recovery (Armstrong–Frederick, γ > 0) has an unsymmetric
//! consistent tangent under non-proportional flow (`material::cyclic`); its symmetric part
//! makes Newton linear there. Such tangents are factored by `SparseLu` (faer's LU with
//! partial pivoting, [`CholeskySolver::factorize_unsymmetric`]): exact, so Newton stays
//! quadratic. Its ordering and symbolic analysis are made once, by the first unsymmetric
//! factorisation; symmetric models never make them. It costs more than Cholesky on the same
//! matrix (plane-strain elastic block, numeric refactorisation: 10k unknowns 0.036 s against
//! 0.011 s, 100k 0.95 s against 0.17 s; solves about twice as long); faer's COLAMD ordering
//! beat the Cholesky (AMD) ordering given to its symbolic LU by 1.2 and 4 times there.
//!
//! Every workspace is kept between calls: the Cholesky factorisation, the solves and BiCGSTAB
//! allocate nothing once the first unsymmetric solve has sized the Krylov workspace (faer's
//! numeric LU keeps its factor storage in `SparseLu` and grows it as pivoting needs).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::matrix_free::bicgstab::{BicgParams, bicgstab, bicgstab_scratch};
use faer::matrix_free::{IdentityPrecond, InitialGuessStatus, LinOp, Precond};
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::linalg::lu::{LuRef, NumericLu, SymbolicLu, factorize_symbolic_lu};
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
    /// The LU of unsymmetric tangents, made by the first [`Self::factorize_unsymmetric`].
    lu: Option<SparseLu>,
    par: Par,
    factorized: bool,
    /// Whether the last factorisation was the LU (else the Cholesky factor).
    unsymmetric: bool,
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
        .map_err(|e| {
            super::faer_error(e, "the symbolic Cholesky factorisation", pattern.nrows())
        })?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, par),
        ]);
        super::ensure_memory(
            || "its sparse Cholesky factor".into(),
            pattern.nrows(),
            8 * symbolic.len_val() as u64 + req.unaligned_bytes_required() as u64,
        )?;
        let workspace = MemBuffer::try_new(req).map_err(|_| {
            Error::allocation_failed("the factorisation workspace", pattern.nrows())
        })?;
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
            lu: None,
            par: crate::solver::condensed::BULK_FACTOR_PARALLELISM,
            factorized: false,
            unsymmetric: false,
            symbolic_seconds: 0.0,
        })
    }

    /// Seconds the orderings, symbolic factorisations and allocation took (0 before the
    /// first factorisation, which makes them; the LU's are added by the first unsymmetric
    /// one).
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
        self.check_size(matrix)?;
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

    /// Numeric LU factorisation of the unsymmetric `matrix` (both triangles read, see the
    /// module docs), used by the next [`Self::solve_in_place`]. The first call makes the
    /// LU's symbolic analysis.
    pub fn factorize_unsymmetric(&mut self, matrix: SparseColMatRef<'_, u32, f64>) -> Result<()> {
        self.check_size(matrix)?;
        let lu = match &mut self.lu {
            Some(lu) => lu,
            slot => {
                let t = std::time::Instant::now();
                let lu = slot.insert(SparseLu::new(matrix.symbolic(), 1, self.par)?);
                self.symbolic_seconds += t.elapsed().as_secs_f64();
                lu
            }
        };
        lu.factorize(matrix, self.par)?;
        self.factorized = true;
        self.unsymmetric = true;
        Ok(())
    }

    /// Checks the size of a matrix to factor and marks the solver unfactored.
    fn check_size(&mut self, matrix: SparseColMatRef<'_, u32, f64>) -> Result<()> {
        self.factorized = false;
        self.unsymmetric = false;
        if matrix.nrows() != self.n || matrix.ncols() != self.n {
            return Err(Error::Linear(format!(
                "a {}×{} matrix given to the sparse solver of {} unknowns",
                matrix.nrows(),
                matrix.ncols(),
                self.n
            )));
        }
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
                .map_err(|_| Error::allocation_failed("the Krylov workspace", n))?;
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

    /// Solves `A x = rhs` in place with the last factorisation (Cholesky or LU).
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) {
        assert!(self.factorized, "solve before factorize");
        let n = rhs.len();
        if self.unsymmetric {
            let lu = self.lu.as_mut().expect("factorised");
            lu.solve_in_place(MatMut::from_column_major_slice_mut(rhs, n, 1), self.par);
            return;
        }
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

/// Sparse LU with partial pivoting (faer's LU, supernodal on FE matrices, columns ordered by
/// COLAMD) of square matrices sharing one pattern. The ordering, symbolic analysis and
/// workspace are made once by [`SparseLu::new`]; [`SparseLu::factorize`] refactors
/// numerically.
pub(crate) struct SparseLu {
    symbolic: SymbolicLu<u32>,
    numeric: NumericLu<u32, f64>,
    workspace: MemBuffer,
    /// Right-hand sides a solve may have at most (the workspace is sized for them).
    max_rhs: usize,
    factored: bool,
}

impl std::fmt::Debug for SparseLu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseLu")
            .field("n", &self.symbolic.nrows())
            .finish()
    }
}

impl SparseLu {
    /// Ordering and symbolic analysis of `pattern` (square), for solves of up to `max_rhs`
    /// right-hand sides at once.
    pub(crate) fn new(
        pattern: SymbolicSparseColMatRef<'_, u32>,
        max_rhs: usize,
        par: Par,
    ) -> Result<Self> {
        let symbolic = factorize_symbolic_lu(pattern, Default::default())
            .map_err(|e| super::faer_error(e, "the symbolic LU factorisation", pattern.nrows()))?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_lu_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(max_rhs, par),
        ]);
        let workspace = MemBuffer::try_new(req)
            .map_err(|_| Error::allocation_failed("the LU workspace", pattern.nrows()))?;
        Ok(Self {
            symbolic,
            numeric: NumericLu::new(),
            workspace,
            max_rhs,
            factored: false,
        })
    }

    /// Numeric factorisation of `matrix` (the pattern given to [`Self::new`]).
    pub(crate) fn factorize(
        &mut self,
        matrix: SparseColMatRef<'_, u32, f64>,
        par: Par,
    ) -> Result<()> {
        self.factored = false;
        self.symbolic
            .factorize_numeric_lu(
                &mut self.numeric,
                matrix,
                par,
                MemStack::new(&mut self.workspace),
                Default::default(),
            )
            .map_err(|e| {
                Error::Linear(format!(
                    "the unsymmetric tangent is singular (LU factorisation: {e:?}): a body is not supported \
                     against rigid-body motion, or the tangent lost definiteness"
                ))
            })?;
        self.factored = true;
        Ok(())
    }

    /// Solves `A X = rhs` in place (up to the `max_rhs` of [`Self::new`] columns) with the
    /// last factorisation.
    pub(crate) fn solve_in_place(&mut self, rhs: MatMut<'_, f64>, par: Par) {
        assert!(self.factored, "solve before factorize");
        assert!(rhs.ncols() <= self.max_rhs);
        LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            rhs,
            par,
            MemStack::new(&mut self.workspace),
        );
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::DofMap;
    use faer::linalg::solvers::Solve;

    /// A 2D grid of `nx` × `ny` 4-node cells, its first row of nodes held: the pattern, and
    /// a matrix on it that is symmetric positive definite (`skew` = 0) or has an unsymmetric
    /// part of relative size `skew`, dense for reference.
    fn grid_matrix(nx: usize, ny: usize, skew: f64) -> (SparsityPattern, Vec<f64>, Mat<f64>) {
        let node = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
        let cells: Vec<[u32; 4]> = (0..ny)
            .flat_map(|j| {
                (0..nx).map(move |i| {
                    [
                        node(i, j),
                        node(i + 1, j),
                        node(i + 1, j + 1),
                        node(i, j + 1),
                    ]
                })
            })
            .collect();
        let node_count = (nx + 1) * (ny + 1);
        let fixed: Vec<bool> = (0..2 * node_count).map(|d| d < 2 * (nx + 1)).collect();
        let dofs = DofMap::new(&fixed);
        let pattern = SparsityPattern::new(node_count, &dofs, cells.iter().map(|c| c.as_slice()));
        let n = dofs.free_count();
        let mut seed = 12345u64;
        let mut random = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let mut dense = Mat::<f64>::zeros(n, n);
        for c in &cells {
            let b = Mat::<f64>::from_fn(8, 8, |_, _| random());
            let k = b.transpose() * &b + Mat::<f64>::from_fn(8, 8, |_, _| skew * random());
            for a in 0..8 {
                for bb in 0..8 {
                    let eq = |x: usize| dofs.equation(2 * c[x / 2] as usize + x % 2);
                    if let (Some(r), Some(s)) = (eq(a), eq(bb)) {
                        dense[(r, s)] += k[(a, bb)];
                    }
                }
            }
        }
        let sym = pattern.symbolic();
        let values = (0..n)
            .flat_map(|j| {
                sym.row_idx_of_col_raw(j)
                    .iter()
                    .map(move |&i| (i as usize, j))
            })
            .map(|(i, j)| dense[(i, j)])
            .collect();
        (pattern, values, dense)
    }

    /// The solution of `solver` for a fixed right-hand side against dense LU's, relative.
    fn error_against_dense(solver: &mut CholeskySolver, dense: &Mat<f64>) -> f64 {
        let n = dense.nrows();
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let mut x = b.clone();
        solver.solve_in_place(&mut x);
        let reference = dense
            .partial_piv_lu()
            .solve(Mat::<f64>::from_fn(n, 1, |i, _| b[i]));
        let x = Mat::<f64>::from_fn(n, 1, |i, _| x[i]);
        (&x - &reference).norm_l2() / reference.norm_l2()
    }

    #[test]
    fn sparse_lu_solves_unsymmetric_systems_and_cholesky_still_works_after_it() {
        let (pattern, unsymmetric, dense) = grid_matrix(12, 9, 0.5);
        let mut solver = CholeskySolver::new(&pattern).unwrap();
        let matrix = SparseColMatRef::new(pattern.symbolic().as_ref(), &unsymmetric);
        solver.factorize_unsymmetric(matrix).unwrap();
        let error = error_against_dense(&mut solver, &dense);
        assert!(error < 1e-10, "LU: {error:e}");
        // The solver switches between the two factorisations on the same pattern.
        let (_, symmetric, dense_symmetric) = grid_matrix(12, 9, 0.0);
        let matrix = SparseColMatRef::new(pattern.symbolic().as_ref(), &symmetric);
        solver.factorize(matrix).unwrap();
        let error = error_against_dense(&mut solver, &dense_symmetric);
        assert!(error < 1e-10, "Cholesky after LU: {error:e}");
        let matrix = SparseColMatRef::new(pattern.symbolic().as_ref(), &unsymmetric);
        solver.factorize_unsymmetric(matrix).unwrap();
        let error = error_against_dense(&mut solver, &dense);
        assert!(error < 1e-10, "LU again (symbolic reused): {error:e}");
    }
}
