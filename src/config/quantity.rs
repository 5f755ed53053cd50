//! Quantities of interest (`[[quantity]]` in a case file, `--quantity` on the command line):
//! what a study measures at the end of the last step, and how it is checked.

use schemars::JsonSchema;
use serde::Deserialize;

use super::{Case, ContactSpec};

/// A quantity of interest of a mesh-convergence study (`[[quantity]]`, or `--quantity` on the
/// command line of `asperity converge`), evaluated at the end of the last step. Which of the
/// optional keys a kind needs is checked by [`QuantitySpec::check`].
#[derive(Clone, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct QuantitySpec {
    /// Name in tables and files: letters, digits, `_`, `-`, `.`.
    pub name: String,
    pub kind: QuantityKind,
    /// `reaction`: the support (its `name`, its group when one support holds it, or `axis`).
    pub support: Option<String>,
    /// `displacement`: a physical point group (the mean over its nodes).
    pub point: Option<String>,
    /// `node_displacement`: the node's tag in the mesh file (gmsh's node number).
    pub node: Option<u64>,
    /// `twist`: a physical curve or point (the mean u_θ / r over its nodes off the axis).
    pub group: Option<String>,
    /// Contact kinds: the pair's name.
    pub pair: Option<String>,
    /// `"x"` (alias `"r"`) or `"y"` (alias `"z"`).
    pub component: Option<Component>,
    /// `contact_pressure`: `"peak"`, `"mean"` or `"at"` (with `x` or `y`).
    pub statistic: Option<Statistic>,
    /// `statistic = "at"`: the coordinate where the pressure is read.
    pub x: Option<f64>,
    /// `statistic = "at"`: the coordinate where the pressure is read (instead of `x`).
    pub y: Option<f64>,
    /// The exact value, if known.
    pub reference: Option<f64>,
    /// Relative tolerance on the change between the two finest levels and on the distance
    /// of the finest level to `reference` (default 1e-3).
    #[serde(default = "default_quantity_tolerance")]
    pub tolerance: f64,
    /// Smallest acceptable observed order of convergence (from the successive differences of
    /// the three finest levels).
    pub min_order: Option<f64>,
}

fn default_quantity_tolerance() -> f64 {
    1e-3
}

/// What a [`QuantitySpec`] measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum QuantityKind {
    /// Reaction force of a support (N; axisymmetry: total over the circle).
    Reaction,
    /// Displacement of a physical point (mm).
    Displacement,
    /// Contact pressure −p_N of a pair (MPa): peak, area-weighted mean, or at a coordinate.
    ContactPressure,
    /// Length of the sticking part of a pair (mm, measured along side B).
    #[serde(alias = "stick_length")]
    StickZone,
    /// Length of the slipping part of a pair (mm, along side B).
    SlipLength,
    /// Length of the open (separated) part of a pair (mm, along side B).
    OpenLength,
    /// Area of a pair in contact, stick or slip (mm²: length × thickness in a plane analysis,
    /// ∫ 2πr dl in axisymmetry; Abaqus' CAREA).
    ContactArea,
    /// Largest accumulated slip over the integration points of a pair (mm).
    MaxSlip,
    /// Displacement of one node, given by its tag in the mesh file (mm).
    NodeDisplacement,
    /// Mean relative displacement (body B minus body A) of a pair over its length (mm).
    RelativeDisplacement,
    /// Secant stiffness of a pair, −F / ū in one direction (N/mm): F the force body A exerts on
    /// body B, ū the mean relative displacement.
    Stiffness,
    /// Twist angle of a physical curve or point about the axis: the mean of u_θ / r over its
    /// nodes off the axis (radians; axisymmetric analyses with twist only).
    Twist,
}

impl QuantityKind {
    /// The kind as written in case files.
    pub fn as_str(self) -> &'static str {
        match self {
            QuantityKind::Reaction => "reaction",
            QuantityKind::Displacement => "displacement",
            QuantityKind::ContactPressure => "contact_pressure",
            QuantityKind::StickZone => "stick_zone",
            QuantityKind::SlipLength => "slip_length",
            QuantityKind::OpenLength => "open_length",
            QuantityKind::ContactArea => "contact_area",
            QuantityKind::MaxSlip => "max_slip",
            QuantityKind::NodeDisplacement => "node_displacement",
            QuantityKind::RelativeDisplacement => "relative_displacement",
            QuantityKind::Stiffness => "stiffness",
            QuantityKind::Twist => "twist",
        }
    }
}

/// A global displacement or force component.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[schemars(extend("enum" = ["x", "y", "r", "z"]))]
pub enum Component {
    #[serde(rename = "x", alias = "r")]
    X,
    #[serde(rename = "y", alias = "z")]
    Y,
}

impl Component {
    /// 0 for x, 1 for y.
    pub fn index(self) -> usize {
        self as usize
    }
}

/// Which value of the contact pressure along a pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Statistic {
    /// The largest nodal value.
    Peak,
    /// ∫ p dA / ∫ dA over the whole pair.
    Mean,
    /// Linear interpolation between the nodes at the coordinate `x` or `y`.
    At,
}

