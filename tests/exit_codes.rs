//! The exit-code table of the guide (docs/guide/troubleshooting.md) against
//! `Error::exit_code`: each class of error, by a representative value, has the code of the
//! table row that describes it, and every sentence of the README and the guide that gives the
//! exit code of a limit load (plastic collapse, friction capacity) gives the same one.

use std::collections::BTreeMap;
use std::path::PathBuf;

use asperity::Error;
use asperity::error::{FreeBody, Mechanism};

fn read(relative: &str) -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(relative);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{relative}: {e}"))
}

/// The page with the exit-code table.
fn troubleshooting() -> String {
    read("docs/guide/troubleshooting.md")
}

/// The README and every page of the guide, one after the other.
fn documentation() -> String {
    let guide = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/guide");
    let mut pages: Vec<PathBuf> = std::fs::read_dir(&guide)
        .expect("docs/guide is readable")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    let mut text = read("README.md");
    for page in pages {
        text.push_str("\n\n");
        text.push_str(&std::fs::read_to_string(&page).unwrap());
    }
    text
}

/// The rows of the table under "**Exit codes**": code → meaning.
fn exit_code_table(page: &str) -> BTreeMap<u8, String> {
    let start = page
        .find("**Exit codes**")
        .expect("the troubleshooting page has an exit-code table");
    let rows: BTreeMap<u8, String> = page[start..]
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .filter_map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            Some((cells.get(1)?.parse().ok()?, cells.get(2)?.to_string()))
        })
        .collect();
    assert!(rows.len() >= 5, "{rows:?}");
    rows
}

fn free_block() -> FreeBody {
    FreeBody {
        body: "block".into(),
        translations: vec![[1.0, 0.0]],
        rotates: false,
        twists: false,
        centre: None,
    }
}

fn collapse(mechanism: Mechanism) -> Error {
    Error::Collapse {
        mechanism,
        converged_load_factor: 0.5,
        failed_load_factor: 0.6,
        details: Box::default(),
    }
}

/// A representative of each class of error, with words of the table row that must describe
/// it.
fn representatives() -> Vec<(Error, &'static str)> {
    let io = || std::io::Error::other("disk full");
    vec![
        (Error::NoConvergence(Box::default()), "did not converge"),
        (Error::Linear("singular".into()), "a singular system"),
        (Error::ArcLengthNoLoad, "arc-length control"),
        (
            Error::TooManySolves {
                at: Box::default(),
                count: 11,
                limit: 10,
                planned: false,
            },
            "reached `[solver] max_solves` through cut-backs",
        ),
        (
            Error::OutputExists {
                dir: "out".into(),
                files: 3,
                example: "history.csv".into(),
            },
            "an output folder holding",
        ),
        (
            Error::Case {
                path: "case.toml".into(),
                message: "bad".into(),
            },
            "bad input: case file",
        ),
        (
            Error::RigidBodyMotion {
                bodies: vec![free_block()],
            },
            "a body free to move as a rigid body",
        ),
        (
            Error::TooManySolves {
                at: Box::default(),
                count: 11,
                limit: 10,
                planned: true,
            },
            "amplitude breakpoints that alone need more solves",
        ),
        (
            Error::Restart {
                path: "restart.bin".into(),
                reason: "other case".into(),
            },
            "a restart record",
        ),
        (
            Error::InsufficientMemory {
                what: "the sparse factor".into(),
                unknowns: 4_000_000,
                needed: 20_000_000_000,
                available: 10_000_000_000,
                limit: asperity::memory::Limit::Machine,
            },
            "a model too large for the memory",
        ),
        (
            Error::AllocationFailed {
                what: "the AMD ordering".into(),
                unknowns: 4_000_000,
            },
            "a model too large for the memory",
        ),
        (Error::io("case.toml", io()), "I/O"),
        (
            Error::OutputForeign {
                dir: "out".into(),
                file: "out/log.txt".into(),
                reason: "not listed".into(),
            },
            "would overwrite but did not write",
        ),
        (
            Error::Interrupted {
                step: 3,
                dir: "out".into(),
                resume: None,
            },
            "interrupted",
        ),
        (
            Error::WornBeyondBody {
                contact: "joint".into(),
                contact_index: 0,
                step_index: None,
                position: [0.0, 0.0],
                body: "base".into(),
                depth: 2.0,
                extent: 1.0,
            },
            "worn deeper than the body",
        ),
        (
            Error::WearEnergy {
                contact: "joint".into(),
                contact_index: 0,
                step_index: None,
                jump_cycles: 1e4,
                interface_energy: -1.0,
                imbalance: 0.0,
                wear_work: 1.0,
                external_work: 1.0,
                tolerance: 0.01,
            },
            "breaking the energy balance",
        ),
        (
            Error::RatchetingJump {
                body: "hub".into(),
                step_index: Some(1),
                jump_cycles: 10,
                ratchet_strain: 1e-4,
                plastic_strain_increment: 5e-4,
                threshold: 1e-6,
                ratchet_share: 0.1,
            },
            "a body still ratcheting",
        ),
        (
            collapse(Mechanism::PlasticCollapse {
                indicator: "stiffness".into(),
            }),
            "plastic collapse",
        ),
        (
            collapse(Mechanism::FrictionCapacity {
                pairs: vec!["joint".into()],
                bodies: vec![free_block()],
            }),
            "friction capacity exceeded",
        ),
        (
            collapse(Mechanism::LostSupport {
                open_pairs: vec!["joint".into()],
                bodies: vec![free_block()],
            }),
            "loss of support",
        ),
    ]
}

#[test]
fn the_guide_exit_code_table_matches_the_program() {
    let text = troubleshooting();
    let table = exit_code_table(&text);
    for (error, words) in representatives() {
        let rows: Vec<u8> = table
            .iter()
            .filter(|(_, meaning)| meaning.contains(words))
            .map(|(code, _)| *code)
            .collect();
        assert_eq!(
            rows,
            [error.exit_code()],
            "`{words}` ({error}) should be described by the row of its exit code only"
        );
    }
}

#[test]
fn every_sentence_on_limit_loads_gives_their_exit_code() {
    let code = collapse(Mechanism::PlasticCollapse {
        indicator: String::new(),
    })
    .exit_code();
    let text = documentation().replace('\n', " ");
    let mut checked = 0;
    for sentence in text.split(". ") {
        let lower = sentence.to_lowercase();
        let about_limit = lower.contains("plastic collapse") || lower.contains("limit load");
        let Some(at) = lower.find("exit code ") else {
            continue;
        };
        if !about_limit || lower.contains("non-convergence (exit code") {
            continue;
        }
        let digit = lower[at + "exit code ".len()..].chars().next().unwrap();
        assert_eq!(
            digit.to_digit(10),
            Some(code as u32),
            "the documentation gives a limit load another exit code: {sentence}"
        );
        checked += 1;
    }
    assert!(
        checked >= 2,
        "the documentation states the exit code of a limit load"
    );
}
