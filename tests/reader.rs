//! Integration tests of the MSH 4.1 reader on the gmsh-generated fixtures of `tests/fixtures`
//! (see `tests/fixtures/README.md` for how each was made).

use std::path::PathBuf;

use asperity::Error;
use asperity::error::MeshProblem;
use asperity::mesh::msh::{describe, read_msh};
use asperity::mesh::{Cell, CellKind, Mesh};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn read(name: &str) -> Mesh {
    read_msh(&fixture(name)).unwrap_or_else(|e| panic!("reading {name}: {e}"))
}

/// Every fixture that must read successfully.
const GOOD: &[&str] = &[
    "two_bodies_ascii.msh",
    "two_bodies_bin.msh",
    "two_bodies_reversed_tags.msh",
    "two_bodies_sparse_tags.msh",
    "tri6.msh",
    "clockwise.msh",
    "sparse.msh",
    "crack.msh",
];

fn corners(cell: &Cell) -> usize {
    cell.kind.corner_count()
}

/// Signed area of the corner polygon, computed here independently of the reader.
fn signed_area(mesh: &Mesh, cell: &Cell) -> f64 {
    let n = corners(cell);
    (0..n)
        .map(|i| {
            let a = mesh.nodes[cell.nodes[i] as usize];
            let b = mesh.nodes[cell.nodes[(i + 1) % n] as usize];
            0.5 * (a[0] * b[1] - b[0] * a[1])
        })
        .sum()
}

fn close(a: [f64; 2], b: [f64; 2], tol: f64) -> bool {
    (a[0] - b[0]).abs() <= tol && (a[1] - b[1]).abs() <= tol
}

fn midpoint(mesh: &Mesh, a: u32, b: u32) -> [f64; 2] {
    let (a, b) = (mesh.nodes[a as usize], mesh.nodes[b as usize]);
    [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]
}

/// (dim, tag, name, entities) of every group, for comparisons.
fn groups(mesh: &Mesh) -> Vec<(u8, i32, String, Vec<i32>)> {
    mesh.groups
        .iter()
        .map(|g| (g.dim, g.tag, g.name.clone(), g.entities.clone()))
        .collect()
}

fn assert_same_mesh(a: &Mesh, b: &Mesh, what: &str) {
    assert_eq!(a.nodes.len(), b.nodes.len(), "{what}: node count");
    for (i, (p, q)) in a.nodes.iter().zip(&b.nodes).enumerate() {
        // gmsh writes 16 significant digits in ascii, so ascii and binary differ in the last bit.
        assert!(close(*p, *q, 1e-13), "{what}: node {i}: {p:?} vs {q:?}");
    }
    assert_eq!(a.cells, b.cells, "{what}: cells");
    assert_eq!(a.lines, b.lines, "{what}: lines");
    assert_eq!(a.points, b.points, "{what}: points");
    assert_eq!(groups(a), groups(b), "{what}: groups");
    assert_eq!(
        a.reoriented_cells, b.reoriented_cells,
        "{what}: reoriented cells"
    );
}

#[test]
fn ascii_and_binary_give_the_same_mesh() {
    let ascii = read("two_bodies_ascii.msh");
    let binary = read("two_bodies_bin.msh");
    assert_same_mesh(&ascii, &binary, "ascii vs binary");
    assert_eq!(ascii.node_tags, binary.node_tags);
}

