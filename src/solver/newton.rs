//! Newton-Raphson for one load increment (Buczkowski & Kleiber (1994), Eq. 32):
//! K_T(u_i) δu = Q − F(u_i), u_{i+1} = u_i + δu, until both the out-of-balance force and the
//! correction are small.
//!
//! # Convergence criteria
//! Engineering criteria as in CalculiX (*CONTROLS, PARAMETERS=FIELD) and Abaqus ([`Criteria`],
//! `docs/convergence_criteria.md`). With r_max = ‖r‖∞ the largest out-of-balance force over the
//! free dofs, q̃ the time-averaged force flux, c_max = ‖α δu‖∞ the largest component of the last
//! (line-searched) correction and Δu_max = ‖u − u_start‖∞ the largest displacement change of the
//! increment, an iteration has converged when
//!
//! * r_max ≤ R_n q̃ (R_p q̃ after `late_iteration` iterations) and c_max ≤ C_n Δu_max, or
//! * r_max ≤ R_l q̃ (a linear increment: one solve, no correction check);
//! * with zero flux (the current flux q̄ ≤ ε q̃, e.g. a body unloaded to a stress-free state)
//!   r_max ≤ ε q̃ and c_max ≤ C_ε Δu_max.
//!
//! The flux q̄ of an iteration is the force-weighted mean magnitude Σf²/Σ|f| of the bodies'
//! nodal forces: the continuum's internal force over all dofs (on the condensed path, before
//! the interface's forces are added; so it holds the applied loads, the reactions and the
//! contact forces the bodies carry), the total internal force otherwise. q̃ is the mean of q̄
//! over the run's converged increments with non-zero flux and the present iteration (zero
//! flux in the first increment is judged against the mean q̄ of its iterations so far;
//! `FluxHistory`; a user's `average_force` replaces q̃). Before the first solve of an increment only r_max ≤ R_l q̃
//! is accepted, so small load changes are never skipped.
//!
//! If the case sets the older relative-norm tolerances, they are required as well:
//! ‖r‖ ≤ tol_f · max(‖f_ext‖, ‖f_int‖, ‖r₀‖, f_floor) and ‖δu‖ ≤ tol_u · ‖u‖, or the next
//! correction estimated from the residual's last rate, ‖δu‖ · ‖r_i‖/‖r_{i−1}‖ ≤ tol_u (as in
//! CalculiX); a residual 1000 × below tol_f is accepted without the correction check.
//!
//! # Linear solves
//! Models with contact pairs are solved exactly by condensation onto the interface unknowns
//! ([`CondensedSolver`], [`LinearSolver::Condensed`], the default): the continuum is assembled
//! into the global pattern and factored (with the interface ordered last) only when its
//! tangent changed — once per model for linear-elastic bodies, every iteration otherwise —
//! and the interface elements into a dense block over the interface unknowns, whose dense LU
//! is formed at every iteration. The consistent (unsymmetric) tangent is used as is. Within
//! an iteration the interface law is iterated to convergence against the bodies'
//! linearisation before they are back-substituted (`newton/interface_iterations.rs`): the contact
//! statuses settle without new assemblies of the bodies. With
//! linear-elastic bodies the continuum's force is K_c u from the stored stiffness throughout
//! (reactions included), under a temperature field K_c u − G ΔT with the thermal load
//! matrices G made once ([`ThermalLoad`]); iterations re-evaluate the interface elements
//! alone, and a converged increment's point states come from one loop that evaluates them
//! alone, when something reads them. Models
//! without contact pairs, and [`LinearSolver::Krylov`], use [`CholeskySolver`] (with BiCGSTAB
//! for unsymmetric tangents).
//!
//! [`Newton`] owns the global system, the linear solver and every vector the loop needs, all
//! sized once for the model: an iteration allocates nothing, which keeps the many small
//! iterations of contact problems free of allocator traffic.
//!
//! # Arc-length increments
//! The same solver, with the same assembly, linear solves and workspaces, solves the
//! increments of arc-length control, whose load factor is an unknown ([`arc`]).

use std::time::Instant;

use faer::{MatMut, MatRef};

use crate::Result;
use crate::assembly::{
    AssemblyInput, DenseScatter, DofMap, GlobalSystem, PrescribedCouplings, SparsityPattern,
};
use crate::contact::ContactAlgorithm;
use crate::element::thermal_load::ThermalLoad;
use crate::solver::condensed::CondensedSolver;
use crate::solver::elastic_cells::ElasticCells;
use crate::solver::floor::SolverWork;
use crate::solver::linear::CholeskySolver;

pub mod arc;
mod criteria;
mod interface_iterations;
mod predictor;
mod stiffness;

pub use arc::{ArcConverged, ArcIncrement};
pub use criteria::{Criteria, ForceAverage};
use criteria::{Flux, FluxHistory, Measures};
use interface_iterations::InterfaceIterations;
pub use predictor::LastIncrement;
use predictor::Predictor;
use stiffness::BulkStiffness;

/// The linear solver of models with contact pairs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LinearSolver {
    /// Exact solves by condensation onto the interface unknowns ([`CondensedSolver`]).
    #[default]
    Condensed,
    /// Cholesky for symmetric tangents, BiCGSTAB preconditioned with the elastic contact
    /// matrix for unsymmetric ones.
    Krylov,
}

/// Settings of the Newton loop (public fields, as in dolfinx's `NewtonSolver`).
#[derive(Clone, Copy, Debug)]
pub struct NewtonSettings {
    pub max_iterations: usize,
    /// The engineering convergence criteria of load-controlled increments.
    pub criteria: Criteria,
    /// Relative-norm tolerances: ‖r‖ / max(‖f_ext‖, ‖f_int‖) and ‖δu‖ / ‖u‖. Arc-length
    /// control always uses them; load-controlled increments only if `criteria.relative_norms`.
    pub force_tolerance: f64,
    pub displacement_tolerance: f64,
    /// How many cut-backs (a failed increment halved and retried) a step may make in all.
    pub max_cutbacks: usize,
    /// Which interface tangent the iterations use (Buczkowski & Kleiber (1994), §2.4 and
    /// conclusions 2–3). A choice of the solution method, not of the model: every algorithm
    /// has the same residual, hence the same solution.
    pub contact_algorithm: ContactAlgorithm,
    /// The linear solver of models with contact pairs (models without use Cholesky).
    pub linear_solver: LinearSolver,
    /// Whether an increment proportional to the last converged one starts from the
    /// extrapolated displacements (`Predictor`).
    pub extrapolate: bool,
    /// Condensed path: the most interface iterations within one Newton iteration
    /// (`newton/interface_iterations.rs`; 0: plain Newton iterations).
    pub interface_iterations: usize,
}

impl NewtonSettings {
    /// The relative-norm test: ‖r‖ ≤ tol_f · reference (`residual`, already relative), and
    /// the correction `correction` ≤ tol_u, unless the residual is 1000 × below tol_f or
    /// this is the `first` evaluation of a load-controlled increment (no correction yet).
    fn relative_norms_met(&self, residual: f64, first: bool, correction: f64) -> bool {
        residual <= self.force_tolerance
            && (first
                || residual <= 1e-3 * self.force_tolerance
                || correction <= self.displacement_tolerance)
    }
}