impl QuantitySpec {
    /// Checks the keys of the quantity against its kind and the names against `case`
    /// (supports and contact pairs; point groups are checked against the mesh later).
    pub fn check(&self, case: &Case) -> std::result::Result<(), String> {
        let name = &self.name;
        let head = format!("quantity '{name}' ({})", self.kind.as_str());
        if name.is_empty()
            || !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c))
        {
            return Err(format!(
                "quantity '{name}': a name needs letters, digits, '_', '-' or '.' only"
            ));
        }
        let given = [
            ("support", self.support.is_some()),
            ("point", self.point.is_some()),
            ("node", self.node.is_some()),
            ("group", self.group.is_some()),
            ("pair", self.pair.is_some()),
            ("component", self.component.is_some()),
            ("statistic", self.statistic.is_some()),
            ("x", self.x.is_some()),
            ("y", self.y.is_some()),
        ];
        let needed: &[&str] = match self.kind {
            QuantityKind::Reaction => &["support", "component"],
            QuantityKind::Displacement => &["point", "component"],
            QuantityKind::ContactPressure => &["pair", "statistic"],
            QuantityKind::StickZone
            | QuantityKind::SlipLength
            | QuantityKind::OpenLength
            | QuantityKind::ContactArea
            | QuantityKind::MaxSlip => &["pair"],
            QuantityKind::NodeDisplacement => &["node", "component"],
            QuantityKind::RelativeDisplacement | QuantityKind::Stiffness => &["pair", "component"],
            QuantityKind::Twist => &["group"],
        };
        if self.kind == QuantityKind::Twist && !case.analysis.has_twist() {
            return Err(format!(
                "{head}: the twist angle needs an axisymmetric analysis with twist ([analysis] \
                 type = \"axisymmetric\", twist = true)"
            ));
        }
        let at = self.statistic == Some(Statistic::At);
        for (key, present) in given {
            let coordinate = key == "x" || key == "y";
            if needed.contains(&key) && !present {
                return Err(format!("{head}: give `{key}`"));
            }
            if present && !needed.contains(&key) && !(coordinate && at) {
                return Err(format!("{head}: `{key}` does not apply to this kind"));
            }
        }
        if at && self.x.is_some() == self.y.is_some() {
            return Err(format!(
                "{head}: statistic \"at\" needs exactly one of `x` and `y`"
            ));
        }
        if let Some(s) = &self.support {
            let axis = case.analysis.is_axisymmetric().then_some("axis");
            let names: Vec<&str> = case.supports.iter().map(|s| s.name()).chain(axis).collect();
            let groups = case.supports.iter().filter(|g| &g.group == s).count();
            if !names.contains(&s.as_str()) && groups != 1 {
                return Err(format!(
                    "{head}: no support '{s}' (the case has: {})",
                    list(&names)
                ));
            }
        }
        if let Some(p) = &self.pair {
            let names: Vec<String> = case.contacts.iter().map(ContactSpec::name).collect();
            if !names.contains(p) {
                let names: Vec<&str> = names.iter().map(String::as_str).collect();
                return Err(format!(
                    "{head}: no contact pair '{p}' (the case has: {})",
                    list(&names)
                ));
            }
        }
        let finite = [self.x, self.y, self.reference, self.min_order];
        if finite.iter().flatten().any(|v| !v.is_finite()) {
            return Err(format!("{head}: values must be finite"));
        }
        if !(self.tolerance > 0.0 && self.tolerance.is_finite()) {
            return Err(format!("{head}: tolerance must be positive"));
        }
        Ok(())
    }
}

fn list(names: &[&str]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}
/// Parses a command-line quantity `name:kind:key=value,key=value`, e.g.
/// `u_bore:displacement:point=bore_point,component=x,reference=0.0123`. The keys are those of
/// `[[quantity]]`; `x`, `y`, `reference`, `tolerance` and `min_order` are numbers, `node` a
/// node tag.
pub fn parse_quantity(text: &str) -> std::result::Result<QuantitySpec, String> {
    let bad =
        |why: String| format!("--quantity '{text}': {why} (syntax: name:kind:key=value,key=value)");
    let mut parts = text.splitn(3, ':');
    let name = parts.next().unwrap_or_default().trim();
    let kind = parts.next().ok_or_else(|| bad("no kind".into()))?.trim();
    let mut table = toml::Table::new();
    table.insert("name".into(), toml::Value::String(name.into()));
    table.insert("kind".into(), toml::Value::String(kind.into()));
    for item in parts.next().unwrap_or_default().split(',') {
        if item.trim().is_empty() {
            continue;
        }
        let (key, value) = item
            .split_once('=')
            .ok_or_else(|| bad(format!("'{item}' is not key=value")))?;
        let (key, value) = (key.trim(), value.trim());
        let value = if key == "node" {
            toml::Value::Integer(
                value
                    .parse()
                    .map_err(|_| bad(format!("node = '{value}' is not a node tag")))?,
            )
        } else if ["x", "y", "reference", "tolerance", "min_order"].contains(&key) {
            toml::Value::Float(
                value
                    .parse()
                    .map_err(|_| bad(format!("{key} = '{value}' is not a number")))?,
            )
        } else {
            toml::Value::String(value.into())
        };
        if table.insert(key.into(), value).is_some() {
            return Err(bad(format!("`{key}` is given twice")));
        }
    }
    serde::Deserialize::deserialize(toml::Value::Table(table)).map_err(|e: toml::de::Error| {
        bad(crate::error::shorten_numbers(e.to_string().trim()).replace('\n', " "))
    })
}
