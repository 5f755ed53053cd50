//! The case file (TOML) as plain data: what to mesh or read, the analysis type, a material per
//! body, the supports, the loads, the contact pairs, the load steps, the solver settings, the
//! output and the quantities of a study. Reading a case checks it once: unknown keys are
//! errors that name the key, and values out of range are [`Error::InvalidParameter`]s with
//! their key path. Nothing here builds or computes anything: [`crate::model::ModelSpec`]
//! turns a case into materials, laws and loads. Relative paths inside a case file are
//! relative to the case file's folder.
//!
//! The full reference, with an example, is in the README ("Case file reference").

use std::collections::BTreeMap;
use std::fmt::Display;
use std::path::{Path, PathBuf};

use schemars::JsonSchema;
use serde::Deserialize;

use crate::{Error, Result};

mod check;
pub mod history;
mod law;
mod names;
mod quantity;
mod steps;
pub mod wear;

pub use check::{MAX_CUTBACKS, MAX_ITERATIONS, MAX_STEPS, MAX_TOLERANCE};
pub use law::LawSpec;
pub use names::{MAX_NAME_LEN, check_name};
pub use quantity::{Component, QuantityKind, QuantitySpec, Statistic, parse_quantity};
pub use steps::{AmplitudeSpec, InlineAmplitude, Leg, Motion, Role, StepSpec, Target};

/// A parsed case file.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Case {
    pub mesh: MeshSource,
    pub analysis: AnalysisSpec,
    /// One entry per body (physical surface).
    #[serde(rename = "body")]
    pub bodies: Vec<BodySpec>,
    #[serde(default, rename = "support")]
    pub supports: Vec<SupportSpec>,
    #[serde(default, rename = "load")]
    pub loads: Vec<LoadSpec>,
    /// Contact pairs carried by interface elements.
    #[serde(default, rename = "contact")]
    pub contacts: Vec<ContactSpec>,
    /// The simple load schedule (exclusive with `[[step]]`).
    #[serde(default)]
    pub steps: Steps,
    /// Analysis steps in sequence (`[[step]]`, exclusive with `[steps]`).
    #[serde(default, rename = "step")]
    pub analysis_steps: Vec<StepSpec>,
    /// Named amplitudes the steps refer to (`[[amplitude]]`).
    #[serde(default, rename = "amplitude")]
    pub amplitudes: Vec<AmplitudeSpec>,
    #[serde(default)]
    pub solver: SolverSpec,
    #[serde(default)]
    pub output: OutputSpec,
    /// Quantities of interest for `asperity converge` (ignored by `asperity run`).
    #[serde(default, rename = "quantity")]
    pub quantities: Vec<QuantitySpec>,
    /// Quantities written to `history.csv` at every step (`[[history]]`, [`history`]).
    #[serde(default, rename = "history")]
    pub history: Vec<QuantitySpec>,
    /// Folder of the case file; relative paths are resolved against it.
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// The case file itself (for messages).
    #[serde(skip)]
    pub path: PathBuf,
}

/// Where the mesh comes from: an existing `.msh` file, or a `.geo` script meshed by gmsh.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MeshSource {
    /// An MSH 4.1 file.
    pub file: Option<PathBuf>,
    /// A gmsh `.geo` script, meshed with `gmsh -2 -order 2` at run time.
    pub geo: Option<PathBuf>,
    /// Mesh size factor passed to gmsh (`-clscale`); smaller is finer.
    #[serde(default = "one")]
    pub size: f64,
    /// Values for the script's `DefineConstant` parameters (`-setnumber NAME VALUE`).
    #[serde(default)]
    pub parameters: BTreeMap<String, f64>,
}

fn one() -> f64 {
    1.0
}

/// The 2D idealisation (`[analysis]`).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum AnalysisSpec {
    /// σ_zz = 0. `thickness` in mm.
    PlaneStress { thickness: f64 },
    /// ε_zz = 0. `thickness` in mm (default 1).
    PlaneStrain {
        #[serde(default = "one")]
        thickness: f64,
    },
    /// Axisymmetric about the y axis: x = r, y = z.
    Axisymmetric,
}

impl AnalysisSpec {
    /// Whether this is an axisymmetric analysis.
    pub fn is_axisymmetric(&self) -> bool {
        matches!(self, AnalysisSpec::Axisymmetric)
    }
}