/// A problem the Newton loop can solve: it assembles internal forces and the tangent (on
/// one thread while the solver analyses its pattern on another, hence `Send`).
pub trait Problem: Send {
    /// Adds the internal force over all dofs into `system` (its forces cleared) and, if
    /// `input.tangent`, sets its matrix values to the tangent over the free dofs (whatever
    /// they held), at the displacements `input.u`, updating trial states. Returns whether
    /// the tangent is symmetric.
    fn assemble(&mut self, system: &mut GlobalSystem, input: &AssemblyInput) -> bool;

    /// The dofs of the interface elements' nodes (free and prescribed), sorted: empty if the
    /// problem has no interface, which keeps it off the condensed path. The methods below are
    /// called only when it is not empty.
    fn interface_dofs(&self) -> Vec<usize>;

    /// Whether the bulk (continuum) is linear: constant tangent, internal force K_c · u.
    fn bulk_is_linear(&self) -> bool;

    /// The scatter map of the interface elements into the dense interface block, `local`
    /// giving the block index of a free equation.
    fn interface_scatter(
        &self,
        dofs: &DofMap,
        local: &dyn Fn(usize) -> Option<usize>,
    ) -> DenseScatter;

    /// Whether the bulk's tangent of the last assembly is symmetric (else it is factored by
    /// LU); by default it always is.
    fn bulk_is_symmetric(&self) -> bool {
        true
    }

    /// A linear bulk's thermal load operator G ([`ThermalLoad`]), whose force under the
    /// problem's temperatures is K_c u − G ΔT: `None` when no thermal strain can change the
    /// bulk's force at fixed displacements (no temperature field, or no body expands), which
    /// is then K_c u. Made once, on the condensed path; fails only for want of memory.
    fn thermal_load(&self) -> Result<Option<ThermalLoad>>;

    /// The nodal forces G ΔT (all dofs) of the problem's temperature field into `force`.
    fn thermal_force(&self, load: &ThermalLoad, force: &mut [f64]);

    /// Adds the bulk's internal force into `system` and, if `input.tangent`, sets its matrix
    /// values to the bulk's tangent (whatever they held: no need to clear them first). A
    /// plastic bulk with `elastic` cells leaves out those that provably stay linear elastic
    /// (and anchors them when they have no anchor: [`ElasticCells`]).
    fn assemble_bulk(
        &mut self,
        system: &mut GlobalSystem,
        input: &AssemblyInput,
        elastic: Option<&mut ElasticCells>,
    );

    /// The cells of a plastic bulk that its evaluations may leave out ([`ElasticCells`]),
    /// dofs numbered by `dofs`; `None` (the default) for none.
    fn elastic_cells(&self, _dofs: &DofMap) -> Option<ElasticCells> {
        None
    }

    /// A linear bulk's tangent assembly (`input.tangent`): as [`Self::assemble_bulk`], and
    /// returns the stiffness's entries in the prescribed rows and columns of `input.dofs`
    /// (which, with the free block it set, make the stiffness over all dofs: its internal
    /// force K_c u, reactions included).
    fn assemble_linear_bulk(
        &mut self,
        system: &mut GlobalSystem,
        input: &AssemblyInput,
    ) -> PrescribedCouplings;

    /// Evaluates the bulk's trial states at `input.u` alone (no force, no tangent): those of
    /// a converged state of a linear bulk whose force is K·u.
    fn bulk_states(&mut self, input: &AssemblyInput);

    /// The largest equivalent strain increment √(⅔ Δε:Δε) of the bulk's points from the
    /// displacements `start_u` to `input.u` (NaN if one is not a number), from their states
    /// at both, made cell by cell and stored nowhere: for a bulk whose states follow the
    /// displacements, which keeps one array of them.
    fn bulk_strain_increment(&mut self, input: &AssemblyInput, start_u: &[f64]) -> f64;

    /// Adds the interface's internal force into `system` and, if `input.tangent`, its
    /// tangent into the dense interface `block` through `map`. Returns whether that tangent
    /// is symmetric.
    fn assemble_interface(
        &mut self,
        system: &mut GlobalSystem,
        input: &AssemblyInput,
        block: MatMut<'_, f64>,
        map: &DenseScatter,
    ) -> bool;
}

/// The condensed path's solver and workspaces (made at the first increment of a problem with
/// an interface).
#[derive(Debug)]
struct Condensed {
    solver: CondensedSolver,
    /// The interface elements' tangent over the interface unknowns.
    block: InterfaceBlock,
    map: DenseScatter,
    /// The entries of `block` the interface elements write, and their values in the block
    /// of the interface LU in force, if `interface_lu_current` (false: none, or made with an
    /// older S_c). A tangent whose block has these bits again has the same factors: the LU
    /// is kept (with a linear bulk and a piecewise-linear law, every iteration after the
    /// statuses settle).
    block_entries: Vec<usize>,
    factored_block: Vec<f64>,
    interface_lu_current: bool,
    /// Whether the bulk is linear (constant K_c, stored in the system's values).
    linear_bulk: bool,
    /// Whether the system's values hold a continuum tangent not yet factored.
    bulk_dirty: bool,
    /// Whether the last correction was solved with a kept bulk factor of another tangent (a
    /// chord step), whose contraction the next iteration checks (`CHORD_CONTRACTION`).
    chord_step: bool,
    /// Linear bulk: whether K_c is assembled and factored.
    bulk_ready: bool,
    /// Linear bulk: the continuum stiffness over all dofs (its free block is the system's
    /// matrix), whose product with the displacements gives the continuum's internal force,
    /// reactions included. Made by the first evaluation. The force is f_c(u) = K_c u − G ΔT
    /// (`thermal`) exactly, so every evaluation after the one that made K_c is a product,
    /// and a converged increment evaluates no element: its point states are made only when
    /// something reads them ([`Newton::complete_states`]).
    stiffness: Option<BulkStiffness>,
    /// Linear bulk under a temperature field with expanding bodies: G and the force G ΔT of
    /// the increment's temperatures.
    thermal: Option<ThermalForce>,
    /// Whether the bulk's trial states are not those of the last evaluation's displacements
    /// (it took its force from a product with K_c and evaluated no element).
    states_stale: bool,
    /// Plastic bulk: the cells its evaluations may leave out (their trial states then not
    /// those of the last evaluation).
    elastic: Option<ElasticCells>,
    /// Linear bulk without thermal strains: the bodies' elastic energy ½ u·K_c u at the last
    /// evaluation (over all dofs, reactions included), taken from its product: that of a
    /// converged state.
    continuum_energy: f64,
    /// The workspaces of the interface iterations.
    iterations: InterfaceIterations,
}

/// A linear bulk's thermal load G and the force G ΔT (all dofs) of the temperatures of the
/// increment being solved (made at its start: [`Newton::update_thermal_force`]).
#[derive(Debug)]
struct ThermalForce {
    load: ThermalLoad,
    force: Vec<f64>,
}

