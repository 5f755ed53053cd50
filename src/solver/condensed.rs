//! Exact solves of the unsymmetric contact tangent by static condensation onto the interface.
//!
//! The tangent of a contact model is K = K_c + K_if: the bodies' (continuum) stiffness K_c is
//! symmetric, and for elastic bodies constant; the interface elements' contribution K_if is
//! unsymmetric with friction, changes every iteration, and — since a 6-node interface element
//! connects only interface nodes — lives only in the rows and columns of the interface
//! unknowns I. Splitting the other ("bulk") unknowns B off,
//!
//! ```text
//! [ K_BB  K_BI        ] [x_B]   [r_B]
//! [ K_IB  K_II + K_if ] [x_I] = [r_I],
//! ```
//!
//! the bulk is eliminated with a sparse Cholesky factorisation, leaving the small dense system
//! (S_c + K_if) x_I = r_I − K_IB K_BB⁻¹ r_B with the continuum Schur complement
//! S_c = K_II − K_IB K_BB⁻¹ K_BI, which is factored by dense LU with partial pivoting at every
//! solve ([`crate::solver::interface_lu`]: by blocks where S_c is block diagonal, as between
//! two bodies or the circumferential and meridional unknowns of twist). No Krylov iteration:
//! the solution is exact to rounding.
//!
//! # How S_c is obtained
//! One supernodal Cholesky factorisation of the whole continuum matrix with the bulk
//! ordered first (AMD on K_BB) and the interface last, stopped after the bulk columns
//! ([`crate::solver::tree_cholesky`]): the bulk part of the factor is L_BB and L_IB, and the
//! trailing block, updated by the bulk columns only, is K_II − L_IB L_IBᵀ = S_c, so S_c falls
//! out of the sparse factorisation, whose supernodal updates exploit the sparsity of K_BI
//! (forming W = L_BB⁻¹ K_BI column block by column block would not). The factorisation runs
//! the independent subtrees of the elimination tree on all threads. S_c is only positive
//! *semi*-definite when a body is held only through the interface (e.g. a shaft pushed into
//! a sleeve); the interface diagonal is shifted by a positive D (the continuum's own
//! diagonal there), which the bulk part of the factor does not see, and taken off S_c again.
//!
//! A solve then costs one sparse forward and backward substitution over the bulk part of the
//! factor, a copy of S_c, the dense LU of S_c + K_if (at most ⅔ n_I³ flops) and its
//! substitutions.
//! All storage is allocated by [`CondensedSolver::new`]; [`CondensedSolver::factor_bulk`] and
//! [`CondensedSolver::solve`] allocate none of their own. (faer's multi-threaded kernels
//! allocate rayon's task bookkeeping: in `factor_bulk`, and in solves from n_I = 1024 on,
//! where the dense LU runs on all threads; measured: no allocation at all in solves with
//! n_I = 835.)
//!
//! # An unsymmetric bulk
//! Kinematic hardening with dynamic recovery makes the continuum's tangent unsymmetric where
//! it yields non-proportionally (`material::cyclic`). [`CondensedSolver::factor_bulk_unsymmetric`]
//! then factors K_BB alone by sparse LU (`SparseLu`) and forms
//! S_c = K_II − K_IB (K_BB⁻¹ K_BI) with `SCHUR_BLOCK` right-hand sides per LU solve (the
//! pivoting LU cannot keep the interface rows last, so S_c does not fall out of the factor);
//! solves substitute twice through the LU around the same dense interface LU. It costs n_I
//! sparse substitutions per factorisation more than the Cholesky path, which stays as it is
//! for symmetric bulks. Its structures are made by its first call.
//!
//! # Use
//! ```text
//! let mut s = CondensedSolver::new(&pattern, &interface_equations)?;  // once per model
//! s.factor_bulk(continuum_matrix)?;     // once for elastic bodies; again when K_c changed
//! loop {                                // every Newton iteration
//!     k_if.fill(0.0); /* assemble interface elements into k_if via s.local_index(eq) */
//!     s.solve(k_if.as_ref(), &mut rhs)?;
//! }
//! ```

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::perm::PermRef;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::linalg::{SupernodalThreshold, SymbolicSupernodalParams};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};
use std::sync::Mutex;

use crate::assembly::{SharedMut, SparsityPattern};
use crate::solver::interface_lu::InterfaceLu;
use crate::solver::linear::SparseLu;
use crate::solver::tree_cholesky::TreeCholesky;
use crate::{Error, Result};

/// Marker for a bulk equation in the equation → interface-index map.
const BULK: u32 = u32::MAX;

/// Interface size from which the dense LU of every solve runs in parallel. Below it the
/// threads' overhead outweighs the gain (n_I = 835: 5–13 ms sequential, 27–33 ms on two
/// threads), and the sequential LU allocates nothing, whereas faer's parallel kernels
/// allocate rayon bookkeeping (~1500 allocations per LU at n_I = 835).
const DENSE_PARALLEL_FROM: usize = 1024;

/// The parallelism of faer's sparse factorisations and substitutions (the sparse LU of an
/// unsymmetric bulk here, the whole tangent in [`crate::solver::linear`]): one thread. (The
/// condensed symmetric bulk is factored by [`crate::solver::tree_cholesky`], which runs
/// subtrees, not dense kernels, in parallel.) faer's parallel supernodal
/// Cholesky was never faster on this project's 2-core machine, and much slower on small
/// fronts (the threads wait: ~30 % of the elasto-plastic punch's samples in the scheduler).
/// Measured, sequential against parallel: condensed path, 43k-unknown elasto-plastic punch
/// (30 factorisations) 1.19–1.43 s against 1.98–2.07 s in all, 244k unknowns 0.54–0.56 s
/// against 0.60–0.64 s per factorisation, 973k 3.35 s against 3.20 s, 3.84M 34.6 s against
/// 34.8 s; Cholesky path (`make bench`, elastic block) 10k 0.015 against 0.025 s, 100k 0.24
/// against 0.35 s, 1M 3.35 against 4.28 s. The other core stays free for the output writer.
pub(crate) const BULK_FACTOR_PARALLELISM: Par = Par::Seq;

/// Default of [`CondensedSolver::set_reuse_threshold`]: the factorisation is kept while no
/// entry of the continuum matrix changed by more than 1 % of the geometric mean of its two
/// diagonal entries. Measured on the elasto-plastic flat punch (43k unknowns, 10
/// increments): τ = 0 (refactor on any change): 76 Newton iterations, 51 factorisations;
/// τ = 0.01: 80 and 31; τ = 0.03: 81 and 29; τ = 0.1: 102 and 27. Late iterations of an
/// increment change the plastic tangent by 1e-4..1e-7 in this measure, where the chord step
/// costs nothing in convergence; the first ones by 0.1..0.6, which are refactored.
pub const DEFAULT_REUSE_THRESHOLD: f64 = 0.01;

/// A bulk right-hand side no larger than this fraction of the interface one (max norms) is
/// taken as zero, sparing the forward substitution through the bulk factor — half of a
/// solve. With an elastic bulk every Newton step after the first leaves the bulk equations
/// balanced to rounding (the interface elements load only interface unknowns), so only the
/// interface residual is left. The step is then that of an inexact Newton method with
/// forcing term ≤ 1e-6 (Dembo, Eisenstat & Steihaug 1982), which converges as the exact one
/// to within that factor; a bulk residual that matters (a plastic bulk, a shortened line
/// search step, the last iterations at rounding level) is solved exactly.
const NEGLIGIBLE_BULK_RESIDUAL: f64 = 1e-6;

/// A bulk right-hand side entry no larger than this fraction of the largest entry (bulk or
/// interface) is taken as zero, and the forward substitution skips the supernodes whose
/// right-hand side is then zero: at the first Newton step of an increment the bulk residual
/// is the load change on a few loaded rows and, elsewhere, the rounding left by the last
/// converged state (measured 1e-16..1e-10 of the largest entry on the tapered press fit),
/// so the forward pass visits only the loaded rows' ancestors in the elimination tree (1M
/// taper: solves 2.8 → 1.5 s). The step is that of an inexact Newton method with forcing
/// term 1e-9 in the max norm, ten times below the tightest criterion (R_l = 1e-8 of a linear
/// increment): the same iterations on every comparison case (a forcing term of 1e-6 cost one
/// more iteration on 12 of 200 increments of the cyclic press fit).
const NEGLIGIBLE_BULK_ENTRY: f64 = 1e-9;

/// Sets to zero the negligible entries of the bulk part (the first `n_bulk`) of the
/// right-hand side `x` in elimination order: all of them if the bulk is balanced
/// ([`NEGLIGIBLE_BULK_RESIDUAL`] of the interface part), otherwise those within
/// [`NEGLIGIBLE_BULK_ENTRY`] of the largest entry. Returns whether the bulk part is zero.
fn drop_negligible_bulk_entries(x: &mut [f64], n_bulk: usize) -> bool {
    let largest = |v: &[f64]| v.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let (x_b, x_i) = x.split_at_mut(n_bulk);
    let (bulk, interface) = (largest(x_b), largest(x_i));
    if bulk <= NEGLIGIBLE_BULK_RESIDUAL * interface {
        x_b.fill(0.0);
        return true;
    }
    let bound = NEGLIGIBLE_BULK_ENTRY * bulk.max(interface);
    for v in x_b.iter_mut().filter(|v| v.abs() <= bound) {
        *v = 0.0;
    }
    false
}

/// Right-hand sides per LU solve when S_c of an unsymmetric bulk is formed (columns of K_BI
/// at a time): wide enough for the substitutions' dense kernels, small enough that the block
/// (n_B × this) stays a few megabytes.
const SCHUR_BLOCK: usize = 32;

