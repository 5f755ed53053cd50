//! The crate's error type. Every error names the file or entity it concerns and what is wrong,
//! so that a user can fix the input without reading the source; the variants carry those
//! facts as data, so that callers (and tests) can act on them without parsing messages.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::memory::{Limit, gigabytes};

/// Errors of asperity. Messages are complete sentences meant for the user.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A mesh file could not be read or is not usable (wrong version, element order, ...):
    /// `problem` says what is wrong, `entity` where (a node, an element, a section).
    #[error("{}: {message}", path.display())]
    Mesh {
        path: PathBuf,
        problem: MeshProblem,
        entity: Option<MeshEntity>,
        message: String,
    },
    /// A case file could not be read or is inconsistent (TOML syntax, unknown keys, missing
    /// sections, keys that do not go together). Invalid values of known keys are
    /// [`Error::InvalidParameter`].
    #[error("{}: {message}", path.display())]
    Case { path: PathBuf, message: String },
    /// A case-file value is out of its range: `key` is its path in the case
    /// (`contact[2].law.friction`, `body[0].material.nu`, `steps.count`).
    #[error("{}: {key}{}: {reason}", file_or_model(path), equals(value))]
    InvalidParameter {
        path: PathBuf,
        key: String,
        value: String,
        reason: String,
    },
    /// A physical group named in the case (by `role`: "body", "support", "load", "contact
    /// 'p': side A curve", ...) is missing from the mesh `mesh`, is not of the `expected`
    /// kind, or has no elements.
    #[error("model: {role} '{name}': {}", group_message(mesh, name, *expected, problem))]
    Group {
        mesh: PathBuf,
        role: String,
        name: String,
        expected: GroupKind,
        problem: GroupProblem,
    },
    /// The faces of contact pair `pair` cannot be joined by interface elements: `problem`
    /// says why, `node` and `element` are the gmsh tags of the offending node and line
    /// element where there is one.
    #[error("model: contact '{pair}': {message}")]
    Topology {
        pair: String,
        problem: TopologyProblem,
        node: Option<u64>,
        element: Option<u64>,
        message: String,
    },
    /// Two supports prescribe different histories of the same displacement component
    /// (`component` 0 = x, 1 = y, 2 = θ) of node `node` (gmsh tag).
    #[error(
        "model: supports '{first}' and '{second}' prescribe different {} displacement histories ({} and {} \
         at factor 1) at node {node} ({position:?})",
        ["x", "y", "θ"][*component], values[0], values[1]
    )]
    ConflictingSupports {
        first: String,
        second: String,
        component: usize,
        values: [f64; 2],
        node: u64,
        position: [f64; 2],
    },
    /// A node of an axisymmetric model lies at negative radius.
    #[error(
        "model: axisymmetric model: node {node} lies at negative radius r = {radius} (the axis is x = r = 0)"
    )]
    NegativeRadius { node: u64, radius: f64 },
    /// A support prescribes a non-zero radial (`component` 0) or circumferential (2)
    /// displacement on the axis.
    #[error(
        "model: node {node} on the axis has a prescribed {} displacement {value}; it must be 0",
        ["radial", "axial", "circumferential"][*component]
    )]
    AxisDisplacement {
        node: u64,
        component: usize,
        value: f64,
    },
    /// A support or load of group `group` reaches a node or boundary element (`entity`, at
    /// `position`) that belongs to no body.
    #[error("model: {role} '{group}': {}", off_body_message(entity, position))]
    NotOnBody {
        role: &'static str,
        group: String,
        entity: MeshEntity,
        position: [f64; 2],
    },
    /// The physical surfaces of two bodies share element `element` (gmsh tag).
    #[error(
        "model: element {element} belongs to bodies '{first}' and '{second}': physical surfaces of bodies must \
         not overlap"
    )]
    OverlappingBodies {
        element: u64,
        first: String,
        second: String,
    },
    /// Element `element` (gmsh tag) of body `body` has a non-positive Jacobian determinant.
    #[error(
        "model: element {element} of body '{body}' is distorted or degenerate (Jacobian determinant \
         {jacobian:.3e} ≤ 0; corners {corners:?}); check mid-side nodes and the mesh quality"
    )]
    DistortedElement {
        element: u64,
        body: String,
        jacobian: f64,
        corners: Vec<[f64; 2]>,
    },
    /// Supports and the nodes outside every body leave no unknown.
    #[error("model: every degree of freedom is prescribed: nothing to solve")]
    NothingToSolve,
    /// A quantity of interest cannot be evaluated on the model: `name` is the quantity's,
    /// `reason` says what is missing or wrong.
    #[error("quantity '{name}': {reason}")]
    Quantity { name: String, reason: String },
    /// An external program (gmsh) failed.
    #[error("{0}")]
    External(String),
    /// The linear solver failed (e.g. the stiffness matrix is singular: a body without supports).
    #[error("linear solver: {0}")]
    Linear(String),

    /// The solver's storage for the model exceeds the memory this process may still take
    /// ([`crate::memory`]): refused before it is allocated, instead of a failed allocation
    /// or the kernel's out-of-memory kill part way through the run.
    #[error(
        "model: the linear solver needs {:.2} GB of memory for the {unknowns} unknowns ({what}), \
         more than the {:.2} GB this run can still take ({}); a coarser mesh needs less (a larger \
         `mesh.size`, or fewer elements where the .geo script sets their number): the factor \
         grows somewhat faster than the unknowns",
        gigabytes(*needed),
        gigabytes(*available),
        limit.describe()
    )]
    InsufficientMemory {
        /// What the bytes are for, with their parts.
        what: String,
        unknowns: usize,
        needed: u64,
        available: u64,
        limit: Limit,
    },
    /// An allocation of the linear solver failed (the symbolic analysis's or a workspace's,
    /// made before [`Error::InsufficientMemory`]'s check or too small for it): the model needs
    /// more memory than the run can take, not a numerical failure.
    #[error(
        "model: the linear solver could not allocate memory for {what} ({unknowns} unknowns): the \
         model needs more memory than this run can take (the machine's, a batch job's or \
         container's limit, `ulimit -v`); a coarser mesh needs less (a larger `mesh.size`)"
    )]
    AllocationFailed { what: String, unknowns: usize },
    /// The steady heat conduction cannot be solved in an increment (open joints cut a body
    /// off from every held temperature, a singular conductivity matrix).
    #[error("heat conduction: {0}")]
    Conduction(String),
    /// A conducting body whose temperature nothing fixes: no temperature support or film on
    /// it or on a body joined to it by a conducting contact pair (the conduction would be
    /// singular): found before anything is solved.
    #[error(
        "model: nothing fixes the temperature of body '{body}' (near ({:.4}, {:.4})): give it a \
         [[thermal_support]] with `temperature` or `film`, or join it through a [[contact]] \
         `conductance` to a body that has one",
        near[0],
        near[1]
    )]
    UnfixedTemperature { body: String, near: [f64; 2] },
    /// A thermal entry the mesh cannot carry (a thermal support or a conducting joint on a
    /// node of no conducting body).
    #[error("model: {0}")]
    ThermalModel(String),
    /// A load step did not converge, even after cutting it back.
    #[error("{0}")]
    NoConvergence(Box<NoConvergence>),
    /// A step could not be completed because the load exceeds what the model can carry:
    /// `mechanism` says how (the bodies yield, a contact's friction is exhausted, a body
    /// loses its support). The converged steps before it have been written.
    #[error(
        "{mechanism} in {}: the load cannot exceed ≈ {} (the last converged state; the smallest \
         failed attempt went to {}); the results up to it are kept",
        details.reached.describe_step(), details.reached, details.failed_attempt()
    )]
    Collapse {
        /// What failed.
        mechanism: Mechanism,
        /// Global load factor of the last converged state.
        converged_load_factor: f64,
        /// Smallest global load factor of a failed attempt of the step.
        failed_load_factor: f64,
        /// The step's attempts and where it stopped, as for [`Error::NoConvergence`].
        details: Box<NoConvergence>,
    },
    /// Supports and contact pairs leave rigid-body motions of some bodies free (the stiffness
    /// matrix would be singular): found before anything is solved.
    #[error("{}", rigid_message(bodies))]
    RigidBodyMotion {
        /// The bodies that can move, with their free motions.
        bodies: Vec<FreeBody>,
    },
    /// The run would need more increment solves than `[solver] max_solves` allows: output
    /// increments, their sub-increments at amplitude breakpoints and after cut-backs, and
    /// every retried attempt all count. `planned`: found before solving, from the
    /// breakpoints alone.
    #[error(
        "{}: the run needs more than [solver] max_solves = {limit} increment solves ({count} {}; \
         every output increment, every sub-increment ending on an amplitude breakpoint or made by \
         a cut-back, and every retried attempt is one); raise solver.max_solves, or use fewer \
         increments or amplitude breakpoints in {}",
        at.describe_step(), if *planned { "are planned before any cut-back" } else { "were made by then" },
        at.step_key()
    )]
    TooManySolves {
        /// Where the limit was reached (for a planned count: the step that passes it).
        at: Box<LoadPoint>,
        /// Solves counted when the limit was passed.
        count: usize,
        limit: usize,
        planned: bool,
    },
    /// One level of a convergence study failed.
    #[error("{}: level {level} (size {size}) failed: {source}", case.display())]
    StudyLevel {
        case: PathBuf,
        level: usize,
        size: f64,
        #[source]
        source: Box<Error>,
    },
    /// Arc-length control has no load to scale: every load of the case is zero.
    #[error(
        "arc-length control: [steps] control = \"arc_length\" needs a non-zero load (pressure, \
         traction or force)"
    )]
    ArcLengthNoLoad,
    /// The first arc-length increment failed, even with its arc halved down to
    /// `min_arc_length`.
    #[error("arc-length control: the first increment failed: {0}")]
    ArcLengthStart(ArcFailure),
    /// The output folder holds the files of an earlier run (`files` of them, e.g.
    /// `example`): a run does not overwrite results unless told to (`--force`, `--resume`).
    #[error(
        "{}: the folder holds the results of an earlier run ({files} files, e.g. {example}); pass \
         --force to replace them, --resume to continue that run, or choose another --out",
        dir.display()
    )]
    OutputExists {
        dir: PathBuf,
        files: usize,
        example: String,
    },
    /// The run was asked to stop (Ctrl-C, SIGTERM, SIGHUP) and stopped after its last
    /// converged step, whose files are complete.
    #[error(
        "interrupted after step {step}: the converged steps' files in {} are complete{}",
        dir.display(),
        resume.as_ref().map_or(String::new(), |case| format!(
            "; continue with `asperity run {} --out {} --resume`",
            shell_quote(&case.to_string_lossy()),
            shell_quote(&dir.to_string_lossy())
        ))
    )]
    Interrupted {
        step: usize,
        dir: PathBuf,
        /// The case file, when the run keeps restart records and so can be resumed.
        resume: Option<PathBuf>,
    },
    /// A file in the output folder that the run must not overwrite or write through: one it
    /// would write but that no run manifest lists as asperity's, a symbolic link, a foreign
    /// manifest ([`crate::run::folder`]).
    #[error("{}: refusing to use the output folder: {}: {reason}", dir.display(), file.display())]
    OutputForeign {
        dir: PathBuf,
        file: PathBuf,
        reason: String,
    },
    /// A restart record cannot be used to continue a run: `reason` says why (corrupt, made
    /// by another case or program version, arc-length control).
    #[error("{}: cannot resume: {reason}", path.display())]
    Restart { path: PathBuf, reason: String },
    /// A wear jump (cycle jumping) would add more depth at a point than its stability limit
    /// allows: `depth` added over the `jump_cycles − 1` extrapolated cycles against `limit` =
    /// `jump_limit` × |p_N| (1/k_N + c_B) (see [`crate::solver::cycles`]). `contact` is the
    /// pair's name, `contact_index` its place in the case (`contact[j]`), `step_index` the `[[step]]` (0-based) when the caller knows
    /// it ([`Error::in_analysis_step`]).
    #[error(
        "contact '{contact}': a wear jump over {jump_cycles} cycles would add a depth of {depth:.4e} mm at ({x}, {y}), more than its stability limit {limit:.4e} mm (contact[{contact_index}].wear.jump_limit = {jump_limit} times the point's elastic closure |p_N| (1/k_N + l/(pi E*)), interface and bodies in series); lower {} or raise contact[{contact_index}].wear.jump_limit (the results up to the cycle before are kept)",
        step_key(*step_index, "cycles_per_jump"), x = position[0], y = position[1]
    )]
    WearJump {
        contact: String,
        contact_index: usize,
        step_index: Option<usize>,
        position: [f64; 2],
        jump_cycles: f64,
        depth: f64,
        limit: f64,
        jump_limit: f64,
    },
    /// After a wear jump over `jump_cycles` cycles, the bodies could not be brought back
    /// into equilibrium under the same loads with the worn gaps (`reason`: the solver's last
    /// word): the jump changed the contact too much at once.
    #[error(
        "the equilibrium after a wear jump over {jump_cycles} cycles did not converge ({reason}); lower {} (the results up to the cycle before are kept)",
        step_key(*step_index, "cycles_per_jump")
    )]
    JumpSettling {
        step_index: Option<usize>,
        jump_cycles: f64,
        reason: String,
    },
    /// A cycle jump over `jump_cycles` cycles after a simulated cycle in which body `body`
    /// ratcheted (its net plastic strain change `ratchet_strain` above `threshold` and
    /// `ratchet_share` of the cycle's `plastic_strain_increment`): the jump would carry its
    /// plastic state unchanged through cycles that each add to it (see
    /// `crate::solver::shakedown`). `step_index` as for [`Error::WearJump`].
    #[error(
        "body '{body}' is still ratcheting: over the last simulated cycle its plastic strain changed by {ratchet_strain:.3e} net at a point (more than {threshold:e} and {ratchet_share} of the {plastic_strain_increment:.3e} it flowed), and a jump over {jump_cycles} cycles would carry its plastic strains and backstresses unchanged through cycles that each add to them; set {} = 1 (simulate every cycle), or simulate the cycles up to shakedown in a cyclic step of their own before the step that jumps (the results up to this cycle are kept)",
        step_key(*step_index, "cycles_per_jump")
    )]
    RatchetingJump {
        body: String,
        step_index: Option<usize>,
        jump_cycles: usize,
        ratchet_strain: f64,
        plastic_strain_increment: f64,
        threshold: f64,
        ratchet_share: f64,
    },
    /// The total wear depth h_A + h_B of a point of contact `contact` (`contact[contact_index]`
    /// in the case) would exceed the pair's `max_depth`: the interface is worn through.
    #[error(
        "contact '{contact}': worn through at ({x}, {y}): the wear depth {depth:.4e} mm exceeds contact[{contact_index}].wear.max_depth = {max_depth} mm{}; the converged results before it are kept",
        step_index.map_or_else(String::new, |i| format!(" in step[{i}]")),
        x = position[0], y = position[1]
    )]
    WornThrough {
        contact: String,
        contact_index: usize,
        step_index: Option<usize>,
        position: [f64; 2],
        depth: f64,
        max_depth: f64,
    },
    /// The wear depth of the surface of body `body` at a point of contact `contact`
    /// (`contact[contact_index]`) would exceed the body's `extent` behind the surface along
    /// the normal (from its bounding box): a depth the model cannot hold, so no result.
    #[error(
        "contact '{contact}': the wear depth of the surface of body '{body}' at ({x}, {y}) would reach {depth:.4e} mm{}, more than the body's extent behind it ({extent:.4e} mm along the normal): the model cannot hold that wear; lower the wear coefficient (contact[{contact_index}].wear) or the cycles, or let contact[{contact_index}].wear.max_depth stop the run at the depth of interest (the converged results before it are kept)",
        step_index.map_or_else(String::new, |i| format!(" in step[{i}]")),
        x = position[0], y = position[1]
    )]
    WornBeyondBody {
        contact: String,
        contact_index: usize,
        step_index: Option<usize>,
        position: [f64; 2],
        body: String,
        depth: f64,
        extent: f64,
    },
    /// After a wear jump over `jump_cycles` cycles (and the re-equilibrium that follows it)
    /// the energy balance of the run is broken: the interfaces' stored energy is below
    /// −(½ `wear_work` + `tolerance` |`external_work`|), or the work imbalance beyond
    /// ± `tolerance` |`external_work`| (see `crate::solver::energy::Energy::balanced_after_jump`).
    /// `contact` (`contact[contact_index]`) is the pair whose jump used most of its
    /// stability limit.
    #[error(
        "contact '{contact}': after a wear jump over {jump_cycles} cycles the energy balance is broken: the interfaces' stored energy is {interface_energy:.4e} N mm and the work imbalance {imbalance:.4e} N mm, with a wear work of {wear_work:.4e} N mm and an external work of {external_work:.4e} N mm (allowed: stored energy down to -(wear work / 2 + {tolerance} external work), imbalance within {tolerance} external work); the jump wore more than the loads can supply: lower {} or contact[{contact_index}].wear.jump_limit (the converged results before it are kept)",
        step_key(*step_index, "cycles_per_jump")
    )]
    WearEnergy {
        contact: String,
        contact_index: usize,
        step_index: Option<usize>,
        jump_cycles: f64,
        interface_energy: f64,
        imbalance: f64,
        wear_work: f64,
        external_work: f64,
        tolerance: f64,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// Result with [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// Why an arc-length increment failed (it is retried with half the arc).
#[derive(Debug, thiserror::Error)]
pub enum ArcFailure {
    /// The tangent is unsymmetric (slipping friction): the constraint's two solves and its
    /// quadratic need a symmetric one.
    #[error("arc-length control needs a symmetric tangent (no slipping friction)")]
    UnsymmetricTangent,
    /// The linear solver failed (a tangent that is not positive definite).
    #[error(transparent)]
    Solver(Box<Error>),
    #[error("the residual is not finite")]
    NotFinite,
    /// The quadratic constraint ‖Δu + δu_r + δλ δu_f‖² = Δl² has no real root δλ.
    #[error("the arc-length constraint has no real root")]
    NoRealRoot,
    #[error("no convergence in {iterations} iterations")]
    NoConvergence { iterations: usize },
    /// The increment converged but is implausible for small-strain theory.
    #[error("{0}")]
    Implausible(Implausible),
}

impl From<Error> for ArcFailure {
    fn from(e: Error) -> Self {
        ArcFailure::Solver(Box::new(e))
    }
}

/// ` = value` of a parameter error, nothing for an error of a key without one value (a
/// count of zero, a missing column).
fn equals(value: &str) -> String {
    if value.is_empty() {
        String::new()
    } else {
        format!(" = {value}")
    }
}

/// The file a parameter error names, or `model` for one the model building found (a
/// torque on the axis, a defaulted penalty out of range), which knows no case file.
fn file_or_model(path: &Path) -> String {
    if path.as_os_str().is_empty() {
        "model".to_string()
    } else {
        path.display().to_string()
    }
}

impl Error {
    /// Shorthand for an [`Error::Mesh`].
    pub fn mesh(
        path: impl Into<PathBuf>,
        problem: MeshProblem,
        entity: Option<MeshEntity>,
        message: impl Into<String>,
    ) -> Self {
        Error::Mesh {
            path: path.into(),
            problem,
            entity,
            message: message.into(),
        }
    }

    /// The process exit status for this error, shared by every subcommand
    /// (docs/guide/troubleshooting.md, "Exit codes"): 1 a computation that did not converge (a step, arc-length control, a
    /// singular system, a run that reached `[solver] max_solves` through cut-backs) or wear
    /// the run cannot follow (a jump beyond its stability limit or breaking the energy
    /// balance, worn through, worn deeper than the body), 3 bad input (case file, mesh, model,
    /// a quantity, gmsh on the `.geo`, breakpoints that alone exceed `max_solves`), 4 reading
    /// or writing a file, 5 a limit load (the load exceeds what the model can carry: plastic
    /// collapse, friction capacity exceeded, a body losing its support; a result, not a
    /// failure of the solver). 2 is a usage error: clap's own for
    /// bad arguments, and an output folder that would be overwritten.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::NoConvergence(_)
            | Error::ArcLengthNoLoad
            | Error::ArcLengthStart(_)
            | Error::Linear(_)
            | Error::Conduction(_)
            | Error::WearJump { .. }
            | Error::WornThrough { .. }
            | Error::WornBeyondBody { .. }
            | Error::WearEnergy { .. }
            | Error::JumpSettling { .. }
            | Error::RatchetingJump { .. } => 1,
            Error::TooManySolves { planned, .. } => {
                if *planned {
                    3
                } else {
                    1
                }
            }
            Error::OutputExists { .. } | Error::OutputForeign { .. } => 2,
            // The shell's code of a process ended by SIGINT.
            Error::Interrupted { .. } => 130,
            Error::Mesh { .. }
            | Error::Case { .. }
            | Error::InvalidParameter { .. }
            | Error::Group { .. }
            | Error::Topology { .. }
            | Error::ConflictingSupports { .. }
            | Error::NegativeRadius { .. }
            | Error::AxisDisplacement { .. }
            | Error::NotOnBody { .. }
            | Error::OverlappingBodies { .. }
            | Error::DistortedElement { .. }
            | Error::NothingToSolve
            | Error::Quantity { .. }
            | Error::External(_)
            | Error::Restart { .. }
            | Error::RigidBodyMotion { .. }
            | Error::UnfixedTemperature { .. }
            | Error::ThermalModel(_)
            | Error::InsufficientMemory { .. }
            | Error::AllocationFailed { .. } => 3,
            Error::Io { .. } => 4,
            Error::Collapse { .. } => 5,
            Error::StudyLevel { source, .. } => source.exit_code(),
        }
    }

    /// The error with the 0-based `[[step]]` index it happened in, for the errors of
    /// [`crate::solver::cycles::end_cycle`] (which knows the model, not the load history);
    /// other errors are returned unchanged.
    pub fn in_analysis_step(mut self, index: usize) -> Self {
        if let Error::WearJump { step_index, .. }
        | Error::WornThrough { step_index, .. }
        | Error::WornBeyondBody { step_index, .. }
        | Error::WearEnergy { step_index, .. }
        | Error::JumpSettling { step_index, .. }
        | Error::RatchetingJump { step_index, .. } = &mut self
        {
            *step_index = Some(index);
        }
        self
    }

    /// The [`Error::Case`] of a TOML file at `path` that does not parse into what it should:
    /// the parser's message (the line, a caret under the value, what was expected), with a
    /// float it quotes in full (`1e300` as its 301 digits) written in exponent form.
    pub fn toml(path: impl Into<PathBuf>, error: &toml::de::Error) -> Self {
        Error::Case {
            path: path.into(),
            message: shorten_numbers(error.to_string().trim_end()),
        }
    }

    /// The message for a terminal, `summary.json` and `run.json`: the `Display` text with
    /// long numbers in exponent form and overlong lines cut.
    pub fn readable(&self) -> String {
        shorten_lines(&shorten_numbers(&self.to_string()))
    }

    /// A failed allocation for `what` in a solver of `unknowns` unknowns: the model's size,
    /// not the numerics (exit code 3, like [`Error::InsufficientMemory`]).
    pub fn allocation_failed(what: &str, unknowns: usize) -> Self {
        Error::AllocationFailed {
            what: what.into(),
            unknowns,
        }
    }

    /// Shorthand for an [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// `message` with every number longer than [`LONG_NUMBER`] characters written as `{:e}`:
/// `f64`'s `Display` (and serde's quote of a float) writes 1e300 as its 301 digits and
/// 1e-300 as 302.
pub(crate) fn shorten_numbers(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        let (head, tail) = rest.split_at(start);
        out.push_str(head);
        let end = tail
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(tail.len());
        let number = &tail[..end];
        // Not a part of a name or path (`run_000…1.toml`, `a-000…1`); a minus sign is.
        let word = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || "_/".contains(c));
        let mut before = head.chars().rev();
        let previous = match before.next() {
            Some('-') => before.next().filter(|c| c.is_alphanumeric()),
            other => other,
        };
        let alone = !word(previous) && !word(tail[end..].chars().next());
        match number.parse::<f64>() {
            Ok(value) if alone && number.len() > LONG_NUMBER => {
                out.push_str(&format!("{value:e}"));
            }
            _ => out.push_str(number),
        }
        rest = &tail[end..];
    }
    out.push_str(rest);
    out
}

/// Longest number [`shorten_numbers`] leaves as it is.
const LONG_NUMBER: usize = 24;

/// `message` with every line longer than [`LONG_LINE`] characters cut there (an echoed
/// 5 000-value array or a 2 MB line of a case file would otherwise fill the terminal).
fn shorten_lines(message: &str) -> String {
    let lines: Vec<String> = message
        .split('\n')
        .map(|line| match line.char_indices().nth(LONG_LINE) {
            Some((cut, _)) => format!(
                "{}… ({} more characters)",
                &line[..cut],
                line[cut..].chars().count()
            ),
            None => line.to_string(),
        })
        .collect();
    lines.join("\n")
}

