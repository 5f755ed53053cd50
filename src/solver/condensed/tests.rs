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
/// random symmetric positive semi-definite cell matrices (translations cost no energy), body
/// A on top of body B along a line of coincident node pairs joined by 2-node interface
/// "elements" with a random unsymmetric matrix (penalty plus `slip` times an unsymmetric
/// part). Body B is held at its bottom; body A only through the interface.
/// `fixed_interface_nodes` additionally prescribes both dofs of some interface nodes.
struct TestSystem {
    pattern: SparsityPattern,
    dofs: DofMap,
    continuum: Vec<f64>,
    interface: Vec<f64>,
    interface_eqs: Vec<usize>,
}

fn test_system(nx: usize, ny: usize, slip: f64, fixed_interface_nodes: &[usize]) -> TestSystem {
    test_system_with(nx, ny, slip, fixed_interface_nodes, false, false)
}

/// With `single_body`, body A is left out and the interface "elements" join neighbouring
/// nodes on the top of body B instead. With `dense_interface` the pattern couples all
/// interface nodes (with zero values), as the conduction's does.
fn test_system_with(
    nx: usize,
    ny: usize,
    slip: f64,
    fixed_interface_nodes: &[usize],
    single_body: bool,
    dense_interface: bool,
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
    let mut all: Vec<u32> = pairs.concat();
    all.sort_unstable();
    all.dedup();
    let block = dense_interface.then_some(all);
    let pattern = SparsityPattern::new(
        node_count,
        &dofs,
        cells
            .iter()
            .chain(&pairs)
            .chain(&block)
            .map(|v| v.as_slice()),
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
    let mut solver = CondensedSolver::with_relaxation(
        &t.pattern,
        &t.interface_eqs,
        relax,
        SystemKind::Mechanical,
    )
    .unwrap();
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
    let (difference, residual) = solve_and_compare(&mut solver, &t, block.as_ref(), &noisy, &clean);
    assert!(
        difference < 1e-12 && residual < 1e-13,
        "{difference:e} {residual:e}"
    );
    // An exactly sparse right-hand side: the skipped supernodes change nothing.
    let (difference, residual) = solve_and_compare(&mut solver, &t, block.as_ref(), &clean, &clean);
    assert!(
        difference < 1e-12 && residual < 1e-13,
        "{difference:e} {residual:e}"
    );
    // Bulk entries above the bound are kept: the noisy system itself is solved.
    let mut loud = noisy.clone();
    for eq in &bulk {
        loud[*eq] += 1e-6 * (1.5 + rng.next());
    }
    let (difference, residual) = solve_and_compare(&mut solver, &t, block.as_ref(), &loud, &loud);
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
    let t = test_system_with(6, 4, 1.5, &[], true, false);
    let solver = CondensedSolver::with_relaxation(
        &t.pattern,
        &t.interface_eqs,
        Some(relax),
        SystemKind::Mechanical,
    )
    .unwrap();
    let sn = &solver.symbolic;
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
    let mut eig = s
        .to_owned()
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .unwrap();
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

/// The forward substitution cut into subtrees run as parallel tasks (each pushing the rows
/// above it into a buffer of its own) solves as the one sequence does, to rounding, with
/// supernodes straddling the interface border too, and gives the same bits on one thread and
/// on two.
#[test]
fn the_forward_substitution_cut_into_subtrees_solves_alike_on_any_number_of_threads() {
    let relax: &[(usize, f64)] = &[(usize::MAX, 1.0)];
    for (single_body, relax) in [(false, None), (true, Some(relax))] {
        let t = test_system_with(12, 8, 0.5, &[], single_body, true);
        let n = t.dofs.free_count();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let solve = |pieces: Option<usize>, threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let kind = SystemKind::Mechanical;
                let mut solver =
                    CondensedSolver::with_relaxation(&t.pattern, &t.interface_eqs, relax, kind)
                        .unwrap();
                let gather_len = solver.gather.len();
                solver.forward =
                    ForwardPlan::cut_into(&solver.symbolic, &solver.tree, gather_len, pieces);
                let block = factor_bulk_of(&mut solver, &t, false);
                let mut x = b.clone();
                solver.solve(block.as_ref(), &mut x).unwrap();
                (x, solver.forward.subtrees())
            })
        };
        let (whole, _) = solve(None, 1);
        let (one, tasks) = solve(Some(16), 1);
        let (two, _) = solve(Some(16), 2);
        assert!(tasks > 4, "{tasks} subtrees");
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one), bits(&two), "single body {single_body}");
        let scale = whole.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let difference = (one.iter().zip(&whole)).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(difference < 1e-12 * scale, "{difference:e} of {scale:e}");
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

/// The memory message names both parts, and the Krylov path only when the dense interface
/// system is the larger one (a long, finely meshed joint).
#[test]
fn the_storage_message_points_to_krylov_when_the_interface_system_dominates() {
    let factor_larger = storage_parts(SystemKind::Mechanical, 2_000_000_000, 500_000_000, 6000);
    assert_eq!(
        factor_larger,
        "the sparse factor of the bodies' stiffness 2.00 GB, the dense system of the 6000 \
         interface unknowns 0.50 GB"
    );
    let dense_larger = storage_parts(SystemKind::Mechanical, 500_000_000, 2_000_000_000, 12000);
    assert!(
        dense_larger.contains("12000 interface unknowns 2.00 GB"),
        "{dense_larger}"
    );
    assert!(
        dense_larger.contains("linear_solver = \"krylov\""),
        "{dense_larger}"
    );
    // The conduction's names its own matrix and unknowns, and no Krylov path (it has none).
    let conduction = storage_parts(SystemKind::Conduction, 500_000_000, 2_000_000_000, 12000);
    assert_eq!(
        conduction,
        "the sparse factor of the heat conduction 0.50 GB, the dense system of the 12000 joint \
         nodes 2.00 GB"
    );
}

/// A failed allocation in faer's symbolic steps is the model's size (exit code 3), any other
/// error of theirs the linear solver's.
#[test]
fn a_failed_allocation_is_a_memory_error_not_a_numerical_one() {
    let memory =
        crate::solver::faer_error(faer::sparse::FaerError::OutOfMemory, "the AMD ordering", 9);
    assert!(
        matches!(memory, Error::AllocationFailed { unknowns: 9, .. }),
        "{memory}"
    );
    assert_eq!(memory.exit_code(), 3);
    let other = crate::solver::faer_error(
        faer::sparse::FaerError::IndexOverflow,
        "the AMD ordering",
        9,
    );
    assert!(matches!(other, Error::Linear(_)), "{other}");
}
