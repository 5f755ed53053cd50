//! Integration tests of the interface topology builder (`asperity::mesh::interface`) on the
//! gmsh fixtures `contact_pair*.msh` (Coincident), `split.msh` (Split) and `hertz*.msh`
//! (Ordered); see `tests/fixtures/README.md`.
//!
//! Orientation is checked independently of the implementation: for every element the normal
//! n = rot90(b1 − b0) must point from the face into the centroid of the B cell that carries
//! the B nodes, and away from the A cell carrying the A nodes (Buczkowski & Kleiber (1994),
//! Eqs. 24–26: n from side B's geometry, u_N = (u^B − u^A)·n).

use std::collections::HashSet;
use std::path::PathBuf;

use asperity::Error;
use asperity::error::{GroupKind, GroupProblem, TopologyProblem};
use asperity::mesh::interface::*;
use asperity::mesh::msh::read_msh;
use asperity::mesh::{Cell, Mesh};

fn read(name: &str) -> Mesh {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name);
    read_msh(&path).unwrap_or_else(|e| panic!("reading {name}: {e}"))
}

fn coincident(a: &str, b: &str) -> Pairing {
    Pairing::Coincident {
        side_a: a.into(),
        side_b: b.into(),
    }
}

fn ordered(a: &str, b: &str) -> Pairing {
    Pairing::Ordered {
        side_a: a.into(),
        side_b: b.into(),
    }
}

fn split(curve: &str, a: &str, b: &str) -> Pairing {
    Pairing::Split {
        curve: curve.into(),
        body_a: a.into(),
        body_b: b.into(),
    }
}

/// The error of a call that must fail.
fn error(mesh: &mut Mesh, pairing: &Pairing, name: &str, bodies: &[&str]) -> Error {
    match insert_interface(mesh, pairing, name, bodies) {
        Ok(t) => panic!("expected an error, got {} elements", t.elements.len()),
        Err(e) => e,
    }
}

/// What a topology error of pair `name` names: the problem, the node's coordinates and the
/// end points of the line element.
type Named = (TopologyProblem, Option<[f64; 2]>, Option<[[f64; 2]; 2]>);

fn topology(mesh: &Mesh, e: Error, name: &str) -> Named {
    let Error::Topology {
        pair,
        problem,
        node,
        element,
        ..
    } = e
    else {
        panic!("expected a topology error, got {e}")
    };
    assert_eq!(pair, name);
    let node = node.map(|t| mesh.nodes[mesh.node_tags.iter().position(|&n| n == t).unwrap()]);
    let line = element.map(|t| {
        let l = mesh.lines.iter().find(|l| l.tag == t).unwrap();
        [x(mesh, l.nodes[0]), x(mesh, l.nodes[1])]
    });
    (problem, node, line)
}

/// The topology error of a call that must fail.
fn topology_error(mesh: &mut Mesh, pairing: &Pairing, name: &str, bodies: &[&str]) -> Named {
    let e = error(mesh, pairing, name, bodies);
    topology(mesh, e, name)
}

/// The group error of a call that must fail: role, name, expected kind and the
/// alternatives listed.
fn group_error(
    mesh: &mut Mesh,
    pairing: &Pairing,
    name: &str,
    bodies: &[&str],
) -> (String, String, GroupKind, String) {
    match error(mesh, pairing, name, bodies) {
        Error::Group {
            role,
            name,
            expected,
            problem: GroupProblem::Missing { available },
            ..
        } => (role, name, expected, available),
        other => panic!("expected a missing group, got {other}"),
    }
}

fn x(mesh: &Mesh, n: u32) -> [f64; 2] {
    mesh.nodes[n as usize]
}

fn dist(p: [f64; 2], q: [f64; 2]) -> f64 {
    (p[0] - q[0]).hypot(p[1] - q[1])
}

fn corners(cell: &Cell) -> &[u32] {
    &cell.nodes[..cell.kind.corner_count()]
}

