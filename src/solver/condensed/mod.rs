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
use faer::sparse::linalg::SymbolicSupernodalParams;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Mat, MatMut, MatRef, Par};
use std::sync::Mutex;

use crate::assembly::SparsityPattern;
use crate::solver::interface_lu::InterfaceLu;
use crate::solver::tree_cholesky::TreeCholesky;
use crate::{Error, Result};

mod supernodal;
mod symbolic;
mod unsymmetric;

use supernodal::{
    ForwardPlan, backward_bulk, first_interface_supernode, forward_bulk, schur_of,
    trailing_supernode,
};
use unsymmetric::UnsymmetricBulk;

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
    symbolic: SymbolicSupernodalCholesky<u32>,
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
    /// Set by [`Self::stop_reuse_in_increment`], cleared by [`Self::start_increment`]: until
    /// then every factorisation request keeps the factor only for an unchanged matrix.
    reuse_stopped: bool,
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
    /// How the forward substitution splits the tree into parallel tasks.
    forward: ForwardPlan,
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
    /// Whether negligible bulk right-hand side entries are dropped (Newton's steps, the
    /// default), or every right-hand side is solved as given ([`Self::solve_exactly`]).
    inexact_rhs: bool,
    /// The LU path of an unsymmetric bulk, made by the first
    /// [`Self::factor_bulk_unsymmetric`], and whether the bulk factor is its LU.
    unsymmetric: Option<Box<UnsymmetricBulk>>,
    lu_bulk: bool,
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
        .map_err(|_| Error::allocation_failed("the AMD ordering", n))?;
    amd::order_maybe_unsorted(
        &mut amd_fwd,
        &mut amd_inv,
        q_pattern,
        Default::default(),
        MemStack::new(&mut mem),
    )
    .map_err(|e| crate::solver::faer_error(e, "the AMD ordering", n))?;
    Ok(amd_fwd
        .iter()
        .flat_map(|&s| first[s as usize]..first[s as usize + 1])
        .map(|k| bulk[k as usize])
        .collect())
}

/// What a condensed solver's matrix is, for its messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SystemKind {
    /// The bodies' stiffness, condensed onto the interface elements' unknowns.
    Mechanical,
    /// The conductivity matrix, condensed onto the conducting joints' nodes.
    Conduction,
}

/// The parts of the condensed solver's storage, for a message: the sparse factor's `sparse`
/// bytes and the `dense` bytes of the interface system of `n_i` unknowns (which the Krylov
/// path of the mechanics does without, named when it is the larger part).
fn storage_parts(kind: SystemKind, sparse: u64, dense: u64, n_i: usize) -> String {
    let gb = crate::memory::gigabytes;
    let (matrix, unknowns) = match kind {
        SystemKind::Mechanical => ("the bodies' stiffness", "interface unknowns"),
        SystemKind::Conduction => ("the heat conduction", "joint nodes"),
    };
    let parts = format!(
        "the sparse factor of {matrix} {:.2} GB, the dense system of the {n_i} {unknowns} \
         {:.2} GB",
        gb(sparse),
        gb(dense)
    );
    if dense > sparse && kind == SystemKind::Mechanical {
        format!("{parts}; `[solver] linear_solver = \"krylov\"` needs no dense interface system")
    } else {
        parts
    }
}

impl CondensedSolver {
    /// Symbolic analysis, once per model: orders the bulk (AMD on K_BB) with the interface
    /// equations `interface` (free equation numbers of the interface nodes, any order,
    /// duplicates allowed) last, factors symbolically, and allocates every buffer.
    pub fn new(pattern: &SparsityPattern, interface: &[usize]) -> Result<Self> {
        Self::with_relaxation(pattern, interface, None, SystemKind::Mechanical)
    }

    /// [`Self::new`] for a conductivity matrix condensed onto the conducting joints' nodes
    /// `joints` (its messages name the heat conduction).
    pub fn for_conduction(pattern: &SparsityPattern, joints: &[usize]) -> Result<Self> {
        Self::with_relaxation(pattern, joints, None, SystemKind::Conduction)
    }

