//! Limits on the size of a mesh: gmsh is not asked for a mesh beyond
//! [`MAX_MESH_ELEMENTS`] (estimated from probe meshes first), a mesh file beyond
//! [`MAX_MESH_FILE_BYTES`] is not read, and gmsh's own reason for a failure reaches the user.

use std::path::{Path, PathBuf};

use asperity::Error;
use asperity::error::MeshProblem;
use asperity::mesh::gmsh::{MAX_MESH_ELEMENTS, estimate_elements, mesh_geo};
use asperity::mesh::msh::{MAX_MESH_FILE_BYTES, read_msh};

/// A fresh folder for `test`.
fn folder(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("mesh_limits")
        .join(test);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A unit square meshed with triangles of characteristic length 0.1 (about 230 at size
/// factor 1; the count goes as 1/size²).
const SQUARE: &str = r#"
lc = 0.1;
Point(1) = {0, 0, 0, lc}; Point(2) = {1, 0, 0, lc}; Point(3) = {1, 1, 0, lc};
Point(4) = {0, 1, 0, lc};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Physical Surface("square") = {1};
"#;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The number of surface elements gmsh makes of `geo` at size factor `size` (counted by our
/// reader in the quadratic mesh).
fn cells(dir: &Path, geo: &Path, size: f64) -> usize {
    let msh = mesh_geo(geo, size, &[], &dir.join("check.msh")).unwrap();
    read_msh(&msh.path).unwrap().cells.len()
}

#[test]
fn a_tiny_size_factor_is_refused_before_meshing() {
    let dir = folder("tiny");
    let geo = write(&dir, "square.geo", SQUARE);
    let out = dir.join("mesh.msh");
    let size = 1e-6;
    let error = mesh_geo(&geo, size, &[], &out).unwrap_err();
    let Error::Mesh {
        path,
        problem,
        message,
        ..
    } = &error
    else {
        panic!("expected a mesh error, got {error}")
    };
    assert_eq!(*problem, MeshProblem::TooLarge, "{error}");
    assert_eq!(path, &geo);
    assert!(
        message.contains("mesh.size") && message.contains(&MAX_MESH_ELEMENTS.to_string()),
        "{error}"
    );
    assert!(!out.exists(), "no mesh is written");

    // The estimate against the count at size factor 1, scaled by 1/size²: gmsh's triangle
    // counts follow the area law to within a few per cent once there are some hundred.
    let estimate = estimate_elements(&geo, size, &[]).unwrap().unwrap();
    let reference = cells(&dir, &geo, 1.0) as f64 / (size * size);
    let ratio = estimate.elements as f64 / reference;
    assert!(
        (0.5..2.0).contains(&ratio),
        "estimated {} elements, the area law gives {reference:.3e}",
        estimate.elements
    );
}

#[test]
fn meshes_within_the_limit_are_made() {
    let dir = folder("within");
    let geo = write(&dir, "square.geo", SQUARE);
    // The estimate bounds the count from above.
    let size = 0.25;
    let estimate = estimate_elements(&geo, size, &[]).unwrap().unwrap();
    let made = cells(&dir, &geo, size) as u64;
    assert!(
        estimate.elements >= made && estimate.elements <= MAX_MESH_ELEMENTS,
        "estimated {} elements for a mesh of {made}",
        estimate.elements
    );
    // A script whose element counts are fixed (transfinite) does not grow with a smaller size
    // factor and is meshed whatever the factor.
    let fixed = write(
        &dir,
        "fixed.geo",
        r#"
Point(1) = {0, 0, 0}; Point(2) = {1, 0, 0}; Point(3) = {1, 1, 0}; Point(4) = {0, 1, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Transfinite Curve{1, 2, 3, 4} = 41; Transfinite Surface{1}; Recombine Surface{1};
Physical Surface("square") = {1};
"#,
    );
    assert_eq!(cells(&dir, &fixed, 1e-4), 1600);
}

#[test]
fn gmsh_failures_carry_gmshs_reason() {
    let dir = folder("reason");
    let out = dir.join("mesh.msh");
    let syntax = write(&dir, "syntax.geo", "Point(1) = {0, 0, 0;\n");
    let message = mesh_geo(&syntax, 1.0, &[], &out).unwrap_err().to_string();
    assert!(
        message.contains("syntax.geo") && message.contains("line 1: syntax error"),
        "{message}"
    );
    // The script's own error message.
    let stop = write(
        &dir,
        "stop.geo",
        "Error(\"the hole is larger than the plate\");\n",
    );
    let message = mesh_geo(&stop, 1.0, &[], &out).unwrap_err().to_string();
    assert!(
        message.contains("the hole is larger than the plate"),
        "{message}"
    );
    // gmsh ends without a mesh and without an error line: say so.
    let quit = write(&dir, "quit.geo", "Exit;\n");
    let message = mesh_geo(&quit, 1.0, &[], &out).unwrap_err().to_string();
    assert!(
        message.contains("quit.geo") && message.contains("gmsh wrote no mesh"),
        "{message}"
    );
}

#[test]
fn dev_zero_is_not_read() {
    let error = read_msh(Path::new("/dev/zero")).unwrap_err();
    let Error::Mesh { path, problem, .. } = &error else {
        panic!("expected a mesh error, got {error}")
    };
    assert_eq!(path, Path::new("/dev/zero"));
    assert_eq!(*problem, MeshProblem::Header, "{error}");
}

#[test]
fn a_file_beyond_the_limit_is_refused_before_reading() {
    let dir = folder("large");
    let path = dir.join("huge.msh");
    // A sparse file: an MSH header, then nothing up to one byte beyond the limit.
    let file = std::fs::File::create(&path).unwrap();
    std::io::Write::write_all(&mut &file, b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n").unwrap();
    file.set_len(MAX_MESH_FILE_BYTES + 1).unwrap();
    drop(file);
    let error = read_msh(&path).unwrap_err();
    std::fs::remove_file(&path).unwrap();
    let Error::Mesh {
        path: named,
        problem,
        message,
        ..
    } = &error
    else {
        panic!("expected a mesh error, got {error}")
    };
    assert_eq!(named, &path);
    assert_eq!(*problem, MeshProblem::TooLarge, "{error}");
    assert!(
        message.contains(&MAX_MESH_FILE_BYTES.to_string()),
        "{error}"
    );
}

/// A script written for fine sizes that gmsh cannot mesh at the coarse factors of the probes
/// (here the shipped plane punch, whose graded face divides by its element count less one,
/// zero at a coarse factor): the failed probes are skipped and the case meshes.
#[test]
fn scripts_that_fail_at_coarse_probe_sizes_still_mesh() {
    let geo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("geo/plane_punch.geo");
    let parameters = [("a".to_string(), 50.0), ("h".to_string(), 50.0)];
    let estimate = estimate_elements(&geo, 3.0, &parameters).unwrap();
    assert!(
        estimate.is_none_or(|e| e.elements <= MAX_MESH_ELEMENTS),
        "{estimate:?}"
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mesh.msh");
    mesh_geo(&geo, 3.0, &parameters, &out).unwrap();
    assert!(out.is_file());
}
