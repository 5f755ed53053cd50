//! Degrees of freedom, the sparsity pattern (built once per model) and the assembly of
//! tangent matrix and internal-force vector from sets of elements.
//!
//! The global matrix is stored in full compressed-column form over the free degrees of
//! freedom, so that unsymmetric element contributions (friction, Buczkowski & Kleiber
//! (1994), Eq. 21) can be assembled as they are; the Cholesky path reads only its lower
//! triangle.
//!
//! Assembly runs in parallel without locks: elements are greedily coloured so that no two
//! elements of one colour share a node, hence no two write the same matrix entry or vector
//! component, and the colours are processed one after another.

use std::sync::Arc;

use faer::MatMut;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use rayon::prelude::*;

use crate::contact::ContactAlgorithm;
use crate::element::quadrature::MAX_CELL_POINTS;
use crate::element::set::{ElementSet, INTERFACE_POINTS};
use crate::element::{
    ElementInput, ElementMatrix, ElementOutput, ElementVector, MAX_ELEMENT_DOFS, MAX_ELEMENT_NODES,
};

/// Marker for a constrained (prescribed) degree of freedom in [`DofMap`].
const FIXED: u32 = u32::MAX;

/// Numbering of the equations: D degrees of freedom per node (x, y, and with twist θ: see
/// [`Analysis::dofs_per_node`](crate::element::Analysis::dofs_per_node)), global dof index
/// `D·node + component`; free dofs get consecutive equation numbers in node order.
#[derive(Clone, Debug)]
pub struct DofMap {
    equation: Vec<u32>,
    free: usize,
}

impl DofMap {
    /// Numbers the dofs of `node_count` nodes; `fixed[dof]` marks prescribed ones.
    pub fn new(fixed: &[bool]) -> Self {
        let mut free = 0u32;
        let equation = fixed
            .iter()
            .map(|&f| {
                if f {
                    FIXED
                } else {
                    free += 1;
                    free - 1
                }
            })
            .collect();
        Self {
            equation,
            free: free as usize,
        }
    }

    /// Number of free dofs (unknowns).
    pub fn free_count(&self) -> usize {
        self.free
    }

    /// Total number of dofs (D per node).
    pub fn dof_count(&self) -> usize {
        self.equation.len()
    }

    /// Equation number of global dof `dof`, or `None` if it is prescribed.
    #[inline]
    pub fn equation(&self, dof: usize) -> Option<usize> {
        let e = self.equation[dof];
        (e != FIXED).then_some(e as usize)
    }

    /// Whether one of the `nodes` (`d` dofs each) has a prescribed dof.
    pub fn holds_prescribed(&self, nodes: &[u32], d: usize) -> bool {
        (nodes.iter()).any(|&n| (0..d).any(|c| self.equation(d * n as usize + c).is_none()))
    }

    /// Gathers the free components of a full dof vector into an equation vector.
    pub fn gather_free(&self, full: &[f64], out: &mut [f64]) {
        for (dof, &v) in full.iter().enumerate() {
            if let Some(eq) = self.equation(dof) {
                out[eq] = v;
            }
        }
    }

    /// Adds `alpha` times an equation vector into the free components of a full dof vector.
    pub fn add_free(&self, alpha: f64, eqs: &[f64], full: &mut [f64]) {
        for (dof, v) in full.iter_mut().enumerate() {
            if let Some(eq) = self.equation(dof) {
                *v += alpha * eqs[eq];
            }
        }
    }
}
/// Groups of elements of one set such that no two elements of a group share a node.
#[derive(Clone, Debug, Default)]
pub struct Coloring {
    groups: Vec<Vec<u32>>,
}

impl Coloring {
    /// Greedy colouring of the elements of `set` over `node_count` nodes.
    pub fn new<S: ElementSet>(set: &S, node_count: usize) -> Self {
        const MAX_COLORS: usize = 64;
        let mut used = vec![0u64; node_count];
        let mut groups: Vec<Vec<u32>> = Vec::new();
        for e in 0..set.len() {
            let nodes = set.nodes(e);
            let taken = nodes.iter().fold(0u64, |m, &n| m | used[n as usize]);
            // With more than 64 colours (never seen on 2D meshes) the rest share the last
            // group, which `assemble` then runs serially.
            let color = (taken.trailing_ones() as usize).min(MAX_COLORS - 1);
            for &n in nodes {
                used[n as usize] |= 1 << color;
            }
            if groups.len() <= color {
                groups.resize_with(color + 1, Vec::new);
            }
            groups[color].push(e as u32);
        }
        Self { groups }
    }

    /// Number of colours.
    pub fn len(&self) -> usize {
        self.groups.len()
    }

    /// Whether there are no elements at all.
    pub fn is_empty(&self) -> bool {
        self.groups.is_empty()
    }
}

/// The compressed-column pattern of the global matrix over the free dofs, built once per
/// model from the element connectivity. Clones share the one pattern (at a million unknowns
/// its row indices are over 100 MB; the model and the Newton system hold the same one).
#[derive(Clone, Debug)]
pub struct SparsityPattern {
    symbolic: Arc<SymbolicSparseColMat<u32>>,
}

/// The nodes of one element for [`SparsityPattern::new`], and whether its matrix couples
/// the in-plane displacements with the circumferential one (twist). An isotropic elastic
/// cell's does not (its stiffness is block diagonal in (u_r, u_z | u_θ)); a plastic cell's
/// and an interface element's (friction) do. Without twist the flag is irrelevant.
#[derive(Clone, Copy, Debug)]
pub struct ElementNodes<'a> {
    pub nodes: &'a [u32],
    pub couples_twist: bool,
}

impl<'a> From<&'a [u32]> for ElementNodes<'a> {
    /// An element whose matrix may couple every component with every other.
    fn from(nodes: &'a [u32]) -> Self {
        Self {
            nodes,
            couples_twist: true,
        }
    }
}

/// Whether components `c` and `d` of two nodes are coupled by an element that does not
/// couple twist: both in-plane (0, 1) or both circumferential (2).
#[inline]
fn same_block(c: usize, d: usize) -> bool {
    (c == 2) == (d == 2)
}

impl SparsityPattern {
    /// Pattern of all element sets' couplings. `connectivity` yields the nodes of every
    /// element of every set (with whether it couples twist, [`ElementNodes`]). With twist,
    /// components that no element couples are left out, so that the factorisation of a
    /// model whose elastic bodies' u_θ decouples from (u_r, u_z) costs the two blocks', not
    /// the whole 3-dof system's.
    pub fn new<'a, E: Into<ElementNodes<'a>>>(
        node_count: usize,
        dofs: &DofMap,
        connectivity: impl Iterator<Item = E>,
    ) -> Self {
        let elements: Vec<ElementNodes> = connectivity.map(Into::into).collect();
        let node_elements = NodeElements::new(node_count, &elements);
        let d = dofs.dof_count() / node_count.max(1);
        // On all cores, by blocks of nodes: the nodes' neighbours and their columns' lengths,
        // then (once the columns' starts are known) their rows, written in place.
        // Blocks small enough to share out evenly on small meshes too.
        const NODES_PER_BLOCK: usize = 512;
        let blocks: Vec<NodeBlock> = (0..node_count.div_ceil(NODES_PER_BLOCK))
            .into_par_iter()
            .map(|b| {
                let nodes = b * NODES_PER_BLOCK..((b + 1) * NODES_PER_BLOCK).min(node_count);
                NodeBlock::new(nodes, (dofs, d), &node_elements, &elements)
            })
            .collect();
        let mut col_ptr = Vec::with_capacity(dofs.free_count() + 1);
        col_ptr.push(0u32);
        for block in &blocks {
            for &l in &block.lengths {
                col_ptr.push(col_ptr[col_ptr.len() - 1] + l);
            }
        }
        let mut row_idx = vec![0u32; col_ptr[col_ptr.len() - 1] as usize];
        let mut rest = row_idx.as_mut_slice();
        let mut parts = Vec::with_capacity(blocks.len());
        for block in &blocks {
            let len = block.lengths.iter().map(|&l| l as usize).sum();
            let (part, tail) = rest.split_at_mut(len);
            parts.push((part, block));
            rest = tail;
        }
        parts
            .into_par_iter()
            .for_each(|(part, block)| block.write_rows((dofs, d), part));
        drop(blocks);
        let n = dofs.free_count();
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        Self {
            symbolic: Arc::new(symbolic),
        }
    }

