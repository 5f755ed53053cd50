//! Numeric supernodal Cholesky factorisation scheduled over the elimination tree, on all
//! threads.
//!
//! faer's `factorize_supernodal_numeric_llt` is left-looking: supernode s gathers the
//! updates of every earlier supernode d whose rows reach into its columns (all of them its
//! descendants in the supernodal elimination tree), then factors its diagonal block and
//! solves its off-diagonal rows. It visits the supernodes one after the other and puts
//! threads only inside the dense kernels, which never paid on this project's machine (see
//! `condensed::BULK_FACTOR_PARALLELISM`): the fronts of a 2D mesh are small. Two subtrees
//! of the elimination tree, however, share nothing: neither reads nor writes the other's
//! columns. `TreeCholesky` therefore runs the sibling subtrees of every large node
//! as separate tasks (rayon), each subtree's supernodes in sequence, and a node after its
//! children — the classic subtree ("tree") parallelism of sparse direct solvers.
//!
//! The supernodes at the top of the tree — the separators under the interface and the
//! interface itself — wait for their whole subtree and then run alone; one that receives much
//! update work gathers it in four column blocks of its own, as parallel tasks (each block's
//! entries get the same updates in the same order as in one pass, by kernels on other
//! shapes).
//!
//! Every supernode is computed by the same operations in the same order (its updaters d in
//! increasing order; its column blocks fixed by its size), whichever thread runs it and
//! however many there are: the factor is bitwise the same on one thread as on two. The dense
//! kernels are faer's, all sequential.
//!
//! The schedule needs each subtree's supernodes to be consecutive (a postorder, as faer's
//! symbolic factorisation numbers them); `TreeCholesky::new` checks it, and without it the
//! supernodes are factored one after the other in their own order (updaters come first in
//! any supernodal numbering), by the same operations.
//!
//! # Only what changed
//! A left-looking supernode reads its own columns of the matrix and its descendants' factor
//! columns, nothing else. When a new matrix differs from the last factored one in a few
//! columns only — the elements of a plastic zone — the supernodes holding them and their
//! ancestors are computed again and the others' values kept
//! (`TreeCholesky::supernodes_to_refactor`): the same bits as the whole factorisation,
//! for the work of the paths from the zone to the root. Measured on the elasto-plastic flat
//! punch (43k unknowns, 4589 supernodes, 30 refactorisations of 19–125 supernodes each):
//! factorisation 1.20–1.30 → 0.70–0.77 s.
//!
//! # Only the bulk columns
//! The condensed solver orders the interface unknowns last and needs the Schur complement
//! of the bulk on them, not their factor. `TreeCholesky::factorize` therefore takes the
//! number of leading (bulk) columns to eliminate: a supernode of trailing columns receives
//! the updates of the bulk columns only and is left as it is, holding its columns of the
//! Schur complement A_II − A_IB A_BB⁻¹ A_BI (lower triangle), and a supernode straddling the
//! border is factored in its bulk columns and updated in the others. That saves the dense
//! Cholesky of the trailing block and its product L_II L_IIᵀ, each ⅓ n_I³ flops.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{BlockStructure, matmul as triangular_matmul};
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::{Accum, MatMut, MatRef, Par};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Mutex;

/// No parent: a root of the elimination forest.
const NONE: u32 = u32::MAX;

/// Multiply-adds of the updates a supernode receives from which it gathers them in
/// `UPDATE_BLOCKS` column blocks as parallel tasks (~20 ms of work): the supernodes at the
/// top of the tree — the separators under the interface and the interface itself — wait for
/// their whole subtree and then run alone (at 3.8 M unknowns the interface supernode took
/// 3.8 s of the 21 s factorisation on one thread).
const SPLIT_UPDATES_FROM: f64 = (1u64 << 26) as f64;

/// Column blocks of a split supernode's updates, of about equal work. Fixed, not the number
/// of threads: each column block is computed by the same operations on any number of
/// threads.
const UPDATE_BLOCKS: usize = 4;

/// Number of tasks per thread the tree is cut into: enough that rayon's work stealing
/// balances unequal subtrees, few enough that a task's bookkeeping is negligible.
const TASKS_PER_THREAD: f64 = 16.0;

/// The failure of a numeric factorisation: the matrix is not positive definite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct NotPositiveDefinite;

/// The updaters of each supernode of a supernodal symbolic factorisation and the task
/// schedule over its elimination tree.
pub(crate) struct TreeCholesky {
    /// The schedule, `None` when the supernodes are not in postorder.
    schedule: Option<Schedule>,
    /// Parent of each supernode in the elimination tree (`NONE` for a root).
    parent: Vec<u32>,
    /// Updaters of each supernode (CSR): the supernodes d < s with a row among s's columns,
    /// in increasing order (faer's order).
    updater_ptr: Vec<u32>,
    updaters: Vec<u32>,
    /// Scratch sizes: the largest supernode (rows, columns).
    max_rows: usize,
    max_cols: usize,
    /// Whether a supernode gathers its updates in `UPDATE_BLOCKS` column blocks, as parallel
    /// tasks: those that receive at least `SPLIT_UPDATES_FROM` multiply-adds.
    split: Vec<bool>,
    /// Scratch of finished tasks and column blocks, taken again by the next ones.
    pool: Mutex<Vec<Scratch>>,
    block_pool: Mutex<Vec<BlockScratch>>,
}

/// The elimination forest in postorder and its cut into tasks.
struct Schedule {
    /// Children of each supernode (CSR), in increasing order, and the roots of the forest.
    child_ptr: Vec<u32>,
    children: Vec<u32>,
    roots: Vec<u32>,
    /// First supernode of each subtree: the subtree of s is `first[s]..=s`.
    first: Vec<u32>,
    /// Estimated flops of each subtree.
    work: Vec<f64>,
    /// A subtree with less work than this is one task.
    grain: f64,
}

/// A task's scratch: global row → row of the current supernode, its column blocks' scratch
/// when it gathers its updates in one pass, and the dense Cholesky's workspace.
struct Scratch {
    global_to_local: Vec<u32>,
    block: BlockScratch,
    stack: MemBuffer,
}