/// Longest line of a message [`Error::readable`] leaves whole: above the longest messages
/// asperity composes itself (the memory check's, with its parts and the Krylov hint, about
/// 640 characters), far below an echoed input.
const LONG_LINE: usize = 1000;

/// What is wrong with a mesh file ([`Error::Mesh`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshProblem {
    /// The file (or the `.geo` script) does not exist.
    NotFound,
    /// The file is empty.
    Empty,
    /// Not an MSH file, or its `$MeshFormat` header is unusable.
    Header,
    /// An MSH version other than 4.1.
    Version,
    /// The file is cut short.
    Truncated,
    /// Parametric node coordinates.
    Parametric,
    /// Corrupt or inconsistent content (parser error, section contents that disagree).
    Corrupt,
    /// The MSH parser (mshio) panicked on the file.
    ParserPanic,
    /// A section the reader needs is missing.
    MissingSection,
    /// The `$Nodes` or `$Elements` section is empty.
    EmptySection,
    /// More nodes than node indices.
    TooManyNodes,
    /// A node coordinate is not finite.
    NonFinite,
    /// A node lies off the x-y plane.
    NotPlanar,
    /// A node tag appears twice.
    DuplicateNode,
    /// An element references a node that is not in the file.
    UnknownNode,
    /// No quadratic surface cells.
    NoCells,
    /// A cell whose corners enclose no area.
    Degenerate,
    /// First-order elements: the mesh must be quadratic.
    FirstOrder,
    /// An element type the solver does not use.
    UnsupportedElement,
    /// The `$PhysicalNames` section is malformed.
    PhysicalNames,
    /// A header count (entities, blocks, nodes, elements) or tag range disagrees with what
    /// follows it.
    CountMismatch,
    /// An entity is declared twice in `$Entities`.
    DuplicateEntity,
    /// A node or element block belongs to an entity that `$Entities` does not declare.
    UndeclaredEntity,
    /// An element block's dimension differs from its element type's.
    MixedDimension,
    /// An element tag appears twice.
    DuplicateElement,
    /// The file, or the mesh a `.geo` script would make, is beyond the size limit.
    TooLarge,
}

