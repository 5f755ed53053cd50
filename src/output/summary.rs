//! `summary.json`: what a run did, as data for scripts (the schema is in the README,
//! "Output").
//!
//! The run fills a [`Summary`] as its steps converge and writes it once at the end: status
//! `converged`, or `failed` with the error and the steps that did converge. (Not after every
//! step: one more synced file per step would cost about a tenth of the output time.)
//! Pipelines read it instead of the printed summary. Non-finite numbers are written as
//! `null`.

use std::path::Path;

use serde::{Serialize, Serializer};

use super::atomic::write_atomically;
use crate::Result;
use crate::model::Model;

/// The contents of `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// `asperity`.
    pub program: &'static str,
    /// The program's version (`Cargo.toml`).
    pub version: &'static str,
    /// The case file as given on the command line.
    pub case: String,
    /// `failed` until the run has converged.
    pub status: Status,
    /// The error that stopped a failed run (the message `asperity` prints).
    pub error: Option<String>,
    /// `plane_stress`, `plane_strain` or `axisymmetric`, once the model is built.
    pub analysis: Option<&'static str>,
    /// Size of the model, once it is built.
    pub model: Option<ModelSize>,
    /// Every converged step, in order.
    pub steps: Vec<StepSummary>,
    pub totals: Totals,
    /// Wall-clock seconds per phase.
    pub seconds: Seconds,
    /// Support reactions at the last converged step.
    pub reactions: Named<Force>,
    /// Relative residual at the end of the last converged step.
    pub final_residual: Option<f64>,
}

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Every step converged and every file is written.
    Converged,
    /// The run stopped with an error.
    Failed,
}

/// Size of a model.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ModelSize {
    pub nodes: usize,
    /// Body (continuum) elements.
    pub elements: usize,
    pub interface_elements: usize,
    /// Free degrees of freedom.
    pub unknowns: usize,
    /// Out-of-plane thickness of a plane analysis (`null` in axisymmetry).
    pub thickness: Option<f64>,
}

/// One converged load step.
#[derive(Clone, Debug, Serialize)]
pub struct StepSummary {
    /// 1-based step number.
    pub step: usize,
    pub load_factor: f64,
    /// Converged (sub-)increments the step took (1 unless it was cut back).
    pub increments: usize,
    /// Failed increments that were halved and retried.
    pub cutbacks: usize,
    /// Newton iterations (linear solves) of all its increments.
    pub iterations: usize,
    /// Final relative residual.
    pub residual: f64,
    /// Reaction of every support, by support name.
    pub reactions: Named<Force>,
    /// Resultants of every contact pair, by pair name.
    pub contact: Named<ContactResultant>,
}

/// A force in the analysis plane (in axisymmetry x is r, y is z, totals over the circle).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Force {
    pub x: f64,
    pub y: f64,
}

/// The resultants of a contact pair (the `<pair>_*` columns of `history.csv`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ContactResultant {
    /// ∫ p_N dA (negative in compression).
    pub normal_force: f64,
    /// ∫ p_T dA.
    pub tangential_force: f64,
    /// The force body A exerts on body B.
    pub force_on_b_x: f64,
    pub force_on_b_y: f64,
}

/// Counters of the whole run. For a failed run they count the converged steps, and the
/// solver counters that are only known for a whole run are `null`.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Totals {
    pub steps: usize,
    pub increments: usize,
    pub cutbacks: usize,
    pub iterations: usize,
    /// Linear solves with an unsymmetric tangent.
    pub unsymmetric_solves: Option<usize>,
    /// BiCGSTAB iterations of those solves.
    pub krylov_iterations: Option<usize>,
}

/// Wall-clock seconds per phase; a phase the run did not reach, or whose time is only known
/// for a whole run (the solver's, when a run fails), is `null`.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Seconds {
    /// Reading the mesh, or meshing the `.geo` script with gmsh.
    pub mesh: f64,
    /// Building the model (numbering, constraints, interface elements).
    pub model: Option<f64>,
    /// Fill-reducing ordering and symbolic Cholesky factorisation.
    pub symbolic: Option<f64>,
    pub assembly: Option<f64>,
    pub factorisation: Option<f64>,
    /// Triangular solves and BiCGSTAB.
    pub solve: Option<f64>,
    /// Writing the result files.
    pub output: Option<f64>,
    /// The whole run, from reading the mesh to the last file.
    pub total: f64,
}