    /// Number of rows (= columns = free dofs).
    pub fn size(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Number of stored entries (both triangles).
    pub fn nnz(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    /// The faer symbolic matrix.
    pub fn symbolic(&self) -> &SymbolicSparseColMat<u32> {
        &self.symbolic
    }
}

/// The entries of a set's matrix in prescribed rows and columns, over every dof (numbered by
/// dof): the set's elements with a prescribed dof, assembled beside the free system by
/// [`GlobalSystem::assemble_with_prescribed`]. With the free system's matrix they are the
/// whole matrix over every dof (its product with every dof's displacements gives the
/// reactions too), for the pattern and values of the supports' elements instead of those of
/// a second matrix over every dof.
#[derive(Debug)]
pub struct PrescribedCouplings {
    /// The flagged elements' pattern over every dof; it also holds their entries between
    /// free dofs, which the free system has.
    pattern: SparsityPattern,
    values: Vec<f64>,
    /// Every dof free.
    all: DofMap,
    /// Whether each element has a prescribed dof.
    elements: Vec<bool>,
}

impl PrescribedCouplings {
    /// Zeroed couplings of the elements `connectivity` (each element's nodes, as in
    /// [`SparsityPattern::new`]) of a mesh of `node_count` nodes whose dofs are numbered by
    /// `dofs`.
    pub fn new(node_count: usize, dofs: &DofMap, connectivity: &[ElementNodes]) -> Self {
        let d = dofs.dof_count() / node_count.max(1);
        let held = |element: &ElementNodes| dofs.holds_prescribed(element.nodes, d);
        let elements: Vec<bool> = connectivity.par_iter().map(held).collect();
        let all = DofMap::new(&vec![false; dofs.dof_count()]);
        let held_elements = connectivity
            .iter()
            .zip(&elements)
            .filter(|&(_, &h)| h)
            .map(|(&element, _)| element);
        let pattern = SparsityPattern::new(node_count, &all, held_elements);
        Self {
            values: vec![0.0; pattern.nnz()],
            pattern,
            all,
            elements,
        }
    }

    /// The couplings as a matrix over every dof.
    pub fn matrix(&self) -> SparseColMatRef<'_, u32, f64> {
        SparseColMatRef::new(self.pattern.symbolic().as_ref(), &self.values)
    }
}

/// The elements at each node of a mesh (compressed rows), for the nodes' neighbours.
struct NodeElements {
    start: Vec<usize>,
    elements: Vec<u32>,
}

impl NodeElements {
    fn new(node_count: usize, elements: &[ElementNodes]) -> Self {
        let mut start = vec![0usize; node_count + 1];
        for element in elements {
            for &n in element.nodes {
                start[n as usize + 1] += 1;
            }
        }
        for i in 0..node_count {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut at_node = vec![0u32; start[node_count]];
        for (e, element) in elements.iter().enumerate() {
            for &n in element.nodes {
                at_node[fill[n as usize]] = e as u32;
                fill[n as usize] += 1;
            }
        }
        Self {
            start,
            elements: at_node,
        }
    }

    /// The nodes sharing an element with `node` (itself included), ascending, each with
    /// whether some element couples twist between the two, into `out`.
    fn neighbours(&self, node: usize, elements: &[ElementNodes], out: &mut Vec<(u32, bool)>) {
        out.clear();
        for &e in &self.elements[self.start[node]..self.start[node + 1]] {
            let element = elements[e as usize];
            out.extend(element.nodes.iter().map(|&m| (m, element.couples_twist)));
        }
        // Coupled entries first among equal nodes, so dedup keeps them.
        out.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(b.1.cmp(&a.1)));
        out.dedup_by_key(|x| x.0);
    }
}

/// The rows of column `c` (component `c` of `node`, `d` components per node) in a pattern whose
/// `node` has neighbours `adjacent` ([`NodeElements::neighbours`]); `None` if the column's dof
/// is prescribed.
fn column_rows<'a>(
    dofs: &'a DofMap,
    d: usize,
    node: usize,
    c: usize,
    adjacent: &'a [(u32, bool)],
) -> Option<impl Iterator<Item = usize> + 'a> {
    dofs.equation(d * node + c)?;
    Some(adjacent.iter().flat_map(move |&(m, coupled)| {
        (0..d)
            .filter(move |&k| coupled || same_block(c, k))
            .filter_map(move |k| dofs.equation(d * m as usize + k))
    }))
}

/// A block of consecutive nodes in [`SparsityPattern::new`]: each node's neighbours (those
/// of node `nodes.start + i` end at `start[i]`) and the lengths of its free columns.
#[derive(Default)]
struct NodeBlock {
    nodes: std::ops::Range<usize>,
    start: Vec<u32>,
    neighbours: Vec<(u32, bool)>,
    lengths: Vec<u32>,
}

impl NodeBlock {
    /// The neighbours of `nodes` and the lengths of their columns (`d` components per node,
    /// numbered by `dofs`).
    fn new(
        nodes: std::ops::Range<usize>,
        (dofs, d): (&DofMap, usize),
        node_elements: &NodeElements,
        elements: &[ElementNodes],
    ) -> Self {
        let mut block = NodeBlock {
            nodes: nodes.clone(),
            ..Default::default()
        };
        let mut adjacent = Vec::new();
        for node in nodes {
            node_elements.neighbours(node, elements, &mut adjacent);
            block.neighbours.extend_from_slice(&adjacent);
            block.start.push(block.neighbours.len() as u32);
            // The components of one block of a node have the same rows: counted once.
            let mut last: Option<(bool, u32)> = None;
            for c in 0..d {
                let Some(column) = column_rows(dofs, d, node, c, &adjacent) else {
                    continue;
                };
                let length = match last {
                    Some((twist, length)) if twist == (c == 2) => length,
                    _ => column.count() as u32,
                };
                block.lengths.push(length);
                last = Some((c == 2, length));
            }
        }
        block
    }

    /// Writes the rows of the block's columns, in order, into `rows` (as long as the
    /// lengths' sum).
    fn write_rows(&self, (dofs, d): (&DofMap, usize), rows: &mut [u32]) {
        let mut at = 0;
        let mut from = 0;
        for (node, &to) in self.nodes.clone().zip(&self.start) {
            let adjacent = &self.neighbours[from..to as usize];
            // The components of one block of a node have the same rows: written once, then
            // copied.
            let mut last: Option<(bool, std::ops::Range<usize>)> = None;
            for c in 0..d {
                let Some(column) = column_rows(dofs, d, node, c, adjacent) else {
                    continue;
                };
                let start = at;
                match &last {
                    Some((twist, written)) if *twist == (c == 2) => {
                        rows.copy_within(written.clone(), at);
                        at += written.len();
                    }
                    _ => {
                        for (eq, slot) in column.zip(&mut rows[at..]) {
                            *slot = eq as u32;
                            at += 1;
                        }
                    }
                }
                last = Some((c == 2, start..at));
            }
            from = to as usize;
        }
        debug_assert_eq!(at, rows.len(), "the rows fill the block's columns");
    }
}

/// Marker for a dof outside the dense block in [`DenseScatter`].
const OUTSIDE: u32 = u32::MAX;

/// Precomputed map from the dofs of every element of a set to the rows/columns of a dense
/// block over some equations (e.g. the interface unknowns of the condensed solver), built
/// once per model so that assembling into the block needs no search and no allocation.
#[derive(Clone, Debug, Default)]
pub struct DenseScatter {
    /// `map[e · STRIDE + a]`: the block index of dof `a` of element `e`, or `OUTSIDE`
    /// (prescribed, or not in the block).
    map: Vec<u32>,
}

impl DenseScatter {
    /// Dofs per element slot (8 nodes · at most 3).
    const STRIDE: usize = MAX_ELEMENT_DOFS;

    /// The map of the elements of `set`: `local(eq)` is the block index of free equation `eq`
    /// (`None` if it is not in the block).
    pub fn new<S: ElementSet>(
        set: &S,
        dofs: &DofMap,
        local: impl Fn(usize) -> Option<usize>,
    ) -> Self {
        let d = set.dofs_per_node();
        let mut map = vec![OUTSIDE; set.len() * Self::STRIDE];
        for e in 0..set.len() {
            for (n, &node) in set.nodes(e).iter().enumerate() {
                for c in 0..d {
                    if let Some(k) = dofs.equation(d * node as usize + c).and_then(&local) {
                        map[e * Self::STRIDE + d * n + c] = k as u32;
                    }
                }
            }
        }
        Self { map }
    }