#[test]
fn two_bodies_counts_and_groups() {
    let mesh = read("two_bodies_ascii.msh");
    assert_eq!(mesh.nodes.len(), 92);
    assert_eq!(mesh.node_tags, (1..=92).collect::<Vec<u64>>());
    assert_eq!(mesh.cells.len(), 22);
    assert!(mesh.cells.iter().all(|c| c.kind == CellKind::Quad8));
    assert_eq!(mesh.lines.len(), 16);
    assert_eq!(mesh.points.len(), 1);
    assert_eq!(mesh.reoriented_cells, 0);
    let expected: Vec<(u8, i32, String, Vec<i32>)> = vec![
        (0, 6, "corner".into(), vec![1]),
        (1, 3, "bottom".into(), vec![1]),
        (1, 4, "top".into(), vec![7]),
        (1, 5, "contact".into(), vec![3, 5]),
        (2, 1, "body_a".into(), vec![1]),
        (2, 2, "body_b".into(), vec![2]),
    ];
    assert_eq!(groups(&mesh), expected);

    let body_a = mesh.group(2, "body_a").expect("body_a");
    let body_b = mesh.group(2, "body_b").expect("body_b");
    assert_eq!(mesh.cells_in(body_a).count(), 11);
    assert_eq!(mesh.cells_in(body_b).count(), 11);
    assert_eq!(mesh.lines_in(mesh.group(1, "contact").unwrap()).count(), 8);
    let corner: Vec<u32> = mesh.points_in(mesh.group(0, "corner").unwrap()).collect();
    assert_eq!(corner.len(), 1);
    assert!(close(mesh.nodes[corner[0] as usize], [0.0, 0.0], 0.0));
    // Lines of "bottom" lie on y = 0, lines of "top" on y = 2.
    for (name, y) in [("bottom", 0.0), ("top", 2.0)] {
        let g = mesh.group(1, name).unwrap();
        assert_eq!(mesh.lines_in(g).count(), 4, "{name}");
        for l in mesh.lines_in(g) {
            for &n in &l.nodes {
                assert!((mesh.nodes[n as usize][1] - y).abs() < 1e-12, "{name}");
            }
        }
    }
    // Body a fills [0,2]x[0,1] and body b [0,2]x[1,2]: the areas add up.
    let area = |g| {
        mesh.cells_in(g)
            .map(|(_, c)| signed_area(&mesh, c))
            .sum::<f64>()
    };
    assert!((area(body_a) - 2.0).abs() < 1e-9);
    assert!((area(body_b) - 2.0).abs() < 1e-9);
}

#[test]
fn every_cell_is_counter_clockwise_with_consistent_mid_nodes() {
    for name in GOOD {
        let mesh = read(name);
        for c in &mesh.cells {
            assert!(
                signed_area(&mesh, c) > 0.0,
                "{name}: element {} is clockwise",
                c.tag
            );
            // All fixtures have straight edges: mid-side node k lies halfway along edge k,
            // which checks the node permutation of reoriented cells.
            let n = corners(c);
            for k in 0..n {
                let mid = midpoint(&mesh, c.nodes[k], c.nodes[(k + 1) % n]);
                let node = mesh.nodes[c.nodes[n + k] as usize];
                assert!(close(mid, node, 1e-9), "{name}: element {} edge {k}", c.tag);
            }
        }
    }
}

#[test]
fn line3_mid_node_is_halfway_on_straight_edges() {
    for name in GOOD {
        let mesh = read(name);
        assert!(!mesh.lines.is_empty(), "{name} has lines");
        for l in &mesh.lines {
            let mid = midpoint(&mesh, l.nodes[0], l.nodes[1]);
            assert!(
                close(mid, mesh.nodes[l.nodes[2] as usize], 1e-9),
                "{name}: line {}",
                l.tag
            );
        }
    }
}

#[test]
fn clockwise_fixture_is_reoriented() {
    let mesh = read("clockwise.msh");
    assert!(mesh.reoriented_cells > 0);
    assert_eq!(
        mesh.reoriented_cells,
        mesh.cells.len(),
        "every cell was clockwise"
    );
    let total: f64 = mesh.cells.iter().map(|c| signed_area(&mesh, c)).sum();
    assert!((total - 2.0).abs() < 1e-9);
}