/// The scratch of one column block's updates: their row and column positions and the dense
/// update block.
struct BlockScratch {
    rows: Vec<u32>,
    cols: Vec<u32>,
    update: Vec<f64>,
}

impl TreeCholesky {
    /// The updaters and the schedule of `symbolic` for `threads` threads.
    pub(crate) fn new(symbolic: &SymbolicSupernodalCholesky<u32>, threads: usize) -> Self {
        Self::with_split(symbolic, threads, SPLIT_UPDATES_FROM)
    }

    /// [`Self::new`] with the supernodes that receive at least `split_from` multiply-adds
    /// of updates gathering them in column blocks (tests split every supernode).
    fn with_split(
        symbolic: &SymbolicSupernodalCholesky<u32>,
        threads: usize,
        split_from: f64,
    ) -> Self {
        let n_s = symbolic.n_supernodes();
        let begin = symbolic.supernode_begin();
        let end = symbolic.supernode_end();
        // Supernode of each column, for the parents and the updaters.
        let mut owner = vec![0u32; symbolic.nrows()];
        for s in 0..n_s {
            owner[begin[s] as usize..end[s] as usize].fill(s as u32);
        }
        let mut parent = vec![NONE; n_s];
        let mut updater_count = vec![0u32; n_s + 1];
        let mut max_rows = 0;
        let mut max_cols = 0;
        let mut own_work = vec![0.0; n_s];
        for s in 0..n_s {
            let pattern = symbolic.supernode(s).pattern();
            if let Some(&row) = pattern.first() {
                parent[s] = owner[row as usize];
            }
            let mut last = NONE;
            for &row in pattern {
                let t = owner[row as usize];
                if t != last {
                    updater_count[t as usize + 1] += 1;
                    last = t;
                }
            }
            let cols = (end[s] - begin[s]) as usize;
            let rows = cols + pattern.len();
            max_rows = max_rows.max(rows);
            max_cols = max_cols.max(cols);
            // Flops of its diagonal block, its off-diagonal solve and the updates it sends.
            own_work[s] = (cols * cols * cols) as f64 / 3.0
                + (cols * cols * pattern.len()) as f64
                + (cols * pattern.len() * pattern.len()) as f64;
        }
        for s in 0..n_s {
            updater_count[s + 1] += updater_count[s];
        }
        let updater_ptr = updater_count;
        let mut fill: Vec<u32> = updater_ptr[..n_s].to_vec();
        let mut updaters = vec![0u32; updater_ptr[n_s] as usize];
        let mut received = vec![0.0; n_s];
        for d in 0..n_s {
            let pattern = symbolic.supernode(d).pattern();
            let d_cols = (end[d] - begin[d]) as f64;
            let mut last = NONE;
            for (k, &row) in pattern.iter().enumerate() {
                let t = owner[row as usize];
                if t != last {
                    updaters[fill[t as usize] as usize] = d as u32;
                    fill[t as usize] += 1;
                    last = t;
                    // The update of t by d: d's rows from here on times its rows in t.
                    let mid = pattern[k..].partition_point(|&r| r < end[t as usize]);
                    received[t as usize] += ((pattern.len() - k) * mid) as f64 * d_cols;
                }
            }
        }
        drop((owner, fill));
        Self {
            schedule: Schedule::new(&parent, own_work, threads),
            parent,
            updater_ptr,
            updaters,
            max_rows,
            max_cols,
            split: received.iter().map(|&w| w >= split_from).collect(),
            pool: Mutex::new(Vec::new()),
            block_pool: Mutex::new(Vec::new()),
        }
    }

    /// Numeric factorisation of the first `eliminated` columns of `a_lower` (the lower
    /// triangle of a matrix with the pattern `symbolic` was made from) into `values`
    /// (`symbolic.len_val()` entries), on all of rayon's threads: the factor's columns
    /// before `eliminated`, and the lower triangle of the Schur complement of that block in
    /// the columns after it (see the module documentation). `eliminated = nrows` is the
    /// whole Cholesky factorisation, as faer's `factorize_supernodal_numeric_llt` with its
    /// default parameters.
    ///
    /// `only`: the supernodes to compute (see [`Self::supernodes_to_refactor`]); the others'
    /// values are left as they are, which must be those of an earlier factorisation of a
    /// matrix that differs only in the columns of the computed ones. The result is then
    /// bitwise that of the whole factorisation: a supernode's values depend on its own
    /// columns of the matrix and on its descendants' values only, by the same operations.
    pub(crate) fn factorize(
        &self,
        values: &mut [f64],
        a_lower: SparseColMatRef<'_, u32, f64>,
        symbolic: &SymbolicSupernodalCholesky<u32>,
        eliminated: usize,
        only: Option<&[bool]>,
    ) -> Result<(), NotPositiveDefinite> {
        assert_eq!(values.len(), symbolic.len_val());
        let job = Job {
            tree: self,
            symbolic,
            a_lower,
            eliminated,
            only,
        };
        match &self.schedule {
            Some(schedule) => job.forest(schedule, &schedule.roots, values, 0),
            None => job.sequence(0..symbolic.n_supernodes(), values, 0),
        }
    }

    /// Sets `refactor[s]` for the supernodes s of `symbolic` that a factorisation of a
    /// matrix differing from the last factored one only in the columns flagged in `changed`
    /// must compute again ([`Self::factorize`]'s `only`): those holding a changed column or
    /// a column after `eliminated` (the Schur complement block, which the condensed solver
    /// completes in place), and all their ancestors. Returns how many there are.
    pub(crate) fn supernodes_to_refactor(
        &self,
        symbolic: &SymbolicSupernodalCholesky<u32>,
        changed: &[bool],
        eliminated: usize,
        refactor: &mut Vec<bool>,
    ) -> usize {
        let (begin, end) = (symbolic.supernode_begin(), symbolic.supernode_end());
        refactor.clear();
        refactor.extend((0..symbolic.n_supernodes()).map(|s| {
            let columns = begin[s] as usize..end[s] as usize;
            columns.end > eliminated || changed[columns].contains(&true)
        }));
        // A parent comes after its children (its columns are their first rows below), so
        // one pass in increasing order reaches every ancestor.
        let mut count = 0;
        for s in 0..refactor.len() {
            if refactor[s] {
                count += 1;
                if let Some(&p) = self.parent.get(s).filter(|&&p| p != NONE) {
                    debug_assert!(p as usize > s, "supernode {s} has parent {p}");
                    refactor[p as usize] = true;
                }
            }
        }
        count
    }

