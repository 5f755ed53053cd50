//! The symbolic Cholesky analysis of the reordered continuum matrix from its triangles:
//! the elimination tree and the factor's column counts, computed here in time proportional to
//! the matrix's entries, then faer's supernodal structure from them.
//!
//! faer's `factorize_symbolic_cholesky` permutes the whole pattern (both triangles) once
//! more and counts each column of the factor by walking every row subtree of the elimination
//! tree, which visits each entry of the factor: at 3.84 M unknowns (822 M factor entries)
//! 3.7 s, on the critical path of a run (the ordering and this analysis run beside the bulk
//! assembly, which finishes first). Here the elimination tree comes from Liu's algorithm
//! with path compression and the column counts from the skeleton of the row subtrees
//! (Gilbert, Ng & Peyton 1994; T. A. Davis, *Direct Methods for Sparse Linear Systems*,
//! SIAM 2006, §4.1–4.5), over the lower triangle the condensed solver builds anyway and the
//! upper one it builds in the same passes: O(nnz(A) α(n)) instead of O(nnz(L)). They are the same tree and counts as
//! faer's (tests below), so the supernodes are too.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::SymbolicSupernodalParams;
use faer::sparse::linalg::cholesky::simplicial::EliminationTreeRef;
use faer::sparse::linalg::cholesky::supernodal::{
    SymbolicSupernodalCholesky, factorize_supernodal_symbolic_cholesky,
    factorize_supernodal_symbolic_cholesky_scratch,
};

use crate::{Error, Result};

/// No parent (a root of the elimination forest), no entry yet.
const NONE: i32 = -1;

/// The supernodal symbolic Cholesky factorisation of the symmetric n × n matrix whose lower
/// and upper triangles (each with the diagonal, CSC, rows in any order) have the patterns
/// `lower` and `upper`, with faer's supernode relaxation `params`.
pub(super) fn supernodal_symbolic(
    lower: SymbolicSparseColMatRef<'_, u32>,
    upper: SymbolicSparseColMatRef<'_, u32>,
    params: SymbolicSupernodalParams<'_>,
) -> Result<SymbolicSupernodalCholesky<u32>> {
    let n = lower.ncols();
    if i32::try_from(n).is_err() {
        return Err(Error::Linear(format!(
            "{n} unknowns are more than the symbolic analysis can index"
        )));
    }
    let parent = elimination_tree(upper);
    let post = postorder(&parent);
    let col_counts = column_counts(lower, &parent, &post);
    drop(post);
    let mut mem = MemBuffer::try_new(factorize_supernodal_symbolic_cholesky_scratch::<u32>(n))
        .map_err(|_| Error::allocation_failed("the symbolic factorisation", n))?;
    // SAFETY: `parent` is the elimination tree of `upper`'s matrix, each node's parent after
    // it and roots −1, as faer's `prefactorize_symbolic_cholesky` fills it (tests below).
    let etree = unsafe { EliminationTreeRef::<u32>::from_inner(&parent) };
    factorize_supernodal_symbolic_cholesky(
        upper,
        etree,
        &col_counts,
        MemStack::new(&mut mem),
        params,
    )
    .map_err(|e| crate::solver::faer_error(e, "the symbolic Cholesky factorisation", n))
}

/// The elimination tree of the symmetric matrix with upper triangle `upper` (CSC): parent of
/// each column, −1 for a root. Liu's algorithm: column k's entries above the diagonal reach,
/// through their virtual ancestors (path-compressed), the roots of the subtrees k joins.
fn elimination_tree(upper: SymbolicSparseColMatRef<'_, u32>) -> Vec<i32> {
    let n = upper.ncols();
    let (cp, ri) = (upper.col_ptr(), upper.row_idx());
    let mut parent = vec![NONE; n];
    let mut ancestor = vec![NONE; n];
    for k in 0..n {
        for &i in &ri[cp[k] as usize..cp[k + 1] as usize] {
            let mut i = i as i32;
            while i != NONE && (i as usize) < k {
                let next = ancestor[i as usize];
                ancestor[i as usize] = k as i32;
                if next == NONE {
                    parent[i as usize] = k as i32;
                }
                i = next;
            }
        }
    }
    parent
}

/// A postorder of the forest `parent` (children before their parent, each subtree
/// consecutive; children visited in increasing order).
fn postorder(parent: &[i32]) -> Vec<u32> {
    let n = parent.len();
    // Children lists, built backwards so that each list is increasing.
    let mut head = vec![NONE; n];
    let mut next = vec![NONE; n];
    for j in (0..n).rev() {
        if parent[j] != NONE {
            let p = parent[j] as usize;
            next[j] = head[p];
            head[p] = j as i32;
        }
    }
    let mut post = Vec::with_capacity(n);
    let mut stack = Vec::new();
    for root in (0..n).filter(|&j| parent[j] == NONE) {
        stack.push(root as i32);
        while let Some(&top) = stack.last() {
            let child = head[top as usize];
            if child == NONE {
                stack.pop();
                post.push(top as u32);
            } else {
                head[top as usize] = next[child as usize];
                stack.push(child);
            }
        }
    }
    post
}