/// Values by name, written as a JSON object in the order given (support and pair names).
#[derive(Clone, Debug, PartialEq)]
pub struct Named<T>(pub Vec<(String, T)>);

impl<T> Default for Named<T> {
    fn default() -> Self {
        Self(Vec::new())
    }
}

impl<T: Serialize> Serialize for Named<T> {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        serializer.collect_map(self.0.iter().map(|(k, v)| (k, v)))
    }
}

impl Summary {
    /// The summary of a run of `case` that has not done anything yet.
    pub fn new(case: &Path) -> Self {
        Self {
            program: env!("CARGO_PKG_NAME"),
            version: env!("CARGO_PKG_VERSION"),
            case: case.display().to_string(),
            status: Status::Failed,
            error: None,
            analysis: None,
            model: None,
            steps: Vec::new(),
            totals: Totals::default(),
            seconds: Seconds::default(),
            reactions: Named::default(),
            final_residual: None,
        }
    }

    /// Appends a converged step and updates the totals and the last values from it.
    pub fn push_step(&mut self, step: StepSummary) {
        self.totals.steps += 1;
        self.totals.increments += step.increments;
        self.totals.cutbacks += step.cutbacks;
        self.totals.iterations += step.iterations;
        self.final_residual = Some(step.residual);
        self.reactions = step.reactions.clone();
        self.steps.push(step);
    }

    /// Marks the run as failed with `error`.
    pub fn fail(&mut self, error: &crate::Error) {
        self.status = Status::Failed;
        self.error = Some(error.to_string());
    }

    /// Writes the summary to `path` (atomically).
    pub fn write(&self, path: &Path) -> Result<()> {
        let json = serde_json::to_vec_pretty(self).map_err(|e| {
            super::atomic::invalid_data(path, format!("cannot encode the summary: {e}"))
        })?;
        write_atomically(path, |w| {
            w.write_all(&json)?;
            w.write_all(b"\n")
        })
    }
}

/// The model as `asperity check` prints it: analysis, size, and per body, contact pair and
/// support what the case made of it (material, formulation, law, elements, prescribed dofs),
/// so a case can be checked before anything is solved.
pub struct ModelReport<'m>(pub &'m Model);

impl std::fmt::Display for ModelReport<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let m = self.0;
        writeln!(
            f,
            "model: {}, {} nodes, {} elements, {} interface elements, {} unknowns, size {:.6e} mm",
            m.analysis.name(),
            m.mesh.nodes.len(),
            m.continuum.cells.len(),
            m.interface.elements.len(),
            m.dofs.free_count(),
            m.size
        )?;
        for (b, name) in m.bodies.iter().enumerate() {
            let elements = m.continuum.cells.iter().filter(|c| c.body as usize == b);
            writeln!(
                f,
                "body '{name}': {} elements, {}, {} formulation",
                elements.count(),
                m.continuum.materials[b].describe(),
                m.continuum.formulations[b].name()
            )?;
        }
        for p in &m.interface.pairs {
            writeln!(
                f,
                "contact '{}': {} interface elements, {}, interference {} mm",
                p.name,
                p.elements.len(),
                p.law.describe(),
                p.interference
            )?;
        }
        for s in &m.supports {
            writeln!(f, "support '{}': {} prescribed dofs", s.name, s.dofs.len())?;
        }
        write!(
            f,
            "loads: {} nodal force entries; steps: {}",
            m.nodal_loads.len(),
            m.schedule.steps()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_summary_is_written_as_json_with_names_in_order() {
        let mut s = Summary::new(Path::new("case.toml"));
        s.push_step(StepSummary {
            step: 1,
            load_factor: 0.5,
            increments: 2,
            cutbacks: 1,
            iterations: 7,
            residual: f64::NAN,
            reactions: Named(vec![
                ("z_support".into(), Force { x: 1.0, y: -2.0 }),
                ("a_support".into(), Force::default()),
            ]),
            contact: Named::default(),
        });
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("summary.json");
        s.write(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let value: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(value["status"], "failed");
        assert_eq!(value["totals"]["cutbacks"], 1);
        assert_eq!(value["steps"][0]["reactions"]["z_support"]["y"], -2.0);
        assert!(value["final_residual"].is_null(), "NaN is written as null");
        assert!(text.find("z_support").unwrap() < text.find("a_support").unwrap());
    }
}
