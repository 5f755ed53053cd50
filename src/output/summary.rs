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
use crate::model::timeline::Frame;
use crate::solver::energy::Energy;

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
    /// The energy balance: totals, per analysis step and per load cycle.
    pub energy: EnergyReport,
}

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Every step converged and every file is written.
    Converged,
    /// The run stopped with an error.
    Failed,
    /// The run was asked to stop (Ctrl-C, SIGTERM); the converged steps are complete.
    Interrupted,
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

/// The energy totals at the end of a load cycle (a step without cycles is one cycle): the
/// marks from which `summary.json`'s `"energy"` is made.
#[derive(Clone, Debug, PartialEq)]
pub struct EnergyMark {
    /// 1-based analysis step, its name, the simulated cycle within it, and the load cycles
    /// of the step completed at the mark (counting those a wear jump stands for).
    pub analysis_step: usize,
    pub name: String,
    pub cycle: usize,
    pub cycles: f64,
    pub total: Energy,
}

/// Number of values of [`EnergyMark::to_row`].
const MARK_VALUES: usize = 11;

impl EnergyMark {
    /// The mark of an output frame with the run's energy `total`, if the frame ends a
    /// cycle. A frame the load history has not placed (analysis step 0) is a step of its own.
    pub fn at(frame: &Frame, step: usize, total: Energy) -> Option<Self> {
        let (analysis_step, cycle, cycles, end) = if frame.analysis_step == 0 {
            (step, 1, 1.0, true)
        } else {
            (
                frame.analysis_step,
                frame.cycle,
                frame.cycles,
                frame.cycle_end,
            )
        };
        end.then(|| Self {
            analysis_step,
            name: step_name(analysis_step),
            cycle,
            cycles,
            total,
        })
    }

    /// The mark as numbers (for a restart record): step, cycle, cycles, then the totals.
    pub fn to_row(&self) -> Vec<f64> {
        let t = &self.total;
        vec![
            self.analysis_step as f64,
            self.cycle as f64,
            self.cycles,
            t.external_work,
            t.elastic_energy,
            t.interface_energy,
            t.plastic_dissipation,
            t.friction_dissipation,
            t.wear_work,
            t.numerical_dissipation,
            t.thermal_work,
        ]
    }

    /// The mark of a row of [`Self::to_row`]; `None` if it has the wrong length.
    pub fn from_row(row: &[f64]) -> Option<Self> {
        let v: &[f64; MARK_VALUES] = row.try_into().ok()?;
        let analysis_step = v[0] as usize;
        Some(Self {
            analysis_step,
            name: step_name(analysis_step),
            cycle: v[1] as usize,
            cycles: v[2],
            total: Energy {
                external_work: v[3],
                elastic_energy: v[4],
                interface_energy: v[5],
                plastic_dissipation: v[6],
                friction_dissipation: v[7],
                wear_work: v[8],
                numerical_dissipation: v[9],
                thermal_work: v[10],
            },
        })
    }
}

/// The default name of analysis step `n` (`[[step]] name`'s default).
fn step_name(n: usize) -> String {
    format!("step-{n}")
}

/// The energy balance of a run, from the totals at the end of each load cycle. Written as
/// `{ "total": {...}, "steps": [...], "cycles": [...] }`: the totals, and per step and per
/// cycle the work and dissipation done in it and the change of the stored energies, each
/// with its imbalance (absolute and relative to |external work|).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EnergyReport {
    /// The marks of the converged cycle ends, in order.
    pub marks: Vec<EnergyMark>,
    /// The names of the analysis steps (`[[step]] name`), in order; a step without one is
    /// reported by its mark's name.
    pub step_names: Vec<String>,
}

/// Energy terms with their imbalance, as written.
#[derive(Serialize)]
struct Terms {
    external_work: f64,
    elastic_energy: f64,
    interface_energy: f64,
    plastic_dissipation: f64,
    friction_dissipation: f64,
    wear_work: f64,
    numerical_dissipation: f64,
    thermal_work: f64,
    imbalance: f64,
    relative_imbalance: Option<f64>,
}

impl From<Energy> for Terms {
    fn from(e: Energy) -> Self {
        Self {
            external_work: e.external_work,
            elastic_energy: e.elastic_energy,
            interface_energy: e.interface_energy,
            plastic_dissipation: e.plastic_dissipation,
            friction_dissipation: e.friction_dissipation,
            wear_work: e.wear_work,
            numerical_dissipation: e.numerical_dissipation,
            thermal_work: e.thermal_work,
            imbalance: e.imbalance(),
            relative_imbalance: e.relative_imbalance(),
        }
    }
}

#[derive(Serialize)]
struct StepEnergy<'a> {
    name: &'a str,
    analysis_step: usize,
    #[serde(flatten)]
    terms: Terms,
}

#[derive(Serialize)]
struct CycleEnergy {
    analysis_step: usize,
    cycle: usize,
    cycles: f64,
    #[serde(flatten)]
    terms: Terms,
}