/// The number of entries (with the diagonal) of each column of the Cholesky factor of the
/// symmetric matrix with lower triangle `lower`, elimination tree `parent` and its postorder
/// `post`.
///
/// Row i of the factor is the row subtree of i: the tree paths from the columns j < i of
/// row i of the matrix up to i. Column j's count is the number of row subtrees holding j.
/// Processing the columns in postorder, an entry (i, j) whose j is a leaf of row subtree i
/// (none of j's descendants is in row i: `first[j]` beyond the largest `first` seen for i)
/// adds one to j's count, and one less at the least common ancestor of j and the previous
/// leaf of the same row subtree (where the two paths join; found through path-compressed
/// sets of processed nodes); every non-root subtracts one at its parent. The count of a
/// column is then the sum of these differences over its subtree.
fn column_counts(
    lower: SymbolicSparseColMatRef<'_, u32>,
    parent: &[i32],
    post: &[u32],
) -> Vec<u32> {
    let n = parent.len();
    let (cp, ri) = (lower.col_ptr(), lower.row_idx());
    // first[j]: the postorder index of j's first descendant (itself for a leaf).
    let mut first = vec![NONE; n];
    let mut delta = vec![0i64; n];
    for (k, &j) in post.iter().enumerate() {
        let mut j = j as i32;
        delta[j as usize] = i64::from(first[j as usize] == NONE);
        while j != NONE && first[j as usize] == NONE {
            first[j as usize] = k as i32;
            j = parent[j as usize];
        }
    }
    let mut max_first = vec![NONE; n];
    let mut previous_leaf = vec![NONE; n];
    let mut ancestor: Vec<u32> = (0..n as u32).collect();
    for &j in post {
        let j = j as usize;
        if parent[j] != NONE {
            delta[parent[j] as usize] -= 1;
        }
        for &i in &ri[cp[j] as usize..cp[j + 1] as usize] {
            let i = i as usize;
            if i <= j || first[j] <= max_first[i] {
                continue; // j is not a leaf of row subtree i
            }
            max_first[i] = first[j];
            let previous = std::mem::replace(&mut previous_leaf[i], j as i32);
            delta[j] += 1;
            if previous != NONE {
                let q = find_root(&mut ancestor, previous as u32);
                delta[q as usize] -= 1;
            }
        }
        if parent[j] != NONE {
            ancestor[j] = parent[j] as u32;
        }
    }
    // Parents come after their children.
    for j in 0..n {
        if parent[j] != NONE {
            delta[parent[j] as usize] += delta[j];
        }
    }
    delta.into_iter().map(|c| c as u32).collect()
}

