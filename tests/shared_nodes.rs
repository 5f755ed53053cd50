//! Contact pairs that share end nodes (an L-shaped joint whose two faces meet at a corner,
//! one joint split into two physical groups that share its middle node), with coincident and
//! with split pairing: each pair's own outputs must come from its own interface points.
//!
//! References, all independent of the output code: the pair's interface-point states
//! (Newton–Cotes points sit at the nodes, so a node's value is the mean of the points of the
//! pair's elements there); `history.csv`'s resultants, which `post::interface::resultants`
//! sums over the integration points, against Simpson's rule over the pair's own contact CSV
//! (the Newton–Cotes rule of a straight quadratic element *is* Simpson's rule on its three
//! nodal values); and the pair's side-A curve as gmsh meshed it, for the wear CSV.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use asperity::config::Case;
use asperity::element::set::INTERFACE_POINTS;
use asperity::mesh::gmsh::mesh_geo;
use asperity::mesh::msh::read_msh;
use asperity::model::{Model, ModelSpec};
use asperity::post::interface::InterfaceOutput;
use asperity::solver::stepping::run_steps;

/// A block pressed into the corner of an L-shaped frame: the frame's floor (y = 0, x ∈ [0, 8])
/// and wall (x = 0, y ∈ [0, 6]) meet the block's bottom and left side, so both pairs end at
/// the corner (0, 0), on side A and on side B. `split = 1` meshes frame and block
/// conformingly (one curve per face, split by asperity), else separately (coincident sides).
const CORNER_GEO: &str = r#"
DefineConstant[ split = 0 ];
Geometry.AutoCoherence = (split == 1);
Point(1) = {-5, -10, 0}; Point(2) = {20, -10, 0}; Point(3) = {20, 0, 0}; Point(4) = {8, 0, 0};
Point(5) = {0, 0, 0}; Point(6) = {0, 6, 0}; Point(7) = {0, 10, 0}; Point(8) = {-5, 10, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5}; Line(5) = {5, 6};
Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6, 7, 8}; Plane Surface(1) = {1};
Point(13) = {8, 6, 0};
If (split == 1)
  Line(12) = {4, 13}; Line(13) = {13, 6};
  Curve Loop(2) = {-4, 12, 13, -5}; Plane Surface(2) = {2};
  Physical Curve("floor") = {4};
  Physical Curve("wall") = {5};
Else
  Point(11) = {0, 0, 0}; Point(12) = {8, 0, 0}; Point(14) = {0, 6, 0};
  Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
  Curve Loop(2) = {11, 12, 13, 14}; Plane Surface(2) = {2};
  Transfinite Curve{11} = 13; Transfinite Curve{14} = 7;
  Physical Curve("floor") = {4};
  Physical Curve("wall") = {5};
  Physical Curve("block_bottom") = {11};
  Physical Curve("block_left") = {14};
EndIf
Transfinite Curve{4} = 13; Transfinite Curve{5} = 7;
Mesh.CharacteristicLengthMax = 1.5;
Recombine Surface{2};
Physical Surface("frame") = {1};
Physical Surface("block") = {2};
Physical Curve("base") = {1};
Physical Curve("block_right") = {12};
Physical Curve("block_top") = {13};
"#;