impl Condensed {
    /// Zeroes the interface block for a new tangent: its element entries, the only ones an
    /// assembly writes (the rest stay zero) — not all n_i² (349 MB at 3.84 M unknowns, at
    /// every tangent).
    fn clear_block(&mut self) {
        for &k in &self.block_entries {
            self.block.values[k] = 0.0;
        }
    }

    /// Records the values of the block's element entries as those of the interface LU in
    /// force (into the same storage each time).
    fn record_factored_block(&mut self) {
        let values = &self.block.values;
        self.factored_block.clear();
        self.factored_block
            .extend(self.block_entries.iter().map(|&k| values[k]));
        self.interface_lu_current = true;
    }

    /// Whether the interface LU in force is that of the current block: made since the last
    /// bulk factorisation from a block with the same bits.
    fn interface_lu_holds(&self) -> bool {
        let values = &self.block.values;
        let same = |(&k, &v): (&usize, &f64)| values[k].to_bits() == v.to_bits();
        self.interface_lu_current
            && self
                .block_entries
                .iter()
                .zip(&self.factored_block)
                .all(same)
    }
}

/// The dense interface block of the condensed path, n_i × n_i in column order (entry
/// k = row + n_i · column), zero but for the interface elements' entries. Its storage comes
/// zeroed from the allocator (fresh pages that read as zero until written), and only its
/// element entries are ever written ([`Condensed::clear_block`], the assembly): only the
/// pages they fall in take memory, where a `Mat::zeros` would write every page (a 1 M-unknown
/// taper's peak fell by 60–80 MB of its 82 MB block; 349 MB at 3.84 M).
#[derive(Debug)]
struct InterfaceBlock {
    n: usize,
    values: Vec<f64>,
}

impl InterfaceBlock {
    fn zeros(n: usize) -> Self {
        Self {
            n,
            values: vec![0.0; n * n],
        }
    }

    fn as_ref(&self) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(&self.values, self.n, self.n)
    }

    fn as_mut(&mut self) -> MatMut<'_, f64> {
        MatMut::from_column_major_slice_mut(&mut self.values, self.n, self.n)
    }
}

/// What happened in one increment.
#[derive(Clone, Debug, Default)]
pub struct NewtonLog {
    /// Number of linear solves.
    pub iterations: usize,
    /// Relative force residual ‖r‖ / max(‖f_ext‖, ‖f_int‖, ‖r₀‖, f_floor) before each solve
    /// and after the last one (the criteria judge ‖r‖∞ / q̃, logged at debug level).
    pub residuals: Vec<f64>,
    /// Relative size ‖δu‖/‖u‖ of each correction.
    pub corrections: Vec<f64>,
    /// Linear solves with an unsymmetric tangent, and their BiCGSTAB iterations.
    pub unsymmetric_solves: usize,
    pub krylov_iterations: usize,
    /// Condensed path: interface iterations beyond each Newton iteration's first step.
    pub interface_iterations: usize,
    pub converged: bool,
    /// The factor s of the predictor u + s Δu_last (0: the increment started from u).
    pub predictor: f64,
    /// Seconds spent assembling, factorising and solving.
    pub assembly_seconds: f64,
    pub factorization_seconds: f64,
    pub solve_seconds: f64,
}

impl NewtonLog {
    /// An empty log sized for an increment of up to `max_iterations` solves, so that logging
    /// an iteration allocates nothing.
    pub fn sized(max_iterations: usize) -> Self {
        Self {
            residuals: Vec::with_capacity(max_iterations + 1),
            corrections: Vec::with_capacity(max_iterations),
            ..Self::default()
        }
    }

    /// Adds the solves, iterations and seconds of `earlier`, a solve of the same increment
    /// before this one (a coupled increment's earlier exchanges); the residuals, corrections,
    /// predictor and convergence stay this solve's.
    pub fn add_earlier(&mut self, earlier: &NewtonLog) {
        self.iterations += earlier.iterations;
        self.unsymmetric_solves += earlier.unsymmetric_solves;
        self.krylov_iterations += earlier.krylov_iterations;
        self.interface_iterations += earlier.interface_iterations;
        self.assembly_seconds += earlier.assembly_seconds;
        self.factorization_seconds += earlier.factorization_seconds;
        self.solve_seconds += earlier.solve_seconds;
    }

    /// This log's solves, iterations and seconds alone (no residuals or corrections).
    pub fn totals(&self) -> NewtonLog {
        NewtonLog {
            residuals: Vec::new(),
            corrections: Vec::new(),
            ..*self
        }
    }
}

/// Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The Euclidean distance between two displacement vectors.
pub fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// Relative residual above which corrections are checked by a line search. Below it Newton is
/// in its quadratic phase and full steps are taken without the extra residual evaluation,
/// unless the residual has risen earlier in the increment (docs/theory.md §7.3).
const LINE_SEARCH_ABOVE: f64 = 1e-3;

/// Largest residual ratio ‖r_{k+1}‖/‖r_k‖ accepted from a chord step (a correction solved with
/// a kept bulk factor of an earlier tangent) before the rest of the increment refactors every
/// changed tangent. The reuse test admits a change whose chord rate is bounded by τ = 0.01
/// (docs/theory.md §7.6); a step that does not even quarter the residual shows the change
/// measure failed (e.g. a nearly incompressible body yielding) and would cost many iterations.
const CHORD_CONTRACTION: f64 = 0.25;

/// The Newton-Raphson solver of a model's increments, with its workspaces.
#[derive(Debug)]
pub struct Newton<'a> {
    settings: NewtonSettings,
    dofs: &'a DofMap,
    system: GlobalSystem,
    linear: CholeskySolver,
    /// Out-of-balance force over the free dofs; the linear solve turns it into the correction.
    residual: Vec<f64>,
    /// External forces over the free dofs.
    external: Vec<f64>,
    /// Line search: the displacements it starts from, and a trial step's out-of-balance force.
    start: Vec<f64>,
    trial_residual: Vec<f64>,
    /// The displacements at the start of the increment (all dofs).
    increment_start: Vec<f64>,
    /// The force flux of the last evaluation, and its history over converged increments.
    flux: Flux,
    flux_history: FluxHistory,
    predictor: Predictor,
    /// The condensed solver, once a problem with an interface asked for it.
    condensed: Option<Condensed>,
    /// Whether the problem was found to have no interface (then Cholesky is used).
    no_interface: bool,
    /// Whether the bulk's tangent of the last tangent assembly is symmetric
    /// ([`Problem::bulk_is_symmetric`]): Cholesky, else LU.
    bulk_symmetric: bool,
    /// The workspaces of arc-length increments, made by [`Self::set_arc_reference`].
    arc: Option<arc::ArcWork>,
    /// The work done so far, by kind (for the run's floor).
    work: SolverWork,
    /// Seconds of the condensed solver's ordering and symbolic analysis.
    condensed_analysis_seconds: f64,
    /// A thermally coupled increment ([`Self::begin_coupled_increment`]): its Newton solves
    /// record nothing of a converged increment until [`Self::end_coupled_increment`], and
    /// those after its first predict nothing.
    coupled: Option<CoupledIncrement>,
}