/// The root of `node`'s set, every node on the way pointed at it.
fn find_root(ancestor: &mut [u32], node: u32) -> u32 {
    let mut root = node;
    while ancestor[root as usize] != root {
        root = ancestor[root as usize];
    }
    let mut s = node;
    while s != root {
        let next = ancestor[s as usize];
        ancestor[s as usize] = root;
        s = next;
    }
    root
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::linalg::cholesky::simplicial::{
        prefactorize_symbolic_cholesky, prefactorize_symbolic_cholesky_scratch,
    };

    /// Lower triangle (CSC, rows increasing, with the diagonal) of the symmetric pattern
    /// with the off-diagonal entries `edges`.
    fn lower(n: usize, edges: &[(usize, usize)]) -> (Vec<u32>, Vec<u32>) {
        let mut cols: Vec<Vec<u32>> = (0..n).map(|j| vec![j as u32]).collect();
        for &(a, b) in edges {
            let (j, i) = (a.min(b), a.max(b));
            cols[j].push(i as u32);
        }
        let mut col_ptr = vec![0u32];
        let mut row_idx = Vec::new();
        for mut c in cols {
            c.sort_unstable();
            c.dedup();
            row_idx.extend(c);
            col_ptr.push(row_idx.len() as u32);
        }
        (col_ptr, row_idx)
    }

    /// The upper triangle (CSC) of the symmetric matrix whose lower triangle is `lower`: its
    /// transpose, each column's rows increasing.
    fn transpose(lower: SymbolicSparseColMatRef<'_, u32>) -> (Vec<u32>, Vec<u32>) {
        let n = lower.ncols();
        let (cp, ri) = (lower.col_ptr(), lower.row_idx());
        let mut col_ptr = vec![0u32; n + 1];
        for &i in ri {
            col_ptr[i as usize + 1] += 1;
        }
        for j in 0..n {
            col_ptr[j + 1] += col_ptr[j];
        }
        let mut fill: Vec<u32> = col_ptr[..n].to_vec();
        let mut row_idx = vec![0u32; ri.len()];
        for j in 0..n {
            for &i in &ri[cp[j] as usize..cp[j + 1] as usize] {
                let slot = &mut fill[i as usize];
                row_idx[*slot as usize] = j as u32;
                *slot += 1;
            }
        }
        (col_ptr, row_idx)
    }

    /// faer's elimination tree and column counts of the same matrix.
    fn faer_tree_and_counts(upper: SymbolicSparseColMatRef<'_, u32>) -> (Vec<i32>, Vec<u32>) {
        let n = upper.ncols();
        let mut etree = vec![0i32; n];
        let mut counts = vec![0u32; n];
        let mut mem = MemBuffer::new(prefactorize_symbolic_cholesky_scratch::<u32>(
            n,
            upper.row_idx().len(),
        ));
        prefactorize_symbolic_cholesky(&mut etree, &mut counts, upper, MemStack::new(&mut mem));
        (etree, counts)
    }

    /// Pseudo-random graphs: a 2D grid of 2-unknown nodes with quadratic-element-like
    /// couplings, renumbered; a random sparse graph; a forest of paths.
    fn cases() -> Vec<(usize, Vec<(usize, usize)>)> {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut random = move |m: usize| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % m as u64) as usize
        };
        let (nx, ny) = (9, 7);
        let nodes = nx * ny;
        let mut perm: Vec<usize> = (0..nodes).collect();
        for k in (1..nodes).rev() {
            perm.swap(k, random(k + 1));
        }
        let mut grid = Vec::new();
        for y in 0..ny {
            for x in 0..nx {
                let a = perm[y * nx + x];
                let near = [(1, 0), (0, 1), (1, 1), (2, 0), (0, 2)];
                for (dx, dy) in near {
                    if x + dx < nx && y + dy < ny {
                        let b = perm[(y + dy) * nx + x + dx];
                        for (da, db) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                            grid.push((2 * a + da, 2 * b + db));
                        }
                    }
                }
                grid.push((2 * a, 2 * a + 1));
            }
        }
        let n = 200;
        let sparse = (0..600).map(|_| (random(n), random(n))).collect();
        let paths = vec![(0, 3), (3, 5), (1, 2), (7, 9), (9, 8)];
        vec![(2 * nodes, grid), (n, sparse), (10, paths), (1, vec![])]
    }

    #[test]
    fn tree_and_counts_are_faers() {
        for (n, edges) in cases() {
            let (lcp, lri) = lower(n, &edges);
            let lower = SymbolicSparseColMatRef::new_unsorted_checked(n, n, &lcp, None, &lri);
            let (ucp, uri) = transpose(lower);
            let upper = SymbolicSparseColMatRef::new_unsorted_checked(n, n, &ucp, None, &uri);
            let parent = elimination_tree(upper);
            let post = postorder(&parent);
            let mut seen = vec![false; n];
            for &j in &post {
                let j = j as usize;
                assert!(!seen[j], "postorder repeats {j}");
                seen[j] = true;
                if parent[j] != NONE {
                    assert!(!seen[parent[j] as usize], "{j} after its parent");
                }
            }
            assert_eq!(post.len(), n);
            let counts = column_counts(lower, &parent, &post);
            assert_eq!((parent, counts), faer_tree_and_counts(upper), "n = {n}");
        }
    }

    #[test]
    fn supernodes_are_faers() {
        use faer::perm::PermRef;
        use faer::sparse::linalg::SupernodalThreshold;
        use faer::sparse::linalg::cholesky::{
            CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering,
            factorize_symbolic_cholesky,
        };
        for (n, edges) in cases() {
            let (lcp, lri) = lower(n, &edges);
            let lower = SymbolicSparseColMatRef::new_unsorted_checked(n, n, &lcp, None, &lri);
            let (ucp, uri) = transpose(lower);
            let upper = SymbolicSparseColMatRef::new_unsorted_checked(n, n, &ucp, None, &uri);
            let ours = supernodal_symbolic(lower, upper, Default::default()).unwrap();
            let identity: Vec<u32> = (0..n as u32).collect();
            let theirs = factorize_symbolic_cholesky(
                lower,
                faer::Side::Lower,
                SymmetricOrdering::Custom(PermRef::new_checked(&identity, &identity, n)),
                CholeskySymbolicParams {
                    supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                    ..Default::default()
                },
            )
            .unwrap();
            let SymbolicCholeskyRaw::Supernodal(theirs) = theirs.raw() else {
                panic!("forced supernodal");
            };
            assert_eq!(ours.supernode_begin(), theirs.supernode_begin());
            assert_eq!(ours.supernode_end(), theirs.supernode_end());
            assert_eq!(ours.col_ptr_for_val(), theirs.col_ptr_for_val());
            for s in 0..ours.n_supernodes() {
                assert_eq!(ours.supernode(s).pattern(), theirs.supernode(s).pattern());
            }
        }
    }
}