    /// The entries of an n × n block the elements can write (column-major positions
    /// i + n·j, sorted): every other entry of the assembled block is zero.
    pub fn entries(&self, n: usize) -> Vec<usize> {
        let mut entries = Vec::new();
        for element in self.map.chunks_exact(Self::STRIDE) {
            let inside = element.iter().filter(|&&k| k != OUTSIDE);
            for &j in inside.clone() {
                entries.extend(inside.clone().map(|&i| i as usize + n * j as usize));
            }
        }
        entries.sort_unstable();
        entries.dedup();
        entries
    }

    /// Block indices of the dofs of element `e`.
    #[inline]
    fn element(&self, e: usize) -> &[u32] {
        &self.map[e * Self::STRIDE..(e + 1) * Self::STRIDE]
    }
}

/// What one assembly pass shares between all its elements: the displacements, their
/// numbering, and what to compute.
#[derive(Clone, Copy, Debug)]
pub struct AssemblyInput<'a> {
    /// The numbering of the equations.
    pub dofs: &'a DofMap,
    /// Displacements over all dofs (2 per node).
    pub u: &'a [f64],
    /// Whether the tangent is assembled; residual-only passes (the line search) skip it.
    pub tangent: bool,
    /// Which interface tangent the global iterations use (Buczkowski & Kleiber (1994),
    /// §2.4); it also decides which points record an unsymmetric tangent, so residual-only
    /// passes need it too.
    pub algorithm: ContactAlgorithm,
}

/// The assembled tangent matrix (values over a [`SparsityPattern`]) and internal-force vector
/// over all dofs (free and prescribed, so reactions can be read from it).
#[derive(Clone, Debug)]
pub struct GlobalSystem {
    pub pattern: SparsityPattern,
    pub values: Vec<f64>,
    pub internal_force: Vec<f64>,
    /// Values of a symmetric positive-definite approximation of an unsymmetric tangent, used
    /// to precondition its solution (see [`GlobalSystem::assemble_preconditioner`]).
    pub preconditioner: Vec<f64>,
    /// The constant part of the tangent of [`GlobalSystem::assemble_reusing`], made by its
    /// first call.
    reference: Option<Reference>,
}

/// The sum of every element's reference (elastic) matrix, made once, so that elements whose
/// tangent is their reference one ("frozen") need not be evaluated for the tangent nor
/// scattered (see [`GlobalSystem::assemble_reusing`]); and whether each element was frozen
/// at its last evaluation, which only decides whether its next one computes a tangent.
#[derive(Clone, Debug)]
struct Reference {
    values: Vec<f64>,
    frozen: Vec<bool>,
    /// Per free equation: whether an element whose tangent was not its reference one at the
    /// last tangent assembly has it (the matrix differs from K_ref in those columns only);
    /// valid only if `off_reference_current` (not after a plain tangent assembly).
    off_reference: Vec<bool>,
    off_reference_current: bool,
    /// Workspaces of the product K_ref u over the free equations (elements left out).
    u_free: Vec<f64>,
    force_free: Vec<f64>,
}

/// A raw pointer that may be shared between threads; its users make the writes through it
/// disjoint (the element colouring of [`GlobalSystem::assemble`]; the subtrees of the
/// condensed solver's backward substitution).
#[derive(Clone, Copy)]
pub(crate) struct SharedMut<T>(pub(crate) *mut T);
// SAFETY: only used to write locations that no other thread touches at the same time (the
// users' disjointness argument is at each use).
unsafe impl<T: Send> Send for SharedMut<T> {}
unsafe impl<T: Send> Sync for SharedMut<T> {}

impl<T> SharedMut<T> {
    /// The pointer. A method (not a field access) so that closures capture the whole
    /// `Sync` wrapper rather than the bare pointer.
    #[inline]
    pub(crate) fn get(self) -> *mut T {
        self.0
    }
}

/// A dense block receiving element tangents: its values and the scatter map of the elements'
/// dofs into it.
#[derive(Debug)]
pub struct DenseBlock<'a> {
    pub values: MatMut<'a, f64>,
    pub map: &'a DenseScatter,
}

/// `n` copies of `value`, written by the pool's threads: the kernel maps a large vector's
/// pages at that first write, in parallel (first touches cost about ten times a later write
/// on the virtual machines measured), and a vector of zeros written so is not left to a
/// later read-then-write (the shared zero page, then a copy-on-write fault with a TLB flush
/// on every core), as an assembly's `+=` into freshly allocated values would be.
pub fn filled_in_parallel<T: Clone + Send + Sync>(value: T, n: usize) -> Vec<T> {
    let mut v = Vec::with_capacity(n);
    v.par_extend(rayon::iter::repeat_n(value, n));
    v
}

impl GlobalSystem {
    /// Zeroed system over `pattern` with `dof_count` total dofs.
    pub fn new(pattern: SparsityPattern, dof_count: usize) -> Self {
        let nnz = pattern.nnz();
        Self {
            pattern,
            values: filled_in_parallel(0.0, nnz),
            internal_force: vec![0.0; dof_count],
            preconditioner: Vec::new(),
            reference: None,
        }
    }

