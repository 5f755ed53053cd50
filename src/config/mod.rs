//! The case file (TOML) as plain data: what to mesh or read, the analysis type, a material per
//! body, the supports, the loads, the contact pairs, the load steps, the solver settings, the
//! output and the quantities of a study. Reading a case checks it once: unknown keys are
//! errors that name the key, and values out of range are [`Error::InvalidParameter`]s with
//! their key path. Nothing here builds or computes anything: [`crate::model::ModelSpec`]
//! turns a case into materials, laws and loads. Relative paths inside a case file are
//! relative to the case file's folder.
//!
//! The doc comments of these types are the case-file reference: `asperity schema` and
//! docs/guide/case-file.md (`crate::reference`) are made from them.

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
mod solver;
mod step_checks;
mod steps;
pub mod thermal;
pub mod wear;

pub use check::{MAX_CUTBACKS, MAX_ITERATIONS, MAX_STEPS, MAX_TOLERANCE};
pub use law::LawSpec;
pub use names::{MAX_NAME_LEN, check_name};
pub use quantity::{Component, QuantityKind, QuantitySpec, Statistic, parse_quantity};
pub use solver::{ContactAlgorithmKind, LinearSolverKind, SolverSpec};
pub use steps::{AmplitudeSpec, InlineAmplitude, Leg, Motion, Role, StepSpec, Target};
pub use thermal::{
    Conductance, ConductanceSpec, FilmSpec, HeatSourceSpec, TemperatureSpec, ThermalSupportSpec,
};

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
    /// Uniform temperature changes of bodies (`[[temperature]]`, [`thermal`]).
    #[serde(default, rename = "temperature")]
    pub temperatures: Vec<TemperatureSpec>,
    /// Boundary conditions of the heat conduction (`[[thermal_support]]`, [`thermal`]).
    #[serde(default, rename = "thermal_support")]
    pub thermal_supports: Vec<ThermalSupportSpec>,
    /// Volumetric heat sources (`[[heat_source]]`, [`thermal`]).
    #[serde(default, rename = "heat_source")]
    pub heat_sources: Vec<HeatSourceSpec>,
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

/// Where the mesh comes from: an existing `.msh` file, or a `.geo` script meshed by gmsh
/// (exactly one of `file` and `geo`).
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MeshSource {
    /// An MSH 4.1 file (ascii or binary, second order) of at most 1 GiB.
    pub file: Option<PathBuf>,
    /// A gmsh `.geo` script, meshed with `gmsh -2 -order 2` at run time into `mesh.msh` of
    /// the output folder (MSH 4.1, binary).
    pub geo: Option<PathBuf>,
    /// Mesh size factor passed to gmsh (`-clscale`), > 0; smaller is finer. A mesh estimated
    /// above 1 000 000 elements is refused before gmsh makes it.
    #[serde(default = "one")]
    pub size: f64,
    /// Values for the script's `DefineConstant` parameters (`-setnumber NAME VALUE`): names
    /// are identifiers, values finite; a name the script never mentions (a misspelt one,
    /// which gmsh would ignore) is an error, a warning only when the script includes other
    /// files. gmsh is stopped after 600 s.
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
    PlaneStress {
        /// Thickness in mm (positive): forces and reactions are per this thickness.
        thickness: f64,
    },
    /// ε_zz = 0. `thickness` in mm (default 1).
    PlaneStrain {
        /// Thickness in mm: forces and reactions are per this thickness.
        #[serde(default = "one")]
        thickness: f64,
    },
    /// Axisymmetric about the y axis: x = r, y = z.
    Axisymmetric {
        /// Twist (Abaqus' CGAX elements): every node also has the circumferential
        /// displacement u_θ (mm), so that the bodies can carry a torque about the axis
        /// (`utheta`, `rotation`, `torque`, a third `traction` component).
        /// See docs/guide/torque.md.
        #[serde(default)]
        twist: bool,
    },
}

impl AnalysisSpec {
    /// Whether this is an axisymmetric analysis (with or without twist).
    pub fn is_axisymmetric(&self) -> bool {
        matches!(self, AnalysisSpec::Axisymmetric { .. })
    }

