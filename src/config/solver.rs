//! `[solver]`: the Newton-Raphson settings of a case, their defaults, and the linear solver
//! and contact algorithm it names.

use schemars::JsonSchema;
use serde::Deserialize;

/// Newton-Raphson settings (`[solver]`). The convergence criteria are the engineering ones of
/// CalculiX and Abaqus (see `docs/convergence_criteria.md`); the older relative-norm keys
/// `force_tolerance` and `displacement_tolerance` still work and, when given, are required in
/// addition.
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema)]
#[serde(from = "RawSolverSpec")]
pub struct SolverSpec {
    /// Iteration limit per step.
    pub max_iterations: usize,
    /// R_n: largest residual force ≤ R_n × the time-averaged force.
    pub residual_tolerance: f64,
    /// C_n: largest correction ≤ C_n × the largest displacement change of the increment.
    pub correction_tolerance: f64,
    /// R_p, used instead of R_n after `late_iteration` (I_P) iterations.
    pub late_residual_tolerance: f64,
    pub late_iteration: usize,
    /// ε: zero flux when the force flux is below ε × its time average.
    pub zero_flux: f64,
    /// C_ε: the correction criterion under zero flux.
    pub zero_flux_correction_tolerance: f64,
    /// R_l: a residual below R_l × the average force is accepted alone (linear increments).
    pub linear_residual_tolerance: f64,
    /// q_u: a user-given average force (N) replacing the time-averaged one.
    pub average_force: Option<f64>,
    /// Relative tolerance on the out-of-balance force: ‖r‖ ≤ tol · max(‖f_ext‖, ‖f_int‖).
    /// Always used by arc-length control; by load control only if given (`relative_norms`).
    pub force_tolerance: f64,
    /// Relative tolerance on the displacement correction: ‖δu‖ ≤ tol · ‖u‖ (as above).
    pub displacement_tolerance: f64,
    /// Whether the case gave `force_tolerance` or `displacement_tolerance`: load-controlled
    /// increments then also require the relative-norm criteria.
    pub relative_norms: bool,
    /// How many cut-backs a step may make in all (each halves a failed increment and retries
    /// it); the step fails at its next failure after that many.
    pub max_cutbacks: usize,
    /// Most increment solves of a load-controlled run: output increments, sub-increments
    /// ending on amplitude breakpoints or made by cut-backs, and retried attempts.
    pub max_solves: usize,
    /// Global algorithm for contact: `"newton"` (consistent tangent, default), `"two_step"`
    /// (normal stress frozen in the friction tangent, symmetric) or `"elastic_contact"`
    /// (elastic contact matrix).
    pub contact_algorithm: ContactAlgorithmKind,
    /// Linear solver of models with contact pairs: `"condensed"` (exact solves by
    /// condensation onto the interface unknowns, default) or `"krylov"` (Cholesky, and
    /// BiCGSTAB preconditioned with the elastic contact matrix for unsymmetric tangents).
    pub linear_solver: LinearSolverKind,
    /// Start an increment proportional to the last converged one from the displacements
    /// extrapolated from it (default true).
    pub extrapolate: bool,
    /// Condensed path: interface iterations per Newton iteration (0: none).
    pub interface_iterations: usize,
    // --- plausibility of a converged increment and collapse detection ----------
    /// Largest nodal displacement increment of a converged increment, as a fraction of the
    /// model size (bounding-box diagonal); a larger one is a failed increment (cut back).
    pub max_displacement_increment: f64,
    /// Largest equivalent strain increment √(⅔ Δε:Δε) at any integration point of a
    /// converged increment; a larger one is a failed increment (cut back).
    pub max_strain_increment: f64,
    /// A step that cannot be completed is reported as plastic collapse when the secant
    /// stiffness Δλ/‖Δu‖ of its last converged increment is below this fraction of that of
    /// the first increment of the run.
    pub collapse_stiffness_ratio: f64,
}