    /// The preconditioner values as a faer view over the same pattern.
    pub fn preconditioner_matrix(&self) -> SparseColMatRef<'_, u32, f64> {
        SparseColMatRef::new(self.pattern.symbolic().as_ref(), &self.preconditioner)
    }

    /// Zeroes the matrix values (if `with_tangent`) and the internal force.
    pub fn clear(&mut self, with_tangent: bool) {
        if with_tangent {
            self.clear_values();
        }
        self.internal_force.fill(0.0);
    }

    /// Zeroes the matrix values alone.
    pub fn clear_values(&mut self) {
        self.values.fill(0.0);
        if let Some(r) = &mut self.reference {
            r.off_reference_current = false;
        }
    }

    /// The assembled matrix as a faer view.
    pub fn matrix(&self) -> SparseColMatRef<'_, u32, f64> {
        SparseColMatRef::new(self.pattern.symbolic().as_ref(), &self.values)
    }

    /// Adds the internal forces (and, if `input.tangent`, the tangents) of every element of
    /// `set` at the displacements `input.u`, updating `trial` states from `committed` ones.
    pub fn assemble<S: ElementSet>(
        &mut self,
        input: &AssemblyInput,
        set: &S,
        coloring: &Coloring,
        committed: &[S::State],
        trial: &mut [S::State],
    ) {
        self.assemble_with_prescribed(input, set, coloring, committed, trial, None);
    }

    /// [`Self::assemble`], with `prescribed` (and the tangent) also adding each element's
    /// matrix into the couplings if the element has a prescribed dof: the entries of the
    /// set's matrix in prescribed rows and columns, over every dof, from the same element
    /// loop. Entry by entry the same sums in the same (colour) order as an assembly over every
    /// dof, so both parts have that assembly's bits.
    pub fn assemble_with_prescribed<S: ElementSet>(
        &mut self,
        input: &AssemblyInput,
        set: &S,
        coloring: &Coloring,
        committed: &[S::State],
        trial: &mut [S::State],
        prescribed: Option<&mut PrescribedCouplings>,
    ) {
        let side = prescribed.map(|prescribed| {
            assert!(input.tangent, "the couplings are those of the tangent");
            assert_eq!(prescribed.elements.len(), set.len());
            Side {
                pattern: &prescribed.pattern,
                dofs: &prescribed.all,
                values: SharedMut(prescribed.values.as_mut_ptr()),
                elements: &prescribed.elements,
            }
        });
        let targets = Targets {
            values: input.tangent.then_some(SharedMut(self.values.as_mut_ptr())),
            force: Some(SharedMut(self.internal_force.as_mut_ptr())),
            dense: None,
            frozen: None,
            prescribed: side,
            left_out: None,
        };
        scatter(
            &self.pattern,
            input,
            set,
            coloring,
            committed,
            trial,
            targets,
        );
    }

    /// [`Self::assemble`] for a set whose elements' tangent is, most of the time, a constant
    /// reference matrix (elastic elements of a plastic body: every point that did not yield
    /// has the elastic tangent, see [`ElementSet::tangent_is_reference`]). The sum K_ref of
    /// all elements' reference matrices is made by the first call and kept; a tangent
    /// assembly is K_ref plus k_e − k_ref,e of the elements whose trial tangent is not their
    /// reference one, and evaluates the others ("frozen") for their forces and states only.
    /// Unlike [`Self::assemble`], a tangent assembly sets the matrix values (whatever they
    /// held) rather than adding to them; the forces are added. The result depends on the
    /// trial states alone, not on earlier assemblies (a resumed
    /// run repeats the uninterrupted one bit for bit), and equals [`Self::assemble`]'s up to
    /// rounding. Meant for one set per system (K_ref is made again if another set's size is
    /// seen); the first call allocates K_ref (one value array) and the flags.
    ///
    /// With `left_out` (a flag per element), the flagged elements are not evaluated at all:
    /// the caller vouches that their force is k_ref,e u_e and their tangent their reference
    /// one (points that stay linear elastic), and that none has a prescribed dof. The force
    /// is then K_ref u (free equations) plus, for each evaluated element, f_e − k_ref,e u_e
    /// over its free dofs (f_e alone in prescribed rows): one sparse product and the
    /// evaluated elements, instead of every element. Their trial states are left as they
    /// were.
    pub fn assemble_reusing<S: ElementSet>(
        &mut self,
        input: &AssemblyInput,
        set: &S,
        coloring: &Coloring,
        committed: &[S::State],
        trial: &mut [S::State],
        left_out: Option<&[bool]>,
    ) {
        if !input.tangent && left_out.is_none() {
            return self.assemble(input, set, coloring, committed, trial);
        }
        self.make_reference(input, set, coloring);
        let reference = self.reference.as_mut().expect("made above");
        if input.tangent {
            // The values are set, not added to: 0 + K_ref, the bits of K_ref added to a
            // cleared matrix, in one pass over it instead of two.
            for (v, r) in self.values.iter_mut().zip(&reference.values) {
                *v = 0.0 + r;
            }
        }
        let targets = Targets {
            values: input.tangent.then_some(SharedMut(self.values.as_mut_ptr())),
            force: Some(SharedMut(self.internal_force.as_mut_ptr())),
            dense: None,
            frozen: input
                .tangent
                .then_some(SharedMut(reference.frozen.as_mut_ptr())),
            prescribed: None,
            left_out,
        };
        scatter(
            &self.pattern,
            input,
            set,
            coloring,
            committed,
            trial,
            targets,
        );
        if left_out.is_some() {
            let dofs = input.dofs;
            dofs.gather_free(input.u, &mut reference.u_free);
            symmetric_product(
                &self.pattern,
                &reference.values,
                &reference.u_free,
                &mut reference.force_free,
            );
            dofs.add_free(1.0, &reference.force_free, &mut self.internal_force);
        }
        if !input.tangent {
            return;
        }
        let off = &mut reference.off_reference;
        off.clear();
        off.resize(input.dofs.free_count(), false);
        let d = set.dofs_per_node();
        for e in (0..set.len()).filter(|&e| !reference.frozen[e]) {
            for &node in set.nodes(e) {
                for c in 0..d {
                    if let Some(eq) = input.dofs.equation(d * node as usize + c) {
                        off[eq] = true;
                    }
                }
            }
        }
        reference.off_reference_current = true;
    }

    /// Makes the K_ref of [`Self::assemble_reusing`] (with its flags and workspaces) unless
    /// there is one for a set of this size.
    fn make_reference<S: ElementSet>(
        &mut self,
        input: &AssemblyInput,
        set: &S,
        coloring: &Coloring,
    ) {
        let nnz = self.values.len();
        let fits = (self.reference.as_ref())
            .is_some_and(|r| r.frozen.len() == set.len() && r.values.len() == nnz);
        if fits {
            return;
        }
        let mut values = filled_in_parallel(0.0, nnz);
        let target = SharedMut(values.as_mut_ptr());
        let pattern = &self.pattern;
        for_each_element(coloring, |e, scratch| {
            let ke = &mut scratch.ke;
            ke.fill(0.0);
            set.reference_tangent(e, ke);
            let nodes = (set.nodes(e), set.dofs_per_node());
            // SAFETY: elements of one colour share no dof.
            unsafe { add_element_matrix(pattern, input.dofs, nodes, ke, 1.0, target.get()) };
        });
        let free = input.dofs.free_count();
        self.reference = Some(Reference {
            values,
            frozen: vec![false; set.len()],
            off_reference: vec![false; free],
            off_reference_current: false,
            u_free: vec![0.0; free],
            force_free: vec![0.0; free],
        });
    }

    /// After a tangent assembly by [`Self::assemble_reusing`]: per free equation, whether its
    /// column may differ from K_ref (an element on it had a tangent other than its
    /// reference one); `None` otherwise.
    pub fn off_reference_columns(&self) -> Option<&[bool]> {
        let r = self.reference.as_ref()?;
        r.off_reference_current
            .then_some(r.off_reference.as_slice())
    }

    /// Number of elements whose tangent was their reference one at the last tangent
    /// assembly of [`Self::assemble_reusing`] (frozen: not evaluated for the tangent).
    pub fn frozen_elements(&self) -> usize {
        self.reference
            .as_ref()
            .map_or(0, |r| r.frozen.iter().filter(|&&f| f).count())
    }

    /// Adds the internal forces of every element of `set` into this system and, if
    /// `input.tangent`, their tangents into `dense` (entries outside the block are dropped:
    /// its map must cover every free dof of the elements).
    pub fn assemble_dense<S: ElementSet>(
        &mut self,
        input: &AssemblyInput,
        set: &S,
        coloring: &Coloring,
        committed: &[S::State],
        trial: &mut [S::State],
        dense: DenseBlock<'_>,
    ) {
        let DenseBlock { values: block, map } = dense;
        assert_eq!(map.map.len(), set.len() * DenseScatter::STRIDE);
        let stride = block.col_stride();
        assert!(block.row_stride() == 1 && stride >= block.nrows() as isize);
        let targets = Targets {
            values: None,
            force: Some(SharedMut(self.internal_force.as_mut_ptr())),
            dense: input.tangent.then_some(Dense {
                values: SharedMut(block.as_ptr_mut()),
                col_stride: stride as usize,
                map,
            }),
            frozen: None,
            prescribed: None,
            left_out: None,
        };
        scatter(
            &self.pattern,
            input,
            set,
            coloring,
            committed,
            trial,
            targets,
        );
    }

    /// Sets the preconditioner to the assembled tangent plus the element matrices of `set`
    /// (e.g. a correction from the consistent to a symmetric positive-definite interface
    /// tangent); internal forces are left alone. The value array is allocated on the first
    /// call and reused after it.
    pub fn assemble_preconditioner<S: ElementSet>(
        &mut self,
        input: &AssemblyInput,
        set: &S,
        coloring: &Coloring,
        committed: &[S::State],
        trial: &mut [S::State],
    ) {
        self.preconditioner.clone_from(&self.values);
        let targets = Targets {
            values: Some(SharedMut(self.preconditioner.as_mut_ptr())),
            force: None,
            dense: None,
            frozen: None,
            prescribed: None,
            left_out: None,
        };
        scatter(
            &self.pattern,
            input,
            set,
            coloring,
            committed,
            trial,
            targets,
        );
    }
}

/// Where one assembly pass adds the element contributions: matrix values over the pattern
/// and internal forces over all dofs, or matrices into a dense block, each only where given.
#[derive(Clone, Copy)]
struct Targets<'m> {
    values: Option<SharedMut<f64>>,
    force: Option<SharedMut<f64>>,
    dense: Option<Dense<'m>>,
    /// The per-element flags of [`GlobalSystem::assemble_reusing`]: with them, `values`
    /// holds the sum of all reference matrices, and an element adds k_e − k_ref,e, nothing
    /// if its tangent is its reference one.
    frozen: Option<SharedMut<bool>>,
    /// With the tangent alone (not with `frozen`): the flagged elements' matrices, added
    /// again over every dof ([`GlobalSystem::assemble_with_prescribed`]).
    prescribed: Option<Side<'m>>,
    /// The elements [`GlobalSystem::assemble_reusing`] leaves out: K_ref u stands for every
    /// element's force, so an evaluated one adds f_e − k_ref,e u_e (free dofs).
    left_out: Option<&'m [bool]>,
}

/// A second value array over every dof, for the matrices of some elements alone.
#[derive(Clone, Copy)]
struct Side<'m> {
    pattern: &'m SparsityPattern,
    /// Every dof free (numbered by dof).
    dofs: &'m DofMap,
    values: SharedMut<f64>,
    /// Whether each element is added.
    elements: &'m [bool],
}

/// A dense column-major block and the map of the elements' dofs into it.
#[derive(Clone, Copy)]
struct Dense<'m> {
    values: SharedMut<f64>,
    col_stride: usize,
    map: &'m DenseScatter,
}