/// A body: a physical surface and its material.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name of the physical surface.
    pub group: String,
    pub material: MaterialSpec,
    /// Element formulation: `"full"` or `"bbar"` (locking-free). Default: B-bar for plastic
    /// bodies and for ν ≥ 0.45 in plane strain and axisymmetry, full otherwise (see
    /// [`Formulation::for_body`](crate::element::continuum::Formulation::for_body)).
    pub formulation: Option<FormulationKind>,
}

/// The element formulation of a body (`[[body]] formulation`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum FormulationKind {
    /// Standard displacement element, full integration.
    Full,
    /// B-bar: projected volumetric strain (locking-free in plane strain and axisymmetry).
    Bbar,
}

/// Material parameters of a body.
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Young's modulus in MPa.
    #[serde(rename = "E")]
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
    /// Initial yield stress σ_Y in MPa: makes the body elasto-plastic (von Mises, J2).
    pub yield_stress: Option<f64>,
    /// Linear isotropic hardening: the plastic modulus H in MPa, σ_y = σ_Y + H ε̄ᵖ (the slope
    /// of stress against plastic strain in uniaxial tension; the tangent modulus is
    /// E_t = E H / (E + H)). The hardening parameter h of Buczkowski & Kleiber (1994),
    /// Fig. 11, is this H.
    /// Default 0 (perfectly plastic).
    pub hardening: Option<f64>,
}

/// Prescribed displacement components on the nodes of a physical curve or point. Values are
/// in mm at load factor 1 and scale with the load factor. An omitted component is free.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(extend("patternProperties" = {
    "^ur$": {"description": "alias of ux: r displacement", "type": ["number", "null"]},
    "^uz$": {"description": "alias of uy: z displacement", "type": ["number", "null"]}
}))]
pub struct SupportSpec {
    /// Name the `[[step]]` tables use (default: the group); unique among supports.
    pub name: Option<String>,
    /// Name of a physical curve or physical point.
    pub group: String,
    /// x (or r) displacement.
    #[serde(alias = "ur")]
    pub ux: Option<f64>,
    /// y (or z) displacement.
    #[serde(alias = "uz")]
    pub uy: Option<f64>,
    /// This support's own history: one factor per step (default: the `[steps]` factors).
    pub factors: Option<Vec<f64>>,
}

/// A load at load factor 1 (it scales with the load factor).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// Name the `[[step]]` tables use (default: the group); unique among loads.
    pub name: Option<String>,
    /// Name of a physical curve (pressure, traction) or physical point (force).
    pub group: String,
    /// Normal pressure in MPa on a curve, positive pushing into the body.
    pub pressure: Option<f64>,
    /// Traction vector (t_x, t_y) in MPa on a curve.
    #[serde(default, deserialize_with = "two_components")]
    pub traction: Option<[f64; 2]>,
    /// Force (F_x, F_y) in N applied at each node of a physical point group (in axisymmetry
    /// the total over the ring).
    #[serde(default, deserialize_with = "two_components")]
    pub force: Option<[f64; 2]>,
    /// This load's own history: one factor per step (default: the `[steps]` factors).
    pub factors: Option<Vec<f64>>,
}

impl SupportSpec {
    /// The support's name: `name`, else its group.
    pub fn name(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.group)
    }

    /// Whether it prescribes a non-zero value (so that its history matters).
    pub fn is_nonzero(&self) -> bool {
        [self.ux, self.uy].iter().flatten().any(|&v| v != 0.0)
    }
}

impl LoadSpec {
    /// The load's name: `name`, else its group.
    pub fn name(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.group)
    }
}

/// A contact pair: which curves face each other, how their nodes are paired, the interface
/// law and its integration rule.
///
/// Give either `side_a` and `side_b` (two physical curves: coincident but distinct nodes, or,
/// with `pairing = "ordered"`, non-coincident curves with equal node counts), or `curve`,
/// `body_a` and `body_b` (one curve of a conforming mesh, split here).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Name used in output files and messages (default: "<side_a>-<side_b>" or the curve).
    pub name: Option<String>,
    pub side_a: Option<String>,
    pub side_b: Option<String>,
    /// `"coincident"` (default with side_a/side_b) or `"ordered"`.
    pub pairing: Option<PairingKind>,
    /// The shared curve of a conforming mesh to split.
    pub curve: Option<String>,
    pub body_a: Option<String>,
    pub body_b: Option<String>,
    /// Integration rule: `"newton_cotes"` (default, lumped) or `"gauss"`.
    #[serde(default)]
    pub integration: IntegrationKind,
    /// Initial interference δ in mm (positive: the faces overlap by δ at the start, as in a
    /// shrink fit; negative: an initial gap). Added to the gap measured from the geometry.
    #[serde(default)]
    pub interference: f64,
    pub law: LawSpec,
    /// Wear of the pair's surfaces (default: none).
    pub wear: Option<wear::WearSpec>,
    /// Points (x, y in mm, on the contact) whose local loops p_T against u_T are written to
    /// `point_loops_<name>.csv` at every frame (default: none).
    #[serde(default)]
    pub hysteresis_points: Vec<[f64; 2]>,
}

