//! One way to write case files in tests and benches: [`CaseBuilder`] assembles a case as TOML
//! data, section by section, and turns it into a [`Case`], a model or a solved model. Shared
//! by the integration tests (`tests/common`) and the benches (`benches/common`).
#![allow(dead_code)]

use std::path::Path;

use asperity::config::Case;
use asperity::mesh::Mesh;
use asperity::model::{Model, ModelSpec};
use asperity::solver::newton::NewtonSettings;
use toml::{Table, Value};

/// A case file under construction. The mesh section is a placeholder: tests and benches hand
/// the mesh to the model directly.
#[derive(Clone, Debug)]
pub struct CaseBuilder {
    root: Table,
}

/// A TOML table from key-value pairs.
pub fn table(entries: &[(&str, Value)]) -> Table {
    entries
        .iter()
        .map(|(k, v)| (k.to_string(), v.clone()))
        .collect()
}

/// A list of numbers.
pub fn list(values: &[f64]) -> Value {
    Value::from(values.to_vec())
}

/// A linear-elastic material.
pub fn elastic(e: f64, nu: f64) -> Table {
    table(&[("E", e.into()), ("nu", nu.into())])
}

/// `table` with the numeric `keys` added (a material's plastic parameters, say).
pub fn with_keys(mut table: Table, keys: &[(&str, f64)]) -> Table {
    for (k, v) in keys {
        table.insert(k.to_string(), (*v).into());
    }
    table
}

/// The linear Coulomb interface law.
pub fn linear_coulomb(normal_stiffness: f64, tangential_stiffness: f64, friction: f64) -> Table {
    table(&[
        ("type", "linear_coulomb".into()),
        ("normal_stiffness", normal_stiffness.into()),
        ("tangential_stiffness", tangential_stiffness.into()),
        ("friction", friction.into()),
    ])
}

/// The rough-joint law (Buczkowski & Kleiber (1994), Eqs. 1–5) with the given parameters
/// (c_n, m, R, S, mu_m, ...).
pub fn rough_joint(parameters: &[(&str, f64)]) -> Table {
    with_keys(table(&[("type", "rough_joint".into())]), parameters)
}

/// The rough joint used by the sliding-block tests and benches: power-law compliance,
/// pressure-dependent shear stiffness and slip-hardening friction.
pub fn sliding_rough_joint() -> Table {
    rough_joint(&[
        ("c_n", 1e-4),
        ("m", 0.5),
        ("R", 1e-3),
        ("S", 0.5),
        ("mu_m", 0.3),
        ("beta", 0.3),
        ("n", 100.0),
    ])
}

impl CaseBuilder {
    fn new(analysis: Table) -> Self {
        let mut root = Table::new();
        root.insert(
            "mesh".into(),
            table(&[("file", "generated.msh".into())]).into(),
        );
        root.insert("analysis".into(), analysis.into());
        Self { root }
    }

    /// A plane-strain case (thickness 1).
    pub fn plane_strain() -> Self {
        Self::new(table(&[("type", "plane_strain".into())]))
    }

    /// A plane-stress case of thickness `thickness`.
    pub fn plane_stress(thickness: f64) -> Self {
        Self::new(table(&[
            ("type", "plane_stress".into()),
            ("thickness", thickness.into()),
        ]))
    }

    /// An axisymmetric case.
    pub fn axisymmetric() -> Self {
        Self::new(table(&[("type", "axisymmetric".into())]))
    }

    /// Appends a table to the array of tables `name` (`[[name]]`).
    pub fn push(mut self, name: &str, entry: Table) -> Self {
        let array = self
            .root
            .entry(name)
            .or_insert_with(|| Value::Array(Vec::new()));
        array
            .as_array_mut()
            .expect("an array of tables")
            .push(entry.into());
        self
    }

    /// Sets `key` of the last table of the array `name` (e.g. a key of the contact pair
    /// pushed last).
    pub fn set_last(mut self, name: &str, key: &str, value: impl Into<Value>) -> Self {
        let last = self
            .root
            .get_mut(name)
            .and_then(Value::as_array_mut)
            .and_then(|array| array.last_mut())
            .and_then(Value::as_table_mut)
            .unwrap_or_else(|| panic!("no [[{name}]] to set `{key}` in"));
        last.insert(key.into(), value.into());
        self
    }

    /// The mesh section: the MSH file at `path`.
    pub fn mesh_file(mut self, path: &Path) -> Self {
        let mesh = table(&[("file", path.display().to_string().into())]);
        self.root.insert("mesh".into(), mesh.into());
        self
    }

    /// The mesh section: the gmsh script at `path`, meshed with element size `size`.
    pub fn mesh_geo(mut self, path: &Path, size: f64) -> Self {
        let mesh = table(&[
            ("geo", path.display().to_string().into()),
            ("size", size.into()),
        ]);
        self.root.insert("mesh".into(), mesh.into());
        self
    }

    /// Sets `key` of the table `section` (`[section]`).
    pub fn set(mut self, section: &str, key: &str, value: impl Into<Value>) -> Self {
        let table = self
            .root
            .entry(section)
            .or_insert_with(|| Value::Table(Table::new()));
        table
            .as_table_mut()
            .expect("a table")
            .insert(key.into(), value.into());
        self
    }

