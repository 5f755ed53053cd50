//! `law` of a `[[contact]]`: `law = { type = "rough_joint", c_n = 2e-3, ... }`, read and
//! described (for `asperity schema`) from the table of interface laws
//! ([`crate::contact::laws`]), which declares every law's parameters, defaults, bounds and
//! documentation once.

use std::borrow::Cow;
use std::fmt;

use schemars::{JsonSchema, Schema, SchemaGenerator};
use serde::de::{Error as _, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};
use serde_json::{Value, json};

use crate::contact::laws::{LAWS, LawDescriptor, ParameterDefault};

/// The interface law of a contact pair and its parameters.
#[derive(Clone, Debug)]
pub struct LawSpec {
    /// Which law (`type`).
    pub law: &'static LawDescriptor,
    /// The value of each of the law's parameters, in the order of its table, defaults filled
    /// in; `None`: an optional parameter not given.
    pub values: Vec<Option<f64>>,
}

impl LawSpec {
    /// The value of parameter `key` (`None`: not given and without default, or not a
    /// parameter of this law).
    pub fn get(&self, key: &str) -> Option<f64> {
        self.law.index(key).and_then(|i| self.values[i])
    }

    /// The values as the law's builder takes them (NaN: not given).
    pub fn numbers(&self) -> Vec<f64> {
        self.values.iter().map(|v| v.unwrap_or(f64::NAN)).collect()
    }
}

/// serde's wording of a list of expected names: "`a`", "`a` or `b`", "one of `a`, `b`, `c`".
fn one_of(names: &[&str]) -> String {
    let quoted: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
    match quoted.as_slice() {
        [one] => one.clone(),
        [a, b] => format!("{a} or {b}"),
        _ => format!("one of {}", quoted.join(", ")),
    }
}

impl<'de> Deserialize<'de> for LawSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_map(LawVisitor)
    }
}

struct LawVisitor;

impl<'de> Visitor<'de> for LawVisitor {
    type Value = LawSpec;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("an interface law: a table with `type` and the law's parameters")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<LawSpec, A::Error> {
        let mut law: Option<&'static LawDescriptor> = None;
        let mut given: Vec<(String, f64)> = Vec::new();
        while let Some(key) = map.next_key::<String>()? {
            if key == "type" {
                law = Some(map.next_value()?);
            } else {
                let value = map.next_value()?;
                given.push((key, value));
            }
        }
        let law = law.ok_or_else(|| A::Error::missing_field("type"))?;
        let mut values: Vec<Option<f64>> = vec![None; law.parameters.len()];
        for (key, value) in given {
            let Some(i) = law.index(&key) else {
                let keys: Vec<&str> = law.parameters.iter().map(|p| p.key).collect();
                return Err(A::Error::custom(format!(
                    "unknown field `{key}`, expected {}",
                    one_of(&keys)
                )));
            };
            if values[i].replace(value).is_some() {
                return Err(A::Error::duplicate_field(law.parameters[i].key));
            }
        }
        for (p, value) in law.parameters.iter().zip(&mut values) {
            if value.is_none() {
                match p.default {
                    ParameterDefault::Required => return Err(A::Error::missing_field(p.key)),
                    ParameterDefault::Value(v) => *value = Some(v),
                    ParameterDefault::Optional | ParameterDefault::Penalty => {}
                }
            }
        }
        Ok(LawSpec { law, values })
    }
}

impl JsonSchema for LawSpec {
    fn schema_name() -> Cow<'static, str> {
        "LawSpec".into()
    }

    /// One object per law of the table: its `type`, its parameters with their documentation,
    /// defaults and bounds, the required ones, nothing else.
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        let laws: Vec<Value> = LAWS.iter().map(|law| law_schema(law)).collect();
        let schema = json!({
            "description": "The interface law of a contact pair and its parameters.",
            "oneOf": laws,
        });
        Schema::try_from(schema).expect("an object is a schema")
    }
}

/// The schema of one law's table.
fn law_schema(law: &LawDescriptor) -> Value {
    let mut properties = serde_json::Map::new();
    properties.insert(
        "type".into(),
        json!({ "type": "string", "const": law.name }),
    );
    let mut required = vec![Value::from("type")];
    for p in law.parameters {
        let mut property = json!({
            "description": p.doc,
            "type": "number",
            "format": "double",
        });
        match p.default {
            ParameterDefault::Required => required.push(p.key.into()),
            ParameterDefault::Value(v) => property["default"] = v.into(),
            ParameterDefault::Optional | ParameterDefault::Penalty => {
                property["type"] = json!(["number", "null"])
            }
        }
        let ((lower, exclusive), upper) = p.bound.limits();
        let minimum = if exclusive {
            "exclusiveMinimum"
        } else {
            "minimum"
        };
        property[minimum] = lower.into();
        if let Some(upper) = upper {
            property["maximum"] = upper.into();
        }
        properties.insert(p.key.into(), property);
    }
    json!({
        "description": law.doc,
        "type": "object",
        "properties": properties,
        "additionalProperties": false,
        "required": required,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law(text: &str) -> Result<LawSpec, toml::de::Error> {
        let table: toml::Table = toml::from_str(&format!("law = {text}")).unwrap();
        table["law"].clone().try_into()
    }

    #[test]
    fn a_law_reads_its_parameters_and_fills_in_defaults() {
        let spec =
            law("{ type = \"rough_joint\", c_n = 2e-3, m = 0.5, R = 1, mu_m = 0.3 }").unwrap();
        assert_eq!(spec.law.name, "rough_joint");
        let expected = [
            2e-3,
            0.5,
            f64::NAN,
            f64::NAN,
            1.0,
            f64::NAN,
            0.3,
            1.0,
            0.0,
            0.1,
        ];
        let numbers = spec.numbers();
        assert!(
            numbers
                .iter()
                .zip(expected)
                .all(|(a, b)| a == &b || (a.is_nan() && b.is_nan())),
            "{numbers:?}"
        );
        assert_eq!((spec.get("S"), spec.get("beta")), (None, Some(1.0)));
    }

    #[test]
    fn unknown_and_missing_keys_are_named() {
        for (text, expected) in [
            (
                "{ type = \"linear_coulomb\", normal_stiffness = 1, tangential_stiffness = 1, mu = 0.2 }",
                "unknown field `mu`, expected one of `normal_stiffness`, `tangential_stiffness`, `friction`",
            ),
            ("{ type = \"rough_joint\", c_n = 1 }", "missing field `m`"),
            ("{ normal_stiffness = 1 }", "missing field `type`"),
            (
                "{ type = \"coulomb\" }",
                "unknown variant `coulomb`, expected `linear_coulomb` or `rough_joint`",
            ),
        ] {
            let message = law(text).unwrap_err().to_string();
            assert!(message.contains(expected), "{message}");
        }
    }
}