/// How the nodes of `side_a` and `side_b` are paired.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PairingKind {
    Coincident,
    Ordered,
}

/// The integration rule of a pair's interface elements.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum IntegrationKind {
    /// 3-point Newton-Cotes (Lobatto) at the nodes: lumped.
    #[default]
    NewtonCotes,
    /// 3-point Gauss: consistent.
    Gauss,
}

/// The faces of a contact pair, as the keys of a [`ContactSpec`] give them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Faces<'c> {
    /// Two physical curves (`side_a`, `side_b`), paired by coordinates or in order.
    Sides {
        side_a: &'c str,
        side_b: &'c str,
        pairing: PairingKind,
    },
    /// One physical curve of a conforming mesh between two bodies, to be split.
    Split {
        curve: &'c str,
        body_a: &'c str,
        body_b: &'c str,
    },
}

/// A plane vector: exactly two components (a third one, say a z component, would otherwise be
/// dropped without a word).
fn two_components<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<Option<[f64; 2]>, D::Error> {
    let v: Vec<f64> = Vec::deserialize(d)?;
    <[f64; 2]>::try_from(v.as_slice()).map(Some).map_err(|_| {
        serde::de::Error::custom(format!(
            "a vector needs exactly two components (x, y), got {}",
            v.len()
        ))
    })
}

impl ContactSpec {
    /// The pair's name.
    pub fn name(&self) -> String {
        if let Some(n) = &self.name {
            return n.clone();
        }
        match (&self.side_a, &self.side_b, &self.curve) {
            (Some(a), Some(b), _) => format!("{a}-{b}"),
            (_, _, Some(c)) => c.clone(),
            _ => "contact".into(),
        }
    }

    /// The faces, or `None` when the keys do not describe them (checked when the case is
    /// read).
    pub fn faces(&self) -> Option<Faces<'_>> {
        match (
            &self.side_a,
            &self.side_b,
            &self.curve,
            &self.body_a,
            &self.body_b,
        ) {
            (Some(a), Some(b), None, None, None) => Some(Faces::Sides {
                side_a: a,
                side_b: b,
                pairing: self.pairing.unwrap_or(PairingKind::Coincident),
            }),
            (None, None, Some(c), Some(a), Some(b)) if self.pairing.is_none() => {
                Some(Faces::Split {
                    curve: c,
                    body_a: a,
                    body_b: b,
                })
            }
            _ => None,
        }
    }
}

/// The load schedule: load factors of the steps, in order.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Steps {
    /// `count` equal steps from 1/count to 1.
    pub count: Option<usize>,
    /// Explicit load factors, e.g. `[0.5, 1.0, 0.5, 0.0]` for loading and unloading.
    pub factors: Option<Vec<f64>>,
    /// `"load"` (default: the factors above) or `"arc_length"` (Riks–Crisfield; the keys
    /// below, `count`/`factors` ignored).
    #[serde(default)]
    pub control: ControlKind,
    /// Arc length: the load-factor increment of the first increment (default 0.1).
    pub initial_increment: Option<f64>,
    /// Arc length: most increments (default 100).
    pub max_increments: Option<usize>,
    /// Arc length: stop once the load factor reaches this (default 1).
    pub max_load_factor: Option<f64>,
    /// Arc length: smallest arc, relative to the first (default 1e-4); below it the path
    /// cannot be followed further and the run ends.
    pub min_arc_length: Option<f64>,
    /// Arc length: largest arc, relative to the first (default 10).
    pub max_arc_length: Option<f64>,
}

/// How the load factor is driven (`[steps] control`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ControlKind {
    /// The load factors of `count` or `factors`.
    #[default]
    Load,
    /// Arc-length (Riks–Crisfield, cylindrical) control.
    ArcLength,
}