#[derive(Serialize)]
struct EnergyJson<'a> {
    total: Terms,
    steps: Vec<StepEnergy<'a>>,
    cycles: Vec<CycleEnergy>,
}

impl EnergyReport {
    /// Records the end of a cycle.
    pub fn push(&mut self, mark: EnergyMark) {
        self.marks.push(mark);
    }

    /// The totals at the last mark (zero before the first).
    pub fn total(&self) -> Energy {
        self.marks.last().map(|m| m.total).unwrap_or_default()
    }

    fn json(&self) -> EnergyJson<'_> {
        let mut steps: Vec<StepEnergy> = Vec::new();
        let mut cycles = Vec::with_capacity(self.marks.len());
        let (mut cycle_start, mut step_start) = (Energy::default(), Energy::default());
        for (i, mark) in self.marks.iter().enumerate() {
            cycles.push(CycleEnergy {
                analysis_step: mark.analysis_step,
                cycle: mark.cycle,
                cycles: mark.cycles,
                terms: (mark.total - cycle_start).into(),
            });
            cycle_start = mark.total;
            let step_ends = self
                .marks
                .get(i + 1)
                .is_none_or(|next| next.analysis_step != mark.analysis_step);
            if step_ends {
                let name = self.step_names.get(mark.analysis_step.wrapping_sub(1));
                steps.push(StepEnergy {
                    name: name.unwrap_or(&mark.name),
                    analysis_step: mark.analysis_step,
                    terms: (mark.total - step_start).into(),
                });
                step_start = mark.total;
            }
        }
        EnergyJson {
            total: self.total().into(),
            steps,
            cycles,
        }
    }
}

impl Serialize for EnergyReport {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        self.json().serialize(serializer)
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
            energy: EnergyReport::default(),
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
        self.status = match error {
            crate::Error::Interrupted { .. } => Status::Interrupted,
            _ => Status::Failed,
        };
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
                p.describe(),
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

    fn energy(work: f64, elastic: f64, friction: f64) -> Energy {
        Energy {
            external_work: work,
            elastic_energy: elastic,
            friction_dissipation: friction,
            ..Energy::default()
        }
    }

    fn frame(analysis_step: usize, cycle: usize, cycle_end: bool) -> Frame {
        Frame {
            analysis_step,
            cycle,
            cycles: cycle as f64,
            step_time: 1.0,
            cycle_end,
        }
    }

    /// Steps and cycles get the differences of the totals at their ends; the stored energy
    /// its change, so each entry balances on its own.
    #[test]
    fn energy_is_split_by_step_and_cycle() {
        let mut report = EnergyReport::default();
        let frames = [
            (frame(1, 1, true), energy(10.0, 10.0, 0.0)),
            (frame(2, 1, false), energy(12.0, 11.0, 0.5)),
            (frame(2, 1, true), energy(13.0, 10.0, 3.0)),
            (frame(2, 2, true), energy(16.0, 10.0, 6.0)),
        ];
        for (i, (f, e)) in frames.iter().enumerate() {
            if let Some(mark) = EnergyMark::at(f, i + 1, *e) {
                assert_eq!(EnergyMark::from_row(&mark.to_row()), Some(mark.clone()));
                report.push(mark);
            }
        }
        let v = serde_json::to_value(&report).unwrap();
        assert_eq!(v["total"]["external_work"], 16.0);
        assert_eq!(v["total"]["imbalance"], 0.0);
        assert_eq!(v["steps"].as_array().unwrap().len(), 2);
        assert_eq!(v["steps"][1]["name"], "step-2");
        assert_eq!(v["steps"][1]["external_work"], 6.0);
        assert_eq!(v["steps"][1]["elastic_energy"], 0.0);
        assert_eq!(v["steps"][1]["friction_dissipation"], 6.0);
        let cycles = v["cycles"].as_array().unwrap();
        assert_eq!(cycles.len(), 3);
        assert_eq!(cycles[2]["cycle"], 2);
        assert_eq!(cycles[2]["external_work"], 3.0);
        assert_eq!(cycles[1]["elastic_energy"], 0.0);
        assert_eq!(cycles[1]["relative_imbalance"], 0.0);
    }

    /// Output steps of a case whose frames are not placed in a load history count as
    /// analysis steps of their own.
    #[test]
    fn unplaced_frames_are_steps() {
        let mark = EnergyMark::at(&Frame::default(), 3, energy(1.0, 0.5, 0.0)).unwrap();
        assert_eq!(
            (mark.analysis_step, mark.cycle, mark.name.as_str()),
            (3, 1, "step-3")
        );
        let value = serde_json::to_value(EnergyReport {
            marks: vec![mark],
            step_names: Vec::new(),
        })
        .unwrap();
        assert_eq!(value["total"]["relative_imbalance"], 0.5);
    }
}
