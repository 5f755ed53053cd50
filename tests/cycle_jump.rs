//! Cycle jumping converges (issue 14): a fretting run whose wear changes the contact pressure
//! noticeably, computed once with every cycle simulated (ΔN = 1) and once with the default
//! jump (about 20 simulated cycles), ends with the same wear-depth profile to 2 % of its
//! largest depth, the same worn volume and the same dissipation in its last cycle to 2 %.
//!
//! The case is the shipped tapered fretting joint (`examples/fretting/tapered_fretting.toml`,
//! with its 5 µm angular mismatch) on a coarse mesh with 200 service cycles of 4 increments
//! and an Archard coefficient large enough (1e-4 mm²/N) that the wear of the 200 cycles,
//! ~0.56 µm, is a sizeable part of the interface's elastic closure: the pressure, the slip
//! and the wear rate change along the run, so the explicit extrapolation is actually tested.
//! The dissipation of a cycle is the one that checks the re-equilibrium after every jump
//! (`settle_after_jump` in src/solver/stepping.rs): without it the cone's re-seating after a
//! jump counted as the next cycle's slip. Measured: the profiles differ by 0.5 % of the
//! largest depth, the worn volumes by 0.16 %, the last cycles' dissipations by 0.7 %.
//!
//! Issue 23: under a stiff penalty and jumps at the stability limit, the two integration
//! points at a shared corner node keep one depth (`coincident_corner_points_…`).

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use asperity::element::set::INTERFACE_POINTS;
use asperity::mesh::Mesh;
use asperity::model::Model;
use asperity::solver::newton::NewtonSettings;
use asperity::solver::state::Solution;
use asperity::solver::stepping::run_steps;
use common::{block_on_base, linear_coulomb, list, settings, sliding_block_mesh, table};
use toml::Value;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The fretting case, coarse and short, with `jump` as its service step's cycles_per_jump
/// (the default when `None`).
fn case_text(jump: Option<usize>) -> String {
    let text = std::fs::read_to_string(root().join("examples/fretting/tapered_fretting.toml"))
        .expect("the shipped fretting case");
    let geo = root().join("examples/tapered_joint/tapered_joint.geo");
    let jump_line = jump.map_or_else(String::new, |n| format!("cycles_per_jump = {n}"));
    let replaced = text
        .replace(
            "../tapered_joint/tapered_joint.geo",
            &geo.display().to_string(),
        )
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
fn csv_table(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
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
    let (header, rows) = csv_table(&out.join("wear_cone.csv"));
    let column = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (cycles, depth) = (column("cycles"), column("wear_depth"));
    let last = rows.iter().map(|r| r[cycles]).fold(0.0, f64::max);
    assert_eq!(last, 200.0, "the run reaches its 200 cycles");
    let profile = rows
        .iter()
        .filter(|r| r[cycles] == last)
        .map(|r| r[depth])
        .collect();
    let (header, rows) = csv_table(&out.join("cycles.csv"));
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

// Issue 23: the two integration points at a corner node shared by two interface elements,
// under a stiff penalty interface and jumps at the stability limit.

/// Penalty stiffness (MPa/mm) of the stiff interface: k_N ℓ / (π E*) = 41 with ℓ = 0.5 mm and
/// E* = 38 462 MPa (E = 70 GPa, ν = 0.3, plane strain): the bodies set k_eff, and a difference
/// between the depths of two coincident points meets k_N alone, 41 times stiffer.
const STIFF: f64 = 1e7;

/// The block on the base (`common::sliding_block_mesh`: four quad8 of ℓ = 0.5 mm along the
/// contact) with the contact line y = 1 made slightly curved, y = 1 + 0.002 (x − 1.5)⁴: the
/// quadratic elements interpolate the quartic with a kink of their tangents at each corner
/// node, so the two integration points there see slightly different normal and tangential
/// displacements, as on any curved contact.
fn wavy_block_mesh() -> Mesh {
    let mut mesh = sliding_block_mesh();
    for x in mesh.nodes.iter_mut().filter(|x| x[1] == 1.0) {
        x[1] += 0.002 * (x[0] - 1.5).powi(4);
    }
    mesh
}

/// The block pressed by 8 MPa, then pushed back and forth by ±5 µm at its top (gross slip)
/// for `cycles` cycles of 8 increments, `jump` to a simulated cycle, with Archard wear
/// (k = 2.5e-6 mm²/N on both faces) and a linear Coulomb penalty k_N = k_T = [`STIFF`].
fn stiff_fretting(cycles: usize, jump: usize) -> (Model, NewtonSettings) {
    let wear = table(&[("model", "archard".into()), ("coefficient", 2.5e-6.into())]);
    let keys = [("name", Value::from("joint")), ("wear", wear.into())];
    let named = |name: &str, entries: &[(&str, Value)]| {
        let mut t = table(entries);
        t.insert("name".into(), name.into());
        t
    };
    let case = block_on_base(70000.0, 0.3, &keys, linear_coulomb(STIFF, STIFF, 0.3))
        .push(
            "support",
            named(
                "push",
                &[("group", "block_top".into()), ("ux", 0.005.into())],
            ),
        )
        .push(
            "load",
            named(
                "press",
                &[("group", "block_top".into()), ("pressure", 8.0.into())],
            ),
        )
        .push(
            "amplitude",
            named(
                "cycle",
                &[
                    ("time", list(&[0.0, 0.25, 0.75, 1.0])),
                    ("value", list(&[0.0, 1.0, -1.0, 0.0])),
                ],
            ),
        )
        .push(
            "step",
            named(
                "press",
                &[
                    ("increments", 2.into()),
                    ("loads", table(&[("press", 1.0.into())]).into()),
                ],
            ),
        )
        .push(
            "step",
            named(
                "fret",
                &[
                    ("cycles", (cycles as i64).into()),
                    ("cycles_per_jump", (jump as i64).into()),
                    ("increments", 8.into()),
                    ("loads", table(&[("press", 1.0.into())]).into()),
                    ("supports", table(&[("push", "cycle".into())]).into()),
                ],
            ),
        )
        .case();
    let model = common::model(wavy_block_mesh(), &case).expect("model builds");
    (model, settings(&case))
}

/// Runs the stiff fretting case to its end.
fn solve(cycles: usize, jump: usize) -> (Model, Solution) {
    let (model, settings) = stiff_fretting(cycles, jump);
    let (solution, _) = run_steps(&model, &settings, |_| Ok(0.0)).expect("the run converges");
    (model, solution)
}

/// The pairs of interface points (state indices) that sit at the same corner node.
fn corner_pairs(model: &Model) -> Vec<[usize; 2]> {
    let set = &model.interface;
    let positions: Vec<[f64; 2]> = (0..set.elements.len() * INTERFACE_POINTS)
        .map(|i| set.point_position(i / INTERFACE_POINTS, i % INTERFACE_POINTS))
        .collect();
    let mut pairs = Vec::new();
    for (i, a) in positions.iter().enumerate() {
        for (j, b) in positions.iter().enumerate().skip(i + 1) {
            if (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-9 {
                pairs.push([i, j]);
            }
        }
    }
    pairs
}

/// With a stiff penalty and jumps at 90 % of the documented stability limit, the two points
/// at each corner node keep the same wear depth and slip, as in a run that simulates every
/// cycle. Before the fix each jump multiplied the difference of their depths by about
/// 1 − 0.9 (1 + 41) ≈ −37 (docs/fretting.md, Eq. J.2): at the end of the 8 jumps one point
/// was open and the other carried the pressure of both, with no slip amplitude at the one.
#[test]
fn coincident_corner_points_do_not_drift_apart_under_a_stiff_penalty() {
    // One jump over a single extra cycle measures the share of the limit a cycle uses.
    let (_, probe) = solve(3, 2);
    let per_cycle = probe.jump_use[0];
    assert!(per_cycle > 0.0);
    let jump = (0.9 / per_cycle).floor() as usize + 1;
    assert!(jump >= 10, "a cycle uses {per_cycle} of the limit");
    let cycles = 1 + 8 * jump;
    let (model, jumped) = solve(cycles, jump);
    let used = jumped.jump_use[0];
    assert!(
        (0.8..=1.0).contains(&used),
        "the jumps use {used} of the limit"
    );
    let (_, every) = solve(cycles, 1);
    let pairs = corner_pairs(&model);
    assert_eq!(pairs.len(), 3, "three inner corner nodes along the contact");
    let depth = |s: &Solution, i: usize| s.interface_committed[i].history.depth();
    let slip = |s: &Solution, i: usize| s.interface_committed[i].history.last_cycle_slip_amplitude;
    let pressure = |s: &Solution, i: usize| -s.interface_committed[i].stress[1];
    let largest = (0..jumped.interface_committed.len())
        .map(|i| depth(&every, i))
        .fold(0.0, f64::max);
    assert!(largest > 0.0);
    for [a, b] in pairs {
        let (da, db) = (depth(&jumped, a), depth(&jumped, b));
        let reference = (depth(&every, a) - depth(&every, b)).abs();
        println!(
            "corner at {:?}: depths {da:.6e} and {db:.6e} mm (every cycle simulated: \
             differ by {reference:.2e}), pressures {:.4} and {:.4} MPa, slip amplitudes \
             {:.4e} and {:.4e} mm (every cycle: {:.4e})",
            model
                .interface
                .point_position(a / INTERFACE_POINTS, a % INTERFACE_POINTS),
            pressure(&jumped, a),
            pressure(&jumped, b),
            slip(&jumped, a),
            slip(&jumped, b),
            slip(&every, a),
        );
        // Both depths within 1 % of the largest depth of each other and of the run that
        // simulates every cycle (whose profile the jumps reproduce to that accuracy).
        assert!((da - db).abs() <= 0.01 * largest, "{da} vs {db}");
        for (i, d) in [(a, da), (b, db)] {
            assert!((d - depth(&every, i)).abs() <= 0.01 * largest);
            // Slip amplitude and pressure as with every cycle simulated: both points
            // closed and slipping, neither halved nor doubled.
            let (s, s_every) = (slip(&jumped, i), slip(&every, i));
            assert!(
                (s - s_every).abs() <= 0.02 * s_every,
                "slip {s} vs {s_every}"
            );
            let (p, p_every) = (pressure(&jumped, i), pressure(&every, i));
            assert!(
                (p - p_every).abs() <= 0.05 * p_every,
                "pressure {p} vs {p_every}"
            );
        }
    }
}