/// Adds `sign` · `ke` over the free dofs of the element with nodes `nodes` (`d` dofs each)
/// into the value array `values` over `pattern`.
///
/// One binary search per pair of nodes (not per pair of dofs): by construction of
/// [`SparsityPattern`] the free dofs of a node have consecutive equation numbers, so they
/// are adjacent rows of every column, and the columns of a node's dofs have the same rows.
/// With twist, where the pattern may leave out the in-plane–circumferential couplings, see
/// [`add_element_matrix_by_column`].
///
/// # Safety
/// `values` must point to a value array over `pattern` that no other thread writes at the
/// entries of this element's dofs.
unsafe fn add_element_matrix(
    pattern: &SparsityPattern,
    dofs: &DofMap,
    (nodes, d): (&[u32], usize),
    ke: &ElementMatrix,
    sign: f64,
    values: *mut f64,
) {
    let equations = element_equations(dofs, nodes, d);
    if d == 3 {
        // SAFETY: the caller's contract.
        unsafe { add_element_matrix_by_column(pattern, &equations, (nodes, d), ke, sign, values) };
        return;
    }
    let (cp, ri) = (pattern.symbolic.col_ptr(), pattern.symbolic.row_idx());
    // The first free dof of each node, as (component, equation).
    let first = |n: usize| (0..d).find_map(|c| equations[d * n + c].map(|eq| (c, eq)));
    for b in 0..nodes.len() {
        let Some((cb0, j0)) = first(b) else { continue };
        let start = cp[j0] as usize;
        let rows = &ri[start..cp[j0 + 1] as usize];
        for a in 0..nodes.len() {
            let Some((ca0, r0)) = first(a) else { continue };
            let p0 = start
                + rows
                    .binary_search(&(r0 as u32))
                    .expect("entry of an element's dofs is in the pattern");
            for cb in cb0..d {
                let Some(j) = equations[d * b + cb] else {
                    continue;
                };
                let p0 = p0 - start + cp[j] as usize;
                for ca in ca0..d {
                    let Some(r) = equations[d * a + ca] else {
                        continue;
                    };
                    let p = p0 + (r - r0);
                    debug_assert_eq!(ri[p] as usize, r);
                    // SAFETY: the caller's contract.
                    unsafe { *values.add(p) += sign * ke[(d * a + ca, d * b + cb)] };
                }
            }
        }
    }
}

/// The equation of each element dof (`None`: prescribed).
fn element_equations(dofs: &DofMap, nodes: &[u32], d: usize) -> [Option<usize>; MAX_ELEMENT_DOFS] {
    let mut equations = [None; MAX_ELEMENT_DOFS];
    for (a, eq) in equations.iter_mut().enumerate().take(d * nodes.len()) {
        *eq = dofs.equation(d * nodes[a / d] as usize + a % d);
    }
    equations
}

/// [`add_element_matrix`] for a pattern that need not hold every component pair of two
/// nodes (twist, [`SparsityPattern::new`]): per column and node, the node's rows present
/// there are found by one search (they are consecutive equations) and each is matched to
/// its component. Entries the pattern leaves out are structurally zero in `ke` (an element
/// that does not couple twist has exact zeros there) and are skipped.
///
/// # Safety
/// As [`add_element_matrix`].
unsafe fn add_element_matrix_by_column(
    pattern: &SparsityPattern,
    equations: &[Option<usize>; MAX_ELEMENT_DOFS],
    (nodes, d): (&[u32], usize),
    ke: &ElementMatrix,
    sign: f64,
    values: *mut f64,
) {
    let (cp, ri) = (pattern.symbolic.col_ptr(), pattern.symbolic.row_idx());
    // Each node's free equations, as (first, component of each).
    let node_rows = |a: usize| {
        let mut first = None;
        let mut components = [0usize; 3];
        let mut count = 0;
        for c in 0..d {
            if let Some(eq) = equations[d * a + c] {
                first.get_or_insert(eq);
                components[count] = c;
                count += 1;
            }
        }
        first.map(|f| (f, components, count))
    };
    for (cb_dof, j) in (0..d * nodes.len()).filter_map(|k| equations[k].map(|j| (k, j))) {
        let (start, end) = (cp[j] as usize, cp[j + 1] as usize);
        let rows = &ri[start..end];
        for a in 0..nodes.len() {
            let Some((first, components, count)) = node_rows(a) else {
                continue;
            };
            let last = first + count - 1;
            let mut p = start + rows.partition_point(|&r| (r as usize) < first);
            while p < end && (ri[p] as usize) <= last {
                let ca = components[ri[p] as usize - first];
                // SAFETY: the caller's contract.
                unsafe { *values.add(p) += sign * ke[(d * a + ca, cb_dof)] };
                p += 1;
            }
        }
    }
}

/// One worker's element matrix and force, reused from element to element (an element
/// zeroes only the block its set can write: a 24×24 matrix zeroed per element was a fifth
/// of a plane run's instructions).
/// On the stack, not boxed: iterations must not allocate (`tests/allocation.rs`).
struct ElementScratch {
    ke: ElementMatrix,
    fe: ElementVector,
}

impl ElementScratch {
    fn new() -> Self {
        Self {
            ke: ElementMatrix::zeros(),
            fe: ElementVector::zeros(),
        }
    }
}

/// Evaluates every element of `set` (colour by colour, in parallel within a colour) and adds
/// its matrix and its force into `targets`. Allocates nothing: element vectors and matrices
/// live on the stack.
fn scatter<S: ElementSet>(
    pattern: &SparsityPattern,
    input: &AssemblyInput,
    set: &S,
    coloring: &Coloring,
    committed: &[S::State],
    trial: &mut [S::State],
    targets: Targets,
) {
    let Targets {
        values,
        force,
        dense,
        frozen,
        prescribed,
        left_out,
    } = targets;
    let AssemblyInput {
        dofs, u, algorithm, ..
    } = *input;
    let ppe = set.points_per_element();
    let d = set.dofs_per_node();
    assert_eq!(trial.len(), set.len() * ppe);
    let committed = CommittedStates::new(committed, trial.len(), ppe);
    let states = SharedMut(trial.as_mut_ptr());
    // The leading block an element of this set can write (8 nodes × D): zeroed per element,
    // the rest of the scratch matrix is never touched.
    let used = MAX_ELEMENT_NODES * d;
    for_each_element(coloring, |e: usize, scratch: &mut ElementScratch| {
        // SAFETY: every element is evaluated exactly once, and its state slots (and its
        // frozen flag) are its own.
        let frozen = frozen.map(|f| unsafe { &mut *f.get().add(e) });
        if left_out.is_some_and(|l| l[e]) {
            // Linear elastic (the caller's guarantee): its tangent is its reference one.
            if let Some(frozen) = frozen {
                *frozen = true;
            }
            return;
        }
        let nodes = set.nodes(e);
        let ue = element_displacements(nodes, d, u);
        // SAFETY: as above.
        let trial_e = unsafe { std::slice::from_raw_parts_mut(states.get().add(e * ppe), ppe) };
        let was_frozen = frozen.as_deref().copied().unwrap_or(false);
        let element_input = ElementInput {
            u: &ue,
            committed: committed.of(e),
            algorithm,
        };
        let (ke, fe): (&mut ElementMatrix, _) = (&mut scratch.ke, &mut scratch.fe);
        // A frozen element's matrix may still be wanted, if one of its points yields.
        let matrix = values.is_some() || dense.is_some() || prescribed.is_some();
        if matrix {
            for column in ke
                .as_mut_slice()
                .chunks_exact_mut(MAX_ELEMENT_DOFS)
                .take(used)
            {
                column[..used].fill(0.0);
            }
        }
        fe.as_mut_slice()[..used].fill(0.0);
        let output = ElementOutput {
            trial: &mut *trial_e,
            k: (matrix && !was_frozen).then_some(&mut *ke),
            f: Some(&mut *fe),
        };
        set.evaluate(e, &element_input, output);
        let global = |a: usize| d * nodes[a / d] as usize + a % d;
        // With elements left out, K_ref u stands for every element's force: this one's
        // reference part comes off over its free dofs.
        let reference = left_out.map(|_| {
            let mut kr = ElementMatrix::zeros();
            set.reference_tangent(e, &mut kr);
            let n = d * nodes.len();
            let mut free = [false; MAX_ELEMENT_DOFS];
            for (a, f) in free.iter_mut().enumerate().take(n) {
                *f = dofs.equation(global(a)).is_some();
            }
            for a in (0..n).filter(|&a| free[a]) {
                let free_b = (0..n).filter(|&b| free[b]);
                fe[a] -= free_b.map(|b| kr[(a, b)] * ue[b]).sum::<f64>();
            }
            kr
        });
        if let Some(force) = force {
            for a in 0..d * nodes.len() {
                // SAFETY: elements of one colour share no node, hence no dof.
                unsafe { *force.get().add(global(a)) += fe[a] };
            }
        }
        if let Some(Dense {
            values,
            col_stride,
            map,
        }) = dense
        {
            let local = map.element(e);
            for b in 0..d * nodes.len() {
                let col = local[b];
                if col == OUTSIDE {
                    continue;
                }
                for a in 0..d * nodes.len() {
                    let row = local[a];
                    if row != OUTSIDE {
                        let at = row as usize + col as usize * col_stride;
                        // SAFETY: as above; the block entries of one element's dofs are
                        // written by no other element of its colour.
                        unsafe { *values.get().add(at) += ke[(a, b)] };
                    }
                }
            }
        }
        if let Some(side) = prescribed.filter(|side| side.elements[e]) {
            // SAFETY: as above, over the side's array.
            unsafe {
                add_element_matrix(
                    side.pattern,
                    side.dofs,
                    (nodes, d),
                    ke,
                    1.0,
                    side.values.get(),
                )
            };
        }
        let Some(values) = values else { return };
        if let Some(frozen) = frozen {
            // `values` holds every element's reference matrix: this one adds its tangent's
            // difference from it, if any. The flag only chose the first evaluation.
            *frozen = set.tangent_is_reference(trial_e);
            if *frozen {
                return;
            }
            if was_frozen {
                // A point yielded: the same evaluation again, with the tangent.
                let output = ElementOutput {
                    trial: &mut *trial_e,
                    k: Some(&mut *ke),
                    f: None,
                };
                set.evaluate(e, &element_input, output);
            }
            let kr = reference.unwrap_or_else(|| {
                let mut kr = ElementMatrix::zeros();
                set.reference_tangent(e, &mut kr);
                kr
            });
            *ke -= kr;
        }
        // SAFETY: as above; the entries of this element's dofs are written by no other
        // element of its colour.
        unsafe { add_element_matrix(pattern, dofs, (nodes, d), ke, 1.0, values.get()) };
    });
}