/// A block on a foundation (half model), the joint y = 0, x ∈ [0, 10] in two physical groups
/// "inner" (x ≤ 5) and "outer" (x ≥ 5) that share the node at x = 5.
const HALVES_GEO: &str = r#"
DefineConstant[ split = 0 ];
Geometry.AutoCoherence = (split == 1);
Point(1) = {0, -20, 0}; Point(2) = {30, -20, 0}; Point(3) = {30, 0, 0};
Point(4) = {10, 0, 0}; Point(10) = {5, 0, 0}; Point(5) = {0, 0, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(41) = {4, 10}; Line(42) = {10, 5};
Line(5) = {5, 1};
Curve Loop(1) = {1, 2, 3, 41, 42, 5}; Plane Surface(1) = {1};
Point(6) = {10, 10, 0}; Point(7) = {0, 10, 0};
If (split == 1)
  Line(6) = {4, 6}; Line(7) = {6, 7}; Line(8) = {7, 5};
  Curve Loop(2) = {-42, -41, 6, 7, 8}; Plane Surface(2) = {2};
  Physical Curve("inner") = {42};
  Physical Curve("outer") = {41};
Else
  Point(8) = {0, 0, 0}; Point(11) = {5, 0, 0}; Point(9) = {10, 0, 0};
  Line(91) = {8, 11}; Line(92) = {11, 9}; Line(6) = {9, 6}; Line(7) = {6, 7}; Line(8) = {7, 8};
  Curve Loop(2) = {91, 92, 6, 7, 8}; Plane Surface(2) = {2};
  Transfinite Curve{91, 92} = 6;
  Physical Curve("inner") = {42};
  Physical Curve("outer") = {41};
  Physical Curve("block_inner") = {91};
  Physical Curve("block_outer") = {92};
EndIf
Transfinite Curve{41, 42} = 6;
Recombine Surface{1, 2};
Physical Surface("foundation") = {1};
Physical Surface("block") = {2};
Physical Curve("base") = {1};
Physical Curve("symmetry") = {5, 8};
Physical Curve("top") = {7};
"#;

const LAW: &str = r#"law = { type = "linear_coulomb", normal_stiffness = 1e5, tangential_stiffness = 1e5, friction = 0.3 }
wear = { model = "archard", coefficient = 1e-6 }"#;

/// The corner case: the block pressed down and into the wall, then rubbed by two load cycles.
fn corner_case(split: bool) -> String {
    let (floor, wall) = if split {
        (
            r#"curve = "floor"
body_a = "frame"
body_b = "block""#,
            r#"curve = "wall"
body_a = "frame"
body_b = "block""#,
        )
    } else {
        (
            "side_a = \"floor\"\nside_b = \"block_bottom\"",
            "side_a = \"wall\"\nside_b = \"block_left\"",
        )
    };
    format!(
        r#"[mesh]
geo = "corner.geo"
parameters = {{ split = {} }}
[analysis]
type = "plane_strain"
thickness = 1.0
[[body]]
group = "frame"
material = {{ E = 70000.0, nu = 0.33 }}
[[body]]
group = "block"
material = {{ E = 210000.0, nu = 0.3 }}
[[support]]
group = "base"
ux = 0.0
uy = 0.0
[[load]]
group = "block_top"
pressure = 50.0
[[load]]
group = "block_right"
pressure = 30.0
[[step]]
name = "press"
loads = {{ block_top = 1.0, block_right = 1.0 }}
[[step]]
name = "rub"
increments = 4
cycles = 2
loads = {{ block_top = {{ time = [0, 0.5, 1], value = [1, 1.5, 1] }}, block_right = {{ time = [0, 0.5, 1], value = [1, 0.2, 1] }} }}
[[contact]]
name = "floor_pair"
{floor}
{LAW}
[[contact]]
name = "wall_pair"
{wall}
{LAW}
"#,
        u8::from(split)
    )
}

/// The halves case: the block pressed onto the foundation and rubbed sideways.
fn halves_case(split: bool) -> String {
    let pair = |name: &str| {
        if split {
            format!("curve = \"{name}\"\nbody_a = \"foundation\"\nbody_b = \"block\"")
        } else {
            format!("side_a = \"{name}\"\nside_b = \"block_{name}\"")
        }
    };
    format!(
        r#"[mesh]
geo = "halves.geo"
parameters = {{ split = {} }}
[analysis]
type = "plane_strain"
thickness = 1.0
[[body]]
group = "foundation"
material = {{ E = 70000.0, nu = 0.33 }}
[[body]]
group = "block"
material = {{ E = 210000.0, nu = 0.3 }}
[[support]]
group = "base"
ux = 0.0
uy = 0.0
[[support]]
group = "symmetry"
ux = 0.0
[[load]]
group = "top"
traction = [0.0, -50.0]
[[step]]
name = "press"
loads = {{ top = 1.0 }}
[[step]]
name = "unload"
increments = 2
cycles = 2
loads = {{ top = {{ time = [0, 0.5, 1], value = [1, 0.3, 1] }} }}
[[contact]]
name = "inner"
{}
{LAW}
[[contact]]
name = "outer"
{}
{LAW}
"#,
        u8::from(split),
        pair("inner"),
        pair("outer"),
    )
}

/// Writes the case `toml` and its script `geo` (named `geo_name`) into a fresh folder.
fn write_case(test: &str, name: &str, geo_name: &str, geo: &str, toml: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("shared_nodes")
        .join(test)
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(geo_name), geo).unwrap();
    let case = dir.join("case.toml");
    std::fs::write(&case, toml).unwrap();
    case
}