/// Where in a mesh file an [`Error::Mesh`] (or [`Error::NotOnBody`]) is: a node or an
/// element by its gmsh tag, or a section.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshEntity {
    Node(u64),
    Element(u64),
    /// A section by its tag, e.g. `"$Nodes"`, `"$MeshFormat"`.
    Section(&'static str),
}

/// The kind of physical group a case entry needs ([`Error::Group`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GroupKind {
    Surface,
    Curve,
    Point,
    /// A curve or a point (supports, loads).
    CurveOrPoint,
}

impl fmt::Display for GroupKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            GroupKind::Surface => "physical surface",
            GroupKind::Curve => "physical curve",
            GroupKind::Point => "physical point",
            GroupKind::CurveOrPoint => "physical curve or point",
        })
    }
}

/// What is wrong with a physical group ([`Error::Group`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GroupProblem {
    /// No group of that name and kind; `available` lists the alternatives, e.g.
    /// "surfaces: lower, upper".
    Missing { available: String },
    /// The name is used by a physical curve and a physical point.
    Ambiguous,
    /// The group is a `found`, but `purpose` ("a force", "a pressure or traction") needs the
    /// expected kind.
    WrongKind {
        found: GroupKind,
        purpose: &'static str,
    },
    /// The group has no elements.
    Empty,
}