/// Exact solver for continuum-plus-interface tangents by condensation onto the interface
/// unknowns (see the module documentation).
pub struct CondensedSolver {
    /// Unknowns: all, bulk, interface.
    n: usize,
    n_bulk: usize,
    /// Interface equations in the order of the dense interface block.
    interface: Vec<usize>,
    /// Equation → index into `interface`, or `BULK`.
    local: Vec<u32>,
    /// Elimination order: `order[new] = old` equation; `position[old] = new`. The bulk comes
    /// first (AMD), then the interface in the order of `interface`.
    order: Vec<u32>,
    position: Vec<u32>,
    /// Symbolic supernodal Cholesky factorisation of the reordered matrix.
    symbolic: SymbolicCholesky<u32>,
    /// Lower triangle of the reordered continuum matrix (plus the interface shift) of the
    /// last factorisation; `source[k]` is the position in the original pattern's value
    /// array of its entry k.
    lower: SymbolicSparseColMat<u32>,
    lower_values: Vec<f64>,
    source: Vec<u32>,
    /// Position in `lower_values` of each column's diagonal entry, and 1/√|K̃_ii| of the
    /// (unshifted) diagonal of the last factored matrix K̃ (∞ for a zero): the scale of the
    /// change test of [`Self::factor_bulk`].
    diagonal: Vec<u32>,
    inverse_scale: Vec<f64>,
    /// The scaled change measured by the last [`Self::factor_bulk`] that had a factor.
    last_change: f64,
    /// Columns (elimination order) in which that matrix differs from the factored one in
    /// any bit, when the comparison ran to the end (`changes_known`); a refactorisation then
    /// computes only the supernodes `refactor` marks (see `TreeCholesky::factorize`).
    changed_columns: Vec<bool>,
    changes_known: bool,
    /// Columns (elimination order) in which the matrix to factor may differ from a constant
    /// reference matrix (a plastic bulk's elastic sum K_ref), as its assembly reports them
    /// ([`Self::factor_bulk_varying`]), and the same for the last factored matrix, if known:
    /// two such matrices can differ in these columns only, and the change test looks at no
    /// other.
    varying: Vec<bool>,
    varying_known: bool,
    factored_varying: Vec<bool>,
    factored_varying_known: bool,
    /// Per supernode (allocated here, so that a Newton iteration allocates nothing).
    refactor: Vec<bool>,
    /// Largest scaled change of the continuum matrix for which the last factorisation is
    /// kept (see [`Self::set_reuse_threshold`]).
    reuse_threshold: f64,
    /// Set by [`Self::start_increment`]: the next factorisation request keeps the factor only
    /// for an unchanged matrix.
    increment_started: bool,
    /// Numeric factorisations done, and calls of [`Self::factor_bulk`] that kept the factor.
    factorizations: usize,
    reuses: usize,
    /// Position in `lower_values` of the diagonal entry of each interface unknown.
    interface_diagonal: Vec<usize>,
    /// Size of the original pattern (a consistency check of the matrices passed in).
    pattern_nnz: usize,
    /// Numeric Cholesky factor (supernodal values).
    factor: Vec<f64>,
    /// The diagonal shift D on the interface unknowns of the last factorisation.
    shift: Vec<f64>,
    /// Continuum Schur complement S_c on the interface unknowns: here, unless the interface
    /// columns are the factor's last supernode (`schur_in_factor`: the offset of its values),
    /// as they are when the interface unknowns couple through the pattern, e.g. over the
    /// interface elements. That supernode holds S_c + D after a factorisation and is completed
    /// to S_c in place, sparing an n_I × n_I copy (88 MB at n_I = 3315). The LU path of an
    /// unsymmetric bulk forms S_c here (allocated by its first call).
    schur: Mat<f64>,
    schur_in_factor: Option<usize>,
    /// Dense LU of S_c + K_if.
    dense: InterfaceLu,
    /// The gather buffers of the backward substitution's parallel tasks, kept from solve to
    /// solve.
    backward_gathers: Mutex<Vec<Vec<f64>>>,
    /// Right-hand side / solution in elimination order, and a gather buffer.
    x: Vec<f64>,
    gather: Vec<f64>,
    /// Parallelism of the sparse LU of an unsymmetric bulk.
    par: Par,
    /// The bulk factorisation's updaters and schedule over the elimination tree.
    tree: TreeCholesky,
    /// Whether the bulk, and the interface system, are factored.
    factored: bool,
    /// Whether [`Self::release_refactorisation_storage`] was called.
    released: bool,
    interface_factored: bool,
    /// Whether the bulk part of the right-hand side of the last [`Self::condense`] was zero.
    balanced_bulk: bool,
    /// The LU path of an unsymmetric bulk, made by the first
    /// [`Self::factor_bulk_unsymmetric`], and whether the bulk factor is its LU.
    unsymmetric: Option<Box<UnsymmetricBulk>>,
    lu_bulk: bool,
}

/// The structures of [`CondensedSolver::factor_bulk_unsymmetric`]: the bulk block K_BB (in
/// elimination order) and its LU, the couplings K_BI, K_IB and the block K_II as positions in
/// the continuum's value array, and the values factored last (for the change test).
struct UnsymmetricBulk {
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

impl std::fmt::Debug for CondensedSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CondensedSolver")
            .field("n", &self.n)
            .field("n_interface", &self.interface.len())
            .field("factor_nnz", &self.factor.len())
            .finish()
    }
}

/// The bulk equations `bulk` (increasing) in AMD order of the bulk block of `global`.
///
/// AMD runs on the quotient graph of the bulk's supervariables: runs of consecutive
/// equations with the same pattern in the bulk block (a node's unknowns, numbered together),
/// each then ordered as one, its equations kept together. AMD would merge them into one
/// supervariable on its own at its first step; compressing first spares it the graph of
/// every equation (at 3.8M unknowns the ordering took 0.77 s instead of 2.1 s, and AMD found
/// 7 % fewer factor entries: its approximate degrees are those of whole nodes).
fn bulk_order(global: SymbolicSparseColMatRef<'_, u32>, bulk: &[u32]) -> Result<Vec<u32>> {
    let n = global.nrows();
    let mut compact = vec![BULK; n];
    for (k, &eq) in bulk.iter().enumerate() {
        compact[eq as usize] = k as u32;
    }
    let (cp, ri) = (global.col_ptr(), global.row_idx());
    let bulk_rows = |eq: u32| {
        let j = eq as usize;
        ri[cp[j] as usize..cp[j + 1] as usize]
            .iter()
            .map(|&i| compact[i as usize])
            .filter(|&i| i != BULK)
    };
    // Supervariable of each bulk equation, and the first equation of each.
    let mut group = vec![0u32; bulk.len()];
    let mut first = vec![0u32];
    for k in 1..bulk.len() {
        if !bulk_rows(bulk[k]).eq(bulk_rows(bulk[k - 1])) {
            first.push(k as u32);
        }
        group[k] = (first.len() - 1) as u32;
    }
    let m = if bulk.is_empty() { 0 } else { first.len() };
    first.push(bulk.len() as u32);
    // The quotient graph's upper triangle: rows are sorted, and so are their groups.
    let mut q_col_ptr = Vec::with_capacity(m + 1);
    q_col_ptr.push(0u32);
    let mut q_row_idx: Vec<u32> = Vec::new();
    for s in 0..m {
        let from = q_row_idx.len();
        let rows = bulk_rows(bulk[first[s] as usize]).map(|k| group[k as usize]);
        for g in rows.take_while(|&g| g as usize <= s) {
            if q_row_idx.len() == from || q_row_idx.last() != Some(&g) {
                q_row_idx.push(g);
            }
        }
        q_col_ptr.push(q_row_idx.len() as u32);
    }
    drop(compact);
    let mut amd_fwd = vec![0u32; m];
    let mut amd_inv = vec![0u32; m];
    let q_pattern =
        SymbolicSparseColMatRef::new_unsorted_checked(m, m, &q_col_ptr, None, &q_row_idx);
    let mut mem = MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<u32>(m, q_row_idx.len()))
        .map_err(|_| Error::Linear("out of memory for the AMD ordering".into()))?;
    amd::order_maybe_unsorted(
        &mut amd_fwd,
        &mut amd_inv,
        q_pattern,
        Default::default(),
        MemStack::new(&mut mem),
    )
    .map_err(|e| Error::Linear(format!("AMD ordering failed: {e:?}")))?;
    Ok(amd_fwd
        .iter()
        .flat_map(|&s| first[s as usize]..first[s as usize + 1])
        .map(|k| bulk[k as usize])
        .collect())
}

impl CondensedSolver {
    /// Symbolic analysis, once per model: orders the bulk (AMD on K_BB) with the interface
    /// equations `interface` (free equation numbers of the interface nodes, any order,
    /// duplicates allowed) last, factors symbolically, and allocates every buffer.
    pub fn new(pattern: &SparsityPattern, interface: &[usize]) -> Result<Self> {
        Self::with_relaxation(pattern, interface, None)
    }

    /// [`Self::new`] with faer's supernode relaxation thresholds `relax` (`None`: faer's
    /// defaults), for tests of supernodes straddling the bulk–interface border.
    fn with_relaxation(
        pattern: &SparsityPattern,
        interface: &[usize],
        relax: Option<&[(usize, f64)]>,
    ) -> Result<Self> {
        let global = pattern.symbolic();
        let n = global.nrows();
        let mut interface = interface.to_vec();
        interface.sort_unstable();
        interface.dedup();
        if let Some(&last) = interface.last()
            && last >= n
        {
            return Err(Error::Linear(format!(
                "interface equation {last} out of range (there are {n} unknowns)"
            )));
        }
        let n_i = interface.len();
        let n_bulk = n - n_i;
        let mut local = vec![BULK; n];
        for (k, &eq) in interface.iter().enumerate() {
            local[eq] = k as u32;
        }

        let bulk: Vec<u32> = (0..n as u32)
            .filter(|&eq| local[eq as usize] == BULK)
            .collect();
        let started = std::time::Instant::now();
        let order: Vec<u32> = bulk_order(global.as_ref(), &bulk)?
            .into_iter()
            .chain(interface.iter().map(|&eq| eq as u32))
            .collect();
        drop(bulk);
        let ordering_seconds = started.elapsed().as_secs_f64();
        let mut position = vec![0u32; n];
        for (new, &old) in order.iter().enumerate() {
            position[old as usize] = new as u32;
        }

        let symbolic = factorize_symbolic_cholesky(
            global.as_ref(),
            Side::Lower,
            SymmetricOrdering::Custom(PermRef::new_checked(&order, &position, n)),
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                supernodal_params: match relax {
                    Some(relax) => SymbolicSupernodalParams { relax: Some(relax) },
                    None => Default::default(),
                },
                ..Default::default()
            },
        )
        .map_err(|e| Error::Linear(format!("symbolic Cholesky factorisation failed: {e:?}")))?;
        let SymbolicCholeskyRaw::Supernodal(supernodal) = symbolic.raw() else {
            return Err(Error::Linear(
                "expected a supernodal symbolic factorisation".into(),
            ));
        };

        // Lower triangle of the reordered matrix: count per column, then the row indices in
        // the traversal order that `factor_bulk` repeats.
        let mut lower_col_ptr = vec![0u32; n + 1];
        for_each_lower(global.as_ref(), &position, |col, _, _| {
            lower_col_ptr[col + 1] += 1
        });
        for c in 0..n {
            lower_col_ptr[c + 1] += lower_col_ptr[c];
        }
        let nnz_lower = lower_col_ptr[n] as usize;
        let mut lower_row_idx = vec![0u32; nnz_lower];
        let mut source = vec![0u32; nnz_lower];
        let mut fill: Vec<u32> = lower_col_ptr[..n].to_vec();
        let mut diagonal = vec![u32::MAX; n];
        for_each_lower(global.as_ref(), &position, |col, row, p| {
            let slot = fill[col] as usize;
            lower_row_idx[slot] = row as u32;
            source[slot] = p as u32;
            fill[col] += 1;
            if row == col {
                diagonal[col] = slot as u32;
            }
        });
        drop(fill);
        if diagonal.contains(&u32::MAX) {
            return Err(Error::Linear(
                "the sparsity pattern lacks a diagonal entry".into(),
            ));
        }
        let interface_diagonal: Vec<usize> = diagonal[n_bulk..]
            .iter()
            .map(|&slot| slot as usize)
            .collect();
        let lower =
            SymbolicSparseColMat::new_unsorted_checked(n, n, lower_col_ptr, None, lower_row_idx);

