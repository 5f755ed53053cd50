//! The dense LU of the condensed interface system A = S_c + K_if of
//! [`crate::solver::condensed`], by blocks where the continuum Schur complement S_c is block
//! diagonal.
//!
//! S_c couples two interface unknowns only through the bulk of a body: the unknowns of
//! different bodies (the two sides of a joint) are not coupled, and with twist neither are
//! the circumferential unknowns of elastic bodies to their meridional ones (their stiffness
//! separates, see `assembly::ElementNodes`). Only K_if couples such groups, and it is sparse:
//! an interface element joins a few neighbouring nodes across the joint. So the interface
//! unknowns fall into groups — the connected components of S_c's nonzero pattern — and with
//! a set E of groups ordered first and the rest, L, last,
//!
//! ```text
//! [ A_EE  A_EL ]    A_EL = K_if,EL and A_LE = K_if,LE (sparse, S_c has no entry there),
//! [ A_LE  A_LL ],
//! ```
//!
//! A is factored as LU(A_EE) (partial pivoting) and its inverse, Y = A_EE⁻¹ A_EL over the c
//! columns K_if couples (from A_EL's nonzeros: e flops each), S' = A_LL − A_LE Y (a
//! sparse-times-dense product) and LU(S'). With e = |E| ≤ l = |L| this costs 2e³ + ⅔l³ flops
//! (plus O(e·nnz(K_if))) against ⅔n³ for the whole: 0.33 n³ for two bodies (e = l = n/2), and
//! 0.28 n³ with twist, where E is the circumferential unknowns (e = n/3). Sticking friction
//! couples nothing across the circumferential–meridional split (c = 0).
//!
//! The elimination pivots only within A_EE, which is exact to rounding when A_EE is well
//! conditioned: it is S_EE, the bodies' stiffness with the other groups held, plus the
//! interface stiffness on E. When A_EE is (nearly) singular — a body held by nothing but an
//! open or freely sliding interface — the factorisation falls back to one LU of the whole A,
//! which then decides whether A itself is singular. Groups are found once per bulk
//! factorisation ([`InterfaceLu::analyse`]), exactly: S_c's entries between unconnected
//! unknowns are exact zeros (sums of products with a zero factor).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::lu::partial_pivoting::{
    factor as lu_factor, inverse as lu_inverse, solve as lu_solve,
};
use faer::linalg::matmul::matmul;
use faer::perm::PermRef;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, Mat, MatMut, MatRef, Par};

use crate::{Error, Result};

/// A split is used only when its flops ([`cost`]) are below this fraction of the whole
/// LU's: below it, the gain outweighs the gathering and the sparse products.
const SPLIT_GAIN: f64 = 0.9;

/// Smallest pivot of LU(A_EE), relative to its largest, for which the split is trusted;
/// below it A_EE is (nearly) singular and the whole A is factored instead. The split's
/// error grows with A_EE's condition, which this bounds well above rounding of a Newton
/// correction.
const SPLIT_PIVOT: f64 = 1e-9;

/// The dense LU of the interface system, whole or by the blocks of the module docs.
pub struct InterfaceLu {
    /// Interface unknowns.
    n: usize,
    /// The factors: of A (unsplit), or, in the split order, LU(A_EE) in the leading e × e
    /// block, Y in the e × c block right of it, LU(S') in the trailing l × l block.
    lu: Mat<f64>,
    /// Row pivots: of A, or of A_EE (first e) and of S' (last l), each local to its block.
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    /// The group split of the last [`Self::analyse`]: E, then L, in interface indices.
    split: Vec<usize>,
    /// |E| of the last analysis (0: no split).
    eliminated: usize,
    /// Order of the last factorisation: E, then L with its c coupled unknowns first.
    order: Vec<usize>,
    /// c of the last factorisation.
    coupled: usize,
    /// Whether the last factorisation was split.
    split_used: bool,
    /// Nonzeros (row in L, value) of A_LE of the last factorisation by column of E:
    /// column jj's are `lower_left[lower_left_ptr[jj]..lower_left_ptr[jj + 1]]`.
    lower_left: Vec<(u32, f64)>,
    lower_left_ptr: Vec<usize>,
    /// Per unknown: its group's root in [`Self::analyse`]; in a split factorisation, its
    /// place in L (or a mark for E).
    marks: Vec<usize>,
    /// Per group root: the group's size.
    group_sizes: Vec<usize>,
    /// Right-hand side in the split order.
    work: Vec<f64>,
    workspace: MemBuffer,
    par: Par,
    factored: bool,
}

