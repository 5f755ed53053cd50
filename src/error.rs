//! The crate's error type. Every error names the file or entity it concerns and what is wrong,
//! so that a user can fix the input without reading the source; the variants carry those
//! facts as data, so that callers (and tests) can act on them without parsing messages.

use std::fmt;
use std::path::PathBuf;

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
    #[error("{}: {key} = {value}: {reason}", path.display())]
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
    /// (`component` 0 = x, 1 = y) of node `node` (gmsh tag).
    #[error(
        "model: supports '{first}' and '{second}' prescribe different {} displacement histories ({} and {} \
         at factor 1) at node {node} ({position:?})",
        ["x", "y"][*component], values[0], values[1]
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
    /// A support prescribes a non-zero radial displacement on the axis.
    #[error(
        "model: node {node} on the axis has a prescribed radial displacement {value}; it must be 0"
    )]
    AxisDisplacement { node: u64, value: f64 },
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
    /// A load step did not converge, even after cutting it back.
    #[error("{0}")]
    NoConvergence(Box<NoConvergence>),
    /// A step could not be completed because the structure collapsed: the load
    /// exceeds what it can carry. The converged steps before it have been written.
    #[error(
        "plastic collapse in step {step}: the load factor cannot exceed ≈ {converged_load_factor:.6} \
         (between the last converged λ_c = {converged_load_factor:.6} and the smallest failed \
         λ_f = {failed_load_factor:.6}; {indicator}); last converged load factor λ_c = \
         {converged_load_factor:.6}"
    )]
    Collapse {
        /// 1-based step that could not be completed.
        step: usize,
        /// Global load factor of the last converged state.
        converged_load_factor: f64,
        /// Smallest global load factor of a failed attempt of the step.
        failed_load_factor: f64,
        /// What showed the collapse (the stiffness ratio, a tangent that lost positive
        /// definiteness, implausible increments).
        indicator: String,
        /// The step's attempts, as for [`Error::NoConvergence`].
        details: Box<NoConvergence>,
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
    /// `jump_limit` × |p_N| (1/k_N + c_B) (see [`crate::solver::cycles`]). `contact` is the pair's name, `contact_index` its place in
    /// the case (`contact[j]`), `step_index` the `[[step]]` (0-based) when the caller knows
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
    /// The increment converged but is implausible for small-strain theory (the reason).
    #[error("{0}")]
    Implausible(String),
}

impl From<Error> for ArcFailure {
    fn from(e: Error) -> Self {
        ArcFailure::Solver(Box::new(e))
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

    /// The process exit status for this error, shared by every subcommand (README "Exit
    /// codes"): 1 a computation that did not converge (a step, arc-length control, a
    /// singular system), 3 bad input (case file, mesh, model, a quantity, gmsh on the `.geo`),
    /// 4 reading or writing a file, 5 plastic collapse (the load exceeds what the structure
    /// carries: a result, not a failure of the solver). 2 is a usage error: clap's own for
    /// bad arguments, and an output folder that would be overwritten.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::NoConvergence(_)
            | Error::ArcLengthNoLoad
            | Error::ArcLengthStart(_)
            | Error::Linear(_)
            | Error::WearJump { .. }
            | Error::WornThrough { .. }
            | Error::JumpSettling { .. } => 1,
            Error::OutputExists { .. } | Error::OutputForeign { .. } => 2,
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
            | Error::Restart { .. } => 3,
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
        | Error::JumpSettling { step_index, .. } = &mut self
        {
            *step_index = Some(index);
        }
        self
    }

    /// Shorthand for an [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

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

/// A load step that could not be made to converge: where it stopped, every attempt, and
/// what the last attempt shows about why.
#[derive(Clone, Debug, Default)]
pub struct NoConvergence {
    /// 1-based step number.
    pub step: usize,
    /// Load factor at the end of the step.
    pub load_factor: f64,
    /// Pseudo-time of the last converged state (step j ends at time j).
    pub converged_time: f64,
    /// Global load factor of the last converged state.
    pub converged_load_factor: f64,
    /// Cut-backs made in this step.
    pub cutbacks: usize,
    /// Every attempt of the step, in order.
    pub attempts: Vec<Attempt>,
    /// The free node carrying the largest out-of-balance force in the last attempt.
    pub largest_residual: Option<ResidualAt>,
    /// Interface integration points whose contact status (open, stick, slip) in the last
    /// attempt differs from the last converged state.
    pub status_changes: usize,
    /// A physical reading of the failure where one is recognisable (friction capacity
    /// exceeded, a body without support).
    pub hint: Option<String>,
}

/// Where the out-of-balance force of a failed attempt is largest.
#[derive(Clone, Debug, PartialEq)]
pub struct ResidualAt {
    /// Gmsh node tag.
    pub node: u64,
    pub position: [f64; 2],
    /// The body (physical surface) the node belongs to.
    pub body: Option<String>,
    /// Out-of-balance force (f_ext − f_int) over the node's free components, in N.
    pub force: [f64; 2],
}

/// One attempted (sub-)increment of a step that failed.
#[derive(Clone, Debug)]
pub struct Attempt {
    /// Pseudo-time the increment tried to reach.
    pub time: f64,
    /// Global load factor at that time.
    pub load_factor: f64,
    /// Newton iterations made.
    pub iterations: usize,
    /// Relative residual before each solve and after the last one.
    pub residuals: Vec<f64>,
    /// Why it stopped when it was not for the iteration limit (e.g. a singular tangent).
    pub reason: Option<String>,
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
            "step {} (load factor {}) did not converge after {} cut-backs; the last converged state is at time \
             {:.6} (load factor {:.6})",
            self.step,
            self.load_factor,
            self.cutbacks,
            self.converged_time,
            self.converged_load_factor
        )?;
        if let Some(hint) = &self.hint {
            write!(f, ".\n  Likely cause: {hint}")?;
        }
        if let Some(r) = &self.largest_residual {
            write!(
                f,
                ".\n  Largest out-of-balance force: ({:.3e}, {:.3e}) N at node {} ({:?}) of body '{}'",
                r.force[0],
                r.force[1],
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
                let smallest = hidden.iter().map(|a| a.time).fold(f64::INFINITY, f64::min);
                write!(
                    f,
                    "\n  … {} more attempts, down to time {smallest:.6} …",
                    hidden.len()
                )?;
            }
            if n > 2 * SHOWN_ATTEMPTS && (SHOWN_ATTEMPTS..n - SHOWN_ATTEMPTS).contains(&i) {
                continue;
            }
            write!(
                f,
                "\n  at time {:.6} (load factor {:.6}): ",
                a.time, a.load_factor
            )?;
            match &a.reason {
                Some(reason) => write!(f, "{reason}")?,
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