    /// Calls `visit(s, scratch)` for every supernode s after its parent (a backward
    /// substitution's order: s reads the solution of its ancestors' columns and writes its
    /// own), running sibling subtrees as parallel tasks as [`Self::factorize`] does, each
    /// task with a scratch taken from `pool` (made by `make` when the pool is empty, given
    /// back at the task's end: the solves after the first allocate nothing) and its
    /// subtree's supernodes in decreasing order. Without a schedule (supernodes not in
    /// postorder) one task visits them all in decreasing order, which is after their parents
    /// too.
    pub(crate) fn top_down<S: Send>(
        &self,
        pool: &Mutex<Vec<S>>,
        make: impl Fn() -> S + Sync,
        visit: impl Fn(usize, &mut S) + Sync,
    ) {
        let walk = TopDown {
            pool,
            make: &make,
            visit: &visit,
        };
        match &self.schedule {
            Some(schedule) => walk.forest(schedule, &schedule.roots),
            None => walk.task((0..self.parent.len()).rev()),
        }
    }

    /// A cut of the elimination forest into subtrees of less than `1 / pieces` of the
    /// factorisation's work each (the largest such: ranges of consecutive supernodes, in
    /// increasing order) and the supernodes above them (in increasing order), the same on
    /// any number of threads; `None` without a schedule (supernodes not in postorder).
    pub(crate) fn cut(&self, pieces: usize) -> Option<(Vec<Range<usize>>, Vec<usize>)> {
        let schedule = self.schedule.as_ref()?;
        let total: f64 = schedule
            .roots
            .iter()
            .map(|&r| schedule.work[r as usize])
            .sum();
        let grain = total / pieces.max(1) as f64;
        let (mut subtrees, mut above) = (Vec::new(), Vec::new());
        // Depth first from the roots, children in increasing order: subtrees come out in
        // increasing order; the supernodes above are sorted afterwards.
        let mut stack: Vec<u32> = schedule.roots.iter().rev().copied().collect();
        while let Some(s) = stack.pop() {
            let s = s as usize;
            if schedule.work[s] < grain {
                subtrees.push(schedule.first[s] as usize..s + 1);
                continue;
            }
            above.push(s);
            let kids = schedule.child_ptr[s] as usize..schedule.child_ptr[s + 1] as usize;
            stack.extend(schedule.children[kids].iter().rev());
        }
        above.sort_unstable();
        Some((subtrees, above))
    }

    /// Scratch for one task: from the pool, or new.
    fn take_scratch(&self, n: usize) -> Scratch {
        if let Some(s) = self.pool.lock().expect("scratch pool").pop() {
            return s;
        }
        Scratch {
            global_to_local: vec![NONE; n],
            block: self.block_scratch(),
            stack: MemBuffer::new(StackReq::any_of(&[cholesky_in_place_scratch::<f64>(
                self.max_cols,
                Par::Seq,
                Default::default(),
            )])),
        }
    }

    fn give_scratch(&self, scratch: Scratch) {
        self.pool.lock().expect("scratch pool").push(scratch);
    }

    /// Scratch for a column block's updates: from the pool, or new.
    fn take_block_scratch(&self) -> BlockScratch {
        let spare = self.block_pool.lock().expect("scratch pool").pop();
        spare.unwrap_or_else(|| self.block_scratch())
    }

    fn give_block_scratch(&self, scratch: BlockScratch) {
        self.block_pool.lock().expect("scratch pool").push(scratch);
    }

    fn block_scratch(&self) -> BlockScratch {
        BlockScratch {
            rows: vec![0; self.max_rows],
            cols: vec![0; self.max_cols],
            update: Vec::new(),
        }
    }

    /// Frees the tasks' scratch (made again by the next factorisation).
    pub(crate) fn release_scratch(&mut self) {
        self.pool.get_mut().expect("scratch pool").clear();
        self.block_pool.get_mut().expect("scratch pool").clear();
    }

    /// Bytes held: the updaters and the tasks' scratch.
    pub(crate) fn memory_bytes(&self) -> usize {
        let block = |b: &BlockScratch| 4 * (b.rows.len() + b.cols.len()) + 8 * b.update.len();
        let scratch: usize = (self.pool.lock().expect("scratch pool").iter())
            .map(|s| 4 * s.global_to_local.len() + block(&s.block) + s.stack.len())
            .sum();
        let blocks: usize = (self.block_pool.lock().expect("scratch pool").iter())
            .map(block)
            .sum();
        4 * (self.updater_ptr.len() + self.updaters.len()) + self.split.len() + scratch + blocks
    }
}

/// An m × n dense block in `buffer`, which grows to the largest block met (once).
fn block(buffer: &mut Vec<f64>, m: usize, n: usize) -> MatMut<'_, f64> {
    if buffer.len() < m * n {
        buffer.resize(m * n, 0.0);
    }
    MatMut::from_column_major_slice_mut(&mut buffer[..m * n], m, n)
}

