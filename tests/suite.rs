//! The integration tests, as one test binary: each file of `tests/` is a module here.
//!
//! Sixty test binaries each linked the library and its dependencies again: on the 2-core CI
//! machine they took 390 of the 1450 CPU-seconds of a clean `cargo test --release` (the whole
//! build 12 minutes of a 15-minute budget). One binary compiles and links them once.
//! `tests/allocation.rs` and `tests/reader.rs` stay binaries of their own: each installs a
//! counting global allocator, which is one per program.
//!
//! Run one file's tests with its module name as the filter, e.g.
//! `cargo test --release --test suite -- cattaneo_mindlin::`.

mod common;

mod arc_states;
mod bad_input;
mod beam;
mod case_file_reference;
mod cattaneo_mindlin;
mod check;
mod cli;
mod contact;
mod converge;
mod crash;
mod criteria;
mod cutbacks;
mod cycle_jump;
mod cyclic_cylinder;
mod cyclic_jump;
mod cyclic_material;
mod cyclic_newton;
mod cyclic_press_fit;
mod cyclic_resume;
mod determinism;
mod diagnosis;
mod elastic_cells;
mod energy;
mod exit_codes;
mod factor_reuse;
mod fit;
mod floor;
mod friction_circle;
mod history;
mod interface_topology;
mod lame;
mod line_search;
mod load_history;
mod locking;
mod logging;
mod material_j2;
mod memory_limit;
mod mesh_cache;
mod mesh_limits;
mod output;
mod output_folder;
mod patch;
mod plasticity;
mod quantities;
mod restart;
mod rigid_body;
mod rough_law;
mod schema;
mod shared_nodes;
mod shell;
mod solve_cap;
mod stick_slip;
mod strain_bound;
mod sweep;
mod thermal_conduction;
mod thermal_strain;
mod torque_joint;
mod torsion_outputs;
mod torsion_plastic;
mod torsion_reissner_sagoci;
mod torsion_shaft;
mod wear;

/// Cargo no longer finds the files of `tests/` by itself (`autotests = false`): a file that
/// is neither a module here nor a `[[test]]` of Cargo.toml would silently never run.
#[test]
fn every_test_file_is_compiled() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let suite = include_str!("suite.rs");
    let manifest = std::fs::read_to_string(root.join("Cargo.toml")).unwrap();
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(root.join("tests")).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        let Some(module) = name.strip_suffix(".rs") else {
            continue;
        };
        let in_suite = suite.lines().any(|l| l == format!("mod {module};"));
        let own_binary = manifest.contains(&format!("path = \"tests/{name}\""));
        if !in_suite && !own_binary {
            missing.push(name);
        }
    }
    assert!(
        missing.is_empty(),
        "{missing:?}: add `mod <file>;` to tests/suite.rs"
    );
}
