//! A thick cylinder (b/a = 3, axisymmetric slice with u_z = 0 on both ends, so in plane
//! strain) under cyclic internal pressure 0 → p → 0, elastic–perfectly plastic (issue 27).
//!
//! The elastic stresses are proportional to p, so a cycle's elastic stress range at the
//! bore reaches 2σ_Y (reverse yield on unloading) at twice the first-yield pressure p_y;
//! below that pressure, and below the limit pressure p_L = (2/√3) σ_Y ln(b/a), Melan's
//! theorem gives elastic shakedown; above it the bore yields in every half cycle
//! (alternating plasticity, "plastic shakedown"). Here 2 p_y = 246 MPa < p_L = 304 MPa.
//! Checked through the whole run: the verdicts in summary.json and the plastic strain
//! increments per cycle in cycles.csv. The same cylinder with Prager kinematic hardening
//! writes the backstress fields and keeps its energy balance.

use std::path::Path;
use std::process::Command;

const A: f64 = 10.0;
const B: f64 = 30.0;
const NU: f64 = 0.3;
const SY: f64 = 240.0;

/// Von Mises stress at the bore per unit internal pressure (Lamé, plane strain).
fn bore_von_mises_per_pressure() -> f64 {
    let (sr, st) = (-1.0, (B * B + A * A) / (B * B - A * A));
    let sz = NU * (sr + st);
    (0.5 * ((sr - st).powi(2) + (st - sz).powi(2) + (sz - sr).powi(2))).sqrt()
}

/// Runs `cycles` pressure cycles to `pressure` with the extra material keys `hardening`;
/// returns the output folder's cycles.csv (header, rows) and summary.json.
fn run(
    dir: &Path,
    pressure: f64,
    hardening: &str,
    vtu: bool,
) -> (Vec<String>, Vec<Vec<String>>, serde_json::Value) {
    let geo = Path::new(env!("CARGO_MANIFEST_DIR")).join("geo/thick_cylinder_axi.geo");
    let case = format!(
        r#"
[mesh]
geo = "{geo}"
size = 1.0
parameters = {{ a = {A}, b = {B}, H = 2.0, n_wall = 12 }}
[analysis]
type = "axisymmetric"
[[body]]
group = "cylinder"
material = {{ E = 200000.0, nu = {NU}, yield_stress = {SY}{hardening} }}
[[support]]
group = "bottom"
uz = 0.0
[[support]]
group = "top"
uz = 0.0
[[load]]
group = "bore"
pressure = {pressure}
[[step]]
name = "cycling"
cycles = 6
increments = 20
loads = {{ bore = {{ time = [0.0, 0.5, 1.0], value = [0.0, 1.0, 0.0] }} }}
[output]
vtu = {vtu}
"#,
        geo = geo.display()
    );
    let path = dir.join("case.toml");
    std::fs::write(&path, case).unwrap();
    let out = dir.join("out");
    let status = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .arg("run")
        .arg(&path)
        .arg("--out")
        .arg(&out)
        .arg("--force")
        .output()
        .unwrap();
    assert!(status.status.success(), "{status:?}");
    let text = std::fs::read_to_string(out.join("cycles.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    (header, rows, serde_json::from_str(&summary).unwrap())
}

/// The column `name` of `rows` as numbers.
fn column(header: &[String], rows: &[Vec<String>], name: &str) -> Vec<f64> {
    let i = header.iter().position(|h| h == name).expect(name);
    rows.iter().map(|r| r[i].parse().unwrap()).collect()
}

fn verdict(summary: &serde_json::Value) -> String {
    let verdicts = summary["shakedown"].as_array().unwrap();
    assert_eq!(verdicts.len(), 1, "one cyclic step, one body");
    assert_eq!(verdicts[0]["body"], "cylinder");
    assert_eq!(verdicts[0]["threshold"], 1e-6);
    verdicts[0]["shakedown"].as_str().unwrap().to_string()
}

#[test]
fn elastic_shakedown_below_twice_first_yield_alternating_plasticity_above() {
    let p_y = SY / bore_von_mises_per_pressure();
    let p_shakedown = 2.0 * p_y;
    let p_limit = 2.0 / 3f64.sqrt() * SY * (B / A).ln();
    assert!(p_shakedown < p_limit);

    // 0.85 p_sd: the first cycle yields the bore (p > p_y), later cycles are elastic.
    let dir = tempfile::tempdir().unwrap();
    let (header, rows, summary) = run(dir.path(), 0.85 * p_shakedown, "", false);
    assert!(header.iter().any(|h| h.contains("ratchet")));
    let increments = column(&header, &rows, "cylinder_plastic_strain_increment");
    assert_eq!(increments.len(), 6);
    assert!(increments[0] > 1e-4, "{increments:?}");
    // Later cycles: round-off of the converged equilibrium only (~1e-13).
    assert!(increments[1..].iter().all(|&d| d < 1e-9), "{increments:?}");
    assert_eq!(verdict(&summary), "elastic shakedown");

    // 1.1 p_sd (< p_L): the bore yields in tension and compression in every cycle with a
    // stabilised plastic strain increment, and the loop closes (no ratcheting).
    let (header, rows, summary) = run(dir.path(), 1.1 * p_shakedown, "", false);
    let increments = column(&header, &rows, "cylinder_plastic_strain_increment");
    let ratchet = column(&header, &rows, "cylinder_ratchet_strain");
    let dissipation = column(&header, &rows, "cylinder_plastic_dissipation");
    let last = increments.len() - 1;
    assert!(increments[last] > 1e-4, "{increments:?}");
    // Stabilised: the last two cycles' increments agree to 0.5 %.
    assert!((increments[last] - increments[last - 1]).abs() < 5e-3 * increments[last]);
    // The net change is a small share of the flow, and falls from cycle to cycle.
    assert!(ratchet[last] < 0.05 * increments[last], "{ratchet:?}");
    assert!(ratchet[last] < ratchet[1], "{ratchet:?}");
    assert!(dissipation[last] > 0.0);
    assert_eq!(verdict(&summary), "plastic shakedown");
}

#[test]
fn kinematic_hardening_run_writes_backstress_and_balances_energy() {
    let p_y = SY / bore_von_mises_per_pressure();
    let dir = tempfile::tempdir().unwrap();
    let hardening = ", kinematic = [{ C = 20000.0, gamma = 0.0 }]";
    let (header, rows, summary) = run(dir.path(), 2.4 * p_y, hardening, true);
    let increments = column(&header, &rows, "cylinder_plastic_strain_increment");
    assert!(increments[0] > 1e-4);
    assert_eq!(verdict(&summary), "plastic shakedown");
    let relative = summary["energy"]["total"]["relative_imbalance"]
        .as_f64()
        .unwrap();
    assert!(relative.abs() < 1e-5, "{relative}");
    let vtu = std::fs::read_dir(dir.path().join("out"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "vtu"))
        .expect("a VTU file");
    let text = std::fs::read(&vtu).unwrap();
    let text = String::from_utf8_lossy(&text);
    assert!(text.contains("Name=\"backstress\""));
    assert!(text.contains("Name=\"backstress_von_mises\""));
}