fn group_message(
    mesh: &std::path::Path,
    name: &str,
    expected: GroupKind,
    problem: &GroupProblem,
) -> String {
    let mesh = mesh.display();
    match problem {
        GroupProblem::Missing { available } => {
            format!("no {expected} of that name in {mesh} ({available})")
        }
        GroupProblem::Ambiguous => format!(
            "the name is used by a physical curve and a physical point in {mesh}; rename one"
        ),
        GroupProblem::WrongKind { found, purpose } => {
            format!("{purpose} needs a {expected} group, and '{name}' is a {found}")
        }
        GroupProblem::Empty => format!(
            "the {expected} has no elements in {mesh} (is it meshed, and are its elements saved?)"
        ),
    }
}

fn off_body_message(entity: &MeshEntity, position: &[f64; 2]) -> String {
    match entity {
        MeshEntity::Element(tag) => format!(
            "boundary element {tag} (from {position:?}) is not an edge of any body's element"
        ),
        MeshEntity::Node(tag) => format!("node {tag} at {position:?} belongs to no body"),
        MeshEntity::Section(s) => format!("{s} belongs to no body"),
    }
}

/// Why the faces of a contact pair cannot be joined ([`Error::Topology`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TopologyProblem {
    /// The mesh itself is inconsistent (node references out of range, missing node tags).
    InvalidMesh,
    /// The case defines no bodies.
    NoBodies,
    /// Side A and side B are the same curve.
    SameCurve,
    /// The two faces share nodes (a conforming mesh: use the Split recipe).
    SharedNodes,
    /// A line of a face is the edge of no body element.
    NoOwner,
    /// A line of a face is shared by two elements: the curve runs inside the bodies.
    Interior,
    /// The two faces are discretised differently.
    Mismatch,
    /// Both bodies lie on the same side of the contact.
    Overlap,
    /// The mesh has no cell of positive size to scale the tolerance.
    NoScale,
    /// A node has no partner on the other face.
    Unpaired,
    /// A node has several candidate partners, or two nodes the same one.
    Ambiguous,
    /// The faces of an Ordered pair have different node counts.
    CountMismatch,
    /// A curve branches (more than two lines meet at a node).
    Branch,
    /// A curve is a closed loop.
    Closed,
    /// A curve is not one connected chain.
    Disconnected,
    /// A body of a Split pair is not one of the case's bodies.
    BodyNotInCase,
    /// The two bodies of a Split pair are the same surface.
    SameBody,
    /// The two bodies of a Split pair share a surface entity.
    SharedEntity,
    /// The curve of a Split pair is not between the two bodies.
    NotBetweenBodies,
    /// The curve of a Split pair was already split by another pair.
    AlreadySplit,
    /// Splitting would exceed the node numbering.
    TooManyNodes,
    /// The pair has no interface elements.
    NoElements,
    /// A face of the pair is a face of another pair too.
    SharedFace,
}