impl Schedule {
    /// The schedule of the forest `parent` (supernode work `own_work`) for `threads`
    /// threads, or `None` when it is not in postorder.
    fn new(parent: &[u32], own_work: Vec<f64>, threads: usize) -> Option<Self> {
        let n_s = parent.len();
        // Children, subtree sizes and work; postorder check.
        let mut child_ptr = vec![0u32; n_s + 1];
        for &p in parent {
            if p != NONE {
                child_ptr[p as usize + 1] += 1;
            }
        }
        for s in 0..n_s {
            child_ptr[s + 1] += child_ptr[s];
        }
        let mut fill: Vec<u32> = child_ptr[..n_s].to_vec();
        let mut children = vec![0u32; child_ptr[n_s] as usize];
        let mut roots = Vec::new();
        for (s, &p) in parent.iter().enumerate() {
            if p == NONE {
                roots.push(s as u32);
            } else {
                if p as usize <= s {
                    return None;
                }
                children[fill[p as usize] as usize] = s as u32;
                fill[p as usize] += 1;
            }
        }
        let mut first = vec![0u32; n_s];
        let mut work = own_work;
        for s in 0..n_s {
            // Children come before s; a postorder puts their subtrees right before it, one
            // after the other.
            let kids = &children[child_ptr[s] as usize..child_ptr[s + 1] as usize];
            let mut next = s as u32;
            for &c in kids.iter().rev() {
                if c + 1 != next {
                    return None;
                }
                next = first[c as usize];
                work[s] += work[c as usize];
            }
            first[s] = next;
        }
        let mut next = n_s as u32;
        for &r in roots.iter().rev() {
            if r + 1 != next {
                return None;
            }
            next = first[r as usize];
        }
        if next != 0 {
            return None;
        }
        let total: f64 = roots.iter().map(|&r| work[r as usize]).sum();
        let grain = total / (TASKS_PER_THREAD * threads.max(1) as f64);
        Some(Self {
            child_ptr,
            children,
            roots,
            first,
            work,
            grain,
        })
    }
}

/// A walk of [`TreeCholesky::top_down`].
struct TopDown<'a, S, F, V> {
    pool: &'a Mutex<Vec<S>>,
    make: &'a F,
    visit: &'a V,
}

impl<S: Send, F: Fn() -> S + Sync, V: Fn(usize, &mut S) + Sync> TopDown<'_, S, F, V> {
    /// The subtrees of `roots`, as parallel tasks.
    fn forest(&self, schedule: &Schedule, roots: &[u32]) {
        match roots {
            [r] => self.subtree(schedule, *r as usize),
            _ => roots
                .par_iter()
                .for_each(|&r| self.subtree(schedule, r as usize)),
        }
    }

    /// The subtree of `s`: one task below the schedule's grain, else `s` and then its
    /// children's subtrees.
    fn subtree(&self, schedule: &Schedule, s: usize) {
        if schedule.work[s] < schedule.grain {
            return self.task((schedule.first[s] as usize..=s).rev());
        }
        self.task(std::iter::once(s));
        let kids = schedule.child_ptr[s] as usize..schedule.child_ptr[s + 1] as usize;
        self.forest(schedule, &schedule.children[kids]);
    }

    /// Visits `supernodes` in one task, with a scratch of the pool.
    fn task(&self, supernodes: impl Iterator<Item = usize>) {
        let taken = self.pool.lock().expect("scratch pool").pop();
        let mut scratch = taken.unwrap_or_else(self.make);
        supernodes.for_each(|t| (self.visit)(t, &mut scratch));
        self.pool.lock().expect("scratch pool").push(scratch);
    }
}

/// Ends of the column blocks of a split supernode of `cols` columns and `rows` rows, of
/// about equal update work (a column's updates reach the rows from its own down).
fn update_block_ends(cols: usize, rows: usize) -> Vec<usize> {
    let work = |j: usize| (rows - j) as f64;
    let total: f64 = (0..cols).map(work).sum();
    let mut ends = Vec::with_capacity(UPDATE_BLOCKS);
    let mut sum = 0.0;
    for j in 0..cols {
        sum += work(j);
        let target = total * (ends.len() + 1) as f64 / UPDATE_BLOCKS as f64;
        if sum >= target && ends.len() + 1 < UPDATE_BLOCKS {
            ends.push(j + 1);
        }
    }
    ends.push(cols);
    ends
}

/// `product` ← `bot` · `top`ᵀ, where `top` is the first rows of `bot`: only the lower
/// triangle of the square top block, and all of the rows below it.
fn lower_product(mut product: MatMut<'_, f64>, bot: MatRef<'_, f64>, top: MatRef<'_, f64>) {
    let (mid, m) = (top.nrows(), bot.nrows());
    triangular_matmul(
        product.rb_mut().subrows_mut(0, mid),
        BlockStructure::TriangularLower,
        Accum::Replace,
        top,
        BlockStructure::Rectangular,
        top.transpose(),
        BlockStructure::Rectangular,
        1.0,
        Par::Seq,
    );
    matmul(
        product.rb_mut().subrows_mut(mid, m - mid),
        Accum::Replace,
        bot.subrows(mid, m - mid),
        top.transpose(),
        1.0,
        Par::Seq,
    );
}

/// One factorisation: the schedule, the symbolic structure and the matrix.
struct Job<'a> {
    tree: &'a TreeCholesky,
    symbolic: &'a SymbolicSupernodalCholesky<u32>,
    a_lower: SparseColMatRef<'a, u32, f64>,
    /// Columns eliminated: the rest is left as the Schur complement.
    eliminated: usize,
    /// The supernodes to compute, `None` for all (see [`TreeCholesky::factorize`]).
    only: Option<&'a [bool]>,
}