        // One thread for the bulk factorisation: see `BULK_FACTOR_PARALLELISM`.
        let par = BULK_FACTOR_PARALLELISM;
        let gather_len = (0..supernodal.n_supernodes())
            .map(|s| supernodal.supernode(s).pattern().len())
            .max()
            .unwrap_or(0);
        let factor = vec![0.0; supernodal.len_val()];
        let tree = TreeCholesky::new(supernodal, rayon::current_num_threads());
        let schur_in_factor = trailing_supernode(supernodal, n_bulk)
            .map(|s| supernodal.col_ptr_for_val()[s] as usize);
        tracing::debug!(
            unknowns = n,
            interface = n_i,
            supernodes = supernodal.n_supernodes(),
            factor_entries = supernodal.len_val(),
            ordering_seconds,
            symbolic_seconds = started.elapsed().as_secs_f64() - ordering_seconds,
            "condensed solver"
        );
        Ok(Self {
            n,
            n_bulk,
            interface,
            local,
            order,
            position,
            lower_values: vec![0.0; nnz_lower],
            lower,
            source,
            diagonal,
            inverse_scale: vec![0.0; n],
            last_change: f64::INFINITY,
            changed_columns: vec![false; n],
            changes_known: false,
            varying: vec![false; n],
            varying_known: false,
            factored_varying: vec![false; n],
            factored_varying_known: false,
            refactor: Vec::with_capacity(supernodal.n_supernodes()),
            reuse_threshold: DEFAULT_REUSE_THRESHOLD,
            increment_started: false,
            factorizations: 0,
            reuses: 0,
            interface_diagonal,
            pattern_nnz: global.row_idx().len(),
            factor,
            shift: vec![0.0; n_i],
            schur: match schur_in_factor {
                Some(_) => Mat::zeros(0, 0),
                None => Mat::zeros(n_i, n_i),
            },
            schur_in_factor,
            dense: InterfaceLu::new(
                n_i,
                if n_i >= DENSE_PARALLEL_FROM {
                    Par::rayon(0)
                } else {
                    Par::Seq
                },
            )?,
            x: vec![0.0; n],
            gather: vec![0.0; gather_len],
            backward_gathers: Mutex::new(Vec::new()),
            par,
            tree,
            symbolic,
            factored: false,
            released: false,
            interface_factored: false,
            balanced_bulk: false,
            unsymmetric: None,
            lu_bulk: false,
        })
    }

    /// Sets the parallelism of the sparse LU of an unsymmetric bulk
    /// ([`Self::factor_bulk_unsymmetric`], `factor`) and of the dense LU and substitutions of
    /// every solve (`dense`). Defaults: one thread for the former
    /// (`BULK_FACTOR_PARALLELISM`); for the latter all threads from n_I = 1024 interface
    /// unknowns, sequential below. (The symmetric bulk is factored on all threads by subtrees,
    /// [`crate::solver::tree_cholesky`]; the sparse substitutions are sequential.)
    pub fn set_parallelism(&mut self, factor: Par, dense: Par) {
        self.par = factor;
        self.dense.set_parallelism(dense);
    }

    /// Sets the reuse threshold τ of [`Self::factor_bulk`]: the last factorisation of K̃ is
    /// kept for a new continuum matrix K when
    /// max_ij |K_ij − K̃_ij| / √(|K̃_ii| |K̃_jj|) ≤ τ. τ = 0 (the default) keeps it only for an
    /// unchanged matrix; τ > 0 makes Newton a chord (inexact Newton) iteration with the exact
    /// residual while the change stays below τ (see docs/theory.md, "Reusing the bulk
    /// factorisation"). Default [`DEFAULT_REUSE_THRESHOLD`].
    pub fn set_reuse_threshold(&mut self, threshold: f64) {
        self.reuse_threshold = threshold.max(0.0);
    }

    /// Marks the start of a load increment: the next [`Self::factor_bulk`] keeps the last
    /// factorisation only for an unchanged matrix. Every increment then starts from a factor
    /// of its own first tangent, whatever earlier increments factored, so a run resumed from
    /// a restart record (which cannot hold the factor) repeats the uninterrupted run bit for
    /// bit.
    pub fn start_increment(&mut self) {
        self.increment_started = true;
    }

    /// The scaled change of the continuum matrix measured by the last [`Self::factor_bulk`]
    /// that found a factorisation to compare with (∞ before).
    pub fn last_change(&self) -> f64 {
        self.last_change
    }

    /// Numeric factorisations done by [`Self::factor_bulk`], and calls that kept the last one.
    pub fn factorizations(&self) -> (usize, usize) {
        (self.factorizations, self.reuses)
    }

    /// max_ij |K_ij − K̃_ij| / √(|K̃_ii| |K̃_jj|) over the lower triangle, K̃ the last factored
    /// matrix (its interface shift removed) and K = `values` (original pattern); ∞ if a
    /// change meets a zero scale or a value is not finite. Flags in `changed_columns` the
    /// columns with a changed entry, and sets `changes_known` if it looked at every entry.
    fn change_from_factored(&mut self, values: &[f64]) -> f64 {
        let (col_ptr, row_idx) = (self.lower.col_ptr(), self.lower.row_idx());
        let mut largest = 0.0f64;
        let restricted = self.varying_known && self.factored_varying_known;
        for col in 0..self.n {
            if restricted && col < self.n_bulk && !self.varying[col] && !self.factored_varying[col]
            {
                // Both matrices have the reference's values here.
                self.changed_columns[col] = false;
                continue;
            }
            let range = col_ptr[col] as usize..col_ptr[col + 1] as usize;
            let scale_col = self.inverse_scale[col];
            let mut changed = false;
            for k in range {
                let row = row_idx[k] as usize;
                let mut old = self.lower_values[k];
                if row == col && col >= self.n_bulk {
                    old -= self.shift[col - self.n_bulk];
                }
                let difference = (values[self.source[k] as usize] - old).abs();
                if difference == 0.0 {
                    continue;
                }
                changed = true;
                let relative = difference * self.inverse_scale[row] * scale_col;
                if !relative.is_finite() {
                    return f64::INFINITY;
                }
                largest = largest.max(relative);
            }
            self.changed_columns[col] = changed;
        }
        self.changes_known = true;
        largest
    }

    /// Number of unknowns.
    pub fn size(&self) -> usize {
        self.n
    }

    /// The interface equations, sorted: row/column k of the dense interface block passed to
    /// [`Self::solve`] is equation `interface_equations()[k]`.
    pub fn interface_equations(&self) -> &[usize] {
        &self.interface
    }

    /// Index of equation `eq` in the dense interface block, or `None` for a bulk unknown.
    #[inline]
    pub fn local_index(&self, eq: usize) -> Option<usize> {
        let k = self.local[eq];
        (k != BULK).then_some(k as usize)
    }

    /// Stored entries of the sparse Cholesky factor (its dense interface block included).
    pub fn factor_nnz(&self) -> usize {
        self.factor.len()
    }

    /// Frees what only a refactorisation needs — the reordered lower triangle and its maps,
    /// the change test's scales, the factorisation's scratch — once the bulk is factored for
    /// good, as an elastic bulk is (about 250 MB beside the 1.4 GB factor of a 1M-unknown
    /// taper). Later calls of [`Self::factor_bulk`] and [`Self::factor_bulk_unsymmetric`]
    /// fail; solves are unaffected.
    pub fn release_refactorisation_storage(&mut self) {
        assert!(self.factored, "release before factor_bulk");
        self.lower_values = Vec::new();
        self.source = Vec::new();
        self.diagonal = Vec::new();
        self.inverse_scale = Vec::new();
        self.lower = SymbolicSparseColMat::new_checked(0, 0, vec![0], None, Vec::new());
        self.tree.release_scratch();
        self.released = true;
    }

    /// Bytes held by this solver (factor, matrices, dense blocks, workspaces).
    pub fn memory_bytes(&self) -> usize {
        let n_i = self.interface.len();
        8 * (self.factor.len()
            + self.lower_values.len()
            + self.schur.nrows() * self.schur.ncols()
            + n_i * n_i
            + 2 * self.n)
            + 4 * (self.lower.row_idx().len() + 4 * self.n)
            + self.changed_columns.len()
            + self.refactor.len()
            + self.tree.memory_bytes()
    }

    /// The continuum Schur complement S_c on the interface (valid after
    /// [`Self::factor_bulk`]).
    pub fn schur_complement(&self) -> MatRef<'_, f64> {
        schur_of(&self.factor, &self.schur, self.schur_location())
    }

    /// Where S_c is: the offset of its values in the factor and n_I, or `None` for
    /// `self.schur`.
    fn schur_location(&self) -> Option<(usize, usize)> {
        (self.schur_in_factor)
            .filter(|_| !self.lu_bulk)
            .map(|at| (at, self.interface.len()))
    }

    /// Numeric factorisation of the symmetric continuum-only matrix `continuum` (the pattern
    /// given to [`Self::new`]; its lower triangle is read) and formation of the dense
    /// continuum Schur complement S_c on the interface. Once per model for elastic bodies,
    /// again whenever the bulk tangent changed. Fails if K_BB is not positive definite (a
    /// body neither supported nor touching an interface).
    ///
    /// The factorisation (and S_c) of the last call is kept when `continuum` differs from
    /// the matrix factored then by at most the reuse threshold in the scaled measure of
    /// [`Self::set_reuse_threshold`] (always when it is unchanged, e.g. a plastic body whose
    /// points all stayed elastic). Returns whether it factored.
    pub fn factor_bulk(&mut self, continuum: SparseColMatRef<'_, u32, f64>) -> Result<bool> {
        self.factor_bulk_varying(continuum, None)
    }

    /// [`Self::factor_bulk`] for a `continuum` that differs from a constant reference matrix
    /// in the columns (equations) `varying` flags at most, if given (a plastic bulk's
    /// elastic sum and its yielding cells:
    /// [`GlobalSystem::off_reference_columns`](crate::assembly::GlobalSystem::off_reference_columns)).
    /// The change test then compares only the columns flagged for this matrix or for the
    /// last factored one, and the interface's.
    pub fn factor_bulk_varying(
        &mut self,
        continuum: SparseColMatRef<'_, u32, f64>,
        varying: Option<&[bool]>,
    ) -> Result<bool> {
        self.varying_known = varying.is_some();
        if let Some(flags) = varying {
            for (eq, &flag) in flags.iter().enumerate() {
                self.varying[self.position[eq] as usize] = flag;
            }
        }
        if self.keeps_factor(continuum, false)? {
            return Ok(false);
        }
        std::mem::swap(&mut self.varying, &mut self.factored_varying);
        self.factored_varying_known = self.varying_known;
        self.factored = false;
        self.interface_factored = false;
        self.lu_bulk = false;
        // Reordered lower triangle: the columns the comparison found changed and the
        // interface's (which hold the shift), or all of them.
        let values = &mut self.lower_values;
        let col_ptr = self.lower.col_ptr();
        for col in 0..self.n {
            if self.changes_known && col < self.n_bulk && !self.changed_columns[col] {
                continue;
            }
            let range = col_ptr[col] as usize..col_ptr[col + 1] as usize;
            for (v, &p) in values[range.clone()].iter_mut().zip(&self.source[range]) {
                *v = continuum.val()[p as usize];
            }
        }
        for (d, &slot) in self.inverse_scale.iter_mut().zip(&self.diagonal) {
            *d = values[slot as usize].abs().sqrt().recip();
        }
        // Shift D on the interface diagonal: makes the trailing block S_c + D definite even
        // when S_c is singular (a body held only through the interface).
        let fallback = self
            .interface_diagonal
            .iter()
            .map(|&p| values[p].abs())
            .fold(0.0, f64::max);
        for (d, &p) in self.shift.iter_mut().zip(&self.interface_diagonal) {
            let own = values[p].abs();
            *d = if own > 0.0 {
                own
            } else if fallback > 0.0 {
                fallback
            } else {
                1.0
            };
            values[p] += *d;
        }
        let SymbolicCholeskyRaw::Supernodal(symbolic) = self.symbolic.raw() else {
            unreachable!("forced supernodal in `new`");
        };
        let n_bulk = self.n_bulk;
        // Only the supernodes whose values change, when the last factor's matrix is known to
        // differ from this one in some columns only (a plastic zone's).
        let only = if self.changes_known {
            let count = self.tree.supernodes_to_refactor(
                symbolic,
                &self.changed_columns,
                n_bulk,
                &mut self.refactor,
            );
            tracing::trace!(
                supernodes = count,
                of = symbolic.n_supernodes(),
                "bulk supernodes refactored"
            );
            Some(self.refactor.as_slice())
        } else {
            None
        };
        // The bulk columns factored, the interface columns left as S_c + D.
        self.tree
            .factorize(
                &mut self.factor,
                SparseColMatRef::new(self.lower.as_ref(), &self.lower_values),
                symbolic,
                n_bulk,
                only,
            )
            .map_err(|_| {
                Error::Linear(
                    "the bodies' stiffness with the interface unknowns held is not positive definite: a body is \
                     neither supported nor in contact, or the bulk tangent lost definiteness"
                        .into(),
                )
            })?;
        let n_i = self.interface.len();
        let mut schur = match self.schur_in_factor {
            Some(at) => {
                MatMut::from_column_major_slice_mut(&mut self.factor[at..at + n_i * n_i], n_i, n_i)
            }
            None => {
                // S_c from the interface columns of the factor's storage (lower triangle);
                // the buffer may hold the LU path's S_c, whose structural zeros are rewritten.
                self.schur.fill(0.0);
                let llt = SupernodalLltRef::new(symbolic, &self.factor);
                for s in first_interface_supernode(symbolic, n_bulk)..symbolic.n_supernodes() {
                    let node = llt.supernode(s);
                    let (start, ls, pattern) = (node.start(), node.val(), node.pattern());
                    let width = ls.ncols();
                    for jj in n_bulk.saturating_sub(start)..width {
                        let col = start + jj - n_bulk;
                        for ii in jj..width {
                            self.schur[(start + ii - n_bulk, col)] = ls[(ii, jj)];
                        }
                        for (idx, &row) in pattern.iter().enumerate() {
                            self.schur[(row as usize - n_bulk, col)] = ls[(width + idx, jj)];
                        }
                    }
                }
                self.schur.as_mut()
            }
        };
        // S_c = (S_c + D) − D, mirrored to the upper triangle.
        for j in 0..n_i {
            schur[(j, j)] -= self.shift[j];
            for i in j + 1..n_i {
                schur[(j, i)] = schur[(i, j)];
            }
        }
        self.dense
            .analyse(schur_of(&self.factor, &self.schur, self.schur_location()));
        self.factored = true;
        self.factorizations += 1;
        Ok(true)
    }

    /// Checks that `continuum` has the pattern of this solver and decides whether the last
    /// bulk factorisation is kept for it (see [`Self::factor_bulk`]): only a factorisation of
    /// the same kind (`lu`: of an unsymmetric bulk) is.
    fn keeps_factor(&mut self, continuum: SparseColMatRef<'_, u32, f64>, lu: bool) -> Result<bool> {
        let n = self.n;
        if continuum.nrows() != n
            || continuum.ncols() != n
            || continuum.row_idx().len() != self.pattern_nnz
        {
            return Err(Error::Linear(
                "the continuum matrix does not have the pattern of the condensed solver".into(),
            ));
        }
        if self.released {
            return Err(Error::Linear(
                "the bulk factor was kept for good (an elastic bulk): it cannot be refactored"
                    .into(),
            ));
        }
        // Set again only by a comparison with a Cholesky factor's matrix that runs through.
        self.changes_known = false;
        if !self.factored {
            return Ok(false);
        }
        let change = match (lu, self.lu_bulk) {
            (false, false) => self.change_from_factored(continuum.val()),
            (true, true) => self.change_from_factored_lu(continuum.val()),
            _ => f64::INFINITY,
        };
        self.last_change = change;
        let threshold = if self.increment_started {
            0.0
        } else {
            self.reuse_threshold
        };
        self.increment_started = false;
        if change <= threshold {
            self.reuses += 1;
            tracing::debug!(change, "bulk factorisation kept");
            return Ok(true);
        }
        tracing::debug!(change, "bulk refactored");
        Ok(false)
    }

    /// [`Self::change_from_factored`] over both triangles, against the last matrix factored
    /// by [`Self::factor_bulk_unsymmetric`].
    fn change_from_factored_lu(&self, values: &[f64]) -> f64 {
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
            pattern: pattern
                .to_owned()
                .map_err(|e| Error::Linear(format!("out of memory for the pattern: {e:?}")))?,
        })
    }

    /// Exact solve of (K_c + K_if) x = `rhs` in place, with K_c the matrix of the last
    /// [`Self::factor_bulk`] and K_if the (possibly unsymmetric) interface contribution given
    /// as the dense n_I × n_I block `interface_block` over [`Self::interface_equations`]
    /// (K_if is zero outside it): [`Self::factor_interface`] then [`Self::solve_in_place`].
    pub fn solve(&mut self, interface_block: MatRef<'_, f64>, rhs: &mut [f64]) -> Result<()> {
        self.factor_interface(interface_block)?;
        self.solve_in_place(rhs);
        Ok(())
    }

    /// Factors S_c + K_if by dense LU with partial pivoting, K_if = `interface_block` as in
    /// [`Self::solve`]. Fails if it is singular to working precision (a pivot below
    /// n_I·ε times the largest) or not finite.
    pub fn factor_interface(&mut self, interface_block: MatRef<'_, f64>) -> Result<()> {
        assert!(self.factored, "factor_interface before factor_bulk");
        self.interface_factored = false;
        let n_i = self.interface.len();
        assert_eq!(
            (interface_block.nrows(), interface_block.ncols()),
            (n_i, n_i)
        );
        let schur = schur_of(&self.factor, &self.schur, self.schur_location());
        if !self.dense.factor(schur, interface_block) {
            return Err(Error::Linear(
                "the condensed interface system is singular: a body is held by nothing but its contact \
                 interface, and the interface does not hold it (open, or sliding freely)"
                    .into(),
            ));
        }
        self.interface_factored = true;
        Ok(())
    }

    /// Solves (K_c + K_if) x = `rhs` in place with the factors of the last
    /// [`Self::factor_bulk`] and [`Self::factor_interface`] (e.g. several right-hand sides
    /// for one tangent): [`Self::condense`], the interface solve, [`Self::expand`].
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) {
        assert!(
            self.interface_factored,
            "solve_in_place before factor_interface"
        );
        self.condense(rhs);
        let n_bulk = self.n_bulk;
        self.dense.solve_in_place(&mut self.x[n_bulk..]);
        self.back_substitute(rhs);
    }

    /// The first half of a solve: takes the right-hand side `rhs` (free equations) into
    /// elimination order and eliminates the bulk from it, leaving the condensed right-hand
    /// side g = r_I − K_IB K_BB⁻¹ r_B ([`Self::condensed_rhs`]). The bulk part is kept for
    /// [`Self::expand`], which finishes the solve for any interface solution.
    pub fn condense(&mut self, rhs: &[f64]) {
        assert!(self.factored, "condense before factor_bulk");
        assert_eq!(rhs.len(), self.n);
        for (x, &old) in self.x.iter_mut().zip(&self.order) {
            *x = rhs[old as usize];
        }
        self.balanced_bulk = drop_negligible_bulk_entries(&mut self.x, self.n_bulk);
        if self.balanced_bulk {
            return;
        }
        let n_bulk = self.n_bulk;
        if self.lu_bulk {
            let u = self.unsymmetric.as_deref_mut().expect("LU made");
            let (x_b, x_i) = self.x.split_at_mut(n_bulk);
            let mut z = u.block.as_mut().subcols_mut(0, 1);
            z.rb_mut()
                .col_mut(0)
                .copy_from(faer::ColRef::from_slice(x_b));
            u.lu.solve_in_place(z.rb_mut(), Par::Seq);
            for &(i, b, p) in &u.ib {
                x_i[i as usize] -= u.factored_values[p as usize] * z[(b as usize, 0)];
            }
        } else {
            let SymbolicCholeskyRaw::Supernodal(symbolic) = self.symbolic.raw() else {
                unreachable!("forced supernodal in `new`");
            };
            let llt = SupernodalLltRef::new(symbolic, &self.factor);
            forward_bulk(llt, n_bulk, &mut self.x, &mut self.gather);
        }
    }

    /// The condensed right-hand side g of the last [`Self::condense`], in the order of
    /// [`Self::interface_equations`].
    pub fn condensed_rhs(&self) -> &[f64] {
        &self.x[self.n_bulk..]
    }

    /// Solves (S_c + K_if) v = `v` in place (interface order) with the LU of the last
    /// [`Self::factor_interface`].
    pub fn solve_interface(&mut self, v: &mut [f64]) {
        assert!(
            self.interface_factored,
            "solve_interface before factor_interface"
        );
        self.dense.solve_in_place(v);
    }

    /// The second half of a solve begun by [`Self::condense`]: with the interface unknowns
    /// `x_interface` (interface order), x_B = K_BB⁻¹ (r_B − K_BI x_I); writes x (free
    /// equations) into `out`.
    pub fn expand(&mut self, x_interface: &[f64], out: &mut [f64]) {
        assert_eq!(out.len(), self.n);
        let n_bulk = self.n_bulk;
        self.x[n_bulk..].copy_from_slice(x_interface);
        self.back_substitute(out);
    }

    /// Back substitution of the bulk from the interface unknowns in `self.x` (after
    /// [`Self::condense`]), the solution written into `out` (free equations).
    fn back_substitute(&mut self, out: &mut [f64]) {
        let n_bulk = self.n_bulk;
        if self.lu_bulk {
            let u = self.unsymmetric.as_deref_mut().expect("LU made");
            let (x_b, x_i) = self.x.split_at_mut(n_bulk);
            let values = &u.factored_values;
            for (k, &xk) in x_i.iter().enumerate() {
                let range = u.bi_ptr[k]..u.bi_ptr[k + 1];
                for (&row, &p) in u.bi_rows[range.clone()].iter().zip(&u.bi_source[range]) {
                    x_b[row as usize] -= values[p as usize] * xk;
                }
            }
            u.lu.solve_in_place(
                MatMut::from_column_major_slice_mut(x_b, n_bulk, 1),
                Par::Seq,
            );
        } else {
            let SymbolicCholeskyRaw::Supernodal(symbolic) = self.symbolic.raw() else {
                unreachable!("forced supernodal in `new`");
            };
            let llt = SupernodalLltRef::new(symbolic, &self.factor);
            let gathers = &self.backward_gathers;
            backward_bulk(
                llt,
                &self.tree,
                n_bulk,
                &mut self.x,
                gathers,
                self.gather.len(),
            );
        }
        for (r, &new) in out.iter_mut().zip(&self.position) {
            *r = self.x[new as usize];
        }
    }

    /// Gathers the interface block of `matrix` (over the pattern given to [`Self::new`], e.g.
    /// the interface elements assembled alone into a global value array) into `out`, in the
    /// order of [`Self::interface_equations`]. Fails if an interface column has a nonzero
    /// entry in a bulk row (interface elements must touch interface unknowns only).
    pub fn gather_interface_block(
        &self,
        matrix: SparseColMatRef<'_, u32, f64>,
        mut out: MatMut<'_, f64>,
    ) -> Result<()> {
        out.fill(0.0);
        for (kj, &j) in self.interface.iter().enumerate() {
            for (&i, &v) in matrix
                .row_idx_of_col_raw(j)
                .iter()
                .zip(matrix.val_of_col(j))
            {
                match self.local_index(i as usize) {
                    Some(ki) => out[(ki, kj)] = v,
                    None if v != 0.0 => {
                        return Err(Error::Linear(format!(
                            "interface contribution at ({i}, {j}) couples a bulk unknown"
                        )));
                    }
                    None => {}
                }
            }
        }
        Ok(())
    }
}