/// Centroid of the corners of the cells of `bodies` containing all three `nodes`.
fn owner_centroids(mesh: &Mesh, bodies: &[&str], nodes: [u32; 3]) -> Vec<[f64; 2]> {
    let groups: Vec<_> = bodies.iter().map(|b| mesh.group(2, b).unwrap()).collect();
    mesh.cells
        .iter()
        .filter(|c| groups.iter().any(|g| g.entities.contains(&c.entity)))
        .filter(|c| nodes.iter().all(|n| c.nodes().contains(n)))
        .map(|c| {
            let k = corners(c);
            let mut s = [0.0; 2];
            for &n in k {
                s[0] += x(mesh, n)[0] / k.len() as f64;
                s[1] += x(mesh, n)[1] / k.len() as f64;
            }
            s
        })
        .collect()
}

/// n = rot90(b1 − b0) points into the B cell and away from the A cell, one cell each side.
fn check_orientation(mesh: &Mesh, t: &InterfaceTopology, bodies: &[&str]) {
    for e in &t.elements {
        let (b0, b1, bm) = (x(mesh, e[3]), x(mesh, e[4]), x(mesh, e[5]));
        let n = [-(b1[1] - b0[1]), b1[0] - b0[0]];
        let side = |c: [f64; 2]| (c[0] - bm[0]) * n[0] + (c[1] - bm[1]) * n[1];
        let b_cells = owner_centroids(mesh, bodies, [e[3], e[4], e[5]]);
        let a_cells = owner_centroids(mesh, bodies, [e[0], e[1], e[2]]);
        assert_eq!(
            b_cells.len(),
            1,
            "B nodes of {e:?} must be a face of one cell"
        );
        assert_eq!(
            a_cells.len(),
            1,
            "A nodes of {e:?} must be a face of one cell"
        );
        assert!(
            side(b_cells[0]) > 0.0,
            "normal of {e:?} does not point into B"
        );
        assert!(
            side(a_cells[0]) < 0.0,
            "A cell of {e:?} is not behind the face"
        );
    }
}

/// Nodes of the lines of curve group `name`.
fn curve_nodes(mesh: &Mesh, name: &str) -> HashSet<u32> {
    let g = mesh.group(1, name).unwrap();
    mesh.lines_in(g).flat_map(|l| l.nodes).collect()
}

/// The B triple of every element is one line of curve `b`, each line used once; A nodes are
/// nodes of curve `a`; offsets are x_B − x_A.
fn check_faces(mesh: &Mesh, t: &InterfaceTopology, a: &str, b: &str) {
    assert_eq!(t.elements.len(), t.offsets.len());
    let g = mesh.group(1, b).unwrap();
    let mut b_lines: Vec<[u32; 3]> = mesh
        .lines_in(g)
        .map(|l| {
            let mut k = l.nodes;
            k[..2].sort_unstable();
            k
        })
        .collect();
    let mut used: Vec<[u32; 3]> = t
        .elements
        .iter()
        .map(|e| {
            let mut k = [e[3], e[4], e[5]];
            k[..2].sort_unstable();
            k
        })
        .collect();
    b_lines.sort_unstable();
    used.sort_unstable();
    assert_eq!(used, b_lines);
    let a_nodes = curve_nodes(mesh, a);
    for (e, o) in t.elements.iter().zip(&t.offsets) {
        assert!(e[..3].iter().all(|n| a_nodes.contains(n)), "{e:?}");
        for i in 0..3 {
            let (pa, pb) = (x(mesh, e[i]), x(mesh, e[i + 3]));
            assert_eq!(o[i], [pb[0] - pa[0], pb[1] - pa[1]], "{e:?}");
        }
    }
}

// ------------------------------------------------------------------------------------------
// Coincident
// ------------------------------------------------------------------------------------------

