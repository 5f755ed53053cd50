//! The bulk columns of the condensed solver's supernodal factor: where its interface block
//! begins, and the substitutions through its bulk columns ([`super::CondensedSolver`]).

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::{Accum, Mat, MatMut, MatRef, Par};
use std::ops::Range;
use std::sync::Mutex;

use crate::assembly::SharedMut;
use crate::solver::tree_cholesky::TreeCholesky;

/// Number of supernodes with a column in the bulk (the last one may straddle the border).
pub(super) fn bulk_supernodes(symbolic: &SymbolicSupernodalCholesky<u32>, n_bulk: usize) -> usize {
    symbolic
        .supernode_begin()
        .iter()
        .position(|&start| start as usize >= n_bulk)
        .unwrap_or(symbolic.n_supernodes())
}

/// S_c: n_I × n_I at offset `at` of the factor's values for `location = Some((at, n_I))`,
/// or `schur`.
pub(super) fn schur_of<'a>(
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
pub(super) fn trailing_supernode(
    symbolic: &SymbolicSupernodalCholesky<u32>,
    n_bulk: usize,
) -> Option<usize> {
    let last = symbolic.n_supernodes().checked_sub(1)?;
    (symbolic.supernode_begin()[last] as usize == n_bulk
        && symbolic.supernode(last).pattern().is_empty()
        && n_bulk < symbolic.nrows())
    .then_some(last)
}

/// Index of the first supernode with a column in the interface block.
pub(super) fn first_interface_supernode(
    symbolic: &SymbolicSupernodalCholesky<u32>,
    n_bulk: usize,
) -> usize {
    symbolic
        .supernode_end()
        .iter()
        .position(|&end| end as usize > n_bulk)
        .unwrap_or(symbolic.n_supernodes())
}

/// Pieces the forward substitution cuts the elimination tree into: subtrees of less than
/// 1/32 of the factorisation's work each, solved as parallel tasks. Fixed, not the number of
/// threads: the cut decides the order in which updates reach a row, so the solution has the
/// same bits on any number of threads.
const FORWARD_PIECES: usize = 32;

/// Factor entries from which the forward substitution runs its subtrees as parallel tasks
/// (~8 MB of factor, some 20 k unknowns): below it a substitution takes about a millisecond,
/// which the tasks' bookkeeping would not shorten.
const FORWARD_PARALLEL_FROM: usize = 1 << 20;

/// How the forward substitution splits the tree ([`forward_bulk`]): subtrees as parallel
/// tasks, each pushing the updates of its supernodes into its own columns and those of the
/// rows above it into a buffer of its own, the buffers then subtracted in task order, and
/// the supernodes above the subtrees after them, one after the other.
#[derive(Debug)]
pub(super) struct ForwardPlan {
    /// The subtrees: their supernodes and their columns (both consecutive, increasing).
    tasks: Vec<(Range<usize>, Range<usize>)>,
    /// The supernodes above them, increasing.
    above: Vec<usize>,
    /// The columns of the supernodes above, and the position of each column among them
    /// (`u32::MAX` for the others).
    above_columns: Vec<u32>,
    above_position: Vec<u32>,
    /// Per task: its buffer over `above_columns` and a gather buffer (`gather_len`).
    buffers: Vec<f64>,
    gathers: Vec<f64>,
    gather_len: usize,
}

impl ForwardPlan {
    /// The plan of the factor `symbolic` with the schedule `tree` (gather buffers of
    /// `gather_len`): one sequence of all supernodes for a small factor or a tree out of
    /// postorder.
    pub(super) fn new(
        symbolic: &SymbolicSupernodalCholesky<u32>,
        tree: &TreeCholesky,
        gather_len: usize,
    ) -> Self {
        let pieces = (symbolic.len_val() >= FORWARD_PARALLEL_FROM).then_some(FORWARD_PIECES);
        Self::cut_into(symbolic, tree, gather_len, pieces)
    }

    /// [`Self::new`] cut into `pieces` subtrees (`None`: one sequence).
    pub(super) fn cut_into(
        symbolic: &SymbolicSupernodalCholesky<u32>,
        tree: &TreeCholesky,
        gather_len: usize,
        pieces: Option<usize>,
    ) -> Self {
        let all = || (Vec::new(), (0..symbolic.n_supernodes()).collect());
        let (subtrees, above) = match pieces {
            Some(pieces) => tree.cut(pieces).unwrap_or_else(all),
            None => all(),
        };
        tracing::debug!(
            subtrees = subtrees.len(),
            supernodes_above = above.len(),
            "forward substitution plan"
        );
        let (begin, end) = (symbolic.supernode_begin(), symbolic.supernode_end());
        let columns = |s: &Range<usize>| begin[s.start] as usize..end[s.end - 1] as usize;
        let tasks: Vec<_> = (subtrees.into_iter())
            .map(|s| {
                let c = columns(&s);
                (s, c)
            })
            .collect();
        let mut above_position = vec![u32::MAX; symbolic.nrows()];
        let mut above_columns = Vec::new();
        for &s in &above {
            let columns = begin[s] as usize..end[s] as usize;
            for (slot, column) in above_position[columns.clone()].iter_mut().zip(columns) {
                *slot = above_columns.len() as u32;
                above_columns.push(column as u32);
            }
        }
        Self {
            buffers: vec![0.0; tasks.len() * above_columns.len()],
            gathers: vec![0.0; tasks.len() * gather_len],
            tasks,
            above,
            above_columns,
            above_position,
            gather_len,
        }
    }