#[test]
fn tri6_fixture() {
    let mesh = read("tri6.msh");
    assert!(mesh.cells.iter().all(|c| c.kind == CellKind::Tri6));
    let left = mesh.group(2, "left").unwrap();
    let right = mesh.group(2, "right").unwrap();
    let (n_left, n_right) = (mesh.cells_in(left).count(), mesh.cells_in(right).count());
    assert!(n_left > 0 && n_right > 0);
    assert_eq!(n_left + n_right, mesh.cells.len());
    // Surface 2 was given by a clockwise curve loop: exactly its cells were reoriented.
    assert_eq!(mesh.reoriented_cells, n_right);
    let base = mesh.group(1, "base").unwrap();
    assert_eq!(base.entities, vec![1, 5]);
    assert!(mesh.lines_in(base).count() > 0);
}

#[test]
fn permuted_and_sparse_node_tags_give_the_same_mesh() {
    let original = read("two_bodies_ascii.msh");
    // Same file with tag t -> 93 - t: still dense (mshio drops such tags), but not in file order.
    let reversed = read("two_bodies_reversed_tags.msh");
    assert_same_mesh(&original, &reversed, "reversed tags");
    let expected: Vec<u64> = original.node_tags.iter().map(|t| 93 - t).collect();
    assert_eq!(reversed.node_tags, expected);
    // Same file with tag t -> 10 t + 3: sparse.
    let sparse = read("two_bodies_sparse_tags.msh");
    assert_same_mesh(&original, &sparse, "sparse tags");
    let expected: Vec<u64> = original.node_tags.iter().map(|t| 10 * t + 3).collect();
    assert_eq!(sparse.node_tags, expected);
}

#[test]
fn gmsh_sparse_tags() {
    let mesh = read("sparse.msh");
    assert_eq!(mesh.nodes.len(), 27);
    assert_eq!(mesh.cells.len(), 6);
    let expected = vec![
        (1, 2, "right".to_string(), vec![6]),
        (2, 1, "kept".to_string(), vec![2]),
    ];
    assert_eq!(groups(&mesh), expected);
    assert_eq!(mesh.lines.len(), 2);
    // Tags are not contiguous and not sorted in the file.
    assert_eq!(*mesh.node_tags.iter().min().unwrap(), 5);
    assert_eq!(*mesh.node_tags.iter().max().unwrap(), 56);
    let total: f64 = mesh.cells.iter().map(|c| signed_area(&mesh, c)).sum();
    assert!((total - 1.0).abs() < 1e-9);
}

#[test]
fn crack_plugin_mesh_separates_the_bodies() {
    let mesh = read("crack.msh");
    let lower = mesh.group(2, "lower").unwrap();
    let upper = mesh.group(2, "upper").unwrap();
    let nodes_of = |g| {
        let mut v: Vec<u32> = mesh
            .cells_in(g)
            .flat_map(|(_, c)| c.nodes().to_vec())
            .collect::<Vec<_>>();
        v.sort_unstable();
        v.dedup();
        v
    };
    let (a, b) = (nodes_of(lower), nodes_of(upper));
    assert!(
        a.iter().all(|n| b.binary_search(n).is_err()),
        "bodies share no node after Crack"
    );
    // Along y = 1 both bodies have nodes at the same places (5 per side for 2 quad8 edges).
    let on_interface = |v: &[u32]| {
        v.iter()
            .filter(|&&n| mesh.nodes[n as usize][1] == 1.0)
            .count()
    };
    assert_eq!(on_interface(&a), 5);
    assert_eq!(on_interface(&b), 5);
}

/// Reads a bad fixture and checks that the error is a mesh error of that file with the
/// expected problem, and that its message stays short.
fn assert_error(name: &str, expected: MeshProblem) {
    let path = fixture(name);
    let result = std::panic::catch_unwind(|| read_msh(&path));
    let result = result.unwrap_or_else(|_| panic!("{name}: the reader panicked"));
    let e = match result {
        Ok(_) => panic!("{name}: read without error"),
        Err(e) => e,
    };
    let message = e.to_string();
    match e {
        Error::Mesh {
            path: file,
            problem,
            ..
        } => {
            assert_eq!(file, path, "{message}");
            assert_eq!(problem, expected, "{name}: {message}");
        }
        other => panic!("{name}: expected a mesh error, got {other}"),
    }
    assert!(message.len() < 600, "{name}: message too long: {message}");
}