#[test]
fn coincident_faces_in_either_direction() {
    // contact_pair.msh: curves drawn in opposite directions; _flipped: in the same direction.
    for file in ["contact_pair.msh", "contact_pair_flipped.msh"] {
        let mut mesh = read(file);
        let before = (mesh.nodes.len(), mesh.cells.clone(), mesh.lines.clone());
        let bodies = ["lower", "upper"];
        for (a, b) in [("lower_top", "upper_bottom"), ("upper_bottom", "lower_top")] {
            let t = insert_interface(&mut mesh, &coincident(a, b), "joint", &bodies)
                .unwrap_or_else(|e| panic!("{file}: {e}"));
            assert_eq!(t.elements.len(), 8, "{file}");
            check_faces(&mesh, &t, a, b);
            for (e, o) in t.elements.iter().zip(&t.offsets) {
                for i in 0..3 {
                    assert_ne!(e[i], e[i + 3], "{file}: A and B nodes must be distinct");
                    // gmsh places the points of the two curves independently: ~1e-12 apart.
                    assert!(dist(x(&mesh, e[i]), x(&mesh, e[i + 3])) < 1e-9);
                    assert!(o[i][0].abs() < 1e-9 && o[i][1].abs() < 1e-9);
                }
                // The upper body is above y = 1: n into it means b0 → b1 walks in +x.
                let dx = x(&mesh, e[4])[0] - x(&mesh, e[3])[0];
                assert!(if b == "upper_bottom" {
                    dx > 0.0
                } else {
                    dx < 0.0
                });
            }
            check_orientation(&mesh, &t, &bodies);
        }
        // Coincident leaves the mesh alone.
        assert_eq!(mesh.nodes.len(), before.0);
        assert_eq!(mesh.cells, before.1);
        assert_eq!(mesh.lines, before.2);
    }
}

#[test]
fn ordered_pairing_of_coincident_faces_matches_coincident() {
    let mut mesh = read("contact_pair_flipped.msh");
    let bodies = ["lower", "upper"];
    let c = insert_interface(
        &mut mesh,
        &coincident("lower_top", "upper_bottom"),
        "joint",
        &bodies,
    )
    .unwrap();
    let o = insert_interface(
        &mut mesh,
        &ordered("lower_top", "upper_bottom"),
        "joint",
        &bodies,
    )
    .unwrap();
    let set = |t: &InterfaceTopology| t.elements.iter().copied().collect::<HashSet<_>>();
    assert_eq!(set(&c), set(&o));
}

// ------------------------------------------------------------------------------------------
// Split
// ------------------------------------------------------------------------------------------