/// The cases, written for `test`: (name, case file, the shared node, the pair names).
fn cases(test: &str) -> Vec<(&'static str, PathBuf, [f64; 2], [&'static str; 2])> {
    let corner = |split| corner_case(split);
    let halves = |split| halves_case(split);
    vec![
        (
            "corner_coincident",
            write_case(
                test,
                "corner_coincident",
                "corner.geo",
                CORNER_GEO,
                &corner(false),
            ),
            [0.0, 0.0],
            ["floor_pair", "wall_pair"],
        ),
        (
            "halves_coincident",
            write_case(
                test,
                "halves_coincident",
                "halves.geo",
                HALVES_GEO,
                &halves(false),
            ),
            [5.0, 0.0],
            ["inner", "outer"],
        ),
        (
            "corner_split",
            write_case(
                test,
                "corner_split",
                "corner.geo",
                CORNER_GEO,
                &corner(true),
            ),
            [0.0, 0.0],
            ["floor_pair", "wall_pair"],
        ),
        (
            "halves_split",
            write_case(
                test,
                "halves_split",
                "halves.geo",
                HALVES_GEO,
                &halves(true),
            ),
            [5.0, 0.0],
            ["inner", "outer"],
        ),
    ]
}

/// A CSV file as a header → column map and its rows.
fn read_csv(path: &Path) -> (HashMap<String, usize>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .enumerate()
        .map(|(i, h)| (h.to_string(), i))
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

fn close(a: [f64; 2], b: [f64; 2]) -> bool {
    (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-9
}

/// Each pair's contact table (as the run writes it) at every side-B node equals the mean of
/// the pair's own Newton–Cotes points at that node (pressure, shear stress, status), at every
/// frame of the load history.
#[test]
fn contact_tables_show_each_pairs_own_points_at_shared_nodes() {
    for (name, path, shared, pairs) in cases("tables") {
        let case = Case::from_file(&path).unwrap();
        let dir = path.parent().unwrap();
        let params: Vec<(String, f64)> = case
            .mesh
            .parameters
            .iter()
            .map(|(k, v)| (k.clone(), *v))
            .collect();
        let geo = case.resolve(case.mesh.geo.as_ref().unwrap());
        let msh = mesh_geo(&geo, 1.0, &params, &dir.join("lib.msh")).unwrap();
        let mesh = read_msh(&msh.path).unwrap();
        let model = Model::build(mesh, ModelSpec::new(&case).unwrap())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let settings = asperity::run::newton_settings(&case.solver);
        let output = InterfaceOutput::new(&model);
        let mut frames = 0;
        run_steps(&model, &settings, |step| {
            frames += 1;
            let states = &step.solution.interface_committed;
            let tables = output.tables(&model, states);
            for (p, table) in tables.iter().enumerate() {
                let column = |c: &str| table.columns.iter().position(|h| h == c).unwrap();
                let (px, py) = (column("x"), column("y"));
                let (pressure, shear, status) = (
                    column("contact_pressure"),
                    column("contact_shear_stress"),
                    column("contact_status"),
                );
                let mut seen_shared = false;
                for row in &table.rows {
                    let at = [row[px], row[py]];
                    seen_shared |= close(at, shared);
                    // The pair's own points at the node.
                    let mut points = Vec::new();
                    for (e, element) in model.interface.elements.iter().enumerate() {
                        if element.pair as usize != p {
                            continue;
                        }
                        for (g, &(xi, _)) in element.rule.points().iter().enumerate() {
                            let k = [(-1.0, 0), (1.0, 1), (0.0, 2)]
                                .iter()
                                .find(|(x, _)| (x - xi).abs() < 1e-12)
                                .map(|&(_, k)| k)
                                .expect("Newton-Cotes points at the nodes");
                            if close(model.mesh.nodes[element.nodes[3 + k] as usize], at) {
                                points.push(states[e * INTERFACE_POINTS + g]);
                            }
                        }
                    }
                    assert!(!points.is_empty(), "{name}: no point of pair {p} at {at:?}");
                    let mean = |f: &dyn Fn(&asperity::contact::InterfaceState) -> f64| {
                        points.iter().map(f).sum::<f64>() / points.len() as f64
                    };
                    let p_expected = mean(&|s| -s.stress[1]).max(0.0);
                    let t_expected = mean(&|s| s.stress[0]);
                    let status_expected =
                        points.iter().map(|s| s.status as i32).max().unwrap() as f64;
                    let scale = 1e-9 * (1.0 + p_expected.abs() + t_expected.abs());
                    assert!(
                        (row[pressure] - p_expected).abs() < scale
                            && (row[shear] - t_expected).abs() < scale
                            && row[status] == status_expected,
                        "{name}, pair '{}', frame {frames}, node {at:?}: table p = {}, p_T = {}, \
                         status {}; the pair's points p = {p_expected}, p_T = {t_expected}, \
                         status {status_expected}",
                        pairs[p],
                        row[pressure],
                        row[shear],
                        row[status]
                    );
                }
                assert!(seen_shared, "{name}: pair {p} does not reach {shared:?}");
            }
            Ok(0.0)
        })
        .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(frames > 3, "{name}: {frames} frames");
    }
}

/// Runs `case` with the program and returns its output folder.
fn run(case: &Path) -> PathBuf {
    let out = case.parent().unwrap().join("out");
    let output = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .arg("run")
        .arg(case)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}: {}",
        case.display(),
        String::from_utf8_lossy(&output.stderr)
    );
    out
}

