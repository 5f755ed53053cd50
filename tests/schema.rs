//! `asperity schema`: the JSON schema of the case file, generated from the same types the
//! case is read into. Every case file shipped with the repository (pipelines, CalculiX
//! comparison cases, the `asperity init` template) must validate against it, and the
//! mistakes a user makes (a misspelt key, a value of the wrong type, an unknown law) must not.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn schema() -> jsonschema::Validator {
    let out = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .arg("schema")
        .output()
        .expect("asperity runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let schema: Value = serde_json::from_slice(&out.stdout).expect("the schema is JSON");
    jsonschema::validator_for(&schema).expect("the schema is a valid JSON schema")
}

/// A TOML case as the JSON value an editor's TOML language server validates.
fn as_json(text: &str) -> Value {
    let value: toml::Value = toml::from_str(text).expect("valid TOML");
    serde_json::to_value(value).expect("TOML maps to JSON")
}

/// The case files of the repository: every tracked `.toml` with a `[mesh]` table.
fn shipped_cases() -> Vec<PathBuf> {
    let mut cases = Vec::new();
    let mut dirs = vec![
        repo().join("pipelines"),
        repo().join("examples"),
        repo().join("benches"),
        repo().join("templates"),
    ];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "toml")
                && std::fs::read_to_string(&path)
                    .unwrap()
                    .lines()
                    .any(|l| l.trim() == "[mesh]")
            {
                cases.push(path);
            }
        }
    }
    cases.sort();
    cases
}

fn errors(validator: &jsonschema::Validator, case: &Value) -> Vec<String> {
    validator
        .iter_errors(case)
        .map(|e| format!("{e} at {}", e.instance_path()))
        .collect()
}

#[test]
fn every_shipped_case_validates_and_is_read() {
    let validator = schema();
    let cases = shipped_cases();
    // 25 in pipelines/ and benches/ when this was written, plus the template: a search that
    // finds none would make this test vacuous.
    assert!(cases.len() >= 20, "found only {cases:?}");
    for path in &cases {
        let text = std::fs::read_to_string(path).unwrap();
        let problems = errors(&validator, &as_json(&text));
        assert!(problems.is_empty(), "{}: {problems:?}", path.display());
        // The schema and the reader agree: the reader accepts it too.
        asperity::config::Case::from_toml(&text, path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
}

/// Each edit of the template is a mistake the reader refuses; the schema must refuse it too.
#[test]
fn mistakes_are_rejected_by_the_schema_and_the_reader() {
    let validator = schema();
    let path = repo().join("templates/case.toml");
    let template = std::fs::read_to_string(&path).unwrap();
    let mistakes = [
        // misspelt key in a table
        ("thickness = 1.0", "thicknes = 1.0"),
        // misspelt key in an array of tables
        ("group = \"top\"\npressure", "group = \"top\"\npresure"),
        // misspelt key inside an inline law table
        ("friction = 0.3", "fricton = 0.3"),
        // unknown law type
        ("\"linear_coulomb\"", "\"linear_colomb\""),
        // wrong type
        ("count = 4", "count = \"four\""),
        // misspelt top-level table
        ("[steps]", "[step]"),
    ];
    for (from, to) in mistakes {
        assert!(template.contains(from), "template has no `{from}`");
        let text = template.replacen(from, to, 1);
        assert!(
            !errors(&validator, &as_json(&text)).is_empty(),
            "the schema accepts `{to}`"
        );
        assert!(
            asperity::config::Case::from_toml(&text, &path).is_err(),
            "the reader accepts `{to}`"
        );
    }
}

/// Aliases the reader accepts (`ur`, `uz` for `ux`, `uy`; components `r`, `z`) are valid for
/// the schema too.
#[test]
fn aliases_are_valid() {
    let validator = schema();
    let path = repo().join("templates/case.toml");
    let mut text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("ux = 0.0\nuy = 0.0", "ur = 0.0\nuz = 0.0");
    assert!(text.contains("ur = 0.0"));
    text.push_str("\n[[quantity]]\nname = \"u\"\nkind = \"reaction\"\nsupport = \"base\"\ncomponent = \"z\"\n");
    assert_eq!(errors(&validator, &as_json(&text)), Vec::<String>::new());
    asperity::config::Case::from_toml(&text, &path).unwrap();
}