    /// Whether the nodes carry the circumferential displacement u_θ (`twist = true`).
    pub fn has_twist(&self) -> bool {
        matches!(self, AnalysisSpec::Axisymmetric { twist: true })
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
    /// Thermal conductivity k in W/(mm·K): the body takes part in the steady heat
    /// conduction, whose temperature drives its thermal strain (exclusive with a
    /// `[[temperature]]` entry for it).
    pub conductivity: Option<f64>,
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
    /// Nonlinear kinematic hardening (Abaqus' *PLASTIC, HARDENING=COMBINED): one to five
    /// Armstrong–Frederick backstresses summed as in Chaboche,
    /// `kinematic = [{ C = 40000.0, gamma = 300.0 }, { C = 2000.0, gamma = 0.0 }]`. Each
    /// evolves as dα = ⅔ C dεᵖ − γ α dε̄ᵖ and saturates at C/γ (uniaxial); `gamma = 0` is
    /// linear Prager/Ziegler hardening. Moves the yield surface (Bauschinger effect,
    /// ratcheting). Needs `yield_stress`. See docs/guide/plasticity.md.
    #[serde(default, deserialize_with = "backstresses")]
    #[schemars(with = "Option<Vec<KinematicSpec>>", length(min = 1, max = 5))]
    pub kinematic: Option<Backstresses>,
    /// Voce saturation isotropic hardening (Abaqus' *CYCLIC HARDENING, PARAMETERS),
    /// `isotropic = { Q = 80.0, b = 10.0 }`: σ_y = σ_Y + Q (1 − e^(−b ε̄ᵖ)), added to the
    /// linear `hardening` when both are given. Q < 0 is cyclic softening. Needs
    /// `yield_stress`.
    pub isotropic: Option<VoceSpec>,
    /// Linear thermal expansion coefficient α in 1/K (default 0): the thermal strain
    /// α ΔT in every direction, ΔT from `[[temperature]]` or the heat conduction. Plastic
    /// strain and the other properties do not depend on the temperature.
    pub expansion: Option<f64>,
}

/// The most backstresses `kinematic` may list (the material's
/// [`MAX_KINEMATIC_TERMS`](crate::material::cyclic::MAX_KINEMATIC_TERMS), checked equal by a
/// test of `model::spec`).
pub const MAX_KINEMATIC_TERMS: usize = 5;

/// The backstresses of `kinematic` (at most [`MAX_KINEMATIC_TERMS`], kept inline so that a
/// material stays plain copyable data).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Backstresses {
    terms: [KinematicSpec; MAX_KINEMATIC_TERMS],
    len: usize,
}

impl Backstresses {
    /// The backstresses, in the order given.
    pub fn as_slice(&self) -> &[KinematicSpec] {
        &self.terms[..self.len]
    }
}

/// `kinematic`: a list of at most [`MAX_KINEMATIC_TERMS`] backstresses (an empty one is
/// refused by the case check, which names the key).
fn backstresses<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<Option<Backstresses>, D::Error> {
    let v: Vec<KinematicSpec> = Vec::deserialize(d)?;
    let mut b = Backstresses {
        len: v.len(),
        ..Backstresses::default()
    };
    b.terms
        .get_mut(..v.len())
        .ok_or_else(|| {
            serde::de::Error::custom(format!(
                "kinematic: give 1 to {MAX_KINEMATIC_TERMS} backstresses {{ C, gamma }}, got {}",
                v.len()
            ))
        })?
        .copy_from_slice(&v);
    Ok(Some(b))
}

/// One Armstrong–Frederick backstress of `kinematic`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct KinematicSpec {
    /// Initial kinematic hardening modulus C in MPa (> 0): the slope of the backstress
    /// against uniaxial plastic strain at the start.
    #[serde(rename = "C")]
    pub c: f64,
    /// Rate of dynamic recovery γ (≥ 0, dimensionless): the backstress saturates at C/γ after
    /// a plastic strain of a few 1/γ; 0 is linear (Prager) hardening.
    pub gamma: f64,
}

/// Voce isotropic hardening, `isotropic`.
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VoceSpec {
    /// Saturation increase of the yield stress Q in MPa (> −yield_stress; negative: cyclic
    /// softening).
    #[serde(rename = "Q")]
    pub q: f64,
    /// Rate b (≥ 0, dimensionless): Q is reached after an accumulated plastic strain of a few
    /// 1/b.
    pub b: f64,
}