/// `[solver]` as written in the case file (the relative-norm keys optional).
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
struct RawSolverSpec {
    /// Newton iterations per increment (1 to 10 000; default 25).
    max_iterations: usize,
    /// R_n: the largest out-of-balance force component, relative to the time-averaged force
    /// q̃ (default 5e-4; CalculiX and Abaqus: 5e-3). This and every tolerance below except R_p
    /// lie in (0, 1e-2].
    residual_tolerance: f64,
    /// C_n: the largest component of the last correction, relative to the largest
    /// displacement change of the increment (default 1e-3; CalculiX and Abaqus: 1e-2).
    correction_tolerance: f64,
    /// R_p: replaces R_n after `late_iteration` iterations (a slowly converging increment);
    /// in (0, 0.2] (default 2e-2).
    late_residual_tolerance: f64,
    /// I_P: the iteration after which R_p replaces R_n (default 9).
    late_iteration: usize,
    /// ε: zero-flux conditions when the force flux is below ε q̃ (e.g. a body unloaded to a
    /// stress-free state); then the residual must be below ε q̃ and the correction below
    /// `zero_flux_correction_tolerance` (default 1e-5).
    zero_flux: f64,
    /// C_ε: the correction criterion under zero flux (default 1e-3).
    zero_flux_correction_tolerance: f64,
    /// R_l: a residual this small relative to q̃ is accepted without the correction check
    /// (a linear increment takes one solve; default 1e-8).
    linear_residual_tolerance: f64,
    /// q_u (N): a fixed average force used instead of the time-averaged q̃ (default: none).
    average_force: Option<f64>,
    /// The older relative-norm criterion ‖r‖ / max(‖f_ext‖, ‖f_int‖): when given, required in
    /// addition to the criteria above (e.g. 1e-10 for a reference run); arc-length control
    /// uses it alone (default there 1e-8).
    force_tolerance: Option<f64>,
    /// The older ‖δu‖ / ‖u‖ criterion, like `force_tolerance`.
    displacement_tolerance: Option<f64>,
    /// How many cut-backs a step may make in all: each halves an increment that does not
    /// converge (or is implausible) and retries it, and a converged sub-increment lets the
    /// next one grow again (doubled); the step fails at its next failure after this many, so
    /// that a load the model cannot carry is not crept up to by ever smaller increments
    /// (at most 20; default 8).
    max_cutbacks: usize,
    /// Most increment solves of a load-controlled run: output increments, sub-increments
    /// ending on amplitude breakpoints or made by cut-backs, and retried attempts (default
    /// 100 000). When the increments and breakpoints alone need more, the model is refused
    /// before solving (exit code 3); when cut-backs reach it, the run stops keeping its
    /// converged results (exit code 1).
    max_solves: usize,
    /// Global algorithm for contact (default `"newton"`). Where they converge, all three
    /// reach the same solution.
    contact_algorithm: ContactAlgorithmKind,
    /// Linear solver of models with contact pairs (default `"condensed"`); models without
    /// contact always use Cholesky.
    linear_solver: LinearSolverKind,
    /// Start an increment whose loads and prescribed displacements change in proportion to
    /// the last converged increment's (s > 0 times its change) from the displacements
    /// extrapolated from it, u + s Δu_last, as Abaqus does by default; otherwise (the first
    /// increment, a reversal, a non-proportional change, after a cut-back's failed attempt)
    /// from the converged state. An extrapolated start that already meets the criteria is
    /// accepted without a solve (default true; false starts every increment from the
    /// converged state).
    extrapolate: bool,
    /// With the condensed linear solver: how many times, within one Newton iteration, the
    /// interface elements are re-evaluated and the interface system (the bodies condensed
    /// onto it, linearised) solved again, so that the stick, slip and open statuses settle
    /// without a new assembly of the bodies (0 to 100; default 12; 0 gives plain Newton
    /// iterations, one interface evaluation each). A further interface iteration is made
    /// only while the interface's out-of-balance force keeps falling and is above R_l q̃.
    /// Load-controlled increments only: arc-length increments keep plain Newton iterations.
    interface_iterations: usize,
    /// Plausibility bound: a converged increment in which a node moves by more than this
    /// fraction of the model size (bounding-box diagonal) is a failed increment and is cut back
    /// (default 0.1). With twist a node's circumferential displacement u_θ counts too.
    max_displacement_increment: f64,
    /// Plausibility bound: a converged increment with an equivalent strain increment
    /// √(⅔ Δε:Δε) above this at any integration point is a failed increment and is cut back
    /// (small-strain theory; default 0.05).
    max_strain_increment: f64,
    /// A step of a model with a plastic body that cannot be completed is reported as plastic
    /// collapse (exit code 5) when the secant stiffness Δλ/‖Δu‖ of its last converged increment
    /// is below this fraction of the run's first increment's (default 0.01).
    collapse_stiffness_ratio: f64,
}