/// The displacements of an element's `nodes` (`d` per node) taken from `u` (all dofs).
fn element_displacements(nodes: &[u32], d: usize, u: &[f64]) -> ElementVector {
    let mut ue = ElementVector::zeros();
    for (a, &n) in nodes.iter().enumerate() {
        for c in 0..d {
            ue[d * a + c] = u[d * n as usize + c];
        }
    }
    ue
}

/// Evaluates the elements of `set` at the displacements `input.u` for their trial states
/// alone, elements in parallel: no matrix and no force is assembled (their force is thrown
/// away), so no element waits for another's colour. For a linear bulk, whose internal force
/// is K·u, the states of a converged state.
pub fn evaluate_states<S: ElementSet>(
    input: &AssemblyInput,
    set: &S,
    committed: &[S::State],
    trial: &mut [S::State],
) {
    let ppe = set.points_per_element();
    let d = set.dofs_per_node();
    assert_eq!(trial.len(), set.len() * ppe);
    let committed = CommittedStates::new(committed, trial.len(), ppe);
    trial
        .par_chunks_mut(ppe)
        .enumerate()
        .with_min_len(64)
        .for_each(|(e, trial)| {
            let ue = element_displacements(set.nodes(e), d, input.u);
            let element_input = ElementInput {
                u: &ue,
                committed: committed.of(e),
                algorithm: input.algorithm,
            };
            let output = ElementOutput {
                trial,
                k: None,
                f: None,
            };
            set.evaluate(e, &element_input, output);
        });
}

/// The most points an element of any set has (a continuum cell's rule, an interface
/// element's).
const MAX_ELEMENT_POINTS: usize = if MAX_CELL_POINTS > INTERFACE_POINTS {
    MAX_CELL_POINTS
} else {
    INTERFACE_POINTS
};

/// The committed states an element loop starts its points from: each element's slots of
/// the set's committed states or, for states that follow the displacements alone and keep
/// none (an empty slice: linear elastic bodies, whose update does not read them), the
/// default states — so such a set holds one array of states, not two.
struct CommittedStates<'c, T> {
    states: &'c [T],
    virgin: [T; MAX_ELEMENT_POINTS],
    points: usize,
}

impl<'c, T: Copy + Default> CommittedStates<'c, T> {
    fn new(states: &'c [T], trial_len: usize, points: usize) -> Self {
        assert!(states.is_empty() || states.len() == trial_len);
        assert!(points <= MAX_ELEMENT_POINTS);
        Self {
            states,
            virgin: [T::default(); MAX_ELEMENT_POINTS],
            points,
        }
    }

    fn of(&self, e: usize) -> &[T] {
        if self.states.is_empty() {
            &self.virgin[..self.points]
        } else {
            &self.states[e * self.points..(e + 1) * self.points]
        }
    }
}

/// `change(e, start, end)` over the elements `e` of `set`, combined by `combine` from 0,
/// `start` and `end` being the element's trial states at the displacements `start_u` and
/// `input.u` (all dofs) from `committed` ones (empty: the default states), made element by
/// element on the stack and stored nowhere. For the plausibility check of an increment of
/// states that follow the displacements, without a second array of them; `combine` must
/// not depend on the order (the largest change: any number of threads, the same bits).
pub fn combine_state_changes<S: ElementSet>(
    input: &AssemblyInput,
    start_u: &[f64],
    set: &S,
    committed: &[S::State],
    change: impl Fn(usize, &[S::State], &[S::State]) -> f64 + Sync,
    combine: impl Fn(f64, f64) -> f64 + Sync + Send,
) -> f64 {
    let ppe = set.points_per_element();
    let d = set.dofs_per_node();
    let committed = CommittedStates::new(committed, set.len() * ppe, ppe);
    let states_at = |e: usize, u: &[f64], out: &mut [S::State]| {
        let ue = element_displacements(set.nodes(e), d, u);
        let element_input = ElementInput {
            u: &ue,
            committed: committed.of(e),
            algorithm: input.algorithm,
        };
        let output = ElementOutput {
            trial: out,
            k: None,
            f: None,
        };
        set.evaluate(e, &element_input, output);
    };
    (0..set.len())
        .into_par_iter()
        .with_min_len(64)
        .map(|e| {
            let mut start = [S::State::default(); MAX_ELEMENT_POINTS];
            let mut end = [S::State::default(); MAX_ELEMENT_POINTS];
            states_at(e, start_u, &mut start[..ppe]);
            states_at(e, input.u, &mut end[..ppe]);
            change(e, &start[..ppe], &end[..ppe])
        })
        .reduce(|| 0.0, combine)
}

/// y = A x over the free equations for a symmetric A with the values `values` over
/// `pattern`: each y_j is column j's dot product with x (A's row j), the columns split
/// between the cores with no two writing the same y_j, every y_j summed in one order
/// whatever the number of threads (the same bits on any of them). For element matrices,
/// symmetric up to rounding, this is Aᵀ x, equal to A x within rounding.
pub(crate) fn symmetric_product(
    pattern: &SparsityPattern,
    values: &[f64],
    x: &[f64],
    y: &mut [f64],
) {
    let symbolic = pattern.symbolic();
    let (cp, ri) = (symbolic.col_ptr(), symbolic.row_idx());
    y.par_iter_mut()
        .enumerate()
        .with_min_len(PRODUCT_COLUMNS_PER_TASK)
        .for_each(|(eq, yj)| {
            let column = cp[eq] as usize..cp[eq + 1] as usize;
            *yj = dot(&ri[column.clone()], &values[column], x);
        });
}

/// Columns per parallel task of [`symmetric_product`] (at least): ~50 k entries, enough to
/// outweigh a task's cost.
const PRODUCT_COLUMNS_PER_TASK: usize = 2048;

/// Σ values[k] x[rows[k]], in four interleaved partial sums (a single sum's additions would
/// wait on each other), added pairwise at the end.
#[inline]
fn dot(rows: &[u32], values: &[f64], x: &[f64]) -> f64 {
    let mut sums = [0.0; 4];
    let (row_chunks, value_chunks) = (rows.chunks_exact(4), values.chunks_exact(4));
    let (row_rest, value_rest) = (row_chunks.remainder(), value_chunks.remainder());
    for (r, v) in row_chunks.zip(value_chunks) {
        for lane in 0..4 {
            sums[lane] += v[lane] * x[r[lane] as usize];
        }
    }
    let mut sum = (sums[0] + sums[1]) + (sums[2] + sums[3]);
    for (&r, &v) in row_rest.iter().zip(value_rest) {
        sum += v * x[r as usize];
    }
    sum
}