/// What a thermally coupled increment's Newton solves keep for its end.
#[derive(Clone, Copy, Debug, Default)]
struct CoupledIncrement {
    /// Whether a solve of this increment ran (the next continues it).
    continuing: bool,
    /// The force flux of the last converged solve, and whether it was zero.
    flux: Option<(f64, bool)>,
}

impl<'a> Newton<'a> {
    /// A solver for the dofs `dofs` whose matrices have the pattern `pattern`: orders and
    /// factors the pattern symbolically and allocates the system and all workspaces.
    pub fn new(
        settings: NewtonSettings,
        dofs: &'a DofMap,
        pattern: &SparsityPattern,
    ) -> Result<Self> {
        let linear = CholeskySolver::new(pattern)?;
        let free = dofs.free_count();
        Ok(Self {
            settings,
            dofs,
            system: GlobalSystem::new(pattern.clone(), dofs.dof_count()),
            linear,
            residual: vec![0.0; free],
            external: vec![0.0; free],
            start: vec![0.0; dofs.dof_count()],
            trial_residual: vec![0.0; free],
            increment_start: vec![0.0; dofs.dof_count()],
            flux: Flux::default(),
            flux_history: FluxHistory::default(),
            predictor: Predictor::new(dofs.dof_count()),
            condensed: None,
            no_interface: false,
            bulk_symmetric: true,
            arc: None,
            work: SolverWork::default(),
            condensed_analysis_seconds: 0.0,
            coupled: None,
        })
    }

    /// The settings this solver was made with.
    pub fn settings(&self) -> &NewtonSettings {
        &self.settings
    }

    /// The system of the last assembly: its internal forces are those of the last solution.
    pub fn system(&self) -> &GlobalSystem {
        &self.system
    }

    /// Whether the bulk's point states of the last evaluation were left out: a linear bulk
    /// whose force is K_c u − G ΔT evaluates no element in an increment, a plastic one leaves
    /// out its cells that provably stay elastic ([`ElasticCells`]). The trial states
    /// are then not those of the converged state, and a
    /// [`Solution`](crate::solver::state::Solution) committed from them holds stale point
    /// states until [`Self::complete_states`] makes them.
    pub fn states_pending(&self) -> bool {
        self.condensed.as_ref().is_some_and(|c| {
            (c.linear_bulk && c.states_stale)
                || c.elastic.as_ref().is_some_and(ElasticCells::states_pending)
        })
    }

    /// The bodies' elastic energy ½ u·K_c u at the last evaluation, for a linear bulk whose
    /// force is that product, without thermal strains (`None` otherwise): the states'
    /// Σ ½ σ:ε dV to rounding, K_c being Σ Bᵀ D B dV over the same points.
    pub fn linear_bulk_energy(&self) -> Option<f64> {
        (self.condensed.as_ref())
            .filter(|c| c.linear_bulk && c.thermal.is_none() && c.bulk_ready)
            .map(|c| c.continuum_energy)
    }

    /// Makes the bulk's trial point states those of `u`, the last evaluation's displacements,
    /// if they were left out ([`Self::states_pending`]): one element loop for the states
    /// alone. Returns its seconds (0 when nothing was pending), tallied as
    /// [`SolverWork::frame_states`]: states are completed for what reads them, a frame's
    /// fields.
    pub fn complete_states(&mut self, problem: &mut impl Problem, u: &[f64]) -> f64 {
        let Some(seconds) = self.make_pending_states(problem, u) else {
            return 0.0;
        };
        self.work.frame_states.add(seconds);
        seconds
    }

    /// [`Self::complete_states`] for a converged increment's pass over its point states
    /// (a linear bulk under thermal strains: its energy terms are the states'), tallied as a
    /// state evaluation.
    pub fn complete_increment_states(&mut self, problem: &mut impl Problem, u: &[f64]) {
        if let Some(seconds) = self.make_pending_states(problem, u) {
            self.work.state_evaluations.add(seconds);
        }
    }

    /// Makes the pending point states ([`Self::states_pending`]) at `u`; returns the seconds
    /// (`None`: nothing was pending).
    fn make_pending_states(&mut self, problem: &mut impl Problem, u: &[f64]) -> Option<f64> {
        if !self.states_pending() {
            return None;
        }
        let t = Instant::now();
        self.bulk_states_at(problem, u);
        if let Some(c) = self.condensed.as_mut() {
            c.states_stale = false;
            if let Some(elastic) = c.elastic.as_mut() {
                elastic.states_made();
            }
        }
        Some(t.elapsed().as_secs_f64())
    }

    /// The largest equivalent strain increment of the bulk's points from the displacements
    /// `start_u` to `u` (all dofs), from their states at both ([`Problem::bulk_strain_increment`]:
    /// two element loops that store nothing, tallied as two state evaluations), leaving the
    /// trial states and [`Self::states_pending`] as they were.
    pub fn strain_increment(
        &mut self,
        problem: &mut impl Problem,
        start_u: &[f64],
        u: &[f64],
    ) -> f64 {
        let t = Instant::now();
        let increment = problem.bulk_strain_increment(
            &AssemblyInput {
                dofs: self.dofs,
                u,
                tangent: false,
                algorithm: self.settings.contact_algorithm,
            },
            start_u,
        );
        let half = t.elapsed().as_secs_f64() / 2.0;
        self.work.state_evaluations.add(half);
        self.work.state_evaluations.add(half);
        increment
    }

    /// Evaluates the bulk's trial point states at the displacements `u` (all dofs): one
    /// element loop, tallied as a state evaluation (a driver leaving a converged state after
    /// a failed attempt, whose states follow the displacements).
    pub fn states_at(&mut self, problem: &mut impl Problem, u: &[f64]) {
        let t = Instant::now();
        self.bulk_states_at(problem, u);
        self.work.state_evaluations.since(t);
    }

    fn bulk_states_at(&self, problem: &mut impl Problem, u: &[f64]) {
        problem.bulk_states(&AssemblyInput {
            dofs: self.dofs,
            u,
            tangent: false,
            algorithm: self.settings.contact_algorithm,
        });
    }

    /// The work done since the solver was made, by kind.
    pub fn work(&self) -> &SolverWork {
        &self.work
    }

    /// Seconds of the fill-reducing orderings and symbolic factorisations so far: of the
    /// Cholesky solver and of the condensed solver (part of the factorisation phase).
    pub fn symbolic_seconds(&self) -> f64 {
        self.linear.symbolic_seconds() + self.condensed_analysis_seconds
    }

    /// The linear solver (for its statistics).
    pub fn linear(&self) -> &CholeskySolver {
        &self.linear
    }

    /// The condensed solver, if the problem solved so far has an interface and the settings
    /// chose it.
    pub fn condensed(&self) -> Option<&CondensedSolver> {
        self.condensed.as_ref().map(|c| &c.solver)
    }