    /// Number of subtrees run as parallel tasks.
    #[cfg(test)]
    pub(super) fn subtrees(&self) -> usize {
        self.tasks.len()
    }

    /// Bytes of its storage.
    pub(super) fn memory_bytes(&self) -> usize {
        8 * (self.buffers.len() + self.gathers.len())
            + 4 * (self.above_columns.len() + self.above_position.len())
    }
}

/// Forward substitution with the bulk columns of the factor: x_B ← L_BB⁻¹ x_B and
/// x_I ← x_I − L_IB x_B, by `plan`. A supernode writes its rows' updates into the solution,
/// or, for the rows above its subtree, into its task's buffer; every row receives the same
/// updates in the same order on any number of threads. Supernodes whose right-hand side is
/// zero are skipped: a right-hand side on a few rows costs the paths from them to the root.
pub(super) fn forward_bulk(
    llt: SupernodalLltRef<'_, u32, f64>,
    plan: &mut ForwardPlan,
    n_bulk: usize,
    x: &mut [f64],
    gather: &mut [f64],
) {
    let bulk = bulk_supernodes(llt.symbolic(), n_bulk);
    let n_above = plan.above_columns.len();
    if !plan.tasks.is_empty() {
        let first = plan.tasks[0].1.start;
        let tasks = Tasks {
            llt,
            bulk,
            n_bulk,
            above_position: &plan.above_position,
            gather_len: plan.gather_len,
        };
        tasks.run(
            &plan.tasks,
            &mut x[first..],
            first,
            &mut plan.buffers,
            &mut plan.gathers,
        );
        for buffer in plan.buffers.chunks_exact_mut(n_above.max(1)) {
            for (v, &c) in buffer.iter_mut().zip(&plan.above_columns) {
                x[c as usize] -= *v;
                *v = 0.0;
            }
        }
    }
    for &s in plan.above.iter().filter(|&&s| s < bulk) {
        forward_supernode(llt, s, n_bulk, x, 0, gather, &mut |x, row, v| x[row] -= v);
    }
}

/// The subtree tasks of a forward substitution ([`forward_bulk`]).
struct Tasks<'a> {
    llt: SupernodalLltRef<'a, u32, f64>,
    bulk: usize,
    n_bulk: usize,
    above_position: &'a [u32],
    gather_len: usize,
}

impl Tasks<'_> {
    /// Runs `tasks`, whose columns `x` holds from column `offset` on, each with its buffer
    /// over the columns above (consecutive in `buffers`) and its gather buffer: halves in
    /// parallel.
    fn run(
        &self,
        tasks: &[(Range<usize>, Range<usize>)],
        x: &mut [f64],
        offset: usize,
        buffers: &mut [f64],
        gathers: &mut [f64],
    ) {
        let per_task = buffers.len() / tasks.len().max(1);
        if let [(supernodes, columns)] = tasks {
            let own = &mut x[..columns.end - offset];
            let mut scatter = |x: &mut [f64], row: usize, v: f64| {
                if row < columns.end {
                    x[row - offset] -= v;
                } else {
                    buffers[self.above_position[row] as usize] += v;
                }
            };
            for s in supernodes.clone().filter(|&s| s < self.bulk) {
                forward_supernode(self.llt, s, self.n_bulk, own, offset, gathers, &mut scatter);
            }
            return;
        }
        let half = tasks.len() / 2;
        let split = tasks[half].1.start - offset;
        let (x_low, x_high) = x.split_at_mut(split);
        let (b_low, b_high) = buffers.split_at_mut(half * per_task);
        let (g_low, g_high) = gathers.split_at_mut(half * self.gather_len);
        rayon::join(
            || self.run(&tasks[..half], x_low, offset, b_low, g_low),
            || self.run(&tasks[half..], x_high, offset + split, b_high, g_high),
        );
    }
}

/// The forward substitution of bulk supernode `s` in `x` (which holds the solution from
/// column `offset` on, up to the supernode's columns at least), its updates of the rows
/// below its columns given to `scatter(x, row, value)` to subtract.
fn forward_supernode(
    llt: SupernodalLltRef<'_, u32, f64>,
    s: usize,
    n_bulk: usize,
    x: &mut [f64],
    offset: usize,
    gather: &mut [f64],
    scatter: &mut impl FnMut(&mut [f64], usize, f64),
) {
    let node = llt.supernode(s);
    let (start, ls, pattern) = (node.start(), node.val(), node.pattern());
    let width = ls.ncols();
    // Columns of this supernode in the bulk (all of them unless it straddles the border).
    let k = width.min(n_bulk - start);
    let local = start - offset;
    if x[local..local + k].iter().all(|&v| v == 0.0) {
        // Nothing to eliminate: the supernode's solution is zero and updates nothing.
        return;
    }
    let (head, tail) = x.split_at_mut(local + k);
    let mut x_top = MatMut::from_column_major_slice_mut(&mut head[local..], k, 1);
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
        scatter(x, row as usize, v);
    }
}

/// Backward substitution with the bulk columns of the factor, x_I holding the interface
/// solution: x_B ← L_BB⁻ᵀ (x_B − L_IBᵀ x_I). Sibling subtrees of the elimination tree share
/// no columns, so they run as parallel tasks ([`TreeCholesky::top_down`]), each supernode
/// after its ancestors; every supernode is computed by the same operations whichever task
/// runs it, so the result has the same bits on any number of threads. `gathers`: the tasks'
/// gather buffers (`gather_len`, the longest row pattern of a supernode, each).
pub(super) fn backward_bulk(
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
