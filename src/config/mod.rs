//! The case file (TOML): what to mesh or read, the analysis type, a material per body, the
//! supports, the loads, the load steps and the output. Unknown keys are errors that name the
//! key. Relative paths inside a case file are relative to the case file's folder.
//!
//! The full reference, with an example, is in the README ("Case file reference").

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::contact::ContactAlgorithm;
use crate::element::Analysis;
use crate::element::interface6::InterfaceRule;
use crate::mesh::interface::Pairing;
use crate::{Error, Result};

mod quantity;

pub use quantity::{Component, QuantityKind, QuantitySpec, Statistic, parse_quantity};

/// A parsed case file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    pub mesh: MeshSource,
    pub analysis: Analysis,
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
    #[serde(default)]
    pub steps: Steps,
    #[serde(default)]
    pub solver: SolverSpec,
    #[serde(default)]
    pub output: OutputSpec,
    /// Quantities of interest for `asperity converge` (ignored by `asperity run`).
    #[serde(default, rename = "quantity")]
    pub quantities: Vec<QuantitySpec>,
    /// Folder of the case file; relative paths are resolved against it.
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// The case file itself (for messages).
    #[serde(skip)]
    pub path: PathBuf,
}

/// Where the mesh comes from: an existing `.msh` file, or a `.geo` script meshed by gmsh.
#[derive(Clone, Debug, Deserialize)]
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

/// A body: a physical surface and its material.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name of the physical surface.
    pub group: String,
    pub material: MaterialSpec,
}

/// Material parameters of a body.
#[derive(Clone, Copy, Debug, Deserialize)]
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
    /// E_t = E H / (E + H)). The paper's hardening parameter h (Fig. 11) is this H.
    /// Default 0 (perfectly plastic).
    pub hardening: Option<f64>,
}

impl MaterialSpec {
    /// The constitutive model: linear elastic, or J2 plasticity when `yield_stress` is given.
    pub fn build(&self) -> std::result::Result<Box<dyn crate::material::Material>, String> {
        let elastic = crate::material::elastic::LinearElastic::new(self.e, self.nu)?;
        match (self.yield_stress, self.hardening) {
            (None, None) => Ok(Box::new(elastic)),
            (None, Some(_)) => Err("`hardening` needs a `yield_stress`".into()),
            (Some(sy), h) => Ok(Box::new(crate::material::j2::J2Plasticity::new(
                elastic,
                sy,
                h.unwrap_or(0.0),
            )?)),
        }
    }
}

/// Prescribed displacement components on the nodes of a physical curve or point. Values are
/// in mm at load factor 1 and scale with the load factor. An omitted component is free.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportSpec {
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
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// Name of a physical curve (pressure, traction) or physical point (force).
    pub group: String,
    /// Normal pressure in MPa on a curve, positive pushing into the body.
    pub pressure: Option<f64>,
    /// Traction vector (t_x, t_y) in MPa on a curve.
    pub traction: Option<[f64; 2]>,
    /// Force (F_x, F_y) in N applied at each node of a physical point group (in axisymmetry
    /// the total over the ring).
    pub force: Option<[f64; 2]>,
    /// This load's own history: one factor per step (default: the `[steps]` factors).
    pub factors: Option<Vec<f64>>,
}

/// A contact pair: which curves face each other, how their nodes are paired, the interface
/// law and its integration rule.
///
/// Give either `side_a` and `side_b` (two physical curves: coincident but distinct nodes, or,
/// with `pairing = "ordered"`, non-coincident curves with equal node counts), or `curve`,
/// `body_a` and `body_b` (one curve of a conforming mesh, split here).
#[derive(Clone, Debug, Deserialize)]
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
    pub integration: InterfaceRule,
    /// Initial interference δ in mm (positive: the faces overlap by δ at the start, as in a
    /// shrink fit; negative: an initial gap). Added to the gap measured from the geometry.
    #[serde(default)]
    pub interference: f64,
    pub law: LawSpec,
}

/// How the nodes of `side_a` and `side_b` are paired.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PairingKind {
    Coincident,
    Ordered,
}