    /// A body: the physical surface `group` of `material` ([`elastic`], or more keys).
    pub fn body(self, group: &str, material: Table) -> Self {
        self.push(
            "body",
            table(&[("group", group.into()), ("material", material.into())]),
        )
    }

    /// A body with an explicit element `formulation` ("full", "bbar").
    pub fn body_with(self, group: &str, material: Table, formulation: &str) -> Self {
        self.push(
            "body",
            table(&[
                ("group", group.into()),
                ("material", material.into()),
                ("formulation", formulation.into()),
            ]),
        )
    }

    /// A support of `group` prescribing `components` (`("ux", 0.0)`, `("uz", 0.0)`, ...).
    pub fn support(self, group: &str, components: &[(&str, f64)]) -> Self {
        self.push("support", with_group(group, components, None))
    }

    /// A support with its own history: one factor per step.
    pub fn support_history(self, group: &str, components: &[(&str, f64)], factors: &[f64]) -> Self {
        self.push("support", with_group(group, components, Some(factors)))
    }

    /// A normal pressure on the curve `group`.
    pub fn pressure(self, group: &str, pressure: f64) -> Self {
        self.push("load", with_group(group, &[("pressure", pressure)], None))
    }

    /// A normal pressure with its own history.
    pub fn pressure_history(self, group: &str, pressure: f64, factors: &[f64]) -> Self {
        let load = with_group(group, &[("pressure", pressure)], Some(factors));
        self.push("load", load)
    }

    /// A traction vector on the curve `group`.
    pub fn traction(self, group: &str, traction: [f64; 2]) -> Self {
        let mut load = with_group(group, &[], None);
        load.insert("traction".into(), list(&traction));
        self.push("load", load)
    }

    /// A contact pair: its faces and other keys (`side_a`, `side_b`, `pairing`,
    /// `interference`, ...) and its law.
    pub fn contact(self, keys: &[(&str, Value)], law: Table) -> Self {
        let mut contact = table(keys);
        contact.insert("law".into(), law.into());
        self.push("contact", contact)
    }

    /// `count` equal load steps.
    pub fn steps(self, count: i64) -> Self {
        self.set("steps", "count", count)
    }

    /// Load steps with explicit factors.
    pub fn step_factors(self, factors: &[f64]) -> Self {
        self.set("steps", "factors", list(factors))
    }

    /// The case file's text.
    pub fn text(&self) -> String {
        toml::to_string(&self.root).expect("a case serialises")
    }

    /// Writes the case file to `path` and returns the path.
    pub fn write(&self, path: &Path) -> std::path::PathBuf {
        std::fs::write(path, self.text()).expect("the case file is written");
        path.to_path_buf()
    }

    /// The case, or why it is not valid.
    pub fn try_case(&self) -> asperity::Result<Case> {
        Case::from_toml(&self.text(), Path::new("test.toml"))
    }

    /// The (valid) case.
    pub fn case(&self) -> Case {
        self.try_case().expect("valid test case")
    }
}

fn with_group(group: &str, values: &[(&str, f64)], factors: Option<&[f64]>) -> Table {
    let mut t = table(&[("group", group.into())]);
    for (k, v) in values {
        t.insert(k.to_string(), (*v).into());
    }
    if let Some(f) = factors {
        t.insert("factors".into(), list(f));
    }
    t
}

/// The block on a base of the sliding tests and benches (plane strain; groups `base`,
/// `block`, `ground`, `base_top`, `block_bottom`, `block_top`): both bodies elastic (E, ν),
/// the base held on the ground, and the contact pair `base_top`–`block_bottom` with `law`
/// (and the pair's other `keys`, e.g. its name).
pub fn block_on_base(e: f64, nu: f64, keys: &[(&str, Value)], law: Table) -> CaseBuilder {
    let mut faces = vec![
        ("side_a", "base_top".into()),
        ("side_b", "block_bottom".into()),
    ];
    faces.extend(keys.iter().cloned());
    CaseBuilder::plane_strain()
        .body("base", elastic(e, nu))
        .body("block", elastic(e, nu))
        .support("ground", &[("ux", 0.0), ("uy", 0.0)])
        .contact(&faces, law)
}

impl CaseBuilder {
    /// The block pressed by `pressure` on its top and pushed sideways by `push`·factor, one
    /// step per factor.
    pub fn pressed_and_pushed(self, pressure: f64, push: f64, factors: &[f64]) -> Self {
        let n = factors.len();
        self.support_history("block_top", &[("ux", push)], factors)
            .pressure_history("block_top", pressure, &vec![1.0; n])
            .steps(n as i64)
    }
}

/// The model of `case` on `mesh`.
pub fn model(mesh: Mesh, case: &Case) -> asperity::Result<Model> {
    Model::build(mesh, ModelSpec::new(case)?)
}

/// The Newton settings of `case`.
pub fn settings(case: &Case) -> NewtonSettings {
    asperity::run::newton_settings(&case.solver)
}