    /// Makes the condensed solver for `problem` if the settings ask for it and it has an
    /// interface (once; later calls return at once). Given the `start` displacements, a
    /// linear bulk whose force is K_c u is assembled there beside the solver's analysis (its
    /// stiffness, force and states). Returns the seconds of the analysis and those the
    /// assembly took beyond them.
    fn prepare_condensed(
        &mut self,
        problem: &mut impl Problem,
        start: Option<&[f64]>,
    ) -> Result<(f64, f64)> {
        if self.settings.linear_solver != LinearSolver::Condensed
            || self.condensed.is_some()
            || self.no_interface
        {
            return Ok((0.0, 0.0));
        }
        let t = std::time::Instant::now();
        let interface_dofs = problem.interface_dofs();
        let interface: Vec<usize> = (interface_dofs.iter())
            .filter_map(|&dof| self.dofs.equation(dof))
            .collect();
        if interface.is_empty() {
            self.no_interface = true;
            return Ok((0.0, 0.0));
        }
        let n = self.dofs.dof_count();
        let linear_bulk = problem.bulk_is_linear();
        // A linear bulk's stiffness (its free block, and the couplings of its prescribed
        // dofs) is assembled while the solver orders and analyses the free pattern: the
        // ordering and the symbolic factorisation run on one core, the element loop takes the
        // other (and both once the analysis is done).
        let stiffness_at = start.filter(|_| linear_bulk);
        let (pattern, dofs, algorithm) = (
            self.system.pattern.clone(),
            self.dofs,
            self.settings.contact_algorithm,
        );
        let system = &mut self.system;
        let ((solver, solver_seconds), couplings) = rayon::join(
            || {
                let t = Instant::now();
                (
                    CondensedSolver::new(&pattern, &interface),
                    t.elapsed().as_secs_f64(),
                )
            },
            || {
                stiffness_at.map(|u| {
                    let t = Instant::now();
                    let couplings = assemble_linear_bulk(problem, system, dofs, u, algorithm);
                    (couplings, t.elapsed().as_secs_f64())
                })
            },
        );
        let solver = solver?;
        self.condensed_analysis_seconds += solver_seconds;
        let map = problem.interface_scatter(self.dofs, &|eq| solver.local_index(eq));
        let n_i = solver.interface_equations().len();
        let mut unknown_dofs = vec![0; n_i];
        for &dof in &interface_dofs {
            if let Some(k) = self
                .dofs
                .equation(dof)
                .and_then(|eq| solver.local_index(eq))
            {
                unknown_dofs[k] = dof;
            }
        }
        let iterations = InterfaceIterations::new(unknown_dofs, interface_dofs, n);
        let thermal = if linear_bulk {
            problem.thermal_load()?
        } else {
            None
        };
        if let Some(load) = &thermal {
            tracing::debug!(
                megabytes = load.memory_bytes() >> 20,
                "thermal load matrices"
            );
        }
        let elastic = if linear_bulk {
            None
        } else {
            problem.elastic_cells(self.dofs)
        };
        tracing::debug!(
            matrix_entries = self.system.pattern.nnz(),
            solver_megabytes = solver.memory_bytes() >> 20,
            "condensed path storage"
        );
        self.condensed = Some(Condensed {
            solver,
            block: InterfaceBlock::zeros(n_i),
            block_entries: map.entries(n_i),
            factored_block: Vec::new(),
            interface_lu_current: false,
            map,
            linear_bulk,
            bulk_dirty: false,
            chord_step: false,
            bulk_ready: false,
            stiffness: None,
            thermal: thermal.map(|load| ThermalForce {
                load,
                force: vec![0.0; n],
            }),
            states_stale: false,
            elastic,
            continuum_energy: 0.0,
            iterations,
        });
        let Some((couplings, assembly_seconds)) = couplings else {
            return Ok((t.elapsed().as_secs_f64(), 0.0));
        };
        let t_keep = Instant::now();
        let c = self.condensed.as_mut().expect("made above");
        keep_linear_bulk(c, self.dofs, &couplings);
        self.work
            .tangent_assemblies
            .add(assembly_seconds + t_keep.elapsed().as_secs_f64());
        // The analysis is the solver's share of the time both took together.
        let both = t.elapsed().as_secs_f64();
        let analysis = solver_seconds.min(both);
        Ok((analysis, both - analysis))
    }

    /// Assembles the internal force at `u` (and the tangent if `tangent`), on the condensed
    /// path if it is active (`fresh`: evaluate the bulk's elements even if it is linear).
    /// Returns whether the tangent is symmetric.
    fn evaluate(
        &mut self,
        problem: &mut impl Problem,
        u: &[f64],
        tangent: bool,
        fresh: bool,
    ) -> bool {
        let input = AssemblyInput {
            dofs: self.dofs,
            u,
            tangent,
            algorithm: self.settings.contact_algorithm,
        };
        let work = &mut self.work;
        let (bulk_work, interface_work) = if tangent {
            (
                &mut work.tangent_assemblies,
                &mut work.interface_tangent_assemblies,
            )
        } else {
            (
                &mut work.force_assemblies,
                &mut work.interface_force_assemblies,
            )
        };
        let t = Instant::now();
        let Some(c) = self.condensed.as_mut() else {
            // The assembly sets the matrix values (the bulk's first): forces alone are cleared.
            self.system.clear(false);
            let symmetric = problem.assemble(&mut self.system, &input);
            bulk_work.since(t);
            if tangent {
                self.bulk_symmetric = problem.bulk_is_symmetric();
            }
            self.flux = Flux::of(&self.system.internal_force);
            return symmetric;
        };
        let system = &mut self.system;
        if !c.linear_bulk {
            // The bulk's tangent assembly sets the matrix (a plastic bulk's from its kept
            // elastic sum in one pass, without zeroing it first).
            system.clear(false);
            // A solve's first evaluation anchors the cells it may leave out later.
            if fresh && let Some(elastic) = c.elastic.as_mut() {
                elastic.unanchor();
            }
            problem.assemble_bulk(system, &input, c.elastic.as_mut());
            bulk_work.since(t);
            if tangent {
                c.bulk_dirty = true;
                self.bulk_symmetric = problem.bulk_is_symmetric();
            }
        } else {
            let first = !c.bulk_ready;
            if first {
                // The continuum's elements, once: K_c (the system's free block, and the
                // entries of prescribed rows and columns kept for K·u), with the states at u.
                let couplings =
                    assemble_linear_bulk(problem, system, self.dofs, u, input.algorithm);
                keep_linear_bulk(c, self.dofs, &couplings);
                work.tangent_assemblies.since(t);
            } else if fresh {
                problem.bulk_states(&AssemblyInput {
                    tangent: false,
                    ..input
                });
                work.state_evaluations.since(t);
            }
            c.states_stale = !(first || fresh);
            // f_c(u) = K_c u − G ΔT over all dofs (the first evaluation's too: the same
            // arithmetic at every evaluation).
            let t = Instant::now();
            let stiffness = c.stiffness.as_mut().expect("linear bulk");
            let f = &mut system.internal_force;
            stiffness.multiply(&system.pattern, &system.values, self.dofs, u, f);
            match &c.thermal {
                Some(thermal) => {
                    for (f, f_t) in f.iter_mut().zip(&thermal.force) {
                        *f -= f_t;
                    }
                }
                None => {
                    c.continuum_energy =
                        0.5 * u.iter().zip(f.iter()).map(|(a, b)| a * b).sum::<f64>();
                }
            }
            work.products.since(t);
        }
        // The bodies' nodal forces, before the interface's are added (they balance them).
        self.flux = Flux::of(&system.internal_force);
        let t = Instant::now();
        if tangent {
            c.clear_block();
        }
        let symmetric = problem.assemble_interface(system, &input, c.block.as_mut(), &c.map);
        interface_work.since(t);
        symmetric
    }