#[test]
fn bad_files_give_clear_errors() {
    assert_error("truncated.msh", MeshProblem::Truncated);
    assert_error("truncated_bin.msh", MeshProblem::Truncated);
    assert_error("msh22.msh", MeshProblem::Version);
    assert_error("linear.msh", MeshProblem::FirstOrder);
    assert_error("quad9.msh", MeshProblem::UnsupportedElement);
    assert_error("empty.msh", MeshProblem::Empty);
    assert_error("does_not_exist.msh", MeshProblem::NotFound);
    assert_error("two_bodies.geo", MeshProblem::Header);
    assert_error("parametric.msh", MeshProblem::Parametric);
}

#[test]
fn describe_reports_counts_groups_and_no_problems() {
    let report = describe(&read("two_bodies_bin.msh"), &[]);
    for expected in [
        "nodes: 92",
        "cells: 22 (quad8: 22, tri6: 0)",
        "lines: 16",
        "points: 1",
        "reoriented to counter-clockwise: 0",
        "physical groups: 6",
        "body_a",
        "contact",
        "problems: none",
    ] {
        assert!(
            report.contains(expected),
            "missing `{expected}` in:\n{report}"
        );
    }
    let mesh = read("clockwise.msh");
    let report = describe(&mesh, &[]);
    let line = format!("counter-clockwise: {}", mesh.cells.len());
    assert!(report.contains(&line), "missing `{line}` in:\n{report}");
}

#[test]
fn describe_reports_problems() {
    let mut mesh = read("two_bodies_ascii.msh");
    // A node used by nothing, an empty group, a degenerate cell.
    mesh.nodes.push([5.0, 5.0]);
    mesh.node_tags.push(1000);
    mesh.groups.push(asperity::mesh::PhysicalGroup {
        dim: 1,
        tag: 99,
        name: "nowhere".into(),
        entities: vec![42],
    });
    let c = &mut mesh.cells[0];
    c.nodes[1] = c.nodes[0];
    c.nodes[2] = c.nodes[0];
    let report = describe(&mesh, &[]);
    for expected in [
        "1 nodes are used by no element (tags 1000)",
        "\"nowhere\"",
        "has no lines",
        "degenerate",
    ] {
        assert!(
            report.contains(expected),
            "missing `{expected}` in:\n{report}"
        );
    }
}

#[test]
#[ignore = "prints the error messages of the bad fixtures, for eyeballing"]
fn print_error_messages() {
    for name in [
        "truncated.msh",
        "truncated_bin.msh",
        "msh22.msh",
        "linear.msh",
        "quad9.msh",
        "empty.msh",
        "does_not_exist.msh",
        "two_bodies.geo",
        "parametric.msh",
    ] {
        println!("{}", read_msh(&fixture(name)).unwrap_err());
    }
    println!("{}", describe(&read("crack.msh"), &[]));
}

/// Timing of a large mesh (e.g. 500k nodes, 170k quad8): set `ASPERITY_BIG_MSH` to its path and
/// run `cargo test --release --test reader -- --ignored --nocapture big_mesh_timing`.
#[test]
#[ignore = "needs a large mesh file in ASPERITY_BIG_MSH"]
fn big_mesh_timing() {
    let Ok(paths) = std::env::var("ASPERITY_BIG_MSH") else {
        return;
    };
    for path in paths.split(':') {
        let start = std::time::Instant::now();
        let mesh = read_msh(std::path::Path::new(path)).unwrap();
        println!(
            "{path}: {} nodes, {} cells, {} lines in {:.2} s",
            mesh.nodes.len(),
            mesh.cells.len(),
            mesh.lines.len(),
            start.elapsed().as_secs_f64()
        );
    }
}

/// Heap use of the reader: the system allocator, tracking the live bytes of this test's
/// thread and their peak (other threads are not counted; the reader runs on the caller's).
mod heap {
    use std::alloc::{GlobalAlloc, Layout, System};
    use std::cell::Cell;