impl InterfaceLu {
    /// Storage for n interface unknowns; `par`: parallelism of the dense kernels.
    pub fn new(n: usize, par: Par) -> Result<Self> {
        let req = StackReq::any_of(&[
            lu_factor::lu_in_place_scratch::<usize, f64>(n, n, par, Default::default()),
            lu_solve::solve_in_place_scratch::<usize, f64>(n, 1, par),
            lu_inverse::inverse_scratch::<usize, f64>(n / 2, par),
        ]);
        let workspace = MemBuffer::try_new(req)
            .map_err(|_| Error::allocation_failed("the interface LU workspace", n))?;
        Ok(Self {
            n,
            lu: Mat::zeros(n, n),
            perm: vec![0; n],
            perm_inv: vec![0; n],
            split: (0..n).collect(),
            eliminated: 0,
            order: (0..n).collect(),
            coupled: 0,
            split_used: false,
            lower_left: Vec::new(),
            lower_left_ptr: Vec::with_capacity(n + 1),
            marks: vec![0; n],
            group_sizes: vec![0; n],
            work: vec![0.0; n],
            workspace,
            par,
            factored: false,
        })
    }

    /// Sets the parallelism of the dense kernels.
    pub fn set_parallelism(&mut self, par: Par) {
        self.par = par;
    }

    /// Finds the groups of `schur` (connected components of its nonzero pattern) and
    /// chooses E: the smallest groups, added while the `cost` falls and E stays no larger
    /// than L; no split unless that cost is below `SPLIT_GAIN` of the whole LU's.
    pub fn analyse(&mut self, schur: MatRef<'_, f64>) {
        let n = self.n;
        self.factored = false;
        let root = &mut self.marks;
        for (k, r) in root.iter_mut().enumerate() {
            *r = k;
        }
        for j in 0..n {
            for i in j + 1..n {
                if schur[(i, j)] != 0.0 || schur[(j, i)] != 0.0 {
                    union(root, i, j);
                }
            }
        }
        for k in 0..n {
            root[k] = find(root, k);
        }
        // Unknowns by (group size, group root, index): the smallest groups first.
        let sizes = &mut self.group_sizes;
        sizes.fill(0);
        for &r in root.iter() {
            sizes[r] += 1;
        }
        self.split
            .sort_unstable_by_key(|&k| (sizes[root[k]], root[k], k));
        let mut best = (cost(n, 0), 0);
        let mut e = 0;
        while e < n {
            let next = e + self.group_sizes[self.marks[self.split[e]]];
            // E no larger than L: A_EE⁻¹ is formed in L's rows.
            if 2 * next > n {
                break;
            }
            e = next;
            let c = cost(n, e);
            if c >= best.0 {
                break;
            }
            best = (c, e);
        }
        self.eliminated = if best.0 < SPLIT_GAIN * cost(n, 0) {
            best.1
        } else {
            0
        };
        tracing::debug!(
            interface = n,
            eliminated = self.eliminated,
            "interface LU blocks"
        );
    }

    /// Factors A = `schur` + `block`. Returns false if A is singular to working precision
    /// (a pivot of the whole LU below n·ε times the largest) or not finite.
    pub fn factor(&mut self, schur: MatRef<'_, f64>, block: MatRef<'_, f64>) -> bool {
        self.factored = false;
        self.split_used = self.eliminated > 0 && self.factor_split(schur, block);
        if !self.split_used && !self.factor_whole(schur, block) {
            return false;
        }
        self.factored = true;
        true
    }

    /// LU of the whole A in the interface order.
    fn factor_whole(&mut self, schur: MatRef<'_, f64>, block: MatRef<'_, f64>) -> bool {
        let mut a = self.lu.as_mut();
        a.copy_from(schur);
        a += block;
        let (smallest, largest) = lu_pivots(
            self.lu.as_mut(),
            &mut self.perm,
            &mut self.perm_inv,
            self.par,
            &mut self.workspace,
        );
        largest.is_finite() && smallest > self.n as f64 * f64::EPSILON * largest
    }