#[test]
fn split_duplicates_the_curve_and_moves_body_b() {
    let mut mesh = read("split.msh");
    let before = mesh.clone();
    let cut = curve_nodes(&mesh, "cut");
    let end_points: Vec<u32> = cut
        .iter()
        .copied()
        .filter(|&n| dist(x(&mesh, n), [2.0, 1.0]) < 1e-12 || dist(x(&mesh, n), [0.0, 1.0]) < 1e-12)
        .collect();
    assert_eq!(end_points.len(), 2);
    let max_tag = *mesh.node_tags.iter().max().unwrap();
    let bodies = ["lower", "upper"];

    let t = insert_interface(&mut mesh, &split("cut", "lower", "upper"), "cut", &bodies).unwrap();

    // One new node per curve node, with fresh tags above the old maximum.
    let n0 = before.nodes.len();
    assert_eq!(mesh.nodes.len(), n0 + cut.len());
    assert_eq!(mesh.node_tags.len(), mesh.nodes.len());
    assert_eq!(mesh.nodes[..n0], before.nodes[..]);
    assert!(mesh.node_tags[n0..].iter().all(|&t| t > max_tag));
    let tags: HashSet<u64> = mesh.node_tags.iter().copied().collect();
    assert_eq!(tags.len(), mesh.node_tags.len());

    // Interface: A = originals on the curve, B = the copies, at the same place.
    assert_eq!(
        t.elements.len(),
        mesh.lines_in(mesh.group(1, "cut").unwrap()).count()
    );
    for (e, o) in t.elements.iter().zip(&t.offsets) {
        assert!(e[..3].iter().all(|n| cut.contains(n)));
        assert!(e[3..].iter().all(|&n| n as usize >= n0));
        for i in 0..3 {
            assert_eq!(x(&mesh, e[i]), x(&mesh, e[i + 3]));
            assert_eq!(o[i], [0.0, 0.0]);
        }
    }
    let b_side: HashSet<u32> = t.elements.iter().flat_map(|e| e[3..].to_vec()).collect();
    assert_eq!(b_side.len(), cut.len());
    check_orientation(&mesh, &t, &bodies);

    // The end points are duplicated too.
    for &p in &end_points {
        assert!(
            b_side
                .iter()
                .any(|&b| b as usize >= n0 && x(&mesh, b) == x(&mesh, p)),
            "end point {:?} not duplicated",
            x(&mesh, p)
        );
    }

    // No lower cell shares a node with an upper cell any more; lower cells are untouched.
    let (lower, upper) = (
        mesh.group(2, "lower").unwrap(),
        mesh.group(2, "upper").unwrap(),
    );
    let lower_nodes: HashSet<u32> = mesh
        .cells_in(lower)
        .flat_map(|(_, c)| c.nodes().to_vec())
        .collect();
    for (_, c) in mesh.cells_in(upper) {
        assert!(
            c.nodes().iter().all(|n| !lower_nodes.contains(n)),
            "cell {}",
            c.tag
        );
    }
    for (i, c) in mesh.cells_in(lower) {
        assert_eq!(*c, before.cells[i]);
    }

    // Boundary lines: the upper body's right side touching the curve's end now uses the copy,
    // the lower body's right side and the curve itself keep the originals.
    let uses_copy = |name: &str| {
        mesh.lines_in(mesh.group(1, name).unwrap())
            .any(|l| l.nodes.iter().any(|&n| n as usize >= n0))
    };
    assert!(uses_copy("upper_right"));
    assert!(!uses_copy("lower_right"));
    assert!(!uses_copy("cut"));
    assert!(!uses_copy("base") && !uses_copy("lid"));
    let corner = mesh
        .lines_in(mesh.group(1, "upper_right").unwrap())
        .flat_map(|l| l.nodes)
        .find(|&n| dist(x(&mesh, n), [2.0, 1.0]) < 1e-12)
        .unwrap();
    assert!(corner as usize >= n0);
    // Point elements stay with body A.
    let point = mesh
        .points_in(mesh.group(0, "cut_end").unwrap())
        .next()
        .unwrap();
    assert!((point as usize) < n0);

    // The curve is already split: splitting again fails and changes nothing.
    let after = mesh.clone();
    let e = topology_error(&mut mesh, &split("cut", "lower", "upper"), "cut", &bodies);
    assert_eq!(e.0, TopologyProblem::AlreadySplit);
    assert_eq!(mesh.nodes, after.nodes);
    assert_eq!(mesh.cells, after.cells);
    assert_eq!(mesh.lines, after.lines);
}

#[test]
fn split_with_roles_swapped_moves_the_lower_body() {
    let mut mesh = read("split.msh");
    let n0 = mesh.nodes.len();
    let bodies = ["lower", "upper"];
    let t = insert_interface(&mut mesh, &split("cut", "upper", "lower"), "cut", &bodies).unwrap();
    check_orientation(&mesh, &t, &bodies);
    let lower = mesh.group(2, "lower").unwrap();
    assert!(
        mesh.cells_in(lower)
            .any(|(_, c)| c.nodes().iter().any(|&n| n as usize >= n0))
    );
    let uses_copy = |name: &str| {
        mesh.lines_in(mesh.group(1, name).unwrap())
            .any(|l| l.nodes.iter().any(|&n| n as usize >= n0))
    };
    assert!(uses_copy("lower_right") && !uses_copy("upper_right"));
}

