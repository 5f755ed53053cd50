//! A fit through a full model: the specimen's case file is solved with the law of one of its
//! contact pairs set to the trial parameters, and a quantity of each step's `summary.json`
//! entry (a dotted path such as `reactions.top.y`) is compared with the measured values of the
//! steps listed in the data. The mesh is read (or meshed by gmsh) once; each evaluation runs in
//! its own temporary folder, so the Jacobian's columns run as independent solves in parallel.
//! A penalty stiffness the fitted law leaves out is fixed once, at the default the fitted
//! contact gets on the specimen's mesh (10 E*/h), and given explicitly to every evaluation.

use std::path::Path;

use crate::config::Case;
use crate::contact::laws::LawDescriptor;
use crate::mesh::Mesh;
use crate::model::{Model, ModelSpec, PenaltyDefault};
use crate::run::{
    self,
    folder::{OutputFolder, RunFile},
};
use crate::sweep::keys;
use crate::{Error, Result};

/// The specimen, ready to be solved with other law parameters.
#[derive(Debug)]
pub struct Specimen {
    /// The case as a TOML tree (the law's keys are replaced per evaluation).
    tree: toml::Value,
    case: Case,
    contact: usize,
    quantity: String,
    /// 0-based step indices, one per measured value.
    steps: Vec<usize>,
    mesh: Mesh,
    /// The default penalty stiffness of the fitted contact, when the fitted law leaves one
    /// out ([`Self::fix_penalty`]): the value every evaluation gives it.
    pub penalty: Option<PenaltyDefault>,
}

impl Specimen {
    /// Reads case `path` and checks the contact index and the measured `steps` (read from
    /// `data`).
    pub fn new(
        path: &Path,
        contact: usize,
        quantity: &str,
        steps: &[f64],
        data: &Path,
    ) -> Result<Self> {
        let text = crate::config::read_input(path)?;
        let mut case = Case::from_toml(&text, path)?;
        if contact >= case.contacts.len() {
            return Err(case.invalid(
                "contact",
                contact,
                format!(
                    "the specimen has {} [[contact]] sections",
                    case.contacts.len()
                ),
            ));
        }
        let n = case.frames();
        let steps = steps
            .iter()
            .enumerate()
            .map(|(row, s)| {
                let k = s.round();
                if k >= 1.0 && k <= n as f64 && k == *s {
                    Ok(k as usize - 1)
                } else {
                    Err(Error::InvalidParameter {
                        path: data.to_path_buf(),
                        key: format!("column 'step', row {}", row + 1),
                        value: s.to_string(),
                        reason: format!(
                            "must be a step number from 1 to {n} (the output steps of {})",
                            path.display()
                        ),
                    })
                }
            })
            .collect::<Result<Vec<_>>>()?;
        case.output.vtu = false;
        let tmp = tempfile::tempdir().map_err(|e| Error::io(std::env::temp_dir(), e))?;
        let mesh = run::load_mesh(&case, &OutputFolder::scratch(tmp.path())?)?.0;
        let tree = toml::from_str(&text).map_err(|e| Error::toml(path, &e))?;
        Ok(Self {
            tree,
            case,
            contact,
            quantity: quantity.to_string(),
            steps,
            mesh,
            penalty: None,
        })
    }

    /// Fixes the penalty stiffnesses the law `kind` at the starting values `x` leaves out at
    /// the default the fitted contact gets on the specimen's mesh, from the model built once
    /// here: it depends on the bodies and the mesh only, so the whole fit keeps it.
    pub fn fix_penalty(&mut self, x: &[f64], kind: &LawDescriptor) -> Result<()> {
        if !kind.defaults_penalty(x) {
            return Ok(());
        }
        let case = self.case_with(x, kind)?;
        let model = Model::build(self.mesh.clone(), ModelSpec::new(&case)?)?;
        let name = &model.interface.pairs[self.contact].name;
        self.penalty = model
            .penalty_defaults
            .into_iter()
            .find(|d| &d.contact == name);
        Ok(())
    }

    /// The case with the fitted law (`kind`, parameters `x` in its order; NaN: left out).
    fn case_with(&self, x: &[f64], kind: &LawDescriptor) -> Result<Case> {
        let mut law = toml::Table::new();
        law.insert("type".into(), toml::Value::String(kind.name.into()));
        let names = kind.parameters.iter().map(|p| p.key);
        for (name, v) in names.zip(x).filter(|(_, v)| !v.is_nan()) {
            law.insert(name.to_string(), toml::Value::Float(*v));
        }
        let mut tree = self.tree.clone();
        keys::set(
            &mut tree,
            &format!("contact.{}.law", self.contact),
            toml::Value::Table(law),
        )
        .map_err(|message| Error::Case {
            path: self.case.path.clone(),
            message,
        })?;
        let mut case = Case::from_toml(
            &toml::to_string(&tree).expect("a TOML tree serialises"),
            &self.case.path,
        )?;
        case.output.vtu = false;
        Ok(case)
    }

    /// The quantity at the measured steps with the law's parameters `x`.
    pub fn simulate(&self, x: &[f64], kind: &LawDescriptor) -> Result<Vec<f64>> {
        let case = match &self.penalty {
            Some(penalty) => self.case_with(&kind.with_penalty(x, penalty.stiffness), kind)?,
            None => self.case_with(x, kind)?,
        };
        let tmp = tempfile::tempdir().map_err(|e| Error::io(std::env::temp_dir(), e))?;
        let folder = OutputFolder::scratch(tmp.path())?;
        run::run_mesh(
            &case,
            self.mesh.clone(),
            run::MeshTime::default(),
            &folder,
            false,
            |_, _| Ok(()),
        )?;
        let file = folder.dir().join(RunFile::Summary.name());
        let text = std::fs::read_to_string(&file).map_err(|e| Error::io(&file, e))?;
        let summary: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| Error::External(e.to_string()))?;
        self.steps
            .iter()
            .map(|k| {
                let key = format!("steps.{k}.{}", self.quantity);
                keys::get_json(&summary, &key)
                    .and_then(serde_json::Value::as_f64)
                    .ok_or_else(|| Error::Quantity {
                        name: self.quantity.clone(),
                        reason: format!(
                            "summary.json of {} has no number at `{key}`",
                            self.case.path.display()
                        ),
                    })
            })
            .collect()
    }
}