impl Job<'_> {
    /// Offset of supernode s's values.
    fn value_start(&self, s: usize) -> usize {
        self.symbolic.col_ptr_for_val()[s] as usize
    }

    /// Whether this factorisation computes supernode s.
    fn computes(&self, s: usize) -> bool {
        self.only.is_none_or(|only| only[s])
    }

    /// Factors the consecutive subtrees rooted at `roots` (in increasing order), whose
    /// values are `values`, starting at value offset `offset`: large ones as parallel tasks.
    fn forest(
        &self,
        schedule: &Schedule,
        roots: &[u32],
        values: &mut [f64],
        offset: usize,
    ) -> Result<(), NotPositiveDefinite> {
        let mut tasks = Vec::with_capacity(roots.len());
        let mut rest = values;
        let mut at = offset;
        for &r in roots {
            let end = self.value_start(r as usize + 1);
            let (mine, tail) = rest.split_at_mut(end - at);
            tasks.push((r as usize, mine, at));
            rest = tail;
            at = end;
        }
        if tasks.len() == 1 {
            let (r, mine, at) = tasks.pop().expect("one task");
            return self.subtree(schedule, r, mine, at);
        }
        tasks
            .into_par_iter()
            .try_for_each(|(r, mine, at)| self.subtree(schedule, r, mine, at))
    }

    /// Factors the subtree of `s` (values `values`, from offset `offset`).
    fn subtree(
        &self,
        schedule: &Schedule,
        s: usize,
        values: &mut [f64],
        offset: usize,
    ) -> Result<(), NotPositiveDefinite> {
        if !self.computes(s) {
            // Nor any of its descendants: a computed one makes its ancestors computed.
            return Ok(());
        }
        if schedule.work[s] < schedule.grain {
            return self.sequence(schedule.first[s] as usize..s + 1, values, offset);
        }
        let kids =
            &schedule.children[schedule.child_ptr[s] as usize..schedule.child_ptr[s + 1] as usize];
        let own = self.value_start(s) - offset;
        self.forest(schedule, kids, &mut values[..own], offset)?;
        self.sequence(s..s + 1, values, offset)
    }

    /// Factors the supernodes `range` one after the other (values `values`, from offset
    /// `offset`), in one task.
    fn sequence(
        &self,
        range: std::ops::Range<usize>,
        values: &mut [f64],
        offset: usize,
    ) -> Result<(), NotPositiveDefinite> {
        let tree = self.tree;
        let mut scratch = tree.take_scratch(self.symbolic.nrows());
        let result = range
            .filter(|&t| self.computes(t))
            .try_for_each(|t| self.supernode_in(t, values, offset, &mut scratch));
        tree.give_scratch(scratch);
        result
    }

    /// Factors supernode `t` whose descendants' values are in `values` (from `offset`).
    fn supernode_in(
        &self,
        t: usize,
        values: &mut [f64],
        offset: usize,
        scratch: &mut Scratch,
    ) -> Result<(), NotPositiveDefinite> {
        let (head, tail) = values.split_at_mut(self.value_start(t) - offset);
        let own = &mut tail[..self.value_start(t + 1) - self.value_start(t)];
        self.supernode(t, head, offset, own, scratch)
    }

    /// Subtracts from `block` — the columns of supernode `s` from its column `first` on, all
    /// its rows — the updates of its updaters' eliminated columns, reading their values from
    /// `head` (from value offset `offset`); `g2l` maps s's pattern rows to its rows.
    #[allow(clippy::too_many_arguments)]
    fn updates(
        &self,
        s: usize,
        head: &[f64],
        offset: usize,
        first: usize,
        mut block: MatMut<'_, f64>,
        g2l: &[u32],
        scratch: &mut BlockScratch,
    ) {
        let symbolic = self.symbolic;
        let s_start = symbolic.supernode_begin()[s] as usize;
        let s_end = symbolic.supernode_end()[s] as usize;
        let (col_lo, col_hi) = (s_start + first, s_start + first + block.ncols());
        let tree = self.tree;
        let ups = &tree.updaters[tree.updater_ptr[s] as usize..tree.updater_ptr[s + 1] as usize];
        for &d in ups {
            let d = d as usize;
            let d_pattern = symbolic.supernode(d).pattern();
            let d_start = symbolic.supernode_begin()[d] as usize;
            let d_ncols = symbolic.supernode_end()[d] as usize - d_start;
            let d_nrows = d_pattern.len() + d_ncols;
            // Only the eliminated columns of d update s.
            let d_used = d_ncols.min(self.eliminated.saturating_sub(d_start));
            if d_used == 0 {
                continue;
            }
            let lo = d_pattern.partition_point(|&r| (r as usize) < col_lo);
            let mid = d_pattern[lo..].partition_point(|&r| (r as usize) < col_hi);
            if mid == 0 {
                continue;
            }
            let start = self.value_start(d) - offset;
            let ld = MatRef::from_column_major_slice(
                &head[start..start + d_nrows * d_ncols],
                d_nrows,
                d_ncols,
            )
            .subcols(0, d_used);
            let bot = ld.subrows(d_ncols + lo, d_pattern.len() - lo);
            let top = bot.subrows(0, mid);
            let m = bot.nrows();
            for (k, &r) in d_pattern[lo..].iter().enumerate() {
                let r = r as usize;
                scratch.rows[k] = if r < s_end {
                    (r - s_start) as u32
                } else {
                    g2l[r]
                };
            }
            for k in 0..mid {
                scratch.cols[k] = (d_pattern[lo + k] as usize - col_lo) as u32;
            }
            // The update block bot·topᵀ (lower triangle of its square top), scattered.
            let mut upd = self::block(&mut scratch.update, m, mid);
            lower_product(upd.rb_mut(), bot, top);
            for j in 0..mid {
                let col = scratch.cols[j] as usize;
                for i in j..m {
                    block[(scratch.rows[i] as usize, col)] -= upd[(i, j)];
                }
            }
        }
    }

    /// Factors supernode `s` into `own`, reading its updaters' values from `head` (which
    /// starts at value offset `offset`): faer's left-looking step.
    fn supernode(
        &self,
        s: usize,
        head: &[f64],
        offset: usize,
        own: &mut [f64],
        scratch: &mut Scratch,
    ) -> Result<(), NotPositiveDefinite> {
        let symbolic = self.symbolic;
        let s_start = symbolic.supernode_begin()[s] as usize;
        let s_end = symbolic.supernode_end()[s] as usize;
        let s_pattern = symbolic.supernode(s).pattern();
        let s_ncols = s_end - s_start;
        let s_nrows = s_pattern.len() + s_ncols;
        let g2l = &mut scratch.global_to_local;
        for (i, &row) in s_pattern.iter().enumerate() {
            g2l[row as usize] = (i + s_ncols) as u32;
        }
        own.fill(0.0);
        let mut ls = MatMut::from_column_major_slice_mut(own, s_nrows, s_ncols);
        for j in s_start..s_end {
            let jj = j - s_start;
            let a = self.a_lower;
            for (i, &v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                if i < j {
                    continue;
                }
                let ii = if i >= s_end {
                    g2l[i] as usize
                } else {
                    i - s_start
                };
                ls[(ii, jj)] += v;
            }
        }
        let tree = self.tree;
        let g2l = &scratch.global_to_local;
        if tree.split[s] {
            let mut blocks = Vec::with_capacity(UPDATE_BLOCKS);
            let mut rest = ls.rb_mut();
            let mut first = 0;
            for end in update_block_ends(s_ncols, s_nrows) {
                let (block, right) = rest.split_at_col_mut(end - first);
                blocks.push((first, block));
                rest = right;
                first = end;
            }
            blocks.into_par_iter().for_each(|(first, block)| {
                let mut local = tree.take_block_scratch();
                self.updates(s, head, offset, first, block, g2l, &mut local);
                tree.give_block_scratch(local);
            });
        } else {
            self.updates(s, head, offset, 0, ls.rb_mut(), g2l, &mut scratch.block);
        }
        let g2l = &mut scratch.global_to_local;
        for &row in s_pattern {
            g2l[row as usize] = NONE;
        }
        // Columns of s to eliminate; a supernode straddling the border then updates its
        // other columns with them.
        let k = s_ncols.min(self.eliminated.saturating_sub(s_start));
        if k == 0 {
            return Ok(());
        }
        let (mut ls_left, mut ls_right) = ls.split_at_col_mut(k);
        let (mut top, mut below) = ls_left.rb_mut().split_at_row_mut(k);
        cholesky_in_place(
            top.rb_mut(),
            Default::default(),
            Par::Seq,
            MemStack::new(&mut scratch.stack),
            Default::default(),
        )
        .map_err(|_| NotPositiveDefinite)?;
        solve_lower_triangular_in_place(top.rb(), below.rb_mut().transpose_mut(), Par::Seq);
        let rest = s_ncols - k;
        if rest > 0 {
            let m = below.nrows();
            let mut upd = block(&mut scratch.block.update, m, rest);
            lower_product(upd.rb_mut(), below.rb(), below.rb().subrows(0, rest));
            for j in 0..rest {
                for i in j..m {
                    ls_right[(k + i, j)] -= upd[(i, j)];
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;
    use faer::Side;
    use faer::dyn_stack::MemBuffer;
    use faer::linalg::solvers::Solve;
    use faer::perm::PermRef;
    use faer::sparse::linalg::cholesky::supernodal::{
        SupernodalLltRef, factorize_supernodal_numeric_llt,
        factorize_supernodal_numeric_llt_scratch,
    };
    use faer::sparse::linalg::cholesky::{
        CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
        factorize_symbolic_cholesky,
    };
    use faer::sparse::linalg::{SupernodalThreshold, SymbolicSupernodalParams, amd};
    use faer::sparse::{SparseColMat, Triplet};

    /// Lower triangle of a symmetric positive definite matrix on an nx × ny grid of nodes
    /// with two unknowns each, coupled over the 3 × 3 neighbourhood (the pattern of bilinear
    /// elements), with pseudo-random off-diagonal values and a dominant diagonal.
    fn grid_matrix(nx: usize, ny: usize) -> SparseColMat<u32, f64> {
        let n = 2 * nx * ny;
        let mut seed = 7u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut triplets = Vec::new();
        let mut row_sum = vec![0.0; n];
        for j in 0..ny {
            for i in 0..nx {
                for (di, dj) in [(0i64, 0i64), (1, 0), (-1, 1), (0, 1), (1, 1)] {
                    let (i2, j2) = (i as i64 + di, j as i64 + dj);
                    if i2 < 0 || i2 >= nx as i64 || j2 >= ny as i64 {
                        continue;
                    }
                    let (a, b) = (j * nx + i, j2 as usize * nx + i2 as usize);
                    for p in 0..2 {
                        for q in 0..2 {
                            let (r, c) = (2 * a + p, 2 * b + q);
                            if r == c || (a == b && p < q) {
                                continue;
                            }
                            let v = next();
                            let (r, c) = if r > c { (r, c) } else { (c, r) };
                            triplets.push(Triplet::new(r as u32, c as u32, v));
                            row_sum[r] += v.abs();
                            row_sum[c] += v.abs();
                        }
                    }
                }
            }
        }
        for (k, s) in row_sum.iter().enumerate() {
            triplets.push(Triplet::new(k as u32, k as u32, s + 1.0));
        }
        SparseColMat::try_new_from_triplets(n, n, &triplets).unwrap()
    }

    /// `a` (lower triangle) renumbered by AMD, as the condensed solver orders its bulk: a
    /// bushy elimination tree (the natural order of a grid gives a path).
    fn amd_ordered(a: &SparseColMat<u32, f64>) -> SparseColMat<u32, f64> {
        let n = a.nrows();
        let (mut fwd, mut inv) = (vec![0u32; n], vec![0u32; n]);
        let mut mem = MemBuffer::new(amd::order_maybe_unsorted_scratch::<u32>(n, a.compute_nnz()));
        amd::order_maybe_unsorted(
            &mut fwd,
            &mut inv,
            a.symbolic(),
            Default::default(),
            MemStack::new(&mut mem),
        )
        .unwrap();
        let triplets: Vec<_> = (0..n)
            .flat_map(|j| {
                let inv = &inv;
                a.row_idx_of_col(j)
                    .zip(a.val_of_col(j))
                    .map(move |(i, &v)| {
                        let (r, c) = (inv[i] as usize, inv[j] as usize);
                        let (r, c) = if r >= c { (r, c) } else { (c, r) };
                        Triplet::new(r as u32, c as u32, v)
                    })
            })
            .collect();
        SparseColMat::try_new_from_triplets(n, n, &triplets).unwrap()
    }

    /// Supernodal symbolic factorisation of `a` (lower triangle) in its own order.
    fn symbolic_of(a: &SparseColMat<u32, f64>) -> SymbolicCholesky<u32> {
        let n = a.nrows();
        let identity: Vec<u32> = (0..n as u32).collect();
        factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            SymmetricOrdering::Custom(PermRef::new_checked(&identity, &identity, n)),
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                supernodal_params: SymbolicSupernodalParams::default(),
                ..Default::default()
            },
        )
        .unwrap()
    }

    /// The AMD-ordered grid matrix of `grid_matrix(nx, ny)` and its symbolic factorisation.
    fn grid_case(nx: usize, ny: usize) -> (SparseColMat<u32, f64>, SymbolicCholesky<u32>) {
        let a = amd_ordered(&grid_matrix(nx, ny));
        let symbolic = symbolic_of(&a);
        (a, symbolic)
    }

    fn supernodal(symbolic: &SymbolicCholesky<u32>) -> &SymbolicSupernodalCholesky<u32> {
        let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
            panic!("supernodal forced")
        };
        s
    }

    /// The factor on a pool of `threads` threads.
    fn tree_factor(
        a: &SparseColMat<u32, f64>,
        symbolic: &SymbolicSupernodalCholesky<u32>,
        threads: usize,
        eliminated: usize,
        split_from: f64,
    ) -> Vec<f64> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let tree = TreeCholesky::with_split(symbolic, threads, split_from);
            let schedule = tree
                .schedule
                .as_ref()
                .expect("faer numbers supernodes in postorder");
            // Count the tasks: subtrees below the grain whose parent is above it.
            let big = |s: usize| schedule.work[s] >= schedule.grain;
            let tasks = (0..symbolic.n_supernodes())
                .filter(|&s| big(s))
                .flat_map(|s| {
                    &schedule.children
                        [schedule.child_ptr[s] as usize..schedule.child_ptr[s + 1] as usize]
                })
                .filter(|&&c| !big(c as usize))
                .count();
            assert!(tasks >= 4 * threads.min(2), "only {tasks} tasks");
            let mut values = vec![0.0; symbolic.len_val()];
            tree.factorize(&mut values, a.as_ref(), symbolic, eliminated, None)
                .unwrap();
            values
        })
    }

    #[test]
    fn tree_factor_matches_faer_and_is_bitwise_the_same_on_one_and_two_threads() {
        let (a, symbolic) = grid_case(40, 30);
        let (n, s) = (a.nrows(), supernodal(&symbolic));
        let one = tree_factor(&a, s, 1, n, SPLIT_UPDATES_FROM);
        let two = tree_factor(&a, s, 2, n, SPLIT_UPDATES_FROM);
        let three = tree_factor(&a, s, 3, n, SPLIT_UPDATES_FROM);
        // Every supernode's updates gathered in column blocks: the same on any threads.
        let split_one = tree_factor(&a, s, 1, n, 0.0);
        let split_two = tree_factor(&a, s, 2, n, 0.0);
        assert!(
            split_one
                .iter()
                .zip(&split_two)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
        assert!(
            one.iter()
                .zip(&two)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
        assert!(
            one.iter()
                .zip(&three)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
        // The same without the schedule (supernodes in their own order, one task).
        let mut tree = TreeCholesky::new(s, 2);
        tree.schedule = None;
        let mut plain = vec![0.0; s.len_val()];
        tree.factorize(&mut plain, a.as_ref(), s, n, None).unwrap();
        assert!(
            one.iter()
                .zip(&plain)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
        // faer's own loop, to rounding: its kernels differ from these (fused scatter).
        let mut reference = vec![0.0; s.len_val()];
        let mut mem = MemBuffer::new(factorize_supernodal_numeric_llt_scratch::<u32, f64>(
            s,
            Par::Seq,
            Default::default(),
        ));
        factorize_supernodal_numeric_llt(
            &mut reference,
            a.as_ref(),
            Default::default(),
            s,
            Par::Seq,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .unwrap();
        let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for values in [&one, &split_one] {
            let worst = values
                .iter()
                .zip(&reference)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            assert!(
                worst <= 1e-13 * scale,
                "differs from faer by {worst:e} (scale {scale:e})"
            );
        }
        // And it solves: L Lᵀ x = b.
        let llt = SupernodalLltRef::new(s, &one);
        let b = Mat::from_fn(n, 1, |i, _| (i % 7) as f64 - 3.0);
        let mut x = b.clone();
        let mut mem = MemBuffer::new(s.solve_in_place_scratch::<f64>(1, Par::Seq));
        llt.solve_in_place_with_conj(
            faer::Conj::No,
            x.as_mut(),
            Par::Seq,
            MemStack::new(&mut mem),
        );
        let full = a.to_dense();
        let sym = Mat::from_fn(
            n,
            n,
            |i, j| if i >= j { full[(i, j)] } else { full[(j, i)] },
        );
        let residual = &sym * &x - &b;
        assert!(residual.norm_max() <= 1e-12 * b.norm_max());
    }

    /// `top_down` visits every supernode exactly once and each after its parent, with the
    /// schedule on one and two threads and without it.
    #[test]
    fn top_down_visits_every_supernode_once_after_its_parent() {
        let (_, symbolic) = grid_case(40, 30);
        let s = supernodal(&symbolic);
        let order_on = |threads: usize, scheduled: bool| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut tree = TreeCholesky::new(s, threads);
                if !scheduled {
                    tree.schedule = None;
                }
                let visits = Mutex::new(Vec::new());
                // Each task's scratch counts the supernodes it visits.
                let pool = Mutex::new(Vec::new());
                tree.top_down(
                    &pool,
                    || 0usize,
                    |t, count| {
                        visits.lock().unwrap().push(t);
                        *count += 1;
                    },
                );
                let tasks = pool.into_inner().unwrap().len();
                (tree, visits.into_inner().unwrap(), tasks)
            })
        };
        for (threads, scheduled) in [(1, true), (2, true), (2, false)] {
            let (tree, order, tasks) = order_on(threads, scheduled);
            let mut when = vec![usize::MAX; s.n_supernodes()];
            for (k, &t) in order.iter().enumerate() {
                assert_eq!(when[t], usize::MAX, "supernode {t} visited twice");
                when[t] = k;
            }
            assert!(
                when.iter().all(|&k| k != usize::MAX),
                "a supernode not visited"
            );
            for (t, &p) in tree.parent.iter().enumerate() {
                if p != NONE {
                    assert!(when[p as usize] < when[t], "{t} before its parent {p}");
                }
            }
            // With the schedule the tree is cut into several tasks, whose scratches the pool
            // keeps (as many as ran at once: at least one).
            assert!(tasks >= 1, "{tasks} scratches");
        }
    }

    #[test]
    fn refactoring_the_supernodes_of_changed_columns_gives_the_whole_factorisations_bits() {
        let (a, symbolic) = grid_case(40, 30);
        let (n, s) = (a.nrows(), supernodal(&symbolic));
        let eliminated = n - 20;
        let tree = TreeCholesky::new(s, 2);
        let mut values = vec![0.0; s.len_val()];
        tree.factorize(&mut values, a.as_ref(), s, eliminated, None)
            .unwrap();
        // Change the entries of a few columns (a small "plastic zone"): scale column j's
        // below-diagonal entries, which keeps the matrix diagonally dominant.
        let mut changed_matrix = a.clone();
        let mut changed = vec![false; n];
        let col_ptr = a.symbolic().col_ptr().to_vec();
        let row_idx = a.symbolic().row_idx().to_vec();
        for j in [3, 4, 5, n / 3] {
            changed[j] = true;
            let range = col_ptr[j] as usize..col_ptr[j + 1] as usize;
            for (v, &row) in changed_matrix.val_mut()[range.clone()]
                .iter_mut()
                .zip(&row_idx[range])
            {
                if row as usize != j {
                    *v *= 0.5;
                }
            }
        }
        let mut refactor = Vec::new();
        let count = tree.supernodes_to_refactor(s, &changed, eliminated, &mut refactor);
        assert_eq!(count, refactor.iter().filter(|&&r| r).count());
        assert!(
            count > 0 && count < s.n_supernodes() / 4,
            "{count} of {}",
            s.n_supernodes()
        );
        tree.factorize(
            &mut values,
            changed_matrix.as_ref(),
            s,
            eliminated,
            Some(&refactor),
        )
        .unwrap();
        let mut whole = vec![0.0; s.len_val()];
        tree.factorize(&mut whole, changed_matrix.as_ref(), s, eliminated, None)
            .unwrap();
        assert!(
            values
                .iter()
                .zip(&whole)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
        // The factor did change: the partial factorisation was not a no-op.
        let mut before = vec![0.0; s.len_val()];
        tree.factorize(&mut before, a.as_ref(), s, eliminated, None)
            .unwrap();
        assert!(before.iter().zip(&whole).any(|(x, y)| x != y));
    }

    #[test]
    fn partial_factor_leaves_the_schur_complement_of_the_eliminated_block() {
        let (a, symbolic) = grid_case(12, 10);
        let (n, s) = (a.nrows(), supernodal(&symbolic));
        let full = a.to_dense();
        let sym = Mat::from_fn(
            n,
            n,
            |i, j| if i >= j { full[(i, j)] } else { full[(j, i)] },
        );
        // Cuts inside supernodes and at their borders.
        for eliminated in [n / 2, n / 2 + 1, n - 30, n - 1] {
            let values = tree_factor(&a, s, 2, eliminated, 0.0);
            let k = eliminated;
            let bb = sym.submatrix(0, 0, k, k).to_owned();
            let bi = sym.submatrix(0, k, k, n - k).to_owned();
            let schur = sym.submatrix(k, k, n - k, n - k).to_owned()
                - bi.transpose() * bb.llt(faer::Side::Lower).unwrap().solve(&bi);
            let llt = SupernodalLltRef::new(s, &values);
            let mut got = Mat::<f64>::zeros(n - k, n - k);
            for t in 0..s.n_supernodes() {
                let node = llt.supernode(t);
                let (start, ls, pattern) = (node.start(), node.val(), node.pattern());
                let width = ls.ncols();
                for jj in k.saturating_sub(start)..width {
                    for ii in jj..width {
                        got[(start + ii - k, start + jj - k)] = ls[(ii, jj)];
                    }
                    for (idx, &row) in pattern.iter().enumerate() {
                        got[(row as usize - k, start + jj - k)] = ls[(width + idx, jj)];
                    }
                }
            }
            for j in 0..n - k {
                for i in j..n - k {
                    let d = (got[(i, j)] - schur[(i, j)]).abs();
                    assert!(
                        d <= 1e-12 * schur.norm_max(),
                        "eliminated {k}: ({i},{j}) off by {d:e}"
                    );
                }
            }
        }
    }

    #[test]
    fn an_indefinite_matrix_is_refused_and_a_tree_out_of_postorder_is_not_scheduled() {
        let mut a = grid_matrix(10, 10);
        let n = a.nrows();
        let symbolic = symbolic_of(&a);
        let s = supernodal(&symbolic);
        // Make the last diagonal entry negative (the last column holds only it).
        let col_start = a.symbolic().col_ptr()[n - 1] as usize;
        a.val_mut()[col_start] = -1.0;
        let tree = TreeCholesky::new(s, 2);
        let mut values = vec![0.0; s.len_val()];
        assert!(tree.factorize(&mut values, a.as_ref(), s, n, None).is_err());
        // Parent 2 ← 0 and 1 ← 2 breaks the postorder (a parent before its child).
        assert!(Schedule::new(&[2, NONE, 1], vec![1.0; 3], 2).is_none());
        // Children 0 and 2 of 3 with 1 (a root) between them: subtrees not consecutive.
        assert!(Schedule::new(&[3, NONE, 3, NONE], vec![1.0; 4], 2).is_none());
        assert!(Schedule::new(&[2, 2, NONE], vec![1.0; 3], 2).is_some());
    }
}