/// The interface law of a contact pair and its parameters.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum LawSpec {
    /// Linear normal stiffness (compression only), linear tangential stiffness and ideal
    /// Coulomb friction.
    LinearCoulomb {
        /// k_N in MPa/mm.
        normal_stiffness: f64,
        /// k_T in MPa/mm.
        tangential_stiffness: f64,
        /// Coulomb coefficient μ (default 0: frictionless).
        #[serde(default)]
        friction: f64,
    },
    /// The paper's law (§2): power-law normal compliance u_N = c_N p^m, tangential stiffness
    /// k_T = p^S / R, slip-hardening friction μ_F = μ_m [1 − (1 − β) exp(−n ū)].
    RoughJoint {
        /// c_N in mm/MPa^m (the paper's values are in µm: multiply them by 1e-3).
        c_n: f64,
        m: f64,
        /// Optional unloading curve (c_N, m); default: the loading curve.
        unloading_c_n: Option<f64>,
        unloading_m: Option<f64>,
        /// R such that p^S / R is in MPa/mm (the paper's values × 1e-3), and S.
        #[serde(rename = "R")]
        r: f64,
        #[serde(rename = "S")]
        s: f64,
        /// Macroscopic friction coefficient μ_m.
        mu_m: f64,
        /// Initial friction as a fraction of μ_m (default 1: no hardening).
        #[serde(default = "default_beta")]
        beta: f64,
        /// Slip-hardening rate n in 1/mm (default 0).
        #[serde(default)]
        n: f64,
        /// Pressure (MPa) below which stiffnesses are evaluated at this value (default 0.1).
        #[serde(default = "default_starting_pressure")]
        starting_pressure: f64,
    },
}

fn default_beta() -> f64 {
    1.0
}

fn default_starting_pressure() -> f64 {
    0.1
}

impl LawSpec {
    /// The law object, or a message saying which parameter is wrong.
    pub fn build(&self) -> std::result::Result<Box<dyn crate::contact::InterfaceLaw>, String> {
        match *self {
            LawSpec::LinearCoulomb {
                normal_stiffness,
                tangential_stiffness,
                friction,
            } => Ok(Box::new(crate::contact::linear::LinearCoulomb::new(
                normal_stiffness,
                tangential_stiffness,
                friction,
            )?)),
            LawSpec::RoughJoint {
                c_n,
                m,
                unloading_c_n,
                unloading_m,
                r,
                s,
                mu_m,
                beta,
                n,
                starting_pressure,
            } => {
                let unloading = match (unloading_c_n, unloading_m) {
                    (None, None) => None,
                    (Some(c), Some(m)) => Some((c, m)),
                    _ => return Err("give both unloading_c_n and unloading_m, or neither".into()),
                };
                let law = crate::contact::rough::RoughJoint {
                    c_n,
                    m,
                    unloading,
                    r,
                    s,
                    mu_m,
                    beta,
                    n,
                    starting_pressure,
                };
                Ok(Box::new(crate::contact::rough::RoughJoint::new(law)?))
            }
        }
    }
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

    /// The pairing recipe.
    pub fn pairing(&self) -> std::result::Result<Pairing, String> {
        let name = self.name();
        match (
            &self.side_a,
            &self.side_b,
            &self.curve,
            &self.body_a,
            &self.body_b,
        ) {
            (Some(a), Some(b), None, None, None) => {
                Ok(match self.pairing.unwrap_or(PairingKind::Coincident) {
                    PairingKind::Coincident => Pairing::Coincident {
                        side_a: a.clone(),
                        side_b: b.clone(),
                    },
                    PairingKind::Ordered => Pairing::Ordered {
                        side_a: a.clone(),
                        side_b: b.clone(),
                    },
                })
            }
            (None, None, Some(c), Some(a), Some(b)) if self.pairing.is_none() => {
                Ok(Pairing::Split {
                    curve: c.clone(),
                    body_a: a.clone(),
                    body_b: b.clone(),
                })
            }
            _ => Err(format!(
                "[[contact]] '{name}': give either side_a and side_b (with optional pairing), or curve, body_a and \
                 body_b"
            )),
        }
    }
}