/// Calls `f(col, row, p)` for every entry p of the lower triangle (row ≥ col) of `pattern`
/// mapped by `position` into the lower triangle of the reordered matrix, in a fixed order.
fn for_each_lower(
    pattern: SymbolicSparseColMatRef<'_, u32>,
    position: &[u32],
    mut f: impl FnMut(usize, usize, usize),
) {
    let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
    for j in 0..pattern.ncols() {
        let pj = position[j] as usize;
        let range = cp[j] as usize..cp[j + 1] as usize;
        for (p, &i) in range.clone().zip(&ri[range]) {
            let i = i as usize;
            if i < j {
                continue;
            }
            let pi = position[i] as usize;
            let (col, row) = if pi >= pj { (pj, pi) } else { (pi, pj) };
            f(col, row, p);
        }
    }
}

/// Number of supernodes with a column in the bulk (the last one may straddle the border).
fn bulk_supernodes(symbolic: &SymbolicSupernodalCholesky<u32>, n_bulk: usize) -> usize {
    symbolic
        .supernode_begin()
        .iter()
        .position(|&start| start as usize >= n_bulk)
        .unwrap_or(symbolic.n_supernodes())
}

/// S_c: n_I × n_I at offset `at` of the factor's values for `location = Some((at, n_I))`,
/// or `schur`.
fn schur_of<'a>(
    factor: &'a [f64],
    schur: &'a Mat<f64>,
    location: Option<(usize, usize)>,
) -> MatRef<'a, f64> {
    match location {
        Some((at, n_i)) => MatRef::from_column_major_slice(&factor[at..at + n_i * n_i], n_i, n_i),
        None => schur.as_ref(),
    }
}