    pub struct Tracking;

    thread_local! {
        /// (tracked, live bytes, peak live bytes) of this thread.
        static STATE: Cell<(bool, isize, isize)> = const { Cell::new((false, 0, 0)) };
    }

    fn add(delta: isize) {
        let _ = STATE.try_with(|s| {
            let (on, live, peak) = s.get();
            if on {
                s.set((on, live + delta, peak.max(live + delta)));
            }
        });
    }

    // SAFETY: every call is forwarded unchanged to the system allocator.
    unsafe impl GlobalAlloc for Tracking {
        unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
            add(layout.size() as isize);
            unsafe { System.alloc(layout) }
        }

        unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
            add(-(layout.size() as isize));
            unsafe { System.dealloc(ptr, layout) }
        }

        unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
            add(layout.size() as isize);
            unsafe { System.alloc_zeroed(layout) }
        }

        unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
            add(new_size as isize - layout.size() as isize);
            unsafe { System.realloc(ptr, layout, new_size) }
        }
    }

    /// Peak heap bytes (above the start) of this thread while `f` runs.
    pub fn peak<T>(f: impl FnOnce() -> T) -> (T, usize) {
        STATE.with(|s| s.set((true, 0, 0)));
        let value = f();
        let (_, _, peak) = STATE.with(|s| s.replace((false, 0, 0)));
        (value, peak.max(0) as usize)
    }
}

#[global_allocator]
static HEAP: heap::Tracking = heap::Tracking;

/// The reader's peak heap use is bounded by a small multiple of the file size, for good files
/// (ascii and binary, up to ~1 MB) and for files whose headers announce 10¹² entries: it
/// never trusts a count for an allocation. The bound: the file's bytes (read whole), mshio's
/// nodes (24 bytes of coordinates per ≥ 24 bytes of binary or ≥ 6 bytes of ascii text) and
/// elements (a `Vec` per element), and the mesh itself, about 8× the ascii size in all;
/// 64 KiB cover fixed costs of tiny files. Measured: 3.6 at most on the ~1 MB files.
#[test]
fn reader_memory_is_a_small_multiple_of_the_file_size() {
    const FACTOR: usize = 8;
    const FIXED: usize = 64 << 10;
    let dir = tempfile::tempdir().unwrap();
    let mut files: Vec<PathBuf> = std::fs::read_dir(fixture(""))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "msh"))
        .collect();
    for (name, binary) in [("fine_ascii.msh", false), ("fine_bin.msh", true)] {
        let out = dir.path().join(name);
        let mut gmsh = std::process::Command::new("gmsh");
        gmsh.arg(fixture("contact_pair.geo"))
            .args([
                "-2",
                "-order",
                "2",
                "-setnumber",
                "Mesh.SecondOrderIncomplete",
                "1",
            ])
            .args(["-format", "msh41", "-clscale", "0.15", "-v", "0", "-o"])
            .arg(&out);
        if binary {
            gmsh.arg("-bin");
        }
        assert!(gmsh.status().unwrap().success());
        files.push(out);
    }
    let lying = std::fs::read_to_string(fixture("two_bodies_ascii.msh"))
        .unwrap()
        .replacen("$Nodes\n", "$Nodes\n1000000000000 ", 1);
    let lying_path = dir.path().join("lying.msh");
    std::fs::write(&lying_path, lying).unwrap();
    files.push(lying_path);
    let mut worst = 0.0f64;
    for path in files {
        let size = std::fs::metadata(&path).unwrap().len() as usize;
        let (_, peak) = heap::peak(|| read_msh(&path));
        assert!(
            peak <= FACTOR * size + FIXED,
            "{}: {peak} bytes for a {size}-byte file",
            path.display()
        );
        if size > 100_000 {
            worst = worst.max(peak as f64 / size as f64);
        }
    }
    println!("worst peak heap / file size of the large files: {worst:.2}");
}
