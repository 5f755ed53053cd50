//! The bulk columns of the condensed solver's supernodal factor: where its interface block
//! begins, and the substitutions through its bulk columns ([`super::CondensedSolver`]).

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::{Accum, Mat, MatMut, MatRef, Par};
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

/// Forward substitution with the bulk columns of the factor: x_B ← L_BB⁻¹ x_B and
/// x_I ← x_I − L_IB x_B.
pub(super) fn forward_bulk(
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