    /// Solves one increment from the displacements in `u` (whose prescribed components
    /// already hold this increment's values) for the external forces `f_ext` (all dofs).
    /// `force_floor` is an absolute force level below which residuals count as zero (e.g.
    /// from earlier steps), for increments whose loads vanish.
    /// Records a converged increment that ended in `u` under `f_ext` with the force `flux`
    /// (and whether it was zero): the history of q̃ and the predictor's last increment.
    fn record_converged(&mut self, (flux, zero_flux): (f64, bool), u: &[f64], f_ext: &[f64]) {
        if self.settings.criteria.average_force.is_none() {
            self.flux_history.record(flux, zero_flux);
        }
        self.predictor.record(u, f_ext);
    }

    /// Starts a thermally coupled increment, whose exchanges solve it several times (each
    /// with the temperatures of the last conduction): the first solve predicts from the last
    /// increment as any increment does, the later ones continue from where the last one
    /// ended, and none records a converged increment — the predictor would take the last
    /// exchange's small change for the increment's and extrapolate nothing from it.
    pub fn begin_coupled_increment(&mut self) {
        self.coupled = Some(CoupledIncrement::default());
    }

    /// Ends the coupled increment begun by [`Self::begin_coupled_increment`]: if it
    /// converged, in `u` under `f_ext`, it is recorded once (from the state it started from).
    pub fn end_coupled_increment(&mut self, converged: Option<(&[f64], &[f64])>) {
        let flux = self.coupled.take().and_then(|c| c.flux);
        if let (Some((u, f_ext)), Some(flux)) = (converged, flux) {
            self.record_converged(flux, u, f_ext);
        }
    }

    /// The converged increments' record of the time-averaged force q̃ (for a restart record).
    pub fn force_average(&self) -> ForceAverage {
        self.flux_history.past
    }

    /// Continues the time average of q̃ of an interrupted run.
    pub fn restore_force_average(&mut self, average: ForceAverage) {
        self.flux_history.past = average;
    }

    /// The last converged increment the predictor extrapolates from (`None` with the predictor
    /// off): what a restart record keeps of it.
    pub fn last_increment(&self) -> Option<&LastIncrement> {
        self.settings.extrapolate.then(|| self.predictor.last())
    }

    /// Continues the predictor of an interrupted run from its `last` converged increment
    /// (read back with this model's sizes, [`crate::output::restart::read_record`]).
    pub fn restore_last_increment(&mut self, last: LastIncrement) {
        self.predictor.restore(last);
    }

    pub fn solve_increment(
        &mut self,
        problem: &mut impl Problem,
        u: &mut [f64],
        f_ext: &[f64],
        force_floor: f64,
    ) -> Result<NewtonLog> {
        let settings = self.settings;
        let dofs = self.dofs;
        let mut log = NewtonLog::sized(settings.max_iterations);
        dofs.gather_free(f_ext, &mut self.external);
        self.increment_start.copy_from_slice(u);
        self.flux_history.start();
        log.factorization_seconds += self.begin_increment(problem)?;
        log.assembly_seconds += self.update_thermal_force(problem);
        let continuing = self.coupled.as_ref().is_some_and(|c| c.continuing);
        if settings.extrapolate && !continuing {
            log.predictor = self.predictor.predict(dofs, u, f_ext);
        }
        if let Some(c) = self.coupled.as_mut() {
            c.continuing = true;
        }
        let f_ext_norm = norm(f_ext);
        let mut last_correction = f64::INFINITY;
        let mut correction_max = f64::INFINITY;
        let mut initial_residual = None;
        // Whether the first evaluation runs the bulk's elements: unless a linear bulk's force
        // is K_c u − G ΔT.
        let mut fresh = !self.condensed.as_ref().is_some_and(|c| c.linear_bulk);
        // The symmetry of a tangent the line search already evaluated at u (its full step).
        let mut evaluated: Option<bool> = None;
        // Whether the residual rose at an iteration of this increment: every later step is
        // then line-searched, below `LINE_SEARCH_ABOVE` too (a full step that would rise
        // again, e.g. friction statuses flipping back and forth, is shortened).
        let mut rose = false;
        loop {
            let t = std::time::Instant::now();
            let symmetric = match evaluated.take() {
                Some(symmetric) => symmetric,
                None => self.evaluate(problem, u, true, fresh),
            };
            fresh = false;
            log.assembly_seconds += t.elapsed().as_secs_f64();
            let r = &mut self.residual;
            out_of_balance(dofs, &self.system.internal_force, &self.external, r);
            let r0 = *initial_residual.get_or_insert(norm(r));
            let reference = f_ext_norm
                .max(norm(&self.system.internal_force))
                .max(r0)
                .max(force_floor)
                .max(f64::MIN_POSITIVE);
            let residual = norm(r) / reference;
            let flux = self.flux.typical();
            let (average, zero_flux) = match settings.criteria.average_force {
                Some(q) => (q, false),
                None => self.flux_history.with(flux, settings.criteria.zero_flux),
            };
            let measures = Measures {
                residual_max: max_abs(r),
                average,
                zero_flux,
                correction_max,
                increment_max: max_change(u, &self.increment_start),
            };
            log.residuals.push(residual);
            self.check_chord_contraction(&log.residuals);
            rose |= matches!(log.residuals[..], [.., before, now] if now > before);
            tracing::debug!(
                iteration = log.iterations,
                residual = Criteria::ratio(&measures),
                correction = correction_max / measures.increment_max,
                relative_residual = residual,
                "newton"
            );
            let criteria = &settings.criteria;
            // A residual that is not finite (an overflowing law, a NaN state) never converges.
            let engineering = residual.is_finite() && criteria.converged(log.iterations, &measures);
            // CalculiX's estimate of the next correction, assuming the residual keeps
            // falling at its last rate: it spares an iteration that would only meet round-off.
            let previous = log.residuals.iter().rev().nth(1).copied();
            let next_correction =
                previous.map_or(f64::INFINITY, |p| last_correction * residual / p);
            let norms = !criteria.relative_norms
                || settings.relative_norms_met(
                    residual,
                    log.iterations == 0,
                    last_correction.min(next_correction),
                );
            if engineering && norms {
                match self.coupled.as_mut() {
                    Some(c) => c.flux = Some((flux, zero_flux)),
                    None => self.record_converged((flux, zero_flux), u, f_ext),
                }
                log.converged = true;
                return Ok(log);
            }
            if log.iterations == settings.max_iterations
                || !residual.is_finite()
                || (!self.bulk_symmetric && stalled(&log.residuals))
            {
                return Ok(log);
            }
            // An unsymmetric bulk is factored by LU, exactly, whatever the interface.
            if self.condensed.is_some() && settings.interface_iterations > 0 {
                self.factor(&mut log)?;
                self.solve_iterating_interface(problem, u, average, &mut log);
                log.unsymmetric_solves += usize::from(!symmetric);
            } else if self.condensed.is_some() || symmetric || !self.bulk_symmetric {
                self.factor(&mut log)?;
                let t = std::time::Instant::now();
                solve_factored(
                    &mut self.condensed,
                    &mut self.linear,
                    &mut self.residual,
                    &mut self.work,
                );
                log.solve_seconds += t.elapsed().as_secs_f64();
                log.unsymmetric_solves += usize::from(!symmetric);
            } else {
                let t = std::time::Instant::now();
                let r = &mut self.residual;
                // Inexact Newton (Eisenstat & Walker): solve only as accurately as the current
                // residual warrants, η_k = 1e-2 ‖r_k‖ (relative), which keeps quadratic
                // convergence.
                let forcing = (1e-2 * residual).clamp(1e-12, 1e-3);
                log.krylov_iterations += self.linear.solve_unsymmetric(
                    self.system.matrix(),
                    self.system.preconditioner_matrix(),
                    r,
                    forcing,
                )?;
                log.unsymmetric_solves += 1;
                log.solve_seconds += t.elapsed().as_secs_f64();
                self.work.solves.since(t);
            }
            let before = norm(u);
            let step = if residual > LINE_SEARCH_ABOVE || rose {
                let t = std::time::Instant::now();
                let alpha;
                (alpha, evaluated) = self.line_search(problem, u, residual * reference);
                log.assembly_seconds += t.elapsed().as_secs_f64();
                alpha
            } else {
                dofs.add_free(1.0, &self.residual, u);
                1.0
            };
            last_correction =
                step * norm(&self.residual) / norm(u).max(before).max(f64::MIN_POSITIVE);
            correction_max = step * max_abs(&self.residual);
            log.corrections.push(last_correction);
            log.iterations += 1;
        }
    }

