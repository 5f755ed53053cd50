//! Dotted key paths into a case file's TOML tree: `contact.0.law.mu_m` is the `mu_m` of the
//! law of the first `[[contact]]`, `mesh.parameters.radius` a gmsh constant. Segments that are
//! numbers index arrays (of tables). The last segment may be a key the case leaves at its
//! default, as long as its table exists; whether the key is one the case knows is checked by
//! parsing the edited tree into a [`Case`](crate::config::Case).

use toml::Value;

/// Sets `key` in `root` to `value`; the error says which segment does not exist.
pub fn set(root: &mut Value, key: &str, value: Value) -> std::result::Result<(), String> {
    let segments: Vec<&str> = key.split('.').collect();
    let (last, parents) = segments.split_last().ok_or("empty key")?;
    let mut node = root;
    for (depth, segment) in parents.iter().enumerate() {
        let here = segments[..=depth].join(".");
        node = match node {
            Value::Table(t) => t
                .get_mut(*segment)
                .ok_or_else(|| format!("the case has no `{here}`"))?,
            Value::Array(a) => {
                let len = a.len();
                let i: usize = segment
                    .parse()
                    .map_err(|_| format!("`{here}`: `{segment}` is not an index of an array"))?;
                a.get_mut(i).ok_or_else(|| {
                    format!("`{here}`: index {i} out of range (the case has {len})")
                })?
            }
            _ => return Err(format!("`{here}` is a value, not a table or array")),
        };
    }
    match node {
        Value::Table(t) => {
            t.insert(last.to_string(), value);
            Ok(())
        }
        Value::Array(a) => {
            let slot = last
                .parse::<usize>()
                .ok()
                .and_then(|i| a.get_mut(i))
                .ok_or_else(|| format!("the case has no `{key}`"))?;
            *slot = value;
            Ok(())
        }
        _ => Err(format!("`{}` is a value, not a table", parents.join("."))),
    }
}

/// The value at `key` in `root`, if there is one.
pub fn get<'v>(root: &'v Value, key: &str) -> Option<&'v Value> {
    key.split('.').try_fold(root, |node, segment| match node {
        Value::Table(t) => t.get(segment),
        Value::Array(a) => a.get(segment.parse::<usize>().ok()?),
        _ => None,
    })
}

/// The value at a dotted path into JSON (`steps.-1.reactions.top.y`: a negative index counts
/// from the end).
pub fn get_json<'v>(root: &'v serde_json::Value, key: &str) -> Option<&'v serde_json::Value> {
    key.split('.').try_fold(root, |node, segment| match node {
        serde_json::Value::Object(o) => o.get(segment),
        serde_json::Value::Array(a) => {
            let i: i64 = segment.parse().ok()?;
            let i = if i < 0 { a.len() as i64 + i } else { i };
            a.get(usize::try_from(i).ok()?)
        }
        _ => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_nested_keys_and_names_missing_ones() {
        let mut v: Value = toml::from_str("[[contact]]\nlaw = { mu_m = 0.2 }\n").unwrap();
        set(&mut v, "contact.0.law.mu_m", Value::Float(0.3)).unwrap();
        set(&mut v, "contact.0.law.n", Value::Float(5.0)).unwrap();
        assert_eq!(get(&v, "contact.0.law.mu_m"), Some(&Value::Float(0.3)));
        assert_eq!(get(&v, "contact.0.law.n"), Some(&Value::Float(5.0)));
        let e = set(&mut v, "contact.1.law.mu_m", Value::Float(0.3)).unwrap_err();
        assert!(e.contains("contact.1") && e.contains("out of range"), "{e}");
        let e = set(&mut v, "solver.max_iterations", Value::Integer(3)).unwrap_err();
        assert!(e.contains("`solver`"), "{e}");
    }

    #[test]
    fn json_paths_count_negative_indices_from_the_end() {
        let j: serde_json::Value =
            serde_json::from_str(r#"{"steps": [{"a": 1}, {"a": 2}]}"#).unwrap();
        assert_eq!(get_json(&j, "steps.-1.a"), Some(&serde_json::json!(2)));
        assert_eq!(get_json(&j, "steps.0.a"), Some(&serde_json::json!(1)));
        assert_eq!(get_json(&j, "steps.2.a"), None);
    }
}
