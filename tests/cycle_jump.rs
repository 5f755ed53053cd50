//! Cycle jumping converges (issue 14): a fretting run whose wear changes the contact pressure
//! noticeably, computed once with every cycle simulated (ΔN = 1) and once with the default
//! jump (about 20 simulated cycles), ends with the same wear-depth profile to 2 % of its
//! largest depth.
//!
//! The case is the shipped tapered fretting joint (`pipelines/fretting/tapered_fretting.toml`)
//! on a coarse mesh with 200 service cycles of 4 increments and an Archard coefficient
//! large enough (1e-4 mm²/N) that the wear of the 200 cycles, ~0.5 µm, is a sizeable part of
//! the interface's elastic closure: the pressure, the slip and the wear rate change along
//! the run (the dissipation per cycle rises by ~25 %), so the explicit extrapolation is
//! actually tested. Measured: the profiles differ by 1.7 % of the largest depth, the largest
//! depths by 0.7 %; the worn volume, dominated by the slipping end whose first cycle after
//! every jump re-accommodates, by 5 %.

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
        .replace("coefficient = 1e-8", "coefficient = 1e-4");
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
    ] {
        let found = lines.iter().filter(|l| l.starts_with(key)).count();
        assert_eq!(found, count, "the shipped case changed: '{key}'");
    }
    lines.join("\n")
}

/// Runs the case with `jump` and returns the last wear-depth profile (mm, along side A).
fn final_profile(dir: &Path, jump: Option<usize>) -> Vec<f64> {
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
    let text = std::fs::read_to_string(out.join("wear_cone.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (cycles, depth) = (column("cycles"), column("wear_depth"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let last = rows.iter().map(|r| r[cycles]).fold(0.0, f64::max);
    assert_eq!(last, 200.0, "the run reaches its 200 cycles");
    rows.iter()
        .filter(|r| r[cycles] == last)
        .map(|r| r[depth])
        .collect()
}

#[test]
fn default_jumps_reach_the_wear_profile_of_every_cycle_simulated() {
    let dir = tempfile::tempdir().unwrap();
    let every = final_profile(dir.path(), Some(1));
    let jumped = final_profile(dir.path(), None);
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