/// The last supernode when it holds exactly the interface columns (from `n_bulk` on) and no
/// rows below them: its values are then the dense n_I × n_I block.
fn trailing_supernode(symbolic: &SymbolicSupernodalCholesky<u32>, n_bulk: usize) -> Option<usize> {
    let last = symbolic.n_supernodes().checked_sub(1)?;
    (symbolic.supernode_begin()[last] as usize == n_bulk
        && symbolic.supernode(last).pattern().is_empty()
        && n_bulk < symbolic.nrows())
    .then_some(last)
}

/// Index of the first supernode with a column in the interface block.
fn first_interface_supernode(symbolic: &SymbolicSupernodalCholesky<u32>, n_bulk: usize) -> usize {
    symbolic
        .supernode_end()
        .iter()
        .position(|&end| end as usize > n_bulk)
        .unwrap_or(symbolic.n_supernodes())
}

/// Forward substitution with the bulk columns of the factor: x_B ← L_BB⁻¹ x_B and
/// x_I ← x_I − L_IB x_B.
fn forward_bulk(
    llt: SupernodalLltRef<'_, u32, f64>,
    n_bulk: usize,
    x: &mut [f64],
    gather: &mut [f64],
) {
    let symbolic = llt.symbolic();
    for s in 0..bulk_supernodes(symbolic, n_bulk) {
        let node = llt.supernode(s);
        let (start, ls, pattern) = (node.start(), node.val(), node.pattern());
        let width = ls.ncols();
        // Columns of this supernode in the bulk (all of them unless it straddles the border).
        let k = width.min(n_bulk - start);
        let (head, tail) = x.split_at_mut(start + k);
        if head[start..].iter().all(|&v| v == 0.0) {
            // Nothing to eliminate: the supernode's solution is zero and updates nothing.
            continue;
        }
        let mut x_top = MatMut::from_column_major_slice_mut(&mut head[start..], k, 1);
        solve_lower_triangular_in_place(ls.submatrix(0, 0, k, k), x_top.rb_mut(), Par::Seq);
        let x_top = x_top.rb();
        if k < width {
            let rest = MatMut::from_column_major_slice_mut(&mut tail[..width - k], width - k, 1);
            matmul(
                rest,
                Accum::Add,
                ls.submatrix(k, 0, width - k, k),
                x_top,
                -1.0,
                Par::Seq,
            );
        }
        let m = pattern.len();
        let g = MatMut::from_column_major_slice_mut(&mut gather[..m], m, 1);
        matmul(
            g,
            Accum::Replace,
            ls.submatrix(width, 0, m, k),
            x_top,
            1.0,
            Par::Seq,
        );
        for (&row, &v) in pattern.iter().zip(&gather[..m]) {
            x[row as usize] -= v;
        }
    }
}

/// Backward substitution with the bulk columns of the factor, x_I holding the interface
/// solution: x_B ← L_BB⁻ᵀ (x_B − L_IBᵀ x_I). Sibling subtrees of the elimination tree share
/// no columns, so they run as parallel tasks ([`TreeCholesky::top_down`]), each supernode
/// after its ancestors; every supernode is computed by the same operations whichever task
/// runs it, so the result has the same bits on any number of threads. `gathers`: the tasks'
/// gather buffers (`gather_len`, the longest row pattern of a supernode, each).
fn backward_bulk(
    llt: SupernodalLltRef<'_, u32, f64>,
    tree: &TreeCholesky,
    n_bulk: usize,
    x: &mut [f64],
    gathers: &Mutex<Vec<Vec<f64>>>,
    gather_len: usize,
) {
    let bulk = bulk_supernodes(llt.symbolic(), n_bulk);
    // Shared by the tasks: each writes the columns of its own supernodes and reads those of
    // their ancestors, final by then (`top_down` visits a supernode after its parent).
    let shared = SharedMut(x.as_mut_ptr());
    tree.top_down(
        gathers,
        || vec![0.0; gather_len],
        |s, gather| {
            if s < bulk {
                backward_supernode(llt, s, n_bulk, shared, gather);
            }
        },
    );
}