impl Default for Steps {
    fn default() -> Self {
        Self {
            count: Some(1),
            factors: None,
            control: ControlKind::Load,
            initial_increment: None,
            max_increments: None,
            max_load_factor: None,
            min_arc_length: None,
            max_arc_length: None,
        }
    }
}

impl Steps {
    /// The number of load steps (of a checked case).
    pub fn len(&self) -> usize {
        match (&self.factors, self.count) {
            (Some(f), _) => f.len(),
            (None, Some(n)) => n,
            (None, None) => 1,
        }
    }

    /// Whether there are no steps (never, in a checked case).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

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
    /// How often a step that fails to converge is halved and retried.
    pub max_cutbacks: usize,
    /// Global algorithm for contact: `"newton"` (consistent tangent, default), `"two_step"`
    /// (normal stress frozen in the friction tangent, symmetric) or `"elastic_contact"`
    /// (elastic contact matrix).
    pub contact_algorithm: ContactAlgorithmKind,
    /// Linear solver of models with contact pairs: `"condensed"` (exact solves by
    /// condensation onto the interface unknowns, default) or `"krylov"` (Cholesky, and
    /// BiCGSTAB preconditioned with the elastic contact matrix for unsymmetric tangents).
    pub linear_solver: LinearSolverKind,
    /// Start an increment proportional to the last converged one from the displacements
    /// extrapolated from it (default false).
    pub extrapolate: bool,
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
    max_iterations: usize,
    residual_tolerance: f64,
    correction_tolerance: f64,
    late_residual_tolerance: f64,
    late_iteration: usize,
    zero_flux: f64,
    zero_flux_correction_tolerance: f64,
    linear_residual_tolerance: f64,
    average_force: Option<f64>,
    force_tolerance: Option<f64>,
    displacement_tolerance: Option<f64>,
    max_cutbacks: usize,
    contact_algorithm: ContactAlgorithmKind,
    linear_solver: LinearSolverKind,
    extrapolate: bool,
    max_displacement_increment: f64,
    max_strain_increment: f64,
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
            contact_algorithm: ContactAlgorithmKind::default(),
            linear_solver: LinearSolverKind::default(),
            extrapolate: false,
            max_displacement_increment: 0.1,
            max_strain_increment: 0.05,
            collapse_stiffness_ratio: 1e-2,
        }
    }
}

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
            contact_algorithm: r.contact_algorithm,
            linear_solver: r.linear_solver,
            extrapolate: r.extrapolate,
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

/// What to write.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Output folder (relative to the case file); the CLI's `--out` overrides it. Default:
    /// `out/<case file name>` in the current folder.
    pub dir: Option<PathBuf>,
    /// Write VTU/PVD field output (on by default). CSV tables are always written.
    #[serde(default = "yes")]
    pub vtu: bool,
    /// Which frames of a cyclic step get field output (VTU, contact CSV): `"ends"`
    /// (default) or `"all"`. `history.csv` always has every frame.
    #[serde(default)]
    pub cycle_frames: CycleFrames,
}

/// The frames of a cyclic step that get field output (`[output] cycle_frames`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum CycleFrames {
    /// Every increment of the first and the last simulated cycle, and the last increment of
    /// every other cycle.
    #[default]
    Ends,
    /// Every increment.
    All,
}

fn yes() -> bool {
    true
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            dir: None,
            vtu: true,
            cycle_frames: CycleFrames::Ends,
        }
    }
}

impl Case {
    /// Reads and checks a case file.
    pub fn from_file(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_toml(&text, path)
    }