    /// The block factorisation of the module docs; false (nothing usable) if A_EE or S' is
    /// too near singular for it.
    fn factor_split(&mut self, schur: MatRef<'_, f64>, block: MatRef<'_, f64>) -> bool {
        let (n, e) = (self.n, self.eliminated);
        let l = n - e;
        self.order_coupled_first(block);
        let (order, c) = (&self.order, self.coupled);

        // LU(A_EE).
        let (mut top, mut bottom) = self.lu.as_mut().split_at_row_mut(e);
        let (mut a_ee, mut y) = top.rb_mut().split_at_col_mut(e);
        gather_sum(schur, block, &order[..e], a_ee.rb_mut());
        let (perm_e, perm_l) = self.perm.split_at_mut(e);
        let (inv_e, inv_l) = self.perm_inv.split_at_mut(e);
        let (smallest, largest) =
            lu_pivots(a_ee.rb_mut(), perm_e, inv_e, self.par, &mut self.workspace);
        if !largest.is_finite() || smallest <= SPLIT_PIVOT * largest {
            return false;
        }

        // A_EE⁻¹ (⁴⁄₃e³ flops), in the rows of L below it (l ≥ e by the choice of E), then
        // Y = A_EE⁻¹ A_EL over the coupled columns from A_EL's nonzeros (e flops each, where
        // substitutions would cost 2e² per column).
        let (mut inverse, mut s) = bottom.rb_mut().split_at_col_mut(e);
        let mut inverse = inverse.rb_mut().subrows_mut(0, e);
        lu_inverse::inverse(
            inverse.rb_mut(),
            a_ee.rb(),
            a_ee.rb(),
            PermRef::new_checked(perm_e, inv_e, e),
            self.par,
            MemStack::new(&mut self.workspace),
        );
        let mut y = y.rb_mut().subcols_mut(0, c);
        for (jj, &j) in order[e..e + c].iter().enumerate() {
            let (from, to) = (column(block, j), column_mut(y.rb_mut(), jj));
            to.fill(0.0);
            for (ii, &i) in order[..e].iter().enumerate() {
                let v = from[i];
                if v != 0.0 {
                    for (t, &w) in to.iter_mut().zip(column(inverse.rb(), ii)) {
                        *t += v * w;
                    }
                }
            }
        }

        // S' = A_LL − A_LE Y, A_LE sparse (by column of E).
        gather_sum(schur, block, &order[e..], s.rb_mut());
        for k in 0..c {
            let y_k = column(y.rb(), k);
            let s_k = column_mut(s.rb_mut(), k);
            for (jj, &y_jk) in y_k.iter().enumerate() {
                if y_jk != 0.0 {
                    let range = self.lower_left_ptr[jj]..self.lower_left_ptr[jj + 1];
                    for &(ii, v) in &self.lower_left[range] {
                        s_k[ii as usize] -= v * y_jk;
                    }
                }
            }
        }
        let (smallest, largest) =
            lu_pivots(s.rb_mut(), perm_l, inv_l, self.par, &mut self.workspace);
        largest.is_finite() && smallest > l as f64 * f64::EPSILON * largest
    }

    /// Orders the unknowns for a split factorisation of A = S_c + `block`: E, then the
    /// unknowns of L that K_if couples to E (a nonzero in their column of A_EL), then the
    /// rest of L; sets `coupled` and A_LE's nonzeros by column of E (`lower_left`).
    fn order_coupled_first(&mut self, block: MatRef<'_, f64>) {
        let (n, e) = (self.n, self.eliminated);
        const IN_E: usize = usize::MAX;
        let (split, place) = (&self.split, &mut self.marks);
        for &k in &split[..e] {
            place[k] = IN_E;
        }
        let order = &mut self.order;
        order[..e].copy_from_slice(&split[..e]);
        for &j in &split[e..] {
            place[j] = usize::from(
                column(block, j)
                    .iter()
                    .zip(place.iter())
                    .any(|(&v, &p)| v != 0.0 && p == IN_E),
            );
        }
        let mut next = e;
        for wanted in [1, 0] {
            for &j in split[e..].iter().filter(|&&j| place[j] == wanted) {
                order[next] = j;
                next += 1;
            }
            if wanted == 1 {
                self.coupled = next - e;
            }
        }
        debug_assert_eq!(next, n);
        // Position of each unknown of L in its block, then A_LE by column of E.
        for (ii, &i) in order[e..].iter().enumerate() {
            place[i] = ii;
        }
        self.lower_left.clear();
        self.lower_left_ptr.clear();
        self.lower_left_ptr.push(0);
        for &j in &order[..e] {
            let col = column(block, j);
            for (&v, &p) in col.iter().zip(place.iter()) {
                if v != 0.0 && p != IN_E {
                    self.lower_left.push((p as u32, v));
                }
            }
            self.lower_left_ptr.push(self.lower_left.len());
        }
    }

