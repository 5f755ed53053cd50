//! Cycle jumping converges (issue 14): a fretting run whose wear changes the contact pressure
//! noticeably, computed once with every cycle simulated (ΔN = 1) and once with the default
//! jump (about 20 simulated cycles), ends with the same wear-depth profile to 2 % of its
//! largest depth, the same worn volume and the same dissipation in its last cycle to 2 %.
//!
//! The case is the shipped tapered fretting joint (`pipelines/fretting/tapered_fretting.toml`,
//! with its 5 µm angular mismatch) on a coarse mesh with 200 service cycles of 4 increments
//! and an Archard coefficient large enough (1e-4 mm²/N) that the wear of the 200 cycles,
//! ~0.56 µm, is a sizeable part of the interface's elastic closure: the pressure, the slip
//! and the wear rate change along the run, so the explicit extrapolation is actually tested.
//! The dissipation of a cycle is the one that checks the re-equilibrium after every jump
//! (`settle_after_jump` in src/solver/stepping.rs): without it the cone's re-seating after a
//! jump counted as the next cycle's slip. Measured: the profiles differ by 0.5 % of the
//! largest depth, the worn volumes by 0.16 %, the last cycles' dissipations by 0.7 %.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The fretting case, coarse and short, with `jump` as its service step's cycles_per_jump
/// (the default when `None`).
fn case_text(jump: Option<usize>) -> String {
    let text = std::fs::read_to_string(root().join("pipelines/fretting/tapered_fretting.toml"))
        .expect("the shipped fretting case");
    let geo = root().join("geo/tapered_joint.geo");
    let jump_line = jump.map_or_else(String::new, |n| format!("cycles_per_jump = {n}"));
    let replaced = text
        .replace("../../geo/tapered_joint.geo", &geo.display().to_string())
        .replace("cycles = 1000000", "cycles = 200")
        .replace("increments = 10", "increments = 4")
        .replace("coefficient = 4e-7", "coefficient = 1e-4");
    let lines: Vec<String> = replaced
        .lines()
        .map(|line| {
            if line.starts_with("size =") {
                "size = 4.0".to_string()
            } else if line.starts_with("cycles_per_jump") {
                jump_line.clone()
            } else {
                line.to_string()
            }
        })
        .collect();
    for (key, count) in [
        ("cycles = 200", 1),
        ("increments = 4", 2),
        ("size = 4.0", 1),
        ("wear = { model = \"archard\", coefficient = 1e-4", 1),
    ] {
        let found = lines.iter().filter(|l| l.starts_with(key)).count();
        assert_eq!(found, count, "the shipped case changed: '{key}'");
    }
    lines.join("\n")
}

/// What a run ends with: its last wear-depth profile (mm, along side A), and the worn
/// volume (mm³) and dissipation (N·mm) of its last simulated cycle.
struct End {
    profile: Vec<f64>,
    worn_volume: f64,
    dissipation: f64,
}

/// The rows of the CSV file `path` as numbers, with the index of each header.
fn table(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|v| v.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    (header, rows)
}

/// Runs the case with `jump` (the default when `None`).
fn run(dir: &Path, jump: Option<usize>) -> End {
    let name = jump.map_or("default".to_string(), |n| format!("jump{n}"));
    let case = dir.join(format!("{name}.toml"));
    std::fs::write(&case, case_text(jump)).unwrap();
    let out = dir.join(&name);
    let run = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(["run", "-q", "--force"])
        .arg(&case)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (header, rows) = table(&out.join("wear_cone.csv"));
    let column = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (cycles, depth) = (column("cycles"), column("wear_depth"));
    let last = rows.iter().map(|r| r[cycles]).fold(0.0, f64::max);
    assert_eq!(last, 200.0, "the run reaches its 200 cycles");
    let profile = rows
        .iter()
        .filter(|r| r[cycles] == last)
        .map(|r| r[depth])
        .collect();
    let (header, rows) = table(&out.join("cycles.csv"));
    let column = |name: &str| header.iter().position(|h| h == name).unwrap();
    let final_cycle = rows.last().unwrap();
    assert_eq!(final_cycle[column("cycles")], 200.0);
    End {
        profile,
        worn_volume: final_cycle[column("worn_volume")],
        dissipation: final_cycle[column("dissipation")],
    }
}

#[test]
fn default_jumps_reach_the_wear_profile_of_every_cycle_simulated() {
    let dir = tempfile::tempdir().unwrap();
    let every = run(dir.path(), Some(1));
    let jumped = run(dir.path(), None);
    let relative = |a: f64, b: f64| (a - b).abs() / a.abs();
    let volume = relative(every.worn_volume, jumped.worn_volume);
    let dissipation = relative(every.dissipation, jumped.dissipation);
    println!("worn volumes differ by {volume:.2e}, last dissipations by {dissipation:.2e}");
    assert!(volume < 0.02 && dissipation < 0.02);
    let (every, jumped) = (every.profile, jumped.profile);
    assert_eq!(every.len(), jumped.len());
    let largest = every.iter().copied().fold(0.0, f64::max);
    assert!(largest > 1e-4, "the wear is sizeable: {largest} mm");
    let worst = every
        .iter()
        .zip(&jumped)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!("largest depth {largest:.4e} mm, profiles differ by {worst:.3e} mm");
    assert!(
        worst < 0.02 * largest,
        "jumped profile off by {worst:.3e} mm of {largest:.3e} mm"
    );
}