    /// Parses case text; `path` is used for messages and to resolve relative paths.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self> {
        let mut case: Case = toml::from_str(text).map_err(|e| Error::Case {
            path: path.to_path_buf(),
            message: e.to_string().trim_end().to_string(),
        })?;
        case.path = path.to_path_buf();
        case.base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        case.validate()?;
        case.check_analysis_keys(text)?;
        case.check_history_form(text)?;
        Ok(case)
    }

    /// A path from the case file, resolved against its folder.
    pub fn resolve(&self, p: &Path) -> PathBuf {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base_dir.join(p)
        }
    }

    /// An [`Error::Case`] of this case.
    fn error(&self, message: impl Into<String>) -> Error {
        Error::Case {
            path: self.path.clone(),
            message: message.into(),
        }
    }

    /// An [`Error::InvalidParameter`] of this case.
    pub fn invalid(
        &self,
        key: impl Into<String>,
        value: impl Display,
        reason: impl Into<String>,
    ) -> Error {
        Error::InvalidParameter {
            path: self.path.clone(),
            key: key.into(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    fn validate(&self) -> Result<()> {
        match (&self.mesh.file, &self.mesh.geo) {
            (Some(_), Some(_)) => {
                return Err(self.error("[mesh]: give either `file` or `geo`, not both"));
            }
            (None, None) => {
                return Err(
                    self.error("[mesh]: give `file` (an .msh file) or `geo` (a gmsh script)")
                );
            }
            _ => {}
        }
        if !self.mesh.size.is_finite() || self.mesh.size <= 0.0 {
            return Err(self.invalid("mesh.size", self.mesh.size, "must be positive"));
        }
        match self.analysis {
            AnalysisSpec::PlaneStress { thickness } | AnalysisSpec::PlaneStrain { thickness }
                if thickness.is_nan() || thickness <= 0.0 =>
            {
                return Err(self.invalid("analysis.thickness", thickness, "must be positive"));
            }
            _ => {}
        }
        if self.bodies.is_empty() {
            return Err(
                self.error("no [[body]]: name at least one physical surface and its material")
            );
        }
        for (i, b) in self.bodies.iter().enumerate() {
            if let (None, Some(h)) = (b.material.yield_stress, b.material.hardening) {
                return Err(self.invalid(
                    format!("body[{i}].material.hardening"),
                    h,
                    format!("`hardening` needs a `yield_stress` (body '{}')", b.group),
                ));
            }
        }
        for (i, s) in self.supports.iter().enumerate() {
            if s.ux.is_none() && s.uy.is_none() {
                return Err(self.error(format!("[[support]] '{}': give ux and/or uy", s.group)));
            }
            for (key, value) in [("ux", s.ux), ("uy", s.uy)] {
                if let Some(v) = value.filter(|v| !v.is_finite()) {
                    return Err(self.invalid(format!("support[{i}].{key}"), v, "must be finite"));
                }
            }
        }
        for (i, l) in self.loads.iter().enumerate() {
            let given = [
                l.pressure.is_some(),
                l.traction.is_some(),
                l.force.is_some(),
            ]
            .iter()
            .filter(|&&b| b)
            .count();
            if given != 1 {
                return Err(self.error(format!(
                    "[[load]] '{}': give exactly one of pressure, traction, force",
                    l.group
                )));
            }
            let values = [
                ("pressure", l.pressure.map(|p| vec![p])),
                ("traction", l.traction.map(Vec::from)),
                ("force", l.force.map(Vec::from)),
            ];
            for (key, value) in values {
                if let Some(v) = value.filter(|v| v.iter().any(|x| !x.is_finite())) {
                    let shown = if v.len() == 1 {
                        v[0].to_string()
                    } else {
                        format!("{v:?}")
                    };
                    return Err(self.invalid(format!("load[{i}].{key}"), shown, "must be finite"));
                }
            }
        }
        for (i, c) in self.contacts.iter().enumerate() {
            if c.faces().is_none() {
                return Err(self.error(format!(
                    "[[contact]] '{}': give either side_a and side_b (with optional pairing), or curve, body_a \
                     and body_b",
                    c.name()
                )));
            }
            if !c.interference.is_finite() {
                return Err(self.invalid(
                    format!("contact[{i}].interference"),
                    c.interference,
                    "must be finite",
                ));
            }
        }
        match (&self.steps.factors, self.steps.count) {
            (Some(_), Some(_)) => {
                return Err(self.error("[steps]: give either `count` or `factors`, not both"));
            }
            (Some(f), None) if f.is_empty() => {
                return Err(self.invalid("steps.factors", "[]", "must not be empty"));
            }
            (Some(f), None) if f.iter().any(|x| !x.is_finite()) => {
                return Err(self.invalid("steps.factors", format!("{f:?}"), "must be finite"));
            }
            (None, Some(0)) => return Err(self.invalid("steps.count", 0, "must be at least 1")),
            _ => {}
        }
        self.check_analysis_steps()?;
        let steps = self.steps.len();
        let own = self.supports.iter().map(|s| &s.factors).enumerate();
        let own = own
            .map(|(i, f)| (format!("support[{i}].factors"), f))
            .chain(
                self.loads
                    .iter()
                    .enumerate()
                    .map(|(i, l)| (format!("load[{i}].factors"), &l.factors)),
            );
        for (key, factors) in own {
            if let Some(f) = factors
                && (f.len() != steps || f.iter().any(|x| !x.is_finite()))
            {
                return Err(self.invalid(
                    key,
                    format!("{f:?}"),
                    format!("needs one finite value per step ({steps}), got {}", f.len()),
                ));
            }
        }
        let s = &self.solver;
        if s.max_iterations == 0 {
            return Err(self.invalid("solver.max_iterations", 0, "must be positive"));
        }
        for (key, value) in [
            ("solver.force_tolerance", s.force_tolerance),
            ("solver.displacement_tolerance", s.displacement_tolerance),
            ("solver.residual_tolerance", s.residual_tolerance),
            ("solver.correction_tolerance", s.correction_tolerance),
            ("solver.late_residual_tolerance", s.late_residual_tolerance),
            ("solver.zero_flux", s.zero_flux),
            (
                "solver.zero_flux_correction_tolerance",
                s.zero_flux_correction_tolerance,
            ),
            (
                "solver.linear_residual_tolerance",
                s.linear_residual_tolerance,
            ),
            ("solver.average_force", s.average_force.unwrap_or(1.0)),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(self.invalid(key, value, "must be positive and finite"));
            }
        }
        if s.linear_residual_tolerance > s.residual_tolerance {
            return Err(self.invalid(
                "solver.linear_residual_tolerance",
                s.linear_residual_tolerance,
                format!(
                    "must not exceed residual_tolerance ({}): a linear increment is accepted \
                     without the correction check",
                    s.residual_tolerance
                ),
            ));
        }
        self.check_ranges()?;
        let mut names = std::collections::BTreeSet::new();
        for q in &self.quantities {
            q.check(self).map_err(|m| self.error(m))?;
            if !names.insert(&q.name) {
                return Err(self.error(format!("[[quantity]] '{}' is defined twice", q.name)));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A minimal valid case: one plane-stress body "plate".
    pub(crate) const MINIMAL: &str = r#"
        [mesh]
        file = "m.msh"
        [analysis]
        type = "plane_stress"
        thickness = 2.0
        [[body]]
        group = "plate"
        material = { E = 210000.0, nu = 0.3 }
    "#;

    fn error(text: &str) -> Error {
        Case::from_toml(text, Path::new("c.toml")).unwrap_err()
    }

    #[test]
    fn minimal_case_parses_with_defaults() {
        let c = Case::from_toml(MINIMAL, Path::new("dir/c.toml")).unwrap();
        assert_eq!(c.analysis, AnalysisSpec::PlaneStress { thickness: 2.0 });
        assert_eq!(c.steps.len(), 1);
        assert_eq!(c.solver.contact_algorithm, ContactAlgorithmKind::Newton);
        assert_eq!(c.resolve(Path::new("m.msh")), PathBuf::from("dir/m.msh"));
    }

    #[test]
    fn unknown_key_is_named() {
        let text = MINIMAL.replace("thickness = 2.0", "thickness = 2.0\nthicknes = 1");
        let Error::Case { path, message } = error(&text) else {
            panic!("expected a case error")
        };
        assert!(
            message.contains("thicknes") && path == Path::new("c.toml"),
            "{message}"
        );
    }

    #[test]
    fn values_out_of_range_name_their_key() {
        for (from, to, expected) in [
            ("thickness = 2.0", "thickness = 0.0", "analysis.thickness"),
            (
                "nu = 0.3 }",
                "nu = 0.3, hardening = 1.0 }",
                "body[0].material.hardening",
            ),
            (
                "nu = 0.3 }",
                "nu = 0.3 }\n[steps]\ncount = 0",
                "steps.count",
            ),
            (
                "nu = 0.3 }",
                "nu = 0.3 }\n[solver]\nforce_tolerance = 0.0",
                "solver.force_tolerance",
            ),
        ] {
            let Error::InvalidParameter { key, .. } = error(&MINIMAL.replace(from, to)) else {
                panic!("expected an invalid parameter for {expected}")
            };
            assert_eq!(key, expected);
        }
    }

    #[test]
    fn step_counts_and_factors_give_the_number_of_steps() {
        let s = Steps {
            count: Some(4),
            factors: None,
            ..Steps::default()
        };
        assert_eq!(s.len(), 4);
        let s = Steps {
            count: None,
            factors: Some(vec![0.5, 1.0, 0.0]),
            ..Steps::default()
        };
        assert_eq!(s.len(), 3);
    }
}