    /// [`Self::new`] with faer's supernode relaxation thresholds `relax` (`None`: faer's
    /// defaults), for tests of supernodes straddling the bulk–interface border.
    fn with_relaxation(
        pattern: &SparsityPattern,
        interface: &[usize],
        relax: Option<&[(usize, f64)]>,
        kind: SystemKind,
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

        // Lower triangle of the reordered matrix: count per column, then the row indices in
        // the traversal order that `factor_bulk` repeats; and in the same passes its upper
        // triangle (the transpose), which the symbolic analysis reads.
        let mut lower_col_ptr = vec![0u32; n + 1];
        let mut upper_col_ptr = vec![0u32; n + 1];
        for_each_lower(global.as_ref(), &position, |col, row, _| {
            lower_col_ptr[col + 1] += 1;
            upper_col_ptr[row + 1] += 1;
        });
        for c in 0..n {
            lower_col_ptr[c + 1] += lower_col_ptr[c];
            upper_col_ptr[c + 1] += upper_col_ptr[c];
        }
        let nnz_lower = lower_col_ptr[n] as usize;
        let mut lower_row_idx = vec![0u32; nnz_lower];
        let mut upper_row_idx = vec![0u32; nnz_lower];
        let mut source = vec![0u32; nnz_lower];
        let mut fill: Vec<u32> = lower_col_ptr[..n].to_vec();
        let mut upper_fill: Vec<u32> = upper_col_ptr[..n].to_vec();
        let mut diagonal = vec![u32::MAX; n];
        for_each_lower(global.as_ref(), &position, |col, row, p| {
            let slot = fill[col] as usize;
            lower_row_idx[slot] = row as u32;
            source[slot] = p as u32;
            fill[col] += 1;
            upper_row_idx[upper_fill[row] as usize] = col as u32;
            upper_fill[row] += 1;
            if row == col {
                diagonal[col] = slot as u32;
            }
        });
        drop((fill, upper_fill));
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
        let upper =
            SymbolicSparseColMat::new_unsorted_checked(n, n, upper_col_ptr, None, upper_row_idx);
        let supernodal = symbolic::supernodal_symbolic(
            lower.as_ref(),
            upper.as_ref(),
            match relax {
                Some(relax) => SymbolicSupernodalParams { relax: Some(relax) },
                None => Default::default(),
            },
        )?;
        drop(upper);

        // The factor, the reordered matrix's values, S_c (when not in the factor) and the
        // interface LU: what is allocated below, refused if it cannot fit.
        let schur_in_factor = trailing_supernode(&supernodal, n_bulk)
            .map(|s| supernodal.col_ptr_for_val()[s] as usize);
        let sparse = 8 * (supernodal.len_val() + nnz_lower + 2 * n) as u64;
        let dense = 8 * (n_i * n_i) as u64 * if schur_in_factor.is_some() { 1 } else { 2 };
        let what = || storage_parts(kind, sparse, dense, n_i);
        crate::solver::ensure_memory(what, n, sparse + dense)?;
        // One thread for the bulk factorisation: see `BULK_FACTOR_PARALLELISM`.
        let par = BULK_FACTOR_PARALLELISM;
        let gather_len = (0..supernodal.n_supernodes())
            .map(|s| supernodal.supernode(s).pattern().len())
            .max()
            .unwrap_or(0);
        let factor = vec![0.0; supernodal.len_val()];
        let tree = TreeCholesky::new(&supernodal, rayon::current_num_threads());
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
            reuse_stopped: false,
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
            forward: ForwardPlan::new(&supernodal, &tree, gather_len),
            gather: vec![0.0; gather_len],
            backward_gathers: Mutex::new(Vec::new()),
            par,
            tree,
            symbolic: supernodal,
            factored: false,
            released: false,
            interface_factored: false,
            balanced_bulk: false,
            inexact_rhs: true,
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
    /// max_ij |K_ij − K̃_ij| / √(|K̃_ii| |K̃_jj|) ≤ τ. τ = 0 keeps it only for an
    /// unchanged matrix; τ > 0 makes Newton a chord (inexact Newton) iteration with the exact
    /// residual while the change stays below τ (see docs/theory.md, "Reusing the bulk
    /// factorisation"), unless [`Self::stop_reuse_in_increment`]. Default
    /// [`DEFAULT_REUSE_THRESHOLD`].
    pub fn set_reuse_threshold(&mut self, threshold: f64) {
        self.reuse_threshold = threshold.max(0.0);
    }

    /// Solves every right-hand side as given, dropping no negligible bulk entry (by default
    /// a bulk part below 1e-6 of the interface part, and entries below 1e-9 of the largest,
    /// are dropped: an inexact Newton step): for a linear problem solved once, not iterated
    /// to a residual tolerance.
    pub fn solve_exactly(&mut self) {
        self.inexact_rhs = false;
    }

    /// Marks the start of a load increment: the next [`Self::factor_bulk`] keeps the last
    /// factorisation only for an unchanged matrix. Every increment then starts from a factor
    /// of its own first tangent, whatever earlier increments factored, so a run resumed from
    /// a restart record (which cannot hold the factor) repeats the uninterrupted run bit for
    /// bit.
    pub fn start_increment(&mut self) {
        self.increment_started = true;
        self.reuse_stopped = false;
    }

    /// Keeps the factor only for an unchanged matrix until the next [`Self::start_increment`]:
    /// for a Newton iteration whose chord step (a kept factor of another matrix) did not
    /// contract. The change measure of [`Self::factor_bulk`] is a proxy of the chord rate that
    /// can fail by orders of magnitude: a nearly incompressible body's diagonal carries its
    /// bulk modulus, so losing all its shear stiffness to yielding shows as a change of
    /// G/λ ~ 1e-5 (ν = 0.49999).
    pub fn stop_reuse_in_increment(&mut self) {
        self.reuse_stopped = true;
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
            + self.forward.memory_bytes()
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
        let symbolic = &self.symbolic;
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
        // An increment's first call keeps only a factor of the same matrix; the later ones
        // of the increment compare with its own factorisations. Cleared before the first
        // factorisation returns too: a resumed run factors first where the uninterrupted one
        // compared, and its next call must decide alike (it kept the factor at the next
        // iteration where the resumed run made a new one: different bits after --resume).
        let threshold = if self.increment_started || self.reuse_stopped {
            0.0
        } else {
            self.reuse_threshold
        };
        self.increment_started = false;
        if !self.factored {
            return Ok(false);
        }
        let change = match (lu, self.lu_bulk) {
            (false, false) => self.change_from_factored(continuum.val()),
            (true, true) => self.change_from_factored_lu(continuum.val()),
            _ => f64::INFINITY,
        };
        self.last_change = change;
        if change <= threshold {
            self.reuses += 1;
            tracing::debug!(change, "bulk factorisation kept");
            return Ok(true);
        }
        tracing::debug!(change, "bulk refactored");
        Ok(false)
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
        self.balanced_bulk =
            self.inexact_rhs && drop_negligible_bulk_entries(&mut self.x, self.n_bulk);
        if self.balanced_bulk {
            return;
        }
        let n_bulk = self.n_bulk;
        if self.lu_bulk {
            let u = self.unsymmetric.as_deref_mut().expect("LU made");
            let (x_b, x_i) = self.x.split_at_mut(n_bulk);
            u.eliminate_bulk(x_b, x_i);
        } else {
            let llt = SupernodalLltRef::new(&self.symbolic, &self.factor);
            forward_bulk(
                llt,
                &mut self.forward,
                n_bulk,
                &mut self.x,
                &mut self.gather,
            );
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
            u.back_substitute(x_b, x_i);
        } else {
            let llt = SupernodalLltRef::new(&self.symbolic, &self.factor);
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

#[cfg(test)]
pub(crate) mod tests;