impl Default for RawSolverSpec {
    /// CalculiX's field defaults (*CONTROLS, PARAMETERS=FIELD), but R_n = 5e-4 and C_n = 1e-3
    /// rather than 5e-3 and 1e-2: with theirs frictional answers drifted by up to 4e-4 from a
    /// tight run, with these by < 1e-5 at a few % more iterations
    /// (docs/convergence_criteria.md).
    fn default() -> Self {
        Self {
            max_iterations: 25,
            residual_tolerance: 5e-4,
            correction_tolerance: 1e-3,
            late_residual_tolerance: 2e-2,
            late_iteration: 9,
            zero_flux: 1e-5,
            zero_flux_correction_tolerance: 1e-3,
            linear_residual_tolerance: 1e-8,
            average_force: None,
            force_tolerance: None,
            displacement_tolerance: None,
            max_cutbacks: 8,
            max_solves: DEFAULT_MAX_SOLVES,
            contact_algorithm: ContactAlgorithmKind::default(),
            linear_solver: LinearSolverKind::default(),
            extrapolate: true,
            interface_iterations: 12,
            max_displacement_increment: 0.1,
            max_strain_increment: 0.05,
            collapse_stiffness_ratio: 1e-2,
        }
    }
}

/// `max_solves` when not given: as many as the output increments a case may ask for
/// ([`super::MAX_STEPS`]), so that a case at that limit fails before solving when its
/// amplitude breakpoints add sub-increments, and a run that cuts back heavily stops.
pub const DEFAULT_MAX_SOLVES: usize = super::check::MAX_STEPS;

/// The relative-norm tolerances' value when not given (arc-length control's criteria).
const DEFAULT_NORM_TOLERANCE: f64 = 1e-8;

impl From<RawSolverSpec> for SolverSpec {
    fn from(r: RawSolverSpec) -> Self {
        Self {
            max_iterations: r.max_iterations,
            residual_tolerance: r.residual_tolerance,
            correction_tolerance: r.correction_tolerance,
            late_residual_tolerance: r.late_residual_tolerance,
            late_iteration: r.late_iteration,
            zero_flux: r.zero_flux,
            zero_flux_correction_tolerance: r.zero_flux_correction_tolerance,
            linear_residual_tolerance: r.linear_residual_tolerance,
            average_force: r.average_force,
            force_tolerance: r.force_tolerance.unwrap_or(DEFAULT_NORM_TOLERANCE),
            displacement_tolerance: r.displacement_tolerance.unwrap_or(DEFAULT_NORM_TOLERANCE),
            relative_norms: r.force_tolerance.is_some() || r.displacement_tolerance.is_some(),
            max_cutbacks: r.max_cutbacks,
            max_solves: r.max_solves,
            contact_algorithm: r.contact_algorithm,
            linear_solver: r.linear_solver,
            extrapolate: r.extrapolate,
            interface_iterations: r.interface_iterations,
            max_displacement_increment: r.max_displacement_increment,
            max_strain_increment: r.max_strain_increment,
            collapse_stiffness_ratio: r.collapse_stiffness_ratio,
        }
    }
}

/// The linear solver of models with contact pairs (`[solver] linear_solver`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LinearSolverKind {
    /// Exact solves by condensation onto the interface unknowns.
    #[default]
    Condensed,
    /// Cholesky for symmetric tangents, preconditioned BiCGSTAB for unsymmetric ones.
    Krylov,
}

/// The global algorithm for contact (`[solver] contact_algorithm`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ContactAlgorithmKind {
    /// Full Newton with the consistent tangent.
    #[default]
    Newton,
    /// The two-step scheme of Buczkowski & Kleiber (1994), §2.4 (normal stress frozen in the
    /// friction tangent).
    TwoStep,
    /// The elastic contact matrix.
    ElasticContact,
}

impl Default for SolverSpec {
    fn default() -> Self {
        RawSolverSpec::default().into()
    }
}