#[test]
fn split_errors() {
    let bodies = ["lower", "upper"];
    let mut mesh = read("split.msh");
    let (problem, _, line) =
        topology_error(&mut mesh, &split("base", "lower", "upper"), "s", &bodies);
    assert_eq!(problem, TopologyProblem::NotBetweenBodies);
    assert!(line.unwrap().iter().all(|p| p[1] == 0.0), "{line:?}");
    let (role, name, kind, available) =
        group_error(&mut mesh, &split("crack", "lower", "upper"), "s", &bodies);
    assert_eq!(
        (role.as_str(), name.as_str(), kind),
        ("contact 's': split curve", "crack", GroupKind::Curve)
    );
    assert!(available.contains("cut_lower"), "{available}");
    let (role, name, kind, available) =
        group_error(&mut mesh, &split("cut", "lower", "middle"), "s", &bodies);
    assert_eq!(
        (role.as_str(), name.as_str(), kind),
        ("contact 's': body", "middle", GroupKind::Surface)
    );
    assert_eq!(available, "surfaces: lower, upper");
    let e = topology_error(&mut mesh, &split("cut", "lower", "upper"), "s", &["lower"]);
    assert_eq!(e.0, TopologyProblem::BodyNotInCase);
    assert_eq!(mesh.nodes.len(), read("split.msh").nodes.len());
}

// ------------------------------------------------------------------------------------------
// Ordered
// ------------------------------------------------------------------------------------------

#[test]
fn ordered_faces_with_a_gap() {
    let mut mesh = read("hertz.msh");
    let bodies = ["base", "punch"];
    for (a, b) in [("flat", "arc"), ("arc", "flat")] {
        let t = insert_interface(&mut mesh, &ordered(a, b), "hertz", &bodies).unwrap();
        assert_eq!(t.elements.len(), 10);
        check_faces(&mesh, &t, a, b);
        check_orientation(&mesh, &t, &bodies);
        // Paired in order from the same end: the flat face and the arc span x = -0.5..0.5
        // with the same number of points, so paired nodes are nearly above each other and the
        // gap is vertical: 0.01 at the centre, the arc's height further out.
        let sign = if b == "arc" { 1.0 } else { -1.0 };
        let mut centre = 0;
        for (e, o) in t.elements.iter().zip(&t.offsets) {
            for i in 0..3 {
                let arc = x(&mesh, e[if b == "arc" { i + 3 } else { i }]);
                let gap = 2.01 - (4.0 - arc[0] * arc[0]).sqrt();
                assert!(o[i][0].abs() < 0.01, "{o:?}");
                assert!((sign * o[i][1] - gap).abs() < 1e-9, "{o:?} vs gap {gap}");
                // gmsh places points on circle arcs to ~1e-9.
                if arc[0].abs() < 1e-6 {
                    centre += 1;
                    assert!((sign * o[i][1] - 0.01).abs() < 1e-9 && o[i][0].abs() < 1e-6);
                }
            }
        }
        assert_eq!(centre, 2, "the centre node ends two elements");
        // Consecutive elements share their end nodes on both sides.
        let mut ends: Vec<u32> = t
            .elements
            .iter()
            .flat_map(|e| [e[0], e[1], e[3], e[4]])
            .collect();
        ends.sort_unstable();
        ends.dedup();
        assert_eq!(ends.len(), 2 * 11);
    }
}

#[test]
fn ordered_errors() {
    let bodies = ["base", "punch"];
    let mut mesh = read("hertz_mismatch.msh");
    let e = topology_error(&mut mesh, &ordered("flat", "arc"), "hertz", &bodies);
    assert_eq!(e.0, TopologyProblem::CountMismatch);
    let mut mesh = read("hertz.msh");
    let (problem, _, line) =
        topology_error(&mut mesh, &ordered("free_top", "arc"), "hertz", &bodies);
    assert_eq!(problem, TopologyProblem::Disconnected);
    let free_top = curve_nodes(&mesh, "free_top");
    let on_free_top = |p: [f64; 2]| free_top.iter().any(|&n| x(&mesh, n) == p);
    assert!(line.unwrap().iter().all(|&p| on_free_top(p)), "{line:?}");
    // Faces with a gap are not coincident (the message points to the Ordered recipe).
    let e = topology_error(&mut mesh, &coincident("flat", "arc"), "hertz", &bodies);
    assert_eq!(e.0, TopologyProblem::Unpaired);
}