impl MaterialSpec {
    /// Whether the material has the cyclic hardening keys (`kinematic` or `isotropic`).
    pub fn has_cyclic_hardening(&self) -> bool {
        self.kinematic.is_some() || self.isotropic.is_some()
    }
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
    /// Circumferential displacement u_θ in mm (axisymmetric analyses with `twist` only;
    /// exclusive with `rotation`).
    pub utheta: Option<f64>,
    /// Rigid rotation φ about the axis in radians: u_θ = φ r at every node of the group
    /// (axisymmetric analyses with `twist` only; exclusive with `utheta`). Positive
    /// counter-clockwise seen from +z.
    pub rotation: Option<f64>,
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
    /// Traction vector (t_x, t_y) in MPa on a curve; with `twist`, also (t_r, t_z, t_θ),
    /// t_θ the circumferential shear traction.
    #[schemars(length(min = 2, max = 3))]
    pub traction: Option<Vec<f64>>,
    /// Torque T in N·mm about the axis on a curve (axisymmetric analyses with `twist`
    /// only): the circumferential traction of a rigid rotation, t_θ ∝ r, scaled so that
    /// its moment ∫ t_θ r dA is T. Positive counter-clockwise seen from +z.
    pub torque: Option<f64>,
    /// Force (F_x, F_y) in N applied at each node of a physical point group (in axisymmetry
    /// the total over the ring); with `twist`, also (F_r, F_z, F_θ), F_θ the ring's
    /// circumferential force (its moment about the axis is F_θ r).
    #[schemars(length(min = 2, max = 3))]
    pub force: Option<Vec<f64>>,
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
        let values = [self.ux, self.uy, self.utheta, self.rotation];
        values.iter().flatten().any(|&v| v != 0.0)
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
    /// The physical curve of body A (the relative displacement is B minus A).
    pub side_a: Option<String>,
    /// The physical curve of body B, facing `side_a`: the normal points into body B.
    pub side_b: Option<String>,
    /// `"coincident"` (default with side_a/side_b) or `"ordered"`.
    pub pairing: Option<PairingKind>,
    /// The shared curve of a conforming mesh to split.
    pub curve: Option<String>,
    /// With `curve`: the physical surface of body A.
    pub body_a: Option<String>,
    /// With `curve`: the physical surface of body B, whose elements move onto the copied
    /// nodes.
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
    /// Joint conductance for the heat conduction: h in W/(mm²·K), or `{ h0, exponent }` for
    /// h = h0 (|p|/1 MPa)^exponent, optionally with `gap` for open points (default: no heat
    /// crosses an open point). See docs/guide/temperature.md.
    pub conductance: Option<ConductanceSpec>,
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

/// What to write.
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Output folder (relative to the case file); the CLI's `--out` overrides it. Default:
    /// `out/<case file name>` next to the case file.
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

/// Largest input file (case, fit or sweep specification) read: far beyond any case's text
/// (a 5 000-point amplitude table is ~100 kB), and a bound on what a mistaken path such as a
/// device or a mesh makes the reader take in.
pub const MAX_INPUT_BYTES: u64 = 64 << 20;

/// The text of the input file `path` (a case, fit or sweep specification): at most
/// [`MAX_INPUT_BYTES`] of UTF-8.
pub fn read_input(path: &Path) -> Result<String> {
    let bytes = read_bounded(path, "not a case, fit or sweep file")?;
    String::from_utf8(bytes).map_err(|e| Error::Case {
        path: path.to_path_buf(),
        message: format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
    })
}

/// The bytes of an input file of at most [`MAX_INPUT_BYTES`] (a case, fit or sweep file, a
/// measured curve), read no further than one byte beyond: a larger file (or `/dev/zero`) is an
/// error naming the file, `what` saying what it cannot be.
pub fn read_bounded(path: &Path, what: &str) -> Result<Vec<u8>> {
    use std::io::Read;
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut bytes = Vec::new();
    file.take(MAX_INPUT_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(Error::Case {
            path: path.to_path_buf(),
            message: format!("larger than {} MiB: {what}", MAX_INPUT_BYTES >> 20),
        });
    }
    Ok(bytes)
}

impl Case {
    /// Reads and checks a case file.
    pub fn from_file(path: &Path) -> Result<Self> {
        let text = read_input(path)?;
        Self::from_toml(&text, path)
    }

    /// Parses case text; `path` is used for messages and to resolve relative paths.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self> {
        check::check_analysis_table(text, path)?;
        let mut case: Case = toml::from_str(text).map_err(|e| Error::toml(path, &e))?;
        case.path = path.to_path_buf();
        case.base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        case.validate()?;
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
