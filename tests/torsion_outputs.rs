//! The torque outputs of a run with twist, end to end through `asperity run`: a tube
//! (`geo/thick_cylinder_axi.geo` meshed by gmsh, a = 5, b = 10, H = 20 mm) held at its bottom
//! and twisted at its top by a torque that a `[[step]]` amplitude takes up to T and back to
//! T/2. Elastic Saint-Venant torsion is exact in the quadratic elements (tests/torsion_shaft.rs),
//! so `history.csv`'s `reaction_bottom_torque` is −T × the multiplier and the `[[history]]`
//! twist of the top is T H / (G J) × the multiplier, to round-off (1e-8 relative, room for
//! the linear solves).

use crate::common;

use std::path::Path;

use common::run_cli;

const A: f64 = 5.0;
const B: f64 = 10.0;
const H: f64 = 20.0;
const E: f64 = 200_000.0;
const NU: f64 = 0.3;
const T: f64 = 1.0e5;

#[test]
fn history_and_summary_carry_the_reaction_torque_and_the_twist_of_a_group() {
    let dir = tempfile::tempdir().unwrap();
    let geo = Path::new(env!("CARGO_MANIFEST_DIR")).join("geo/thick_cylinder_axi.geo");
    let case = format!(
        r#"
[mesh]
geo = "{geo}"
parameters = {{ a = {A}, b = {B}, H = {H}, n_wall = 2 }}
[analysis]
type = "axisymmetric"
twist = true
[[body]]
group = "cylinder"
material = {{ E = {E}, nu = {NU} }}
[[support]]
group = "bottom"
uz = 0.0
utheta = 0.0
[[load]]
group = "top"
torque = {T}
[[step]]
increments = 2
loads = {{ top = {{ time = [0.0, 0.5, 1.0], value = [0.0, 1.0, 0.5] }} }}
[[history]]
name = "top_twist"
kind = "twist"
group = "top"
[output]
vtu = false
"#,
        geo = geo.display()
    );
    let path = dir.path().join("case.toml");
    std::fs::write(&path, case).unwrap();
    let out = dir.path().join("out");
    run_cli(&path, &out, &[]);

    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let column = |name: &str| {
        let i = header.iter().position(|&h| h == name).unwrap_or_else(|| {
            panic!("no column {name} in {header:?}");
        });
        rows.iter().map(|r| r[i]).collect::<Vec<f64>>()
    };
    let g = E / (2.0 * (1.0 + NU));
    let j = std::f64::consts::PI * (B.powi(4) - A.powi(4)) / 2.0;
    let multiplier = column("factor_load_top");
    let torque = column("reaction_bottom_torque");
    let twist = column("top_twist");
    assert_eq!(multiplier.len(), 3, "step 0 and two increments");
    assert_eq!(multiplier[1..], [1.0, 0.5]);
    for ((m, torque), twist) in multiplier.iter().zip(&torque).zip(&twist) {
        assert!(
            (torque + m * T).abs() <= 1e-8 * T,
            "{torque} at multiplier {m}"
        );
        let phi = m * T * H / (g * j);
        let scale = T * H / (g * j);
        assert!((twist - phi).abs() <= 1e-8 * scale, "{twist} against {phi}");
    }

    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["twist"], true);
    let last = &summary["steps"][1]["reactions"]["bottom"]["torque"];
    let last = last.as_f64().expect("a reaction torque in summary.json");
    assert!((last + 0.5 * T).abs() <= 1e-8 * T, "{last}");
}