    /// Sets the state the run starts from, `u` (all dofs; the committed displacements of a
    /// new or resumed run): a linear bulk on the condensed path makes its stiffness there
    /// (and the states at `u`), its force being K_c u − G ΔT from then on: a resumed run
    /// multiplies the same K_c and u as the uninterrupted one, to the same bits. Other
    /// problems are left to their first increment, unless `states`: then the bulk's elements
    /// are evaluated at `u` for their trial states (those a restart record leaves out when
    /// they follow from the displacements). The log holds the seconds spent (making the
    /// condensed solver counts as factorisation, as in an increment).
    pub fn start_from(
        &mut self,
        problem: &mut impl Problem,
        u: &[f64],
        states: bool,
    ) -> Result<NewtonLog> {
        let mut log = NewtonLog::default();
        (log.factorization_seconds, log.assembly_seconds) =
            self.prepare_condensed(problem, Some(u))?;
        // A linear bulk was assembled at u beside the analysis.
        let linear_bulk = self.condensed.as_ref().is_some_and(|c| c.linear_bulk);
        if states && !linear_bulk {
            let t = Instant::now();
            self.evaluate(problem, u, false, true);
            log.assembly_seconds += t.elapsed().as_secs_f64();
        }
        Ok(log)
    }

    /// Starts an increment of `problem`. Nothing cached from earlier increments may change
    /// this one's iterates (a resumed run must repeat the uninterrupted one): the bulk
    /// factor is kept only for an unchanged tangent (the tangent itself depends on the trial
    /// states alone, `GlobalSystem::assemble_reusing`). Makes the condensed solver at the
    /// first increment; returns the seconds that took.
    fn begin_increment(&mut self, problem: &mut impl Problem) -> Result<f64> {
        if let Some(c) = &mut self.condensed {
            c.solver.start_increment();
            c.chord_step = false;
            if let Some(elastic) = c.elastic.as_mut() {
                elastic.unanchor();
            }
        }
        Ok(self.prepare_condensed(problem, None)?.0)
    }

    /// Makes a linear bulk's thermal force G ΔT of the temperatures `problem` has now (those
    /// of the increment about to be solved); returns the seconds (0 without one).
    fn update_thermal_force(&mut self, problem: &impl Problem) -> f64 {
        let Some(thermal) = self.condensed.as_mut().and_then(|c| c.thermal.as_mut()) else {
            return 0.0;
        };
        let t = Instant::now();
        problem.thermal_force(&thermal.load, &mut thermal.force);
        self.work.products.since(t);
        t.elapsed().as_secs_f64()
    }

    /// After a chord step: stops the bulk factor's reuse for the rest of the increment if the
    /// residual (the last of `residuals`) fell by less than `CHORD_CONTRACTION`.
    fn check_chord_contraction(&mut self, residuals: &[f64]) {
        let Some(c) = self.condensed.as_mut().filter(|c| c.chord_step) else {
            return;
        };
        c.chord_step = false;
        if let [.., before, now] = residuals
            && (*now > CHORD_CONTRACTION * before || !now.is_finite())
        {
            tracing::debug!(
                ratio = now / before,
                "chord step did not contract: refactoring"
            );
            c.solver.stop_reuse_in_increment();
        }
    }