/// Runs `element(e, scratch)` for every element of `coloring`: colour by colour, in
/// parallel within a colour (each worker with its own scratch), so that no two elements run
/// at once share a node.
fn for_each_element(coloring: &Coloring, element: impl Fn(usize, &mut ElementScratch) + Sync) {
    let last = coloring.groups.len().saturating_sub(1);
    for (c, group) in coloring.groups.iter().enumerate() {
        if c == last && coloring.groups.len() == 64 {
            let mut scratch = ElementScratch::new();
            group
                .iter()
                .for_each(|&e| element(e as usize, &mut scratch));
        } else {
            group
                .par_iter()
                .with_min_len(64)
                .for_each_init(ElementScratch::new, |scratch, &e| {
                    element(e as usize, scratch)
                });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::Analysis;
    use crate::element::continuum::Formulation;
    use crate::element::set::{ContinuumCell, ContinuumSet};
    use crate::material::PointState;
    use crate::material::elastic::LinearElastic;
    use crate::material::j2::J2Plasticity;
    use crate::mesh::CellKind;
    use faer::Mat;

    /// An `nx` × `ny` grid of unit quad8 cells of a J2 material in plane strain, held at
    /// its bottom, with its node count.
    fn plastic_block(nx: usize, ny: usize) -> (ContinuumSet, usize, Vec<bool>) {
        // Nodes on the (2nx+1) × (2ny+1) lattice of half-cells; mid-cell nodes unused.
        let row = 2 * nx + 1;
        let node = |i: usize, j: usize| (j * row + i) as u32;
        let mut cells = Vec::new();
        for cj in 0..ny {
            for ci in 0..nx {
                let (i, j) = (2 * ci, 2 * cj);
                let lattice = [
                    (i, j),
                    (i + 2, j),
                    (i + 2, j + 2),
                    (i, j + 2),
                    (i + 1, j),
                    (i + 2, j + 1),
                    (i + 1, j + 2),
                    (i, j + 1),
                ];
                let nodes = lattice.map(|(i, j)| node(i, j));
                // A slightly distorted cell, so that the points' stresses differ.
                let coords =
                    lattice.map(|(i, j)| [i as f64 / 2.0 + 0.03 * j as f64, j as f64 / 2.0]);
                cells.push(ContinuumCell {
                    kind: CellKind::Quad8,
                    nodes,
                    coords,
                    body: 0,
                    mesh_cell: cells.len() as u32,
                });
            }
        }
        let node_count = row * (2 * ny + 1);
        let mut fixed = vec![false; 2 * node_count];
        for i in 0..row {
            fixed[2 * i] = true;
            fixed[2 * i + 1] = true;
        }
        let elastic = LinearElastic::new(1000.0, 0.3).unwrap();
        let set = ContinuumSet {
            analysis: Analysis::PlaneStrain { thickness: 1.0 },
            cells,
            materials: vec![Box::new(J2Plasticity::new(elastic, 1.0, 50.0).unwrap())],
            formulations: vec![Formulation::Full],
            expansions: vec![0.0],
        };
        (set, node_count, fixed)
    }

    /// [`plastic_block`] with its dof numbering, pattern and colouring.
    fn plastic_system(
        nx: usize,
        ny: usize,
    ) -> (ContinuumSet, usize, DofMap, SparsityPattern, Coloring) {
        let (set, node_count, fixed) = plastic_block(nx, ny);
        let dofs = DofMap::new(&fixed);
        let connectivity = (0..set.len()).map(|e| set.nodes(e));
        let pattern = SparsityPattern::new(node_count, &dofs, connectivity);
        let coloring = Coloring::new(&set, node_count);
        (set, node_count, dofs, pattern, coloring)
    }

    #[test]
    fn assembling_with_the_prescribed_couplings_splits_the_all_dof_assembly_bit_for_bit() {
        let (set, node_count, fixed) = plastic_block(3, 2);
        let dofs = DofMap::new(&fixed);
        let all = DofMap::new(&vec![false; fixed.len()]);
        let cells = (0..set.len()).map(|e| set.nodes(e));
        // The free pattern also couples two far nodes (as an interface element would), an
        // entry the cells' all-dof pattern lacks.
        let far: [u32; 2] = [(2 * 3 + 1) as u32, node_count as u32 - 1];
        let free_pattern = SparsityPattern::new(node_count, &dofs, cells.clone().chain([&far[..]]));
        let coloring = Coloring::new(&set, node_count);
        let mut plain = GlobalSystem::new(free_pattern.clone(), dofs.dof_count());
        let mut split = GlobalSystem::new(free_pattern, dofs.dof_count());
        let mut whole = GlobalSystem::new(
            SparsityPattern::new(node_count, &all, cells.clone()),
            dofs.dof_count(),
        );
        let connectivity: Vec<ElementNodes> = cells.map(ElementNodes::from).collect();
        let mut couplings = PrescribedCouplings::new(node_count, &dofs, &connectivity);
        let committed = vec![PointState::default(); set.len() * set.points_per_element()];
        let mut trial = committed.clone();
        let u: Vec<f64> = (0..dofs.dof_count())
            .map(|k| {
                if fixed[k] {
                    0.0
                } else {
                    1e-3 * (k as f64).sin()
                }
            })
            .collect();
        let input = |dofs| AssemblyInput {
            dofs,
            u: &u,
            tangent: true,
            algorithm: ContactAlgorithm::default(),
        };
        plain.assemble(&input(&dofs), &set, &coloring, &committed, &mut trial);
        whole.assemble(&input(&all), &set, &coloring, &committed, &mut trial);
        split.assemble_with_prescribed(
            &input(&dofs),
            &set,
            &coloring,
            &committed,
            &mut trial,
            Some(&mut couplings),
        );
        // Bit for bit: the same sums in the same order.
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&split.values), bits(&plain.values));
        assert_eq!(bits(&split.internal_force), bits(&plain.internal_force));
        // The couplings hold the whole matrix's entries in every prescribed row and column
        // (the block's bottom row of nodes), with its bits; only the cells on that row.
        let entries = |m: SparseColMatRef<'_, u32, f64>| {
            let mut held = Vec::new();
            for j in 0..m.ncols() {
                let column = m.col_ptr()[j] as usize..m.col_ptr()[j + 1] as usize;
                for (&i, &v) in m.row_idx()[column.clone()].iter().zip(&m.val()[column]) {
                    if fixed[i as usize] || fixed[j] {
                        held.push((i, j, v.to_bits()));
                    }
                }
            }
            held
        };
        let held = entries(couplings.matrix());
        assert!(!held.is_empty());
        assert_eq!(held, entries(whole.matrix()));
        assert!(couplings.values.len() < whole.values.len());
        assert_eq!(couplings.elements.iter().filter(|&&h| h).count(), 3);
    }

    #[test]
    fn reusing_assembly_equals_plain_assembly_while_cells_yield_and_unload() {
        let (set, node_count, dofs, pattern, coloring) = plastic_system(4, 3);
        let mut plain = GlobalSystem::new(pattern.clone(), dofs.dof_count());
        let mut reusing = GlobalSystem::new(pattern, dofs.dof_count());
        let points = set.len() * set.points_per_element();
        let committed = vec![PointState::default(); points];
        let (mut trial_a, mut trial_b) = (committed.clone(), committed.clone());
        // A shear growing towards the right (γ = a (1 + x/4)): cells yield from the right
        // as the amplitude a grows (pure shear yields at γ = √3 σ_Y / (3G) = 1.5e-3), and
        // every point is elastic again at the small amplitudes (unloading).
        let width = 4.0;
        let mut u = vec![0.0; dofs.dof_count()];
        let mut frozen = Vec::new();
        for amplitude in [1e-5, 0.9e-3, 1.2e-3, 1.4e-3, 1e-5, 1.2e-3, 0.0] {
            for n in 0..node_count {
                let (i, j) = (n % 9, n / 9);
                let (x, y) = (i as f64 / 2.0, j as f64 / 2.0);
                u[2 * n] = amplitude * y * (1.0 + x / width);
                u[2 * n + 1] = -0.3 * amplitude * y * x / width;
            }
            let input = AssemblyInput {
                dofs: &dofs,
                u: &u,
                tangent: true,
                algorithm: Default::default(),
            };
            plain.clear(true);
            plain.assemble(&input, &set, &coloring, &committed, &mut trial_a);
            reusing.clear(true);
            reusing.assemble_reusing(&input, &set, &coloring, &committed, &mut trial_b, None);
            assert_eq!(trial_a, trial_b);
            // Independent of the assemblies before: a new system's first gives the same bits.
            let mut fresh = GlobalSystem::new(plain.pattern.clone(), dofs.dof_count());
            let mut trial_c = committed.clone();
            fresh.assemble_reusing(&input, &set, &coloring, &committed, &mut trial_c, None);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fresh.values), bits(&reusing.values));
            assert_eq!(plain.internal_force, reusing.internal_force);
            let scale = plain.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let difference = plain
                .values
                .iter()
                .zip(&reusing.values)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(
                difference <= 1e-13 * scale,
                "amplitude {amplitude}: {difference:e}"
            );
            let yielded = (0..set.len())
                .filter(|&e| trial_a[e * 9..(e + 1) * 9].iter().any(|s| s.yielding))
                .count();
            assert_eq!(reusing.frozen_elements(), set.len() - yielded);
            frozen.push(reusing.frozen_elements());
            // The matrix differs from K_ref only in the columns reported off it, which are
            // those of the yielding cells.
            let reference = &reusing.reference.as_ref().unwrap().values;
            let off = reusing
                .off_reference_columns()
                .expect("after a reusing assembly");
            let symbolic = reusing.pattern.symbolic();
            for (col, &flagged) in off.iter().enumerate() {
                let range = symbolic.col_range(col);
                let differs = reusing.values[range.clone()] != reference[range];
                assert!(flagged || !differs, "column {col} differs, not flagged");
            }
            assert_eq!(off.iter().any(|&f| f), yielded > 0);
            // A cleared matrix has none (until the next reusing assembly).
            reusing.clear(true);
            assert!(reusing.off_reference_columns().is_none());
            reusing.assemble_reusing(&input, &set, &coloring, &committed, &mut trial_b, None);
        }
        // Elastic, partly plastic (more cells at larger amplitudes), elastic again.
        assert_eq!(frozen[0], set.len());
        assert!(
            set.len() > frozen[1] && frozen[1] > frozen[2] && frozen[2] > frozen[3],
            "{frozen:?}"
        );
        assert_eq!(frozen[4], set.len());
        assert_eq!(frozen[6], set.len());
    }

    #[test]
    fn cells_left_out_give_the_force_and_tangent_of_their_evaluation() {
        let (set, node_count, dofs, pattern, coloring) = plastic_system(4, 3);
        let ppe = set.points_per_element();
        let committed = vec![PointState::default(); set.len() * ppe];
        // The shear of the test above at an amplitude where the right-hand cells yield, and
        // a vertical stretch so that the prescribed bottom row moves too (u_y = 1e-4).
        let mut u = vec![0.0; dofs.dof_count()];
        for n in 0..node_count {
            let (i, j) = (n % 9, n / 9);
            let (x, y) = (i as f64 / 2.0, j as f64 / 2.0);
            u[2 * n] = 1.2e-3 * y * (1.0 + x / 4.0);
            u[2 * n + 1] = 1e-4 + 2e-4 * y - 0.3 * 1.2e-3 * y * x / 4.0;
        }
        for tangent in [true, false] {
            let input = AssemblyInput {
                dofs: &dofs,
                u: &u,
                tangent,
                algorithm: Default::default(),
            };
            let mut whole = GlobalSystem::new(pattern.clone(), dofs.dof_count());
            let mut trial = committed.clone();
            whole.assemble_reusing(&input, &set, &coloring, &committed, &mut trial, None);
            // Left out: the cells with no prescribed dof none of whose points yielded.
            let left_out: Vec<bool> = (0..set.len())
                .map(|e| {
                    !dofs.holds_prescribed(set.nodes(e), 2)
                        && !trial[e * ppe..(e + 1) * ppe].iter().any(|s| s.yielding)
                })
                .collect();
            let count = left_out.iter().filter(|&&l| l).count();
            assert!(count > 0 && count < set.len() - 3, "{count} left out");
            let mut leaving = GlobalSystem::new(pattern.clone(), dofs.dof_count());
            let sentinel = PointState {
                equivalent_plastic_strain: 7.0,
                ..PointState::default()
            };
            let mut trial_left = vec![sentinel; set.len() * ppe];
            leaving.assemble_reusing(
                &input,
                &set,
                &coloring,
                &committed,
                &mut trial_left,
                Some(&left_out),
            );
            for e in 0..set.len() {
                let (mine, theirs) = (
                    &trial_left[e * ppe..(e + 1) * ppe],
                    &trial[e * ppe..(e + 1) * ppe],
                );
                if left_out[e] {
                    assert!(
                        mine.iter().all(|s| *s == sentinel),
                        "cell {e} was evaluated"
                    );
                } else {
                    assert_eq!(mine, theirs, "cell {e}");
                }
            }
            // Forces over all dofs (reactions included) and the tangent to rounding: K_ref u
            // sums the left-out cells' k_e u_e in another order than their points did.
            let close = |a: &[f64], b: &[f64], what: &str| {
                let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let difference = (a.iter().zip(b)).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
                assert!(
                    difference <= 1e-12 * scale,
                    "{what}: {difference:e} of {scale:e}"
                );
            };
            close(&leaving.internal_force, &whole.internal_force, "force");
            if tangent {
                close(&leaving.values, &whole.values, "tangent");
                assert_eq!(leaving.frozen_elements(), whole.frozen_elements());
            }
        }
    }

    #[test]
    fn a_twist_pattern_leaves_out_only_the_couplings_elastic_cells_do_not_have() {
        // Axisymmetry with twist, the block moved off the axis: the left half of the cells
        // elastic (body 0), the right half J2 (body 1), sheared and twisted past yield.
        let (mut set, node_count, _) = plastic_block(4, 2);
        set.analysis = Analysis::AxisymmetricTwist;
        for cell in &mut set.cells {
            cell.coords.iter_mut().for_each(|x| x[0] += 1.0);
            cell.body = u32::from(cell.coords[0][0] >= 3.0);
        }
        let elastic = LinearElastic::new(1000.0, 0.3).unwrap();
        set.materials.insert(0, Box::new(elastic));
        set.formulations.push(Formulation::Full);
        set.expansions.push(0.0);
        let mut fixed = vec![false; 3 * node_count];
        fixed[..3 * 9].fill(true);
        let dofs = DofMap::new(&fixed);
        let split = (0..set.len()).map(|e| ElementNodes {
            nodes: set.nodes(e),
            couples_twist: set.couples_twist(e),
        });
        let pattern = SparsityPattern::new(node_count, &dofs, split);
        let full = SparsityPattern::new(node_count, &dofs, (0..set.len()).map(|e| set.nodes(e)));
        assert!(
            pattern.nnz() < full.nnz(),
            "{} vs {}",
            pattern.nnz(),
            full.nnz()
        );
        let coloring = Coloring::new(&set, node_count);
        let mut system = GlobalSystem::new(pattern.clone(), dofs.dof_count());
        let mut u = vec![0.0; dofs.dof_count()];
        for n in 0..node_count {
            let (x, y) = ((n % 9) as f64 / 2.0 + 1.0, (n / 9) as f64 / 2.0);
            u[3 * n] = 2e-3 * y * x;
            u[3 * n + 1] = -1e-3 * y;
            u[3 * n + 2] = 3e-3 * y * x;
        }
        let input = AssemblyInput {
            dofs: &dofs,
            u: &u,
            tangent: true,
            algorithm: Default::default(),
        };
        let states = set.len() * set.points_per_element();
        let committed = vec![PointState::default(); states];
        let mut trial = committed.clone();
        system.clear(true);
        system.assemble(&input, &set, &coloring, &committed, &mut trial);
        assert!(trial.iter().any(|s| s.yielding), "the J2 half yields");
        // The same matrix assembled densely (every entry of every element kept).
        let n = dofs.free_count();
        let map = DenseScatter::new(&set, &dofs, Some);
        let mut dense = Mat::<f64>::zeros(n, n);
        let mut other = GlobalSystem::new(pattern.clone(), dofs.dof_count());
        let mut trial = committed.clone();
        other.clear(true);
        let block = DenseBlock {
            values: dense.as_mut(),
            map: &map,
        };
        other.assemble_dense(&input, &set, &coloring, &committed, &mut trial, block);
        let (cp, ri) = (pattern.symbolic.col_ptr(), pattern.symbolic.row_idx());
        let mut sparse = Mat::<f64>::zeros(n, n);
        for j in 0..n {
            for p in cp[j] as usize..cp[j + 1] as usize {
                sparse[(ri[p] as usize, j)] = system.values[p];
            }
        }
        let scale = dense.norm_max();
        // Identical sums, only the entries left out of the pattern are exact zeros.
        assert!((&sparse - &dense).norm_max() <= 1e-14 * scale);
        let coupled = (0..n).any(|j| (0..n).any(|i| dense[(i, j)] != 0.0 && i % 3 != j % 3));
        assert!(coupled, "the yielded cells couple twist");
    }
}