    /// Solves A x = `x` in place (interface order) with the last [`Self::factor`].
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        assert!(self.factored, "solve before factor");
        assert_eq!(x.len(), self.n);
        if !self.split_used {
            let lu = self.lu.as_ref();
            lu_solve_vector(
                lu,
                &self.perm,
                &self.perm_inv,
                x,
                self.par,
                &mut self.workspace,
            );
            return;
        }
        let (n, e, c) = (self.n, self.eliminated, self.coupled);
        for (t, &k) in self.work.iter_mut().zip(&self.order) {
            *t = x[k];
        }
        let (t_e, t_l) = self.work.split_at_mut(e);
        let (top, bottom) = self.lu.as_ref().split_at_row(e);
        let (a_ee, y) = top.split_at_col(e);
        let s = bottom.subcols(e, n - e);
        let (perm_e, perm_l) = self.perm.split_at(e);
        let (inv_e, inv_l) = self.perm_inv.split_at(e);
        // z_E = A_EE⁻¹ t_E.
        lu_solve_vector(a_ee, perm_e, inv_e, t_e, self.par, &mut self.workspace);
        // t_L ← S'⁻¹ (t_L − A_LE z_E).
        for (jj, &z) in t_e.iter().enumerate() {
            let range = self.lower_left_ptr[jj]..self.lower_left_ptr[jj + 1];
            for &(ii, v) in &self.lower_left[range] {
                t_l[ii as usize] -= v * z;
            }
        }
        lu_solve_vector(s, perm_l, inv_l, t_l, self.par, &mut self.workspace);
        // x_E = z_E − Y x_L (coupled columns).
        matmul(
            MatMut::from_column_major_slice_mut(t_e, e, 1),
            Accum::Add,
            y.subcols(0, c),
            MatRef::from_column_major_slice(&t_l[..c], c, 1),
            -1.0,
            self.par,
        );
        for (t, &k) in self.work.iter().zip(&self.order) {
            x[k] = *t;
        }
    }
}

/// Flops of the split with e eliminated unknowns (n in all): LU(A_EE) and its inverse, and
/// LU(S'); e = 0: the whole LU. (Y and the sparse products cost O(e · nnz(K_if)).)
fn cost(n: usize, e: usize) -> f64 {
    let (n, e) = (n as f64, e as f64);
    2.0 * e.powi(3) + 2.0 / 3.0 * (n - e).powi(3)
}

/// Column `j` of a column-major matrix.
fn column(m: MatRef<'_, f64>, j: usize) -> &[f64] {
    m.col(j)
        .try_as_col_major()
        .expect("column-major storage")
        .as_slice()
}

/// Column `j` of a column-major matrix, mutable.
fn column_mut(m: MatMut<'_, f64>, j: usize) -> &mut [f64] {
    m.col_mut(j)
        .try_as_col_major_mut()
        .expect("column-major storage")
        .as_slice_mut()
}

/// `out` = (S + B)[rows, rows] for the unknowns `rows`.
fn gather_sum(s: MatRef<'_, f64>, b: MatRef<'_, f64>, rows: &[usize], mut out: MatMut<'_, f64>) {
    for (jj, &j) in rows.iter().enumerate() {
        let (s_j, b_j) = (column(s, j), column(b, j));
        for (to, &i) in column_mut(out.rb_mut(), jj).iter_mut().zip(rows) {
            *to = s_j[i] + b_j[i];
        }
    }
}