    /// Factors the tangent of the last evaluation: on the condensed path the bulk (when its
    /// tangent changed) and the interface block, otherwise by Cholesky (a symmetric tangent);
    /// an unsymmetric bulk tangent by LU.
    fn factor(&mut self, log: &mut NewtonLog) -> Result<()> {
        let t = Instant::now();
        let matrix = self.system.matrix();
        let work = &mut self.work;
        if let Some(c) = self.condensed.as_mut() {
            if c.bulk_dirty {
                let factored = if self.bulk_symmetric {
                    let varying = self.system.off_reference_columns();
                    c.solver.factor_bulk_varying(matrix, varying)?
                } else {
                    c.solver.factor_bulk_unsymmetric(matrix)?
                };
                if c.linear_bulk {
                    // Factored for good: K_c is constant.
                    c.solver.release_refactorisation_storage();
                }
                // A kept factor of a different matrix makes the next step a chord step.
                c.chord_step = !factored && c.solver.last_change() > 0.0;
                let kind = if factored {
                    &mut work.factorisations
                } else {
                    &mut work.kept_factorisations
                };
                kind.since(t);
                c.bulk_dirty = false;
                c.interface_lu_current = false;
            }
            let t = Instant::now();
            if c.interface_lu_holds() {
                work.kept_interface_factorisations.since(t);
            } else {
                c.interface_lu_current = false;
                c.solver.factor_interface(c.block.as_ref())?;
                c.record_factored_block();
                work.interface_factorisations.since(t);
            }
        } else {
            // The first factorisation runs the symbolic analysis, timed on its own.
            let symbolic = self.linear.symbolic_seconds();
            if self.bulk_symmetric {
                self.linear.factorize(matrix)?;
            } else {
                self.linear.factorize_unsymmetric(matrix)?;
            }
            let symbolic = self.linear.symbolic_seconds() - symbolic;
            work.factorisations
                .add(t.elapsed().as_secs_f64() - symbolic);
        }
        log.factorization_seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// Backtracking line search along the Newton correction δu held in the residual: takes
    /// u + α δu with the first α ∈ {1, ½, ¼, ⅛, 1/16} that lowers the out-of-balance force
    /// ‖r‖ below `current`, or the α with the smallest ‖r‖. Contact and friction make the
    /// residual piecewise smooth, and a point flipping between stick and slip (or open and
    /// closed) can make full Newton steps cycle; shortening the step breaks the cycle.
    ///
    /// The full step, taken in most iterations, is evaluated with its tangent: accepted, it
    /// is the next iteration's evaluation, which is then not repeated (the same trial states
    /// as a second pass at the same u, hence the same bits: a plastic bulk's tangent depends
    /// on the trial states alone, `GlobalSystem::assemble_reusing`). A rejected full step
    /// costs the tangent part of one evaluation. Measured on the elasto-plastic flat punch
    /// (43k unknowns, 40 iterations, 36 of 42 full steps accepted): assembly 0.96 → 0.73 s,
    /// the same iterations. Returns α, with the symmetry of that tangent when the full step
    /// was taken; `u` holds u + α δu.
    fn line_search(
        &mut self,
        problem: &mut impl Problem,
        u: &mut [f64],
        current: f64,
    ) -> (f64, Option<bool>) {
        self.start.copy_from_slice(u);
        let mut best = (f64::INFINITY, 1.0);
        let mut alpha = 1.0;
        for _ in 0..5 {
            u.copy_from_slice(&self.start);
            self.dofs.add_free(alpha, &self.residual, u);
            let full = alpha == 1.0;
            let symmetric = self.evaluate(problem, u, full, false);
            self.work.line_search_evaluations += 1;
            let trial = &mut self.trial_residual;
            out_of_balance(
                self.dofs,
                &self.system.internal_force,
                &self.external,
                trial,
            );
            let value = norm(trial);
            if value < best.0 {
                best = (value, alpha);
            }
            if value < current {
                return (alpha, full.then_some(symmetric));
            }
            alpha *= 0.5;
        }
        u.copy_from_slice(&self.start);
        self.dofs.add_free(best.1, &self.residual, u);
        (best.1, None)
    }
}

/// A linear bulk's stiffness K_c, with the force and the states at `u`, once per model: its
/// free block and force into `system`, its entries in prescribed rows and columns returned.
fn assemble_linear_bulk(
    problem: &mut impl Problem,
    system: &mut GlobalSystem,
    dofs: &DofMap,
    u: &[f64],
    algorithm: ContactAlgorithm,
) -> PrescribedCouplings {
    let input = AssemblyInput {
        dofs,
        u,
        tangent: true,
        algorithm,
    };
    system.clear(false);
    problem.assemble_linear_bulk(system, &input)
}

/// Keeps a linear bulk's entries in prescribed rows and columns ([`assemble_linear_bulk`])
/// for K·u; its free block, in the Newton system, is factored next.
fn keep_linear_bulk(c: &mut Condensed, dofs: &DofMap, couplings: &PrescribedCouplings) {
    let stiffness = BulkStiffness::new(couplings.matrix(), dofs);
    tracing::debug!(
        prescribed_entries = stiffness.len(),
        "linear bulk stiffness"
    );
    c.stiffness = Some(stiffness);
    c.bulk_dirty = true;
    c.bulk_ready = true;
}

/// The out-of-balance force Q − F over the free dofs, from the external forces `external`
/// (free dofs) and the internal forces `internal` (all dofs), into `out`.
fn out_of_balance(dofs: &DofMap, internal: &[f64], external: &[f64], out: &mut [f64]) {
    dofs.gather_free(internal, out);
    for (ri, ei) in out.iter_mut().zip(external) {
        *ri = ei - *ri;
    }
}

/// Solves the tangent factored by [`Newton::factor`] for `x` (free dofs) in place, tallied
/// in `work`.
fn solve_factored(
    condensed: &mut Option<Condensed>,
    linear: &mut CholeskySolver,
    x: &mut [f64],
    work: &mut SolverWork,
) {
    let t = Instant::now();
    match condensed {
        Some(c) => c.solver.solve_in_place(x),
        None => linear.solve_in_place(x),
    }
    work.solves.since(t);
}

/// ‖v‖∞.
fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| nan_max(m, x.abs()))
}

/// The larger of `m` and `x`, NaN if either is (`f64::max` drops a NaN: a NaN residual
/// would read as the largest finite entry and could pass a convergence test).
fn nan_max(m: f64, x: f64) -> f64 {
    if m.is_nan() || x.is_nan() {
        f64::NAN
    } else {
        m.max(x)
    }
}

/// ‖a − b‖∞.
fn max_change(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0, |m, (x, y)| nan_max(m, (x - y).abs()))
}

/// Iterations after which an increment of an unsymmetric (LU-factored) bulk may be given up
/// as stalled ([`stalled`]), and how many iterations back its residual is compared.
const STALL_AFTER: usize = 8;
const STALL_WINDOW: usize = 4;

/// Whether the residuals of an increment (one per iteration so far) show an iteration that
/// will not converge: after [`STALL_AFTER`] iterations, the last residual is no smaller than
/// the one [`STALL_WINDOW`] iterations before. Used only with an unsymmetric bulk tangent
/// (Armstrong–Frederick hardening): its exact LU never fails, whereas the Cholesky of a
/// symmetric tangent refuses a hopeless increment early, so without this check an increment
/// that cannot converge ran to `max_iterations` before being cut back (measured on
/// `pipelines/cyclic_press_fit/nonproportional.toml`: 522 → 940 Newton iterations). A
/// converging Newton iteration falls by orders of magnitude within four iterations.
fn stalled(residuals: &[f64]) -> bool {
    let n = residuals.len();
    n > STALL_AFTER && residuals[n - 1] >= residuals[n - 1 - STALL_WINDOW]
}

#[cfg(test)]
mod tests {
    use super::stalled;

    #[test]
    fn an_increment_is_stalled_only_when_its_residual_stops_falling_after_eight_iterations() {
        // Quadratic convergence from 1: never stalled.
        let converging: Vec<f64> = (0..12).map(|k| 0.5f64.powi(1 << k.min(9))).collect();
        assert!((1..=converging.len()).all(|n| !stalled(&converging[..n])));
        // Slow but steady linear convergence: not stalled either.
        let linear: Vec<f64> = (0..20).map(|k| 0.9f64.powi(k)).collect();
        assert!((1..=linear.len()).all(|n| !stalled(&linear[..n])));
        // Wandering: stalled once there are more than 8 residuals.
        let wandering = [1.0, 0.5, 0.8, 0.3, 0.9, 0.4, 0.7, 0.6, 0.5, 0.65];
        assert!(!stalled(&wandering[..8]));
        assert!(stalled(&wandering[..10]));
    }
}