/// The run's files of each pair agree with each other and with its side-A curve: the
/// resultants of `history.csv` are the integrals of the pair's contact CSV, and the wear CSV
/// lists the pair's side-A nodes in order along the curve (here coincident with side B, so
/// at the positions and arc lengths of the contact CSV) with the contact CSV's wear depths.
#[test]
fn history_and_wear_files_agree_with_each_pairs_contact_table() {
    for (name, path, shared, pairs) in cases("files") {
        let out = run(&path);
        let (hh, history) = read_csv(&out.join("history.csv"));
        let frames = history.len() - 1;
        let last = &history[frames];
        let mut worn = false;
        for pair in pairs {
            let (ch, rows) = read_csv(&out.join(format!("contact_{pair}_{frames:04}.csv")));
            let col = |c: &str| ch[c];
            // Simpson's rule per element over the rows (end, mid, end, mid, ..., end).
            assert_eq!(rows.len() % 2, 1, "{name} {pair}: rows");
            let integral = |c: usize| {
                (0..rows.len() / 2)
                    .map(|k| {
                        let (a, m, b) = (&rows[2 * k], &rows[2 * k + 1], &rows[2 * k + 2]);
                        let h = b[ch["arc_length"]] - a[ch["arc_length"]];
                        h / 6.0 * (a[c] + 4.0 * m[c] + b[c])
                    })
                    .sum::<f64>()
            };
            let normal = integral(col("contact_normal_stress"));
            let shear = integral(col("contact_shear_stress"));
            let n_history = last[hh[&format!("{pair}_normal_force")]];
            let t_history = last[hh[&format!("{pair}_tangential_force")]];
            assert!(n_history < -10.0, "{name} {pair}: the pair carries load");
            let tol = 1e-8 * n_history.abs();
            assert!(
                (normal - n_history).abs() < tol && (shear - t_history).abs() < tol,
                "{name} {pair}: the contact CSV integrates to N = {normal}, T = {shear}; \
                 history.csv has N = {n_history}, T = {t_history}"
            );
            let at_shared = rows
                .iter()
                .find(|r| close([r[col("x")], r[col("y")]], shared))
                .unwrap_or_else(|| panic!("{name} {pair}: no row at {shared:?}"));
            assert!(
                at_shared[col("contact_pressure")] > 0.0 && at_shared[col("contact_status")] > 0.0,
                "{name} {pair}: open at the shared node"
            );

            // The wear profile of the last cycle end.
            let (wh, wear) = read_csv(&out.join(format!("wear_{pair}.csv")));
            let last_cycle = wear.last().unwrap()[wh["cycles"]];
            let step = wear.last().unwrap()[wh["analysis_step"]];
            let profile: Vec<&Vec<f64>> = wear
                .iter()
                .filter(|r| r[wh["cycles"]] == last_cycle && r[wh["analysis_step"]] == step)
                .collect();
            assert_eq!(profile.len(), rows.len(), "{name} {pair}: wear rows");
            for (w, c) in profile.iter().zip(&rows) {
                let (wx, cx) = ([w[wh["x"]], w[wh["y"]]], [c[col("x")], c[col("y")]]);
                assert!(
                    close(wx, cx) && (w[wh["s"]] - c[col("arc_length")]).abs() < 1e-9,
                    "{name} {pair}: wear row at {wx:?} (s = {}), contact row at {cx:?} \
                     (s = {})",
                    w[wh["s"]],
                    c[col("arc_length")]
                );
                assert!(
                    (w[wh["wear_depth"]] - c[col("wear_depth")]).abs()
                        <= 1e-9 * c[col("wear_depth")].abs() + 1e-300,
                    "{name} {pair} at {wx:?}: wear depth {} in the wear CSV, {} in the \
                     contact CSV",
                    w[wh["wear_depth"]],
                    c[col("wear_depth")]
                );
            }
            worn |= profile.iter().any(|w| w[wh["wear_depth"]] > 0.0);
        }
        assert!(worn, "{name}: nothing wears");
    }
}