/// Solves with the LU factor `lu` (pivots `perm`, `perm_inv`) for the vector `rhs` in place.
fn lu_solve_vector(
    lu: MatRef<'_, f64>,
    perm: &[usize],
    perm_inv: &[usize],
    rhs: &mut [f64],
    par: Par,
    workspace: &mut MemBuffer,
) {
    let n = rhs.len();
    lu_solve::solve_in_place(
        lu,
        lu,
        PermRef::new_checked(perm, perm_inv, n),
        MatMut::from_column_major_slice_mut(rhs, n, 1),
        par,
        MemStack::new(workspace),
    );
}

/// LU with partial pivoting of `a` in place (row pivots into `perm`, `perm_inv`); returns
/// its smallest and largest |pivot|.
fn lu_pivots(
    mut a: MatMut<'_, f64>,
    perm: &mut [usize],
    perm_inv: &mut [usize],
    par: Par,
    workspace: &mut MemBuffer,
) -> (f64, f64) {
    lu_factor::lu_in_place(
        a.rb_mut(),
        perm,
        perm_inv,
        par,
        MemStack::new(workspace),
        Default::default(),
    );
    pivot_range(a.rb())
}

/// Smallest and largest |pivot| of an LU factor.
fn pivot_range(lu: MatRef<'_, f64>) -> (f64, f64) {
    (0..lu.nrows()).fold((f64::INFINITY, 0.0f64), |(lo, hi), k| {
        let p = lu[(k, k)].abs();
        (lo.min(p), hi.max(p))
    })
}

/// Union–find root of `k` (with path halving).
fn find(root: &mut [usize], mut k: usize) -> usize {
    while root[k] != k {
        root[k] = root[root[k]];
        k = root[k];
    }
    k
}

