//! The case-file reference cannot drift from the program: `docs/guide/case-file.md` must be
//! exactly the page `asperity schema --markdown` makes from the same schema as `asperity
//! schema` (the doc comments of the config structs). A key added, renamed or re-documented
//! without `make reference` fails here.

use std::path::Path;
use std::process::Command;

use asperity::reference::{CASE_FILE_PAGE, case_file_markdown, case_schema};

fn committed_page() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(CASE_FILE_PAGE);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn asperity(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("asperity runs");
    assert!(out.status.success(), "{args:?}: {out:?}");
    String::from_utf8(out.stdout).expect("UTF-8")
}

#[test]
fn the_committed_reference_is_what_the_schema_generates() {
    let committed = committed_page();
    let generated = case_file_markdown();
    if committed != generated {
        let line = committed
            .lines()
            .zip(generated.lines())
            .position(|(a, b)| a != b)
            .unwrap_or_else(|| committed.lines().count().min(generated.lines().count()));
        panic!(
            "{CASE_FILE_PAGE} differs from the schema's page from line {}:\n  committed: {:?}\n  generated: {:?}\nrun `make reference` and commit the page",
            line + 1,
            committed.lines().nth(line),
            generated.lines().nth(line)
        );
    }
}

/// The command prints the same page, and `asperity schema` the schema it is made from.
#[test]
fn the_command_prints_the_page_and_the_schema() {
    assert_eq!(asperity(&["schema", "--markdown"]), committed_page());
    let printed: serde_json::Value =
        serde_json::from_str(&asperity(&["schema"])).expect("the schema is JSON");
    assert_eq!(printed, case_schema());
}

/// Every key the schema documents has its row: a key the walk over the schema missed would
/// be undocumented.
#[test]
fn every_documented_key_of_a_section_has_a_row() {
    let page = committed_page();
    let schema = case_schema();
    for (name, def) in schema["$defs"].as_object().unwrap() {
        let Some(properties) = def["properties"].as_object() else {
            continue;
        };
        for (key, property) in properties {
            if property.get("const").is_some() || name == "InlineAmplitude" {
                continue;
            }
            assert!(
                page.contains(&format!("| `{key}` |")),
                "{name}.{key} has no row in {CASE_FILE_PAGE}"
            );
        }
    }
}