/// A constitutive parameter out of its range, as a material or interface-law constructor
/// reports it: `name` is the parameter's key in the case file (`E`, `friction`). The model
/// turns it into an [`Error::InvalidParameter`] with the full key path.
#[derive(Clone, Debug, PartialEq)]
pub struct ParameterError {
    pub name: &'static str,
    pub value: f64,
    /// Why the value is wrong, e.g. "Young's modulus must be positive".
    pub reason: String,
}

impl ParameterError {
    /// `name = value` is wrong because of `reason`.
    pub fn new(name: &'static str, value: f64, reason: impl Into<String>) -> Self {
        Self {
            name,
            value,
            reason: reason.into(),
        }
    }
}

impl fmt::Display for ParameterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {}: {}", self.name, self.value, self.reason)
    }
}

impl std::error::Error for ParameterError {}

/// A load step that could not be made to converge: where it stopped (in the case's own
/// `[[step]]` terms), every attempt, and what the last attempt shows about why.
#[derive(Clone, Debug, Default)]
pub struct NoConvergence {
    /// 1-based output increment (over all steps and simulated cycles) being solved.
    pub step: usize,
    /// Global load factor at the end of that increment.
    pub load_factor: f64,
    /// Pseudo-time of the last converged state (output increment j ends at time j).
    pub converged_time: f64,
    /// Global load factor of the last converged state.
    pub converged_load_factor: f64,
    /// Where the last converged state lies in the load history.
    pub reached: LoadPoint,
    /// Where the increment was to end.
    pub target: LoadPoint,
    /// Cut-backs made in this step.
    pub cutbacks: usize,
    /// Every attempt of the step, in order.
    pub attempts: Vec<Attempt>,
    /// The free node carrying the largest out-of-balance force in the last attempt.
    pub largest_residual: Option<ResidualAt>,
    /// Interface integration points whose contact status (open, stick, slip) in the last
    /// attempt differs from the last converged state.
    pub status_changes: usize,
    /// The mechanism the contact states of the last attempt show (friction capacity
    /// exhausted, a body that lost its support), if one does.
    pub mechanism: Option<Mechanism>,
    /// The input that drove the last attempt's forces, stresses or displacements beyond the
    /// range of double precision, if one did (the mechanism is not looked for then).
    pub out_of_range: Option<String>,
    /// What else the run showed (the secant stiffness of the last converged increment).
    pub note: Option<String>,
}

impl NoConvergence {
    /// Where the smallest failed attempt was to end (the last one: each halves the last).
    pub fn failed_attempt(&self) -> &LoadPoint {
        self.attempts.last().map_or(&self.target, |a| &a.at)
    }
}

/// A point of the case's load history in the user's terms: the `[[step]]` by name, the
/// fraction of it reached, and the multipliers of the loads and supports with their own
/// history; the load factor for the `[steps]` form.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadPoint {
    /// The `[[step]]`'s name and 0-based index; `None` for the `[steps]` form.
    pub step: Option<(String, usize)>,
    /// 1-based output increment containing the point (the `[steps]` load step).
    pub increment: usize,
    /// The simulated cycle of a cyclic step and the step's simulated cycles.
    pub cycle: Option<(usize, usize)>,
    /// Fraction of the step (of the cycle, in a cyclic step) reached, in [0, 1].
    pub step_time: f64,
    /// The global load factor: the `[steps]` factor (total analysis time with `[[step]]`).
    pub load_factor: f64,
    /// The multipliers of the loads and supports with their own history, by their
    /// `history.csv` column (`factor_load_<name>`, `factor_support_<name>`).
    pub multipliers: Vec<(String, f64)>,
}

impl LoadPoint {
    /// "step 'press' (`step[0]`)", or "load step 3" of the `[steps]` form.
    pub fn step_name(&self) -> String {
        match &self.step {
            Some((name, i)) => format!("step '{name}' (step[{i}])"),
            None => format!("load step {}", self.increment),
        }
    }

    /// The step and, in a cyclic step, the cycle: "step 'service' (`step[1]`), cycle 3 of 21".
    pub fn describe_step(&self) -> String {
        match self.cycle {
            Some((c, n)) => format!("{}, simulated cycle {c} of {n}", self.step_name()),
            None => self.step_name(),
        }
    }

    /// The case keys that set the step's increments: `step[i]` or `[steps]`.
    pub fn step_key(&self) -> String {
        match &self.step {
            Some((_, i)) => format!("step[{i}]"),
            None => "[steps]".into(),
        }
    }
}

impl fmt::Display for LoadPoint {
    /// "62.5 % of step 'shear' (factor_load_shear = 0.625)", or "load factor 0.95".
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.step.is_none() {
            return write!(f, "load factor {:.6}", self.load_factor);
        }
        let percent = 100.0 * self.step_time;
        match self.cycle {
            Some((c, _)) => write!(f, "{percent:.4} % of cycle {c} of {}", self.step_name())?,
            None => write!(f, "{percent:.4} % of {}", self.step_name())?,
        }
        if !self.multipliers.is_empty() {
            let list: Vec<String> = self
                .multipliers
                .iter()
                .map(|(column, v)| format!("{column} = {v:.6}"))
                .collect();
            write!(f, " ({})", list.join(", "))?;
        }
        Ok(())
    }
}

/// How a step's load exceeded what the model can carry ([`Error::Collapse`]), or what the
/// contact states of a failed attempt show ([`NoConvergence::mechanism`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Mechanism {
    /// The plastic bodies cannot carry the load: `indicator` says what showed it (the secant
    /// stiffness, a tangent that lost positive definiteness, implausible increments).
    PlasticCollapse { indicator: String },
    /// Friction is exhausted: the closed points of contacts `pairs` that hold `bodies` all
    /// slip, and nothing else holds those bodies along the contact (Buczkowski & Kleiber
    /// (1994), Eq. 11: F = 0 at every point; with slip-hardening friction, μ has reached
    /// what the slip gives).
    FrictionCapacity {
        pairs: Vec<String>,
        bodies: Vec<FreeBody>,
    },
    /// `bodies` are no longer held: the contacts `open_pairs` that held them opened.
    LostSupport {
        open_pairs: Vec<String>,
        bodies: Vec<FreeBody>,
    },
}