/// The load schedule: load factors of the steps, in order.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Steps {
    /// `count` equal steps from 1/count to 1.
    pub count: Option<usize>,
    /// Explicit load factors, e.g. `[0.5, 1.0, 0.5, 0.0]` for loading and unloading.
    pub factors: Option<Vec<f64>>,
}

impl Default for Steps {
    fn default() -> Self {
        Self {
            count: Some(1),
            factors: None,
        }
    }
}

impl Steps {
    /// The load factors of the schedule.
    pub fn factors(&self) -> std::result::Result<Vec<f64>, String> {
        match (&self.factors, self.count) {
            (Some(_), Some(_)) => Err("[steps]: give either `count` or `factors`, not both".into()),
            (Some(f), None) if f.is_empty() => Err("[steps]: `factors` is empty".into()),
            (Some(f), None) if f.iter().any(|x| !x.is_finite()) => {
                Err("[steps]: `factors` must be finite".into())
            }
            (Some(f), None) => Ok(f.clone()),
            (None, Some(0)) => Err("[steps]: `count` must be at least 1".into()),
            (None, Some(n)) => Ok((1..=n).map(|i| i as f64 / n as f64).collect()),
            (None, None) => Ok(vec![1.0]),
        }
    }
}

/// Newton-Raphson settings.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// Iteration limit per step.
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// Relative tolerance on the out-of-balance force: ‖r‖ ≤ tol · max(‖f_ext‖, ‖f_int‖).
    #[serde(default = "default_tolerance")]
    pub force_tolerance: f64,
    /// Relative tolerance on the displacement correction: ‖δu‖ ≤ tol · ‖u‖.
    #[serde(default = "default_tolerance")]
    pub displacement_tolerance: f64,
    /// How often a step that fails to converge is halved and retried.
    #[serde(default = "default_max_cutbacks")]
    pub max_cutbacks: usize,
    /// Global algorithm for contact: `"newton"` (consistent tangent, default), `"two_step"`
    /// (normal stress frozen in the friction tangent, symmetric) or `"elastic_contact"`
    /// (elastic contact matrix).
    #[serde(default)]
    pub contact_algorithm: ContactAlgorithm,
}

fn default_max_cutbacks() -> usize {
    8
}

fn default_max_iterations() -> usize {
    25
}
fn default_tolerance() -> f64 {
    1e-8
}

impl Default for SolverSpec {
    fn default() -> Self {
        Self {
            max_iterations: default_max_iterations(),
            force_tolerance: default_tolerance(),
            displacement_tolerance: default_tolerance(),
            max_cutbacks: default_max_cutbacks(),
            contact_algorithm: ContactAlgorithm::default(),
        }
    }
}

/// What to write.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Output folder (relative to the case file); the CLI's `--out` overrides it. Default:
    /// `out/<case file name>` in the current folder.
    pub dir: Option<PathBuf>,
    /// Write VTU/PVD field output (on by default). CSV tables are always written.
    #[serde(default = "yes")]
    pub vtu: bool,
}