/// Joins the groups of `a` and `b`.
fn union(root: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(root, a), find(root, b));
    if ra != rb {
        root[ra.max(rb)] = ra.min(rb);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::condensed::tests::Rng;
    use faer::linalg::solvers::Solve;

    /// A block-diagonal "Schur complement" with symmetric positive definite groups of the
    /// given sizes (a group's unknowns are interleaved with the others' as the unknowns of
    /// different components are in a real interface), and a sparse unsymmetric "interface"
    /// block coupling unknowns at most `band` apart, scaled by `coupling`.
    fn system(sizes: &[usize], band: usize, coupling: f64, seed: u64) -> (Mat<f64>, Mat<f64>) {
        let n: usize = sizes.iter().sum();
        let mut rng = Rng(seed);
        // Unknown k belongs to group k mod (number of groups) until that group is full.
        let mut group = Vec::with_capacity(n);
        let mut left = sizes.to_vec();
        while group.len() < n {
            for (g, left) in left.iter_mut().enumerate() {
                if *left > 0 {
                    group.push(g);
                    *left -= 1;
                }
            }
        }
        let mut s = Mat::zeros(n, n);
        for g in 0..sizes.len() {
            let members: Vec<usize> = (0..n).filter(|&k| group[k] == g).collect();
            let m = members.len();
            let r = Mat::<f64>::from_fn(m, m, |_, _| rng.next());
            let spd = &r * r.transpose() + Mat::<f64>::identity(m, m) * (m as f64);
            for (a, &i) in members.iter().enumerate() {
                for (b, &j) in members.iter().enumerate() {
                    s[(i, j)] = spd[(a, b)];
                }
            }
        }
        let b = Mat::from_fn(n, n, |i, j| {
            if i.abs_diff(j) <= band {
                coupling * rng.next()
            } else {
                0.0
            }
        });
        (s, b)
    }

    /// max |A x − r| / max |r| for the solution of `lu` against the dense A = S + B.
    fn residual(lu: &mut InterfaceLu, s: &Mat<f64>, b: &Mat<f64>) -> f64 {
        let n = s.nrows();
        let r: Vec<f64> = (0..n).map(|k| ((k * 7 % 11) as f64) - 5.0).collect();
        let mut x = r.clone();
        lu.solve_in_place(&mut x);
        let a = s + b;
        (0..n)
            .map(|i| ((0..n).map(|j| a[(i, j)] * x[j]).sum::<f64>() - r[i]).abs())
            .fold(0.0, f64::max)
            / 5.0
    }

    #[test]
    fn two_bodies_and_twist_split_by_their_groups_and_solve_exactly() {
        // Two sides (two groups) and twist (four: two meridional, two circumferential).
        for (sizes, eliminated) in [(&[40, 41][..], 40), (&[40, 41, 20, 21][..], 41)] {
            let (s, b) = system(sizes, 6, 3.0, 7);
            let mut lu = InterfaceLu::new(s.nrows(), Par::Seq).unwrap();
            lu.analyse(s.as_ref());
            assert_eq!(lu.eliminated, eliminated, "{sizes:?}");
            assert!(lu.factor(s.as_ref(), b.as_ref()));
            assert!(lu.split_used);
            assert!(lu.coupled > 0);
            let reference = s.as_ref() + b.as_ref();
            let dense = reference.partial_piv_lu();
            let r: Vec<f64> = (0..s.nrows()).map(|k| (k as f64).sin()).collect();
            let expected = dense.solve(faer::ColRef::from_slice(&r));
            let mut x = r.clone();
            lu.solve_in_place(&mut x);
            let error = (0..x.len())
                .map(|k| (x[k] - expected[k]).abs())
                .fold(0.0, f64::max);
            assert!(error < 1e-12, "{sizes:?}: {error:e}");
            assert!(residual(&mut lu, &s, &b) < 1e-12);
        }
    }

    #[test]
    fn groups_not_coupled_by_the_interface_factor_as_blocks_alone() {
        // Sticking friction: no coupling across the groups at all (c = 0).
        let (s, _) = system(&[30, 31], 0, 0.0, 3);
        let b = Mat::from_fn(61, 61, |i, j| if i == j { 2.0 } else { 0.0 });
        let mut lu = InterfaceLu::new(61, Par::Seq).unwrap();
        lu.analyse(s.as_ref());
        assert!(lu.factor(s.as_ref(), b.as_ref()));
        assert!(lu.split_used);
        assert_eq!(lu.coupled, 0);
        assert!(residual(&mut lu, &s, &b) < 1e-12);
    }

    #[test]
    fn a_singular_eliminated_block_falls_back_to_the_whole_lu() {
        // The smaller group's stiffness vanishes (a body held only through the interface),
        // and the interface holds it only through couplings to the other group: A_EE is
        // singular, A is not.
        let (mut s, _) = system(&[20, 30], 0, 0.0, 5);
        let small: Vec<usize> = (0..50).filter(|&k| k % 2 == 0).take(20).collect();
        for &i in &small {
            for &j in &small {
                s[(i, j)] = 0.0;
            }
        }
        // The zeroed group is now 20 groups of one (no couplings): give it one tiny
        // self-coupling chain so it stays one group, singular as a whole.
        for w in small.windows(2) {
            s[(w[0], w[1])] = 1e-30;
            s[(w[1], w[0])] = 1e-30;
        }
        let b = Mat::from_fn(50, 50, |i, j| {
            let (si, sj) = (small.contains(&i), small.contains(&j));
            if si != sj && i.abs_diff(j) == 1 {
                1.0
            } else {
                0.0
            }
        });
        let mut lu = InterfaceLu::new(50, Par::Seq).unwrap();
        lu.analyse(s.as_ref());
        assert_eq!(lu.eliminated, 20);
        assert!(lu.factor(s.as_ref(), b.as_ref()));
        assert!(!lu.split_used);
        assert!(residual(&mut lu, &s, &b) < 1e-9);
    }

    #[test]
    fn one_group_is_not_split_and_a_singular_system_is_refused() {
        let (s, b) = system(&[60], 3, 1.0, 11);
        let mut lu = InterfaceLu::new(60, Par::Seq).unwrap();
        lu.analyse(s.as_ref());
        assert_eq!(lu.eliminated, 0);
        assert!(lu.factor(s.as_ref(), b.as_ref()));
        assert!(!lu.split_used);
        assert!(residual(&mut lu, &s, &b) < 1e-12);
        let zero = Mat::<f64>::zeros(60, 60);
        let mut split = InterfaceLu::new(60, Par::Seq).unwrap();
        let (two, _) = system(&[30, 30], 0, 0.0, 13);
        split.analyse(two.as_ref());
        assert!(split.eliminated > 0);
        assert!(!split.factor(zero.as_ref(), zero.as_ref()));
    }
}