impl fmt::Display for Mechanism {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Mechanism::PlasticCollapse { indicator } => {
                write!(f, "plastic collapse ({indicator})")
            }
            Mechanism::FrictionCapacity { pairs, bodies } => write!(
                f,
                "friction capacity exceeded at contact {}: every closed point that holds the \
                 sliding body slips, so friction cannot carry the tangential load ({}; raise the \
                 friction or the normal load, or support the sliding body)",
                quoted(pairs),
                free_list(bodies)
            ),
            Mechanism::LostSupport { open_pairs, bodies } => {
                write!(f, "loss of support: ")?;
                if !open_pairs.is_empty() {
                    write!(f, "contact {} opened and ", quoted(open_pairs))?;
                }
                write!(
                    f,
                    "nothing else holds the bodies against rigid-body motion ({})",
                    free_list(bodies)
                )
            }
        }
    }
}

/// Single-quotes `s` for a POSIX shell (a `'` becomes `'\''`): nothing in it is expanded,
/// for the commands the program writes (job files) or shows to be pasted.
pub fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// 'a', 'b'
fn quoted(names: &[String]) -> String {
    let list: Vec<String> = names.iter().map(|n| format!("'{n}'")).collect();
    list.join(", ")
}

/// "body 'a' is free to move in x; body 'b' …"
fn free_list(bodies: &[FreeBody]) -> String {
    let list: Vec<String> = bodies.iter().map(ToString::to_string).collect();
    list.join("; ")
}

/// A body that supports and contacts leave free to move as a rigid body, and how.
#[derive(Clone, Debug, PartialEq)]
pub struct FreeBody {
    pub body: String,
    /// Unit directions of its free translations: none, one, or two (any direction).
    pub translations: Vec<[f64; 2]>,
    /// Whether it can rotate (plane models).
    pub rotates: bool,
    /// Whether it can turn about the axis (axisymmetric models with twist).
    pub twists: bool,
    /// The one point it can rotate about, when it can rotate but not translate.
    pub centre: Option<[f64; 2]>,
}

impl FreeBody {
    /// "in x", "in x and y", "along (0.6, 0.8)".
    fn translation(&self) -> Option<String> {
        match self.translations.as_slice() {
            [] => None,
            [d] if d[1].abs() <= 1e-6 => Some("in x".into()),
            [d] if d[0].abs() <= 1e-6 => Some("in y".into()),
            [d] => Some(format!("along ({:.4}, {:.4})", d[0], d[1])),
            _ => Some("in x and y".into()),
        }
    }

    /// The support that would hold the body.
    pub fn suggestion(&self) -> String {
        let b = &self.body;
        let components = match self.translations.as_slice() {
            [] => None,
            [d] if d[0].abs() >= d[1].abs() => Some("ux"),
            [_] => Some("uy"),
            _ => Some("ux and uy"),
        };
        let twist = format!(
            "hold utheta or rotation on a curve or point of '{b}' off the axis (or apply no \
             torque that nothing resists)"
        );
        match (components, self.rotates) {
            _ if self.twists && components.is_none() => twist,
            (Some(c), false) if self.twists => {
                format!("hold {c} on a curve or point of '{b}', and {twist}")
            }
            (Some(c), false) => format!("hold {c} on a curve or point of '{b}'"),
            (Some(c), true) => format!(
                "hold {c} on a curve of '{b}' (or at two points of it, a point holding only \
                 one direction together with a curve not parallel to that direction)"
            ),
            (None, _) => format!(
                "hold a second point of '{b}', or a curve not parallel to the direction held \
                 (a support at a single point, or one holding a curve only along itself, does \
                 not stop rotation)"
            ),
        }
    }
}

impl fmt::Display for FreeBody {
    /// "body 'b' is free to move in x and to rotate".
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "body '{}' is free to ", self.body)?;
        if self.twists {
            return match self.translation() {
                Some(t) => write!(f, "move {t} and to turn about the axis"),
                None => write!(f, "turn about the axis"),
            };
        }
        match (self.translation(), self.rotates, self.centre) {
            (Some(t), false, _) => write!(f, "move {t}"),
            (Some(t), true, _) => write!(f, "move {t} and to rotate"),
            (None, true, Some(c)) => write!(f, "rotate about ({:.6}, {:.6})", c[0], c[1]),
            (None, _, _) => write!(f, "rotate"),
        }
    }
}

/// The message of [`Error::RigidBodyMotion`].
fn rigid_message(bodies: &[FreeBody]) -> String {
    let fixes: Vec<String> = bodies.iter().map(FreeBody::suggestion).collect();
    format!(
        "model: the supports leave rigid-body motion free: {}. Add supports: {} (contacts \
         count as defined: a contact holds its bodies against each other normal to it, and \
         along it only with friction; a frictionless contact does not stop sliding)",
        free_list(bodies),
        fixes.join("; ")
    )
}

/// Where the out-of-balance force of a failed attempt is largest.
#[derive(Clone, Debug, PartialEq)]
pub struct ResidualAt {
    /// Gmsh node tag.
    pub node: u64,
    pub position: [f64; 2],
    /// The body (physical surface) the node belongs to.
    pub body: Option<String>,
    /// Out-of-balance force (f_ext − f_int) over the node's free components, in N: x and y
    /// (r and z), and θ with twist (0 without).
    pub force: [f64; 3],
}

/// One attempted (sub-)increment of a step that failed.
#[derive(Clone, Debug)]
pub struct Attempt {
    /// Pseudo-time the increment tried to reach.
    pub time: f64,
    /// Global load factor at that time.
    pub load_factor: f64,
    /// Where that is in the load history.
    pub at: LoadPoint,
    /// Newton iterations made.
    pub iterations: usize,
    /// Relative residual before each solve and after the last one.
    pub residuals: Vec<f64>,
    /// Why it stopped when it was not for the iteration limit.
    pub failure: Option<AttemptFailure>,
}

/// Why an attempt failed other than by running out of iterations.
#[derive(Clone, Debug, PartialEq)]
pub enum AttemptFailure {
    /// The linear solver could not factor the tangent (not positive definite, singular).
    Tangent(String),
    /// It converged, but to an increment implausible for small-strain theory.
    Implausible(Implausible),
    /// Any other error of the solve.
    Other(String),
}

impl fmt::Display for AttemptFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AttemptFailure::Tangent(m) => write!(f, "linear solver: {m}"),
            AttemptFailure::Implausible(i) => write!(f, "{i}"),
            AttemptFailure::Other(m) => f.write_str(m),
        }
    }
}