// ------------------------------------------------------------------------------------------
// Errors common to the recipes
// ------------------------------------------------------------------------------------------

#[test]
fn missing_groups_are_listed() {
    let mut mesh = read("contact_pair.msh");
    let bodies = ["lower", "upper"];
    let (role, name, kind, available) = group_error(
        &mut mesh,
        &coincident("lower_top", "nope"),
        "joint",
        &bodies,
    );
    assert_eq!(
        (role.as_str(), name.as_str(), kind),
        ("contact 'joint': side B curve", "nope", GroupKind::Curve)
    );
    assert!(available.contains("lower_top, upper_bottom"), "{available}");
    let (role, name, _, _) = group_error(
        &mut mesh,
        &ordered("nope", "upper_bottom"),
        "joint",
        &bodies,
    );
    assert_eq!(
        (role.as_str(), name.as_str()),
        ("contact 'joint': side A curve", "nope")
    );
    let (role, name, kind, available) = group_error(
        &mut mesh,
        &coincident("lower_top", "upper_bottom"),
        "joint",
        &["lower", "ghost"],
    );
    assert_eq!(
        (role.as_str(), name.as_str(), kind),
        ("contact 'joint': body", "ghost", GroupKind::Surface)
    );
    assert_eq!(available, "surfaces: lower, upper");
}

#[test]
fn unpaired_nodes_name_counts_and_coordinates() {
    // upper_bottom has 7 mesh points (13 nodes), lower_top 9 (17 nodes).
    let mut mesh = read("contact_pair_mismatch.msh");
    let (problem, node, _) = topology_error(
        &mut mesh,
        &coincident("lower_top", "upper_bottom"),
        "joint",
        &["lower", "upper"],
    );
    assert_eq!(problem, TopologyProblem::Unpaired);
    assert_eq!(node.unwrap()[1], 1.0);
    let e = topology_error(
        &mut mesh,
        &ordered("lower_top", "upper_bottom"),
        "joint",
        &["lower", "upper"],
    );
    assert_eq!(e.0, TopologyProblem::CountMismatch);
}

#[test]
fn curve_of_no_listed_body() {
    let mut mesh = read("contact_pair.msh");
    for pairing in [
        coincident("lower_top", "upper_bottom"),
        ordered("lower_top", "upper_bottom"),
    ] {
        let (problem, _, line) = topology_error(&mut mesh, &pairing, "joint", &["lower"]);
        assert_eq!(problem, TopologyProblem::NoOwner);
        let on_upper_bottom = curve_nodes(&mesh, "upper_bottom");
        let line = line.unwrap();
        assert!(line.iter().all(|p| p[1] == 1.0), "{line:?}");
        assert!(
            line.iter()
                .all(|&p| on_upper_bottom.iter().any(|&n| x(&mesh, n) == p))
        );
    }
}

#[test]
fn conforming_faces_with_coincident_suggest_split() {
    let mut mesh = read("split.msh");
    let (problem, node, _) = topology_error(
        &mut mesh,
        &coincident("cut_lower", "cut_upper"),
        "joint",
        &["lower", "upper"],
    );
    assert_eq!(problem, TopologyProblem::SharedNodes);
    assert_eq!(node.unwrap()[1], 1.0);
    // Same name on both sides, on the old two_bodies fixture (one group for both faces).
    let mut mesh = read("two_bodies_ascii.msh");
    let e = topology_error(
        &mut mesh,
        &coincident("contact", "contact"),
        "joint",
        &["body_a", "body_b"],
    );
    assert_eq!(e.0, TopologyProblem::SameCurve);
}