fn yes() -> bool {
    true
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            dir: None,
            vtu: true,
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
        let err = |message: String| Error::Case {
            path: path.to_path_buf(),
            message,
        };
        let mut case: Case =
            toml::from_str(text).map_err(|e| err(e.to_string().trim_end().to_string()))?;
        case.path = path.to_path_buf();
        case.base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        case.validate().map_err(err)?;
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

    fn validate(&self) -> std::result::Result<(), String> {
        match (&self.mesh.file, &self.mesh.geo) {
            (Some(_), Some(_)) => {
                return Err("[mesh]: give either `file` or `geo`, not both".into());
            }
            (None, None) => {
                return Err("[mesh]: give `file` (an .msh file) or `geo` (a gmsh script)".into());
            }
            _ => {}
        }
        if !self.mesh.size.is_finite() || self.mesh.size <= 0.0 {
            return Err(format!(
                "[mesh]: size = {} must be positive",
                self.mesh.size
            ));
        }
        match self.analysis {
            Analysis::PlaneStress { thickness } | Analysis::PlaneStrain { thickness }
                if thickness.is_nan() || thickness <= 0.0 =>
            {
                return Err(format!(
                    "[analysis]: thickness = {thickness} must be positive"
                ));
            }
            _ => {}
        }
        if self.bodies.is_empty() {
            return Err("no [[body]]: name at least one physical surface and its material".into());
        }
        for b in &self.bodies {
            b.material
                .build()
                .map_err(|m| format!("[[body]] '{}': {m}", b.group))?;
        }
        for s in &self.supports {
            if s.ux.is_none() && s.uy.is_none() {
                return Err(format!("[[support]] '{}': give ux and/or uy", s.group));
            }
            if s.ux.iter().chain(&s.uy).any(|v| !v.is_finite()) {
                return Err(format!("[[support]] '{}': values must be finite", s.group));
            }
        }
        for l in &self.loads {
            let given = [
                l.pressure.is_some(),
                l.traction.is_some(),
                l.force.is_some(),
            ]
            .iter()
            .filter(|&&b| b)
            .count();
            if given != 1 {
                return Err(format!(
                    "[[load]] '{}': give exactly one of pressure, traction, force",
                    l.group
                ));
            }
            let values = l
                .pressure
                .into_iter()
                .chain(l.traction.into_iter().flatten())
                .chain(l.force.into_iter().flatten());
            if values.clone().any(|v| !v.is_finite()) {
                return Err(format!("[[load]] '{}': values must be finite", l.group));
            }
        }
        for c in &self.contacts {
            c.pairing()?;
            c.law
                .build()
                .map_err(|m| format!("[[contact]] '{}': {m}", c.name()))?;
            if !c.interference.is_finite() {
                return Err(format!(
                    "[[contact]] '{}': interference must be finite",
                    c.name()
                ));
            }
        }
        let steps = self.steps.factors()?.len();
        let own = self
            .supports
            .iter()
            .map(|s| (&s.group, &s.factors, "support"));
        for (group, factors, what) in
            own.chain(self.loads.iter().map(|l| (&l.group, &l.factors, "load")))
        {
            if let Some(f) = factors
                && (f.len() != steps || f.iter().any(|x| !x.is_finite()))
            {
                return Err(format!(
                    "[[{what}]] '{group}': `factors` needs one finite value per step ({steps}), got {}",
                    f.len()
                ));
            }
        }
        let s = &self.solver;
        let positive = |x: f64| x > 0.0;
        if s.max_iterations == 0
            || !positive(s.force_tolerance)
            || !positive(s.displacement_tolerance)
        {
            return Err("[solver]: max_iterations and tolerances must be positive".into());
        }
        let mut names = std::collections::BTreeSet::new();
        for q in &self.quantities {
            q.check(self)?;
            if !names.insert(&q.name) {
                return Err(format!("[[quantity]] '{}' is defined twice", q.name));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
        [mesh]
        file = "m.msh"
        [analysis]
        type = "plane_stress"
        thickness = 2.0
        [[body]]
        group = "plate"
        material = { E = 210000.0, nu = 0.3 }
    "#;

    #[test]
    fn minimal_case_parses_with_defaults() {
        let c = Case::from_toml(MINIMAL, Path::new("dir/c.toml")).unwrap();
        assert_eq!(c.analysis, Analysis::PlaneStress { thickness: 2.0 });
        assert_eq!(c.steps.factors().unwrap(), vec![1.0]);
        assert_eq!(c.resolve(Path::new("m.msh")), PathBuf::from("dir/m.msh"));
    }

    #[test]
    fn unknown_key_is_named() {
        let text = MINIMAL.replace("thickness = 2.0", "thickness = 2.0\nthicknes = 1");
        let e = Case::from_toml(&text, Path::new("c.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("thicknes") && e.contains("c.toml"), "{e}");
    }

    #[test]
    fn negative_modulus_names_the_body() {
        let text = MINIMAL.replace("E = 210000.0", "E = -1.0");
        let e = Case::from_toml(&text, Path::new("c.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("plate") && e.contains("positive"), "{e}");
    }

    #[test]
    fn step_counts_make_uniform_factors() {
        let s = Steps {
            count: Some(4),
            factors: None,
        };
        assert_eq!(s.factors().unwrap(), vec![0.25, 0.5, 0.75, 1.0]);
    }
}