/// A converged increment that small-strain theory cannot describe (a collapse mechanism, or a
/// locked mesh "carrying" a load above its limit load).
#[derive(Clone, Debug, PartialEq)]
pub enum Implausible {
    /// Node `node` (gmsh tag) moved by `increment` mm, more than `fraction`
    /// (`[solver] max_displacement_increment`) of the model size `size`.
    Displacement {
        node: u64,
        increment: f64,
        fraction: f64,
        size: f64,
    },
    /// An equivalent strain increment `increment` above `limit` (`[solver]
    /// max_strain_increment`).
    Strain { increment: f64, limit: f64 },
}

impl fmt::Display for Implausible {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Implausible::Displacement {
                node,
                increment,
                fraction,
                size,
            } => write!(
                f,
                "implausible increment: node {node} moves by {increment:.3e} mm in one \
                 increment, more than {fraction} of the model size {size:.3e} mm ([solver] \
                 max_displacement_increment)"
            )?,
            Implausible::Strain { increment, limit } => write!(
                f,
                "implausible increment: an equivalent strain increment of {increment:.3e}, more \
                 than {limit} ([solver] max_strain_increment)"
            )?,
        }
        f.write_str(
            "; small-strain theory does not hold there (a collapse mechanism, or a locked mesh)",
        )
    }
}

/// Attempts listed in full at each end of a [`NoConvergence`] message; the ones between are
/// summarised in one line.
const SHOWN_ATTEMPTS: usize = 3;
/// Residuals listed at each end of an attempt's residual history.
const SHOWN_RESIDUALS: usize = 4;

impl fmt::Display for NoConvergence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} did not converge after {} cut-backs in the step: it reached {} (the last converged state), \
             on the way to {}",
            self.reached.describe_step(),
            self.cutbacks,
            self.reached,
            self.target
        )?;
        if let Some(input) = &self.out_of_range {
            write!(
                f,
                ".\n  Likely cause: values beyond the range of double precision (1e150): {input}"
            )?;
        }
        if let Some(mechanism) = &self.mechanism {
            write!(f, ".\n  Likely cause: {mechanism}")?;
        }
        if let Some(note) = &self.note {
            write!(f, ".\n  {note}")?;
        }
        if let Some(r) = &self.largest_residual {
            write!(
                f,
                ".\n  Largest out-of-balance force: ({:.3e}, {:.3e}{}) N at node {} ({:?}) of body '{}'",
                r.force[0],
                r.force[1],
                if r.force[2] == 0.0 {
                    String::new()
                } else {
                    format!(", θ {:.3e}", r.force[2])
                },
                r.node,
                r.position,
                r.body.as_deref().unwrap_or("?")
            )?;
        }
        if self.status_changes > 0 {
            write!(
                f,
                ".\n  {} interface points changed contact status against the last converged state",
                self.status_changes
            )?;
        }
        write!(f, ".\n  Attempts ({}):", self.attempts.len())?;
        let n = self.attempts.len();
        for (i, a) in self.attempts.iter().enumerate() {
            if n > 2 * SHOWN_ATTEMPTS && i == SHOWN_ATTEMPTS {
                let hidden = &self.attempts[SHOWN_ATTEMPTS..n - SHOWN_ATTEMPTS];
                let smallest = hidden
                    .iter()
                    .min_by(|a, b| a.time.total_cmp(&b.time))
                    .map(|a| &a.at);
                if let Some(smallest) = smallest {
                    write!(
                        f,
                        "\n  … {} more attempts, down to {smallest} …",
                        hidden.len()
                    )?;
                }
            }
            if n > 2 * SHOWN_ATTEMPTS && (SHOWN_ATTEMPTS..n - SHOWN_ATTEMPTS).contains(&i) {
                continue;
            }
            write!(f, "\n  to {}: ", a.at)?;
            match &a.failure {
                Some(failure) => write!(f, "{failure}")?,
                None => write!(f, "relative residuals {}", residual_history(&a.residuals))?,
            }
        }
        Ok(())
    }
}

/// The residual history of an attempt, its middle elided when it is long.
fn residual_history(residuals: &[f64]) -> String {
    let text = |r: &[f64]| {
        r.iter()
            .map(|r| format!("{r:.2e}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let n = residuals.len();
    if n <= 2 * SHOWN_RESIDUALS {
        text(residuals)
    } else {
        format!(
            "{}, … ({} more), {}",
            text(&residuals[..SHOWN_RESIDUALS]),
            n - 2 * SHOWN_RESIDUALS,
            text(&residuals[n - SHOWN_RESIDUALS..])
        )
    }
}

/// The case key `step[i].<key>` of a step, or a description when the step is unknown.
fn step_key(index: Option<usize>, key: &str) -> String {
    match index {
        Some(i) => format!("step[{i}].{key}"),
        None => format!("the step's {key}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The longest message the solver composes, the memory check's with every part, reaches
    /// the terminal and `summary.json` whole.
    #[test]
    fn the_memory_checks_message_is_not_cut() {
        let error = Error::InsufficientMemory {
            what: "the sparse factor of the bodies' stiffness 12.34 GB, the dense system of the \
                   123456 interface unknowns 123.45 GB; `[solver] linear_solver = \"krylov\"` \
                   needs no dense interface system"
                .into(),
            unknowns: 12_345_678,
            needed: 123_456_789_012,
            available: 12_345_678_901,
            limit: Limit::AddressSpace,
        };
        let text = error.to_string();
        assert!(text.chars().count() > 400, "{text}");
        assert_eq!(error.readable(), text);
    }

    #[test]
    fn long_numbers_are_written_in_exponent_form_but_names_are_left_alone() {
        let huge = format!("{}", 1e300);
        let tiny = format!("{}", -1e-300);
        let message = format!("a = {huge}, b = {tiny}: run_{huge}.toml, x-{huge} 12.5 0.001");
        assert_eq!(
            shorten_numbers(&message),
            format!("a = 1e300, b = -1e-300: run_{huge}.toml, x-{huge} 12.5 0.001")
        );
        assert_eq!(
            shorten_numbers("floating point `100000000000000000000000000.0`"),
            "floating point `1e26`"
        );
    }

    #[test]
    fn overlong_lines_are_cut_with_the_count_of_what_is_left_out() {
        let long = "x".repeat(LONG_LINE + 10);
        let cut = shorten_lines(&format!("first\n{long}\nlast"));
        assert_eq!(
            cut,
            format!("first\n{}… (10 more characters)\nlast", &long[..LONG_LINE])
        );
        assert_eq!(shorten_lines("ünïcode"), "ünïcode");
    }
}