/// The backward substitution of bulk supernode `s` in `x` (see [`backward_bulk`]).
fn backward_supernode(
    llt: SupernodalLltRef<'_, u32, f64>,
    s: usize,
    n_bulk: usize,
    x: SharedMut<f64>,
    gather: &mut [f64],
) {
    let node = llt.supernode(s);
    let (start, ls, pattern) = (node.start(), node.val(), node.pattern());
    let width = ls.ncols();
    let k = width.min(n_bulk - start);
    let m = pattern.len();
    let x = x.get();
    // SAFETY: the rows of `pattern` and the interface columns of a supernode straddling the
    // border (after its bulk columns) belong to ancestors of `s`, solved before it and
    // written by no task any more; its own bulk columns `start..start + k` are written by
    // this call alone. All lie within the solution vector of the factor's order.
    let (x_top, tail) = unsafe {
        for (g, &row) in gather[..m].iter_mut().zip(pattern) {
            *g = *x.add(row as usize);
        }
        (
            std::slice::from_raw_parts_mut(x.add(start), k),
            std::slice::from_raw_parts(x.add(start + k), width - k),
        )
    };
    let mut x_top = MatMut::from_column_major_slice_mut(x_top, k, 1);
    matmul(
        x_top.rb_mut(),
        Accum::Add,
        ls.submatrix(width, 0, m, k).transpose(),
        MatRef::from_column_major_slice(&gather[..m], m, 1),
        -1.0,
        Par::Seq,
    );
    if k < width {
        matmul(
            x_top.rb_mut(),
            Accum::Add,
            ls.submatrix(k, 0, width - k, k).transpose(),
            MatRef::from_column_major_slice(tail, width - k, 1),
            -1.0,
            Par::Seq,
        );
    }
    solve_upper_triangular_in_place(ls.submatrix(0, 0, k, k).transpose(), x_top, Par::Seq);
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::assembly::DofMap;
    use faer::linalg::solvers::Solve;

    /// Small deterministic pseudo-random numbers in [−1, 1) (also for `interface_lu`'s tests).
    pub(crate) struct Rng(pub(crate) u64);
    impl Rng {
        pub(crate) fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    /// A contact-like test system: two bodies, each an `nx` × `ny` grid of 4-node cells with
    /// random symmetric positive semi-definite cell matrices (translations cost no energy), body A on top of body B along a line of coincident node pairs
    /// joined by 2-node interface "elements" with a random unsymmetric matrix (penalty
    /// plus `slip` times an unsymmetric part). Body B is held at its bottom; body A only
    /// through the interface. `fixed_interface_nodes` additionally prescribes both dofs of
    /// some interface nodes.
    struct TestSystem {
        pattern: SparsityPattern,
        dofs: DofMap,
        continuum: Vec<f64>,
        interface: Vec<f64>,
        interface_eqs: Vec<usize>,
    }

    fn test_system(nx: usize, ny: usize, slip: f64, fixed_interface_nodes: &[usize]) -> TestSystem {
        test_system_with(nx, ny, slip, fixed_interface_nodes, false)
    }

    /// With `single_body`, body A is left out and the interface "elements" join neighbouring
    /// nodes on the top of body B instead.
    fn test_system_with(
        nx: usize,
        ny: usize,
        slip: f64,
        fixed_interface_nodes: &[usize],
        single_body: bool,
    ) -> TestSystem {
        let mut rng = Rng(12345);
        let per_body = (nx + 1) * (ny + 1);
        let node = |body: usize, i: usize, j: usize| (body * per_body + j * (nx + 1) + i) as u32;
        let mut cells: Vec<Vec<u32>> = Vec::new();
        let first_body = usize::from(single_body);
        for body in first_body..2 {
            for j in 0..ny {
                for i in 0..nx {
                    cells.push(vec![
                        node(body, i, j),
                        node(body, i + 1, j),
                        node(body, i + 1, j + 1),
                        node(body, i, j + 1),
                    ]);
                }
            }
        }
        // Interface: bottom row of body A (body 0) against top row of body B (body 1).
        let pairs: Vec<Vec<u32>> = if single_body {
            (0..nx)
                .map(|i| vec![node(1, i, ny), node(1, i + 1, ny)])
                .collect()
        } else {
            (0..=nx)
                .map(|i| vec![node(0, i, 0), node(1, i, ny)])
                .collect()
        };
        let node_count = 2 * per_body;
        let mut fixed = vec![false; 2 * node_count];
        for i in 0..=nx {
            let n = node(1, i, 0) as usize;
            fixed[2 * n] = true;
            fixed[2 * n + 1] = true;
        }
        for &i in fixed_interface_nodes {
            let n = node(0, i, 0) as usize;
            fixed[2 * n] = true;
            fixed[2 * n + 1] = true;
        }
        if single_body {
            fixed[..2 * per_body].fill(true);
        }
        let dofs = DofMap::new(&fixed);
        let pattern = SparsityPattern::new(
            node_count,
            &dofs,
            cells.iter().chain(&pairs).map(|v| v.as_slice()),
        );
        let n = dofs.free_count();
        let mut kc = Mat::<f64>::zeros(n, n);
        let mut ki = Mat::<f64>::zeros(n, n);
        let eq = |nodes: &[u32], a: usize| dofs.equation(2 * nodes[a / 2] as usize + a % 2);
        for c in &cells {
            // PSD cell matrix of rank 5 whose null space contains the two translations (as
            // a plane cell's), so that a body held only through the interface floats.
            let b = Mat::<f64>::from_fn(5, 8, |_, _| rng.next());
            let translations = Mat::<f64>::from_fn(8, 8, |a, c| {
                f64::from(u8::from(a == c)) - f64::from(u8::from(a % 2 == c % 2)) / 4.0
            });
            let b = &b * &translations;
            let k = b.transpose() * &b;
            for a in 0..8 {
                for bb in 0..8 {
                    if let (Some(r), Some(s)) = (eq(c, a), eq(c, bb)) {
                        kc[(r, s)] += k[(a, bb)];
                    }
                }
            }
        }
        for p in &pairs {
            let penalty = 3.0;
            let mut k = Mat::<f64>::zeros(4, 4);
            for d in 0..2 {
                k[(d, d)] += penalty;
                k[(2 + d, 2 + d)] += penalty;
                k[(d, 2 + d)] -= penalty;
                k[(2 + d, d)] -= penalty;
            }
            // Unsymmetric friction-like coupling: tangential force from normal motion.
            let u = slip * penalty * (1.0 + 0.5 * rng.next());
            for (row, sign) in [(0, 1.0), (2, -1.0)] {
                k[(row, 1)] += sign * u;
                k[(row, 3)] -= sign * u;
            }
            for a in 0..4 {
                for bb in 0..4 {
                    if let (Some(r), Some(s)) = (eq(p, a), eq(p, bb)) {
                        ki[(r, s)] += k[(a, bb)];
                    }
                }
            }
        }
        let sym = pattern.symbolic();
        let (mut continuum, mut interface) = (Vec::new(), Vec::new());
        for j in 0..n {
            for &i in &sym.row_idx()[sym.col_ptr()[j] as usize..sym.col_ptr()[j + 1] as usize] {
                continuum.push(kc[(i as usize, j)]);
                interface.push(ki[(i as usize, j)]);
            }
        }
        let mut interface_eqs: Vec<usize> = pairs
            .iter()
            .flat_map(|p| (0..4).filter_map(|a| eq(p, a)))
            .collect();
        interface_eqs.reverse(); // any order is accepted
        TestSystem {
            pattern,
            dofs,
            continuum,
            interface,
            interface_eqs,
        }
    }

    /// ‖b − A x‖ / ‖b‖ for A = Σ `values` over `sym`.
    fn relative_residual(
        sym: SymbolicSparseColMatRef<'_, u32>,
        values: &[&[f64]],
        x: &[f64],
        b: &[f64],
    ) -> f64 {
        let mut r = b.to_vec();
        for (j, &xj) in x.iter().enumerate() {
            for p in sym.col_range(j) {
                let a: f64 = values.iter().map(|v| v[p]).sum();
                r[sym.row_idx()[p] as usize] -= a * xj;
            }
        }
        crate::solver::newton::norm(&r) / crate::solver::newton::norm(b)
    }

    /// Solves with the condensed solver and with dense LU of the assembled matrix; returns
    /// the relative difference and the relative residual of the condensed solution.
    fn compare(t: &TestSystem, relax: Option<&[(usize, f64)]>) -> (f64, f64) {
        let mut solver =
            CondensedSolver::with_relaxation(&t.pattern, &t.interface_eqs, relax).unwrap();
        compare_with(&mut solver, t, false)
    }

    /// [`compare`] with `solver`, its bulk factored by LU if `lu`.
    fn compare_with(solver: &mut CondensedSolver, t: &TestSystem, lu: bool) -> (f64, f64) {
        compare_scaled(solver, t, lu, 1.0)
    }

    /// Factors the bulk of `t` (by LU if `lu`) and returns its interface block.
    fn factor_bulk_of(solver: &mut CondensedSolver, t: &TestSystem, lu: bool) -> Mat<f64> {
        let sym = t.pattern.symbolic().as_ref();
        let kc = SparseColMatRef::new(sym, &t.continuum);
        if lu {
            solver.factor_bulk_unsymmetric(kc).unwrap();
        } else {
            solver.factor_bulk(kc).unwrap();
        }
        let n_i = solver.interface_equations().len();
        let mut block = Mat::<f64>::zeros(n_i, n_i);
        let ki = SparseColMatRef::new(sym, &t.interface);
        solver.gather_interface_block(ki, block.as_mut()).unwrap();
        block
    }

    /// [`compare_with`] for a right-hand side whose bulk entries are scaled by `bulk_rhs`.
    fn compare_scaled(
        solver: &mut CondensedSolver,
        t: &TestSystem,
        lu: bool,
        bulk_rhs: f64,
    ) -> (f64, f64) {
        let n = t.dofs.free_count();
        let block = factor_bulk_of(solver, t, lu);
        let mut rng = Rng(777);
        let b: Vec<f64> = (0..n)
            .map(|eq| match solver.local_index(eq) {
                Some(_) => rng.next(),
                None => bulk_rhs * rng.next(),
            })
            .collect();
        solve_and_compare(solver, t, block.as_ref(), &b, &b)
    }

    /// Solves for `b` with the factored bulk and the interface `block`, and returns the
    /// relative difference from the dense LU solution for `reference_rhs` and the relative
    /// residual of that system.
    fn solve_and_compare(
        solver: &mut CondensedSolver,
        t: &TestSystem,
        block: MatRef<'_, f64>,
        b: &[f64],
        reference_rhs: &[f64],
    ) -> (f64, f64) {
        let n = t.dofs.free_count();
        let sym = t.pattern.symbolic().as_ref();
        let mut x = b.to_vec();
        solver.solve(block, &mut x).unwrap();
        // Reference: dense LU of K_c + K_if.
        let mut dense = Mat::<f64>::zeros(n, n);
        for j in 0..n {
            for (p, &i) in sym.row_idx_of_col_raw(j).iter().enumerate() {
                let p = sym.col_range(j).start + p;
                dense[(i as usize, j)] = t.continuum[p] + t.interface[p];
            }
        }
        let rhs = Mat::<f64>::from_fn(n, 1, |i, _| reference_rhs[i]);
        let reference = dense.partial_piv_lu().solve(&rhs);
        let xm = Mat::<f64>::from_fn(n, 1, |i, _| x[i]);
        let difference = (&xm - &reference).norm_l2() / reference.norm_l2();
        let residual = (&rhs - &dense * &xm).norm_l2() / rhs.norm_l2();
        (difference, residual)
    }

    /// Adds to every off-diagonal continuum entry `scale` times a random number, independently
    /// of its mirror: an unsymmetric bulk (as kinematic hardening's tangent).
    fn make_bulk_unsymmetric(t: &mut TestSystem, scale: f64) {
        let mut rng = Rng(4242);
        let sym = t.pattern.symbolic();
        for j in 0..sym.ncols() {
            for p in sym.col_range(j) {
                if sym.row_idx()[p] as usize != j {
                    t.continuum[p] += scale * rng.next();
                }
            }
        }
    }

    #[test]
    fn the_bulk_is_ordered_with_each_nodes_unknowns_together() {
        // A 3 × 3 grid of 4-node cells, 16 nodes; node 5 has its x prescribed (one unknown)
        // and node 0's unknowns are the "interface".
        let node = |i: u32, j: u32| j * 4 + i;
        let cells: Vec<Vec<u32>> = (0..3)
            .flat_map(|j| {
                (0..3).map(move |i| {
                    vec![
                        node(i, j),
                        node(i + 1, j),
                        node(i + 1, j + 1),
                        node(i, j + 1),
                    ]
                })
            })
            .collect();
        let mut fixed = vec![false; 32];
        fixed[10] = true;
        let dofs = DofMap::new(&fixed);
        let pattern = SparsityPattern::new(16, &dofs, cells.iter().map(|c| c.as_slice()));
        let bulk: Vec<u32> = (2..dofs.free_count() as u32).collect();
        let order = bulk_order(pattern.symbolic().as_ref(), &bulk).unwrap();
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, bulk, "a permutation of the bulk");
        let position = |eq: usize| order.iter().position(|&e| e as usize == eq).unwrap();
        for n in 1..16 {
            let eqs: Vec<usize> = (0..2).filter_map(|c| dofs.equation(2 * n + c)).collect();
            if n == 5 {
                assert_eq!(eqs.len(), 1);
            } else {
                assert_eq!(position(eqs[1]), position(eqs[0]) + 1, "node {n}");
            }
        }
    }

    #[test]
    fn condensed_with_an_unsymmetric_bulk_matches_dense_lu() {
        // Bulk and interface both unsymmetric; body A held only through the interface.
        let mut t = test_system(20, 4, 1.0, &[]);
        make_bulk_unsymmetric(&mut t, 0.3);
        let mut solver = CondensedSolver::new(&t.pattern, &t.interface_eqs).unwrap();
        // More interface unknowns than one block of S_c's right-hand sides.
        assert!(solver.interface_equations().len() > SCHUR_BLOCK);
        let (d, r) = compare_with(&mut solver, &t, true);
        assert!(d < 1e-10 && r < 1e-12, "difference {d:e}, residual {r:e}");
        // The same matrix again keeps the LU; a symmetric bulk next goes back to Cholesky,
        // and an unsymmetric one after it to a fresh LU.
        let sym = t.pattern.symbolic().as_ref();
        let kc = SparseColMatRef::new(sym, &t.continuum);
        assert!(
            !solver.factor_bulk_unsymmetric(kc).unwrap(),
            "unchanged: kept"
        );
        let symmetric = test_system(20, 4, 1.0, &[]);
        let (d, r) = compare_with(&mut solver, &symmetric, false);
        assert!(d < 1e-10 && r < 1e-12, "Cholesky after LU: {d:e}, {r:e}");
        let (d, r) = compare_with(&mut solver, &t, true);
        assert!(d < 1e-10 && r < 1e-12, "LU after Cholesky: {d:e}, {r:e}");
        assert_eq!(solver.factorizations(), (3, 1));
    }

    #[test]
    fn condensed_unsymmetric_bulk_with_prescribed_interface_dofs() {
        let mut t = test_system(8, 3, 1.0, &[0, 3, 8]);
        make_bulk_unsymmetric(&mut t, 0.5);
        let mut solver = CondensedSolver::new(&t.pattern, &t.interface_eqs).unwrap();
        let (d, r) = compare_with(&mut solver, &t, true);
        assert!(d < 1e-10 && r < 1e-12, "difference {d:e}, residual {r:e}");
    }

    #[test]
    fn condensed_takes_a_negligible_bulk_right_hand_side_as_zero_and_solves_others_exactly() {
        // Both bulk factorisations: Cholesky and LU.
        for lu in [false, true] {
            let mut t = test_system(6, 4, 0.3, &[]);
            if lu {
                make_bulk_unsymmetric(&mut t, 0.05);
            }
            let mut solver = CondensedSolver::new(&t.pattern, &t.interface_eqs).unwrap();
            // Balanced bulk (the forward substitution is skipped): exact.
            let (difference, residual) = compare_scaled(&mut solver, &t, lu, 0.0);
            assert!(
                difference < 1e-10 && residual < 1e-12,
                "{difference:e} {residual:e}"
            );
            // Rounding-level bulk residual, below the threshold: an inexact step whose error
            // is of the size of the residual left out.
            let (difference, residual) = compare_scaled(&mut solver, &t, lu, 1e-9);
            assert!(residual < 1e-8, "{residual:e}");
            assert!(difference < 1e-7, "{difference:e}");
            // A bulk residual that matters: solved exactly.
            let (difference, residual) = compare_scaled(&mut solver, &t, lu, 1e-4);
            assert!(
                difference < 1e-10 && residual < 1e-12,
                "{difference:e} {residual:e}"
            );
        }
    }

    #[test]
    fn condensed_drops_rounding_level_bulk_entries_and_solves_a_few_loaded_rows_exactly() {
        // A load on three bulk rows, rounding noise on every other bulk row and a residual
        // on the interface: the forward substitution visits only the loaded rows' ancestors.
        let t = test_system(12, 8, 0.3, &[]);
        let mut solver = CondensedSolver::new(&t.pattern, &t.interface_eqs).unwrap();
        let sym = t.pattern.symbolic().as_ref();
        let kc = SparseColMatRef::new(sym, &t.continuum);
        let ki = SparseColMatRef::new(sym, &t.interface);
        solver.factor_bulk(kc).unwrap();
        let n_i = solver.interface_equations().len();
        let mut block = Mat::<f64>::zeros(n_i, n_i);
        solver.gather_interface_block(ki, block.as_mut()).unwrap();
        let n = t.dofs.free_count();
        let bulk: Vec<usize> = (0..n)
            .filter(|&eq| solver.local_index(eq).is_none())
            .collect();
        let loaded = [bulk[0], bulk[bulk.len() / 2], bulk[bulk.len() - 1]];
        let mut rng = Rng(99);
        let mut noisy = vec![0.0; n];
        let mut clean = vec![0.0; n];
        for eq in 0..n {
            let interface = solver.local_index(eq).is_some();
            clean[eq] = if interface || loaded.contains(&eq) {
                rng.next() + 2.0
            } else {
                0.0
            };
            noisy[eq] = clean[eq] + 1e-13 * rng.next();
        }
        // The noise is dropped: the solution of the clean system, to rounding.
        let (difference, residual) =
            solve_and_compare(&mut solver, &t, block.as_ref(), &noisy, &clean);
        assert!(
            difference < 1e-12 && residual < 1e-13,
            "{difference:e} {residual:e}"
        );
        // An exactly sparse right-hand side: the skipped supernodes change nothing.
        let (difference, residual) =
            solve_and_compare(&mut solver, &t, block.as_ref(), &clean, &clean);
        assert!(
            difference < 1e-12 && residual < 1e-13,
            "{difference:e} {residual:e}"
        );
        // Bulk entries above the bound are kept: the noisy system itself is solved.
        let mut loud = noisy.clone();
        for eq in &bulk {
            loud[*eq] += 1e-6 * (1.5 + rng.next());
        }
        let (difference, residual) =
            solve_and_compare(&mut solver, &t, block.as_ref(), &loud, &loud);
        assert!(
            difference < 1e-10 && residual < 1e-12,
            "{difference:e} {residual:e}"
        );
    }

    #[test]
    fn condensed_matches_dense_lu_sticking() {
        let t = test_system(6, 4, 0.0, &[]);
        let (d, r) = compare(&t, None);
        assert!(d < 1e-10 && r < 1e-12, "difference {d:e}, residual {r:e}");
    }

    #[test]
    fn condensed_matches_dense_lu_strongly_unsymmetric() {
        // Interface block far from symmetric (|K − Kᵀ| comparable with |K|).
        let t = test_system(7, 5, 2.0, &[]);
        let n_i = t.interface_eqs.len();
        assert!(n_i > 0);
        let (d, r) = compare(&t, None);
        assert!(d < 1e-10 && r < 1e-12, "difference {d:e}, residual {r:e}");
    }

    #[test]
    fn condensed_matches_dense_lu_with_prescribed_interface_dofs() {
        let t = test_system(8, 3, 1.0, &[0, 3, 8]);
        assert_eq!(t.interface_eqs.len(), 2 * 9 + 2 * (9 - 3));
        let (d, r) = compare(&t, None);
        assert!(d < 1e-10 && r < 1e-12, "difference {d:e}, residual {r:e}");
    }

    #[test]
    fn condensed_handles_supernodes_straddling_the_interface_border() {
        // Merging every pair of adjacent supernodes puts bulk and interface columns into one.
        let relax: &[(usize, f64)] = &[(usize::MAX, 1.0)];
        let t = test_system_with(6, 4, 1.5, &[], true);
        let solver =
            CondensedSolver::with_relaxation(&t.pattern, &t.interface_eqs, Some(relax)).unwrap();
        let SymbolicCholeskyRaw::Supernodal(sn) = solver.symbolic.raw() else {
            unreachable!()
        };
        let straddling = (0..sn.n_supernodes())
            .filter(|&s| {
                (sn.supernode_begin()[s] as usize) < solver.n_bulk
                    && sn.supernode_end()[s] as usize > solver.n_bulk
            })
            .count();
        assert_eq!(straddling, 1);
        assert!(
            solver.schur_in_factor.is_none(),
            "S_c has a buffer of its own here"
        );
        let (d, r) = compare(&t, Some(relax));
        assert!(d < 1e-10 && r < 1e-12, "difference {d:e}, residual {r:e}");
    }

    #[test]
    fn condensed_schur_complement_in_the_factor_equals_that_of_the_lu_path_and_survives_it() {
        let t = test_system(5, 4, 0.0, &[]);
        let mut solver = CondensedSolver::new(&t.pattern, &t.interface_eqs).unwrap();
        assert!(
            solver.schur_in_factor.is_some(),
            "the interface is the last supernode"
        );
        let kc = SparseColMatRef::new(t.pattern.symbolic().as_ref(), &t.continuum);
        solver.factor_bulk(kc).unwrap();
        let in_factor = solver.schur_complement().to_owned();
        solver.factor_bulk_unsymmetric(kc).unwrap();
        let by_lu = solver.schur_complement().to_owned();
        let scale = in_factor.norm_max();
        assert!((&in_factor - &by_lu).norm_max() <= 1e-12 * scale);
        // Back on the Cholesky path, S_c is the factor's again, unchanged.
        solver.factor_bulk(kc).unwrap();
        assert_eq!(solver.schur_complement().to_owned(), in_factor);
        // Symmetric.
        assert_eq!(in_factor.transpose().to_owned(), in_factor);
    }

    #[test]
    fn condensed_reuses_the_bulk_factor_over_changing_interface_blocks() {
        let t = test_system(5, 5, 0.0, &[]);
        let sym = t.pattern.symbolic().as_ref();
        let mut solver = CondensedSolver::new(&t.pattern, &t.interface_eqs).unwrap();
        let continuum = SparseColMatRef::new(sym, &t.continuum);
        solver.factor_bulk(continuum).unwrap();
        // Factored for good (an elastic bulk): solves go on, refactorisations are refused.
        let before = solver.memory_bytes();
        solver.release_refactorisation_storage();
        assert!(solver.memory_bytes() < before);
        assert!(solver.factor_bulk(continuum).is_err());
        assert!(solver.factor_bulk_unsymmetric(continuum).is_err());
        for slip in [0.0, 0.5, 3.0] {
            let other = test_system(5, 5, slip, &[]);
            let n_i = solver.interface_equations().len();
            let mut block = Mat::<f64>::zeros(n_i, n_i);
            solver
                .gather_interface_block(SparseColMatRef::new(sym, &other.interface), block.as_mut())
                .unwrap();
            let n = t.dofs.free_count();
            let mut x: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
            let b = x.clone();
            solver.solve(block.as_ref(), &mut x).unwrap();
            let rel = relative_residual(sym, &[&t.continuum, &other.interface], &x, &b);
            assert!(rel < 1e-12, "slip {slip}: residual {rel:e}");
        }
    }

    /// A small test system, its solver with reuse threshold 0, and a bulk equation j with
    /// the position p of its diagonal entry among the matrix values.
    fn reuse_case() -> (TestSystem, CondensedSolver, usize, usize) {
        let t = test_system(5, 4, 1.0, &[]);
        let mut solver = CondensedSolver::new(&t.pattern, &t.interface_eqs).unwrap();
        solver.set_reuse_threshold(0.0);
        let sym = t.pattern.symbolic();
        let j = (0..sym.ncols())
            .find(|&j| solver.local_index(j).is_none())
            .unwrap();
        let p = sym.col_range(j).start
            + sym
                .row_idx_of_col_raw(j)
                .iter()
                .position(|&i| i as usize == j)
                .unwrap();
        (t, solver, j, p)
    }

    #[test]
    fn condensed_keeps_the_bulk_factorisation_below_the_reuse_threshold() {
        let (t, mut solver, _, p) = reuse_case();
        let sym = t.pattern.symbolic().as_ref();
        let mut kc = t.continuum.clone();
        let factor = |solver: &mut CondensedSolver, kc: &[f64]| {
            solver.factor_bulk(SparseColMatRef::new(sym, kc)).unwrap()
        };
        assert!(factor(&mut solver, &kc));
        assert!(!factor(&mut solver, &kc), "unchanged: kept");
        assert_eq!(solver.last_change(), 0.0);
        // Change the diagonal entry of a bulk unknown by a fraction ε of itself: the scaled
        // change is ε.
        let eps = 1e-3;
        kc[p] *= 1.0 + eps;
        assert!(factor(&mut solver, &kc), "threshold 0: refactored");
        assert!(
            (solver.last_change() - eps).abs() < 1e-12,
            "{}",
            solver.last_change()
        );
        // Below the threshold the factor of the previous matrix is kept: solves are exact for
        // it, not for the changed one.
        solver.set_reuse_threshold(2.0 * eps);
        let factored = kc.clone();
        kc[p] *= 1.0 + eps;
        assert!(!factor(&mut solver, &kc));
        let n_i = solver.interface_equations().len();
        let mut block = Mat::<f64>::zeros(n_i, n_i);
        solver
            .gather_interface_block(SparseColMatRef::new(sym, &t.interface), block.as_mut())
            .unwrap();
        let n = t.dofs.free_count();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
        let mut x = b.clone();
        solver.solve(block.as_ref(), &mut x).unwrap();
        let kept = relative_residual(sym, &[&factored, &t.interface], &x, &b);
        let changed = relative_residual(sym, &[&kc, &t.interface], &x, &b);
        assert!(kept < 1e-12 && changed > 1e-8, "{kept:e} {changed:e}");
        // The change is measured against the factored matrix, so it accumulates.
        kc[p] *= 1.0 + 1.5 * eps;
        assert!(factor(&mut solver, &kc));
        assert_eq!(solver.factorizations(), (3, 2));
        // A non-finite entry is a change that is never ignored.
        solver.set_reuse_threshold(f64::MAX);
        kc[p] = f64::NAN;
        assert!(solver.factor_bulk(SparseColMatRef::new(sym, &kc)).is_err());
    }

    #[test]
    fn the_change_test_looks_only_at_columns_flagged_now_or_at_the_last_factorisation() {
        let (t, mut solver, j, p) = reuse_case();
        let sym = t.pattern.symbolic().as_ref();
        let n = t.dofs.free_count();
        let mut kc = t.continuum.clone();
        let mut flags = vec![false; n];
        let factor = |solver: &mut CondensedSolver, kc: &[f64], flags: &[bool]| {
            let matrix = SparseColMatRef::new(sym, kc);
            solver.factor_bulk_varying(matrix, Some(flags)).unwrap()
        };
        assert!(factor(&mut solver, &kc, &flags));
        // Bulk column j changes and is flagged: measured as by the whole comparison.
        kc[p] *= 1.0 + 1e-3;
        flags[j] = true;
        assert!(factor(&mut solver, &kc, &flags));
        assert!((solver.last_change() - 1e-3).abs() < 1e-12);
        // Back to the reference: column j is no longer flagged now, but was for the factored
        // matrix, so the change is still seen.
        kc[p] = t.continuum[p];
        flags[j] = false;
        assert!(factor(&mut solver, &kc, &flags));
        assert!((solver.last_change() - 1e-3 / (1.0 + 1e-3)).abs() < 1e-12);
        // A change in a column flagged neither now nor then is not looked at (the assembly
        // promises there is none): the factorisation is kept.
        kc[p] *= 1.0 + 1e-3;
        assert!(!factor(&mut solver, &kc, &flags));
        assert_eq!(solver.last_change(), 0.0);
        // Without flags every column is compared.
        assert!(solver.factor_bulk(SparseColMatRef::new(sym, &kc)).unwrap());
    }

    #[test]
    fn condensed_schur_complement_is_symmetric_and_singular_for_a_floating_body() {
        let t = test_system(4, 3, 0.0, &[]);
        let sym = t.pattern.symbolic().as_ref();
        let mut solver = CondensedSolver::new(&t.pattern, &t.interface_eqs).unwrap();
        solver
            .factor_bulk(SparseColMatRef::new(sym, &t.continuum))
            .unwrap();
        let s = solver.schur_complement();
        let asym = (s - s.transpose()).norm_l2() / s.norm_l2();
        assert!(asym < 1e-13, "asymmetry {asym:e}");
        // Body A is held only through the interface: it can translate freely, so S_c (no
        // interface stiffness) has two zero eigenvalues; the rest are positive.
        let mut eig = s.to_owned().self_adjoint_eigenvalues(Side::Lower).unwrap();
        eig.sort_by(f64::total_cmp);
        let scale = eig[eig.len() - 1];
        assert!(
            eig[0].abs() < 1e-12 * scale && eig[1].abs() < 1e-12 * scale,
            "{eig:?}"
        );
        assert!(eig[2] > 1e-6 * scale, "{eig:?}");
    }

    #[test]
    fn condensed_solves_several_right_hand_sides_and_rejects_a_singular_interface() {
        let t = test_system(5, 3, 1.0, &[]);
        let sym = t.pattern.symbolic().as_ref();
        let mut solver = CondensedSolver::new(&t.pattern, &t.interface_eqs).unwrap();
        solver
            .factor_bulk(SparseColMatRef::new(sym, &t.continuum))
            .unwrap();
        let n_i = solver.interface_equations().len();
        let mut block = Mat::<f64>::zeros(n_i, n_i);
        solver
            .gather_interface_block(SparseColMatRef::new(sym, &t.interface), block.as_mut())
            .unwrap();
        solver.factor_interface(block.as_ref()).unwrap();
        let n = t.dofs.free_count();
        for k in 0..3 {
            let b: Vec<f64> = (0..n).map(|i| ((i * (k + 2)) as f64).cos()).collect();
            let mut x = b.clone();
            solver.solve_in_place(&mut x);
            let rel = relative_residual(sym, &[&t.continuum, &t.interface], &x, &b);
            assert!(rel < 1e-12, "right-hand side {k}: residual {rel:e}");
        }
        // Without interface stiffness body A floats: singular, reported as an error.
        let zero = Mat::<f64>::zeros(n_i, n_i);
        let err = solver.factor_interface(zero.as_ref()).unwrap_err();
        assert!(err.to_string().contains("singular"), "{err}");
    }

    /// The two halves of a solve, [`CondensedSolver::condense`] and
    /// [`CondensedSolver::expand`], with the interface solve between them, are
    /// [`CondensedSolver::solve_in_place`] bit for bit; and for any interface unknowns the
    /// expanded solution balances the bulk rows, K_BB x_B + K_BI x_I = r_B (Cholesky and LU
    /// bulk).
    #[test]
    fn condense_and_expand_split_a_solve_and_balance_the_bulk_for_any_interface_unknowns() {
        for unsymmetric in [false, true] {
            let mut t = test_system(5, 3, 1.0, &[]);
            if unsymmetric {
                make_bulk_unsymmetric(&mut t, 0.05);
            }
            let sym = t.pattern.symbolic().as_ref();
            let mut solver = CondensedSolver::new(&t.pattern, &t.interface_eqs).unwrap();
            let block = factor_bulk_of(&mut solver, &t, unsymmetric);
            let n_i = block.nrows();
            solver.factor_interface(block.as_ref()).unwrap();
            let n = t.dofs.free_count();
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
            let mut whole = b.clone();
            solver.solve_in_place(&mut whole);
            solver.condense(&b);
            let mut x_i = solver.condensed_rhs().to_vec();
            solver.solve_interface(&mut x_i);
            let mut split = vec![0.0; n];
            solver.expand(&x_i, &mut split);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&split), bits(&whole), "unsymmetric {unsymmetric}");
            // Any interface unknowns: the bulk rows of K_c x − b vanish.
            let v: Vec<f64> = (0..n_i).map(|k| (k as f64).cos()).collect();
            solver.condense(&b);
            solver.expand(&v, &mut split);
            let mut r = b.clone();
            for (j, &xj) in split.iter().enumerate() {
                for p in sym.col_range(j) {
                    r[sym.row_idx()[p] as usize] -= t.continuum[p] * xj;
                }
            }
            let bulk_residual = (0..n)
                .filter(|&eq| solver.local_index(eq).is_none())
                .fold(0.0f64, |m, eq| m.max(r[eq].abs()));
            assert!(
                bulk_residual < 1e-12,
                "unsymmetric {unsymmetric}: {bulk_residual:e}"
            );
        }
    }

    #[test]
    fn condensed_without_interface_is_a_cholesky_solve() {
        let t = test_system(3, 3, 0.0, &[]);
        let sym = t.pattern.symbolic().as_ref();
        // Holding body A's interface dofs through the interface block is impossible without
        // an interface; use the sum as the "continuum" (symmetric part only: slip = 0).
        let sum: Vec<f64> = t
            .continuum
            .iter()
            .zip(&t.interface)
            .map(|(a, b)| a + b)
            .collect();
        let mut solver = CondensedSolver::new(&t.pattern, &[]).unwrap();
        solver.factor_bulk(SparseColMatRef::new(sym, &sum)).unwrap();
        let n = t.dofs.free_count();
        let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let mut x = b.clone();
        solver
            .solve(Mat::<f64>::zeros(0, 0).as_ref(), &mut x)
            .unwrap();
        let rel = relative_residual(sym, &[&sum], &x, &b);
        assert!(rel < 1e-12, "residual {rel:e}");
    }
}
