//! The bad-input suite: malformed meshes, case files with values out of range, and names and
//! paths that would write outside the output folder. Every case is run as `asperity run`
//! runs it (read the case, then [`run::run`]) on a small valid mesh with one thing
//! broken, and must give the expected [`Error`] variant (and for mesh errors the expected
//! [`MeshProblem`], for parameters the case-file key), and leave no result file behind: the
//! output folder may hold only the `summary.json` of the failed run, and nothing may be
//! written anywhere else.
//!
//! The base case is checked to run, so that every error below is due to its one defect.

use crate::common;

use std::path::{Path, PathBuf};

use asperity::config::Case;
use asperity::error::MeshProblem;
use asperity::{Error, run};
use common::PLATE_MSH;

/// A plane-stress plate pressed on its top edge and held at its bottom edge.
const CASE: &str = "[mesh]
file = \"m.msh\"
[analysis]
type = \"plane_stress\"
thickness = 1.0
[[body]]
group = \"plate\"
material = { E = 1000.0, nu = 0.3 }
[[support]]
group = \"bottom\"
ux = 0.0
uy = 0.0
[[load]]
group = \"top\"
pressure = 1.0
";

/// A contact pair appended to [`CASE`] (only read, never solved, by the cases using it).
const PAIR: &str = "[[contact]]
side_a = \"bottom\"
side_b = \"top\"
";

/// The error a case must give.
#[derive(Debug)]
enum Expected {
    /// [`Error::Case`] (syntax, unknown keys, keys that do not go together).
    Case,
    /// [`Error::InvalidParameter`] with this key.
    Invalid(&'static str),
    /// [`Error::Mesh`] with this problem.
    Mesh(MeshProblem),
    /// [`Error::Group`].
    Group,
    /// [`Error::Io`].
    Io,
}

/// Runs `case` (with `mesh` as `m.msh`, if given) in a fresh folder and returns the error
/// and the folder.
fn run(case: &str, mesh: Option<&[u8]>) -> (Result<(), Error>, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    if let Some(mesh) = mesh {
        std::fs::write(dir.path().join("m.msh"), mesh).unwrap();
    }
    let case_path = dir.path().join("case.toml");
    std::fs::write(&case_path, case).unwrap();
    let out = dir.path().join("out");
    let result =
        Case::from_file(&case_path).and_then(|case| run::run(&case, &out, false).map(drop));
    (result, dir)
}

/// Every file under `dir`, relative to it.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            found.extend(files(&path));
        } else {
            found.push(path);
        }
    }
    found
}

/// Runs one bad case and checks its error and that it left no result file.
fn check(label: &str, case: &str, mesh: Option<&[u8]>, expected: Expected) {
    let (result, dir) = run(case, mesh);
    let error = match result {
        Ok(()) => panic!("{label}: accepted"),
        Err(e) => e,
    };
    let ok = match (&error, &expected) {
        (Error::Case { .. }, Expected::Case) | (Error::Group { .. }, Expected::Group) => true,
        (Error::Io { .. }, Expected::Io) => true,
        (Error::InvalidParameter { key, .. }, Expected::Invalid(k)) => key == k,
        (Error::Mesh { problem, .. }, Expected::Mesh(p)) => problem == p,
        _ => false,
    };
    assert!(ok, "{label}: expected {expected:?}, got {error:?}");
    let message = error.to_string();
    assert!(
        !message.is_empty() && message.len() < 1000,
        "{label}: {message}"
    );
    for file in files(dir.path()) {
        let name = file.strip_prefix(dir.path()).unwrap();
        // A run that stopped after reading its case records it: run.json (status failed),
        // summary.json (status failed), its log, and the manifest listing them.
        let allowed = [
            "case.toml",
            "m.msh",
            "out/summary.json",
            "out/run.json",
            "out/log.txt",
            "out/run_files.txt",
        ];
        assert!(
            allowed.iter().any(|a| Path::new(a) == name),
            "{label}: wrote {}",
            name.display()
        );
        if name == Path::new("out/summary.json") || name == Path::new("out/run.json") {
            let summary = std::fs::read_to_string(&file).unwrap();
            assert!(summary.contains("\"failed\""), "{label}: {summary}");
        }
    }
}

fn bad_mesh(label: &str, mesh: &[u8], problem: MeshProblem) {
    check(label, CASE, Some(mesh), Expected::Mesh(problem));
}

/// [`PLATE_MSH`] with `from` replaced by `to` (which must occur).
fn edit(from: &str, to: &str) -> String {
    assert!(PLATE_MSH.contains(from), "{from}");
    PLATE_MSH.replacen(from, to, 1)
}

fn bad_case(label: &str, case: &str, expected: Expected) {
    check(label, case, Some(PLATE_MSH.as_bytes()), expected);
}

/// [`CASE`] with `from` replaced by `to` (which must occur).
fn case_edit(from: &str, to: &str) -> String {
    assert!(CASE.contains(from), "{from}");
    CASE.replacen(from, to, 1)
}

/// [`CASE`] plus `extra` (a table or key at the end).
fn case_plus(extra: &str) -> String {
    format!("{CASE}{extra}\n")
}

#[test]
fn the_base_case_runs() {
    let (result, dir) = run(CASE, Some(PLATE_MSH.as_bytes()));
    result.unwrap();
    assert!(dir.path().join("out/bodies_0001.vtu").is_file());
    assert!(dir.path().join("out/history.csv").is_file());
}

#[test]
fn malformed_meshes_are_mesh_errors() {
    use MeshProblem::*;
    let cases: Vec<(&str, String, MeshProblem)> = vec![
        ("empty file", String::new(), Empty),
        ("blank file", " \n\t\n".into(), Empty),
        ("not an MSH file", "hello\nworld\n".into(), Header),
        ("MSH 2.2", edit("4.1 0 8", "2.2 0 8"), Version),
        ("MSH 4.0", edit("4.1 0 8", "4.0 0 8"), Version),
        (
            "data size overflowing i32",
            edit("4.1 0 8", "4.1 0 2147483648"),
            Header,
        ),
        ("data size 3", edit("4.1 0 8", "4.1 0 3"), Header),
        ("file type 7", edit("4.1 0 8", "4.1 7 8"), Header),
        (
            "no $EndMeshFormat",
            edit("$EndMeshFormat", "$End"),
            Truncated,
        ),
        (
            "cut in the coordinates",
            PLATE_MSH[..PLATE_MSH.find("2 0.5 0").unwrap()].into(),
            Truncated,
        ),
        (
            "cut in the elements",
            PLATE_MSH[..PLATE_MSH.len() - 30].into(),
            Truncated,
        ),
        (
            "node total 10^12",
            edit("1 8 1 8", "1 1000000000000 1 8"),
            CountMismatch,
        ),
        (
            "node total u64::MAX",
            edit("1 8 1 8", "1 18446744073709551615 1 8"),
            CountMismatch,
        ),
        (
            "node total too small",
            edit("1 8 1 8", "1 7 1 8"),
            CountMismatch,
        ),
        (
            "node blocks 10^12",
            edit("1 8 1 8", "1000000000000 8 1 8"),
            CountMismatch,
        ),
        (
            "node block size 10^12",
            edit("2 1 0 8", "2 1 0 1000000000000"),
            CountMismatch,
        ),
        (
            "node tag range lies",
            edit("1 8 1 8", "1 8 1 9"),
            CountMismatch,
        ),
        (
            "element total 10^12",
            edit("5 5 1 5", "5 1000000000000 1 5"),
            CountMismatch,
        ),
        (
            "element total too large",
            edit("5 5 1 5", "5 6 1 5"),
            CountMismatch,
        ),
        (
            "element block size u64::MAX",
            edit("2 1 16 1", "2 1 16 18446744073709551615"),
            CountMismatch,
        ),
        (
            "entity count 10^12",
            edit("0 4 1 0", "0 4 1000000000000 0"),
            CountMismatch,
        ),
        (
            "physical tag count 10^12",
            edit("1 0 0 0 2 0 0 1 1 0", "1 0 0 0 2 0 0 1000000000000 1 0"),
            CountMismatch,
        ),
        (
            "entity declared twice",
            edit("2 2 0 0 2 1 0 1 2 0", "1 2 0 0 2 1 0 1 2 0"),
            DuplicateEntity,
        ),
        (
            "duplicate element tag",
            edit("2 2 3 6\n", "1 2 3 6\n"),
            DuplicateElement,
        ),
        (
            "duplicate node tag",
            edit("1\n2\n3\n", "1\n1\n3\n"),
            DuplicateNode,
        ),
        (
            "elements of an undeclared entity",
            edit("2 1 16 1", "2 5 16 1"),
            UndeclaredEntity,
        ),
        (
            "nodes of an undeclared entity",
            edit("2 1 0 8", "2 9 0 8"),
            UndeclaredEntity,
        ),
        ("block dimension 7", edit("2 1 0 8", "7 1 0 8"), Corrupt),
        (
            "line block holding a quad",
            edit("2 1 16 1", "1 1 16 1"),
            MixedDimension,
        ),
        (
            "unknown element type",
            edit("2 1 16 1", "2 1 99 1"),
            UnsupportedElement,
        ),
        (
            "element of a missing node",
            edit("5 1 2 3 4 5 6 7 8", "5 1 2 3 4 5 6 7 88"),
            UnknownNode,
        ),
        ("NaN coordinate", edit("2 0.5 0", "nan 0.5 0"), NonFinite),
        ("infinite coordinate", edit("2 0.5 0", "2 inf 0"), NonFinite),
        (
            "node off the plane",
            edit("2 0.5 0", "2 0.5 0.25"),
            NotPlanar,
        ),
        (
            "degenerate cell",
            edit("2 1 0\n0 1 0\n", "0 0 0\n2 0 0\n"),
            Degenerate,
        ),
        ("parametric nodes", edit("2 1 0 8", "2 1 1 8"), Parametric),
        (
            "no $Entities",
            edit("$Entities", "$Entitie"),
            MissingSection,
        ),
        (
            "no $Elements",
            edit("$Elements\n", "$Elementz\n"),
            MissingSection,
        ),
        (
            "first-order quad",
            edit("2 1 16 1\n5 1 2 3 4 5 6 7 8", "2 1 3 1\n5 1 2 3 4"),
            FirstOrder,
        ),
        (
            "only lines",
            edit("5 5 1 5", "4 4 1 4").replace("2 1 16 1\n5 1 2 3 4 5 6 7 8\n", ""),
            NoCells,
        ),
        (
            "malformed physical name",
            edit("\"top\"", "top"),
            PhysicalNames,
        ),
        (
            "physical name count wrong",
            edit("$PhysicalNames\n5", "$PhysicalNames\n6"),
            PhysicalNames,
        ),
    ];
    let count = cases.len();
    for (label, mesh, problem) in cases {
        bad_mesh(label, mesh.as_bytes(), problem);
    }
    assert!(count >= 40);
}

#[test]
fn missing_or_unreadable_mesh_files() {
    check(
        "mesh file missing",
        CASE,
        None,
        Expected::Mesh(MeshProblem::NotFound),
    );
    let geo = case_edit("file = \"m.msh\"", "geo = \"missing.geo\"");
    check(
        "geo script missing",
        &geo,
        None,
        Expected::Mesh(MeshProblem::NotFound),
    );
    let dir_as_mesh = case_edit("file = \"m.msh\"", "file = \".\"");
    check("mesh is a folder", &dir_as_mesh, None, Expected::Io);
    let nul = case_edit("file = \"m.msh\"", "file = \"m\\u0000.msh\"");
    check("NUL in the mesh path", &nul, None, Expected::Io);
}

#[test]
fn binary_meshes_with_lying_headers_are_mesh_errors() {
    // Binary header and the $Nodes header of a binary file claiming 2^60 blocks.
    let mut bytes = b"$MeshFormat\n4.1 1 8\n".to_vec();
    bytes.extend_from_slice(&1i32.to_le_bytes());
    bytes.extend_from_slice(b"\n$EndMeshFormat\n$Entities\n");
    for count in [0u64, 0, 1, 0] {
        bytes.extend_from_slice(&count.to_le_bytes());
    }
    bytes.extend_from_slice(&1i32.to_le_bytes());
    bytes.extend_from_slice(&[0u8; 48]);
    bytes.extend_from_slice(&0u64.to_le_bytes());
    bytes.extend_from_slice(&0u64.to_le_bytes());
    bytes.extend_from_slice(b"\n$EndEntities\n$Nodes\n");
    for value in [1u64 << 60, 1, 1, 1] {
        bytes.extend_from_slice(&value.to_le_bytes());
    }
    bytes.extend_from_slice(b"\n$EndNodes\n$Elements\n$EndElements\n");
    bad_mesh(
        "binary node blocks 2^60",
        &bytes,
        MeshProblem::CountMismatch,
    );
    let mut bad_size = b"$MeshFormat\n4.1 1 2147483648\n".to_vec();
    bad_size.extend_from_slice(&1i32.to_le_bytes());
    bad_size.extend_from_slice(b"\n$EndMeshFormat\n");
    bad_mesh(
        "binary data size overflowing i32",
        &bad_size,
        MeshProblem::Header,
    );
}

/// serde quotes a float given where an integer belongs in full: `1e300` as 301 digits. The
/// message names it in exponent form.
#[test]
fn huge_floats_are_quoted_in_exponent_form() {
    for (key, value) in [
        ("[solver]\nmax_iterations", "1e300"),
        ("[solver]\ninterface_iterations", "-1.5e200"),
        ("[steps]\ncount", "1e308"),
    ] {
        let case = case_plus(&format!("{key} = {value}"));
        let (result, _dir) = run(&case, Some(PLATE_MSH.as_bytes()));
        let message = result.unwrap_err().to_string();
        let exponent = value.parse::<f64>().unwrap();
        assert!(
            message.contains(&format!("floating point `{exponent:e}`")),
            "{key}: {message}"
        );
        let longest_digits = message
            .split(|c: char| !c.is_ascii_digit())
            .map(str::len)
            .max();
        assert!(longest_digits < Some(20), "{key}: {message}");
    }
}

#[test]
fn case_values_out_of_range_are_named() {
    use Expected::*;
    let cases: Vec<(&str, String, Expected)> = vec![
        ("TOML syntax", case_plus("[steps"), Case),
        (
            "unknown key",
            case_plus("[solver]\nmax_iteration = 3"),
            Case,
        ),
        (
            "unknown section",
            case_plus("[solvers]\nmax_iterations = 3"),
            Case,
        ),
        (
            // a case-file mistake, named by its key rather than by an element both claim
            "one physical surface in two bodies",
            case_plus("[[body]]\ngroup = \"plate\"\nmaterial = { E = 2000.0, nu = 0.3 }"),
            Invalid("body[1].group"),
        ),
        (
            // named by its own key, not by the Voce Q it makes look out of range
            "negative yield stress with cyclic hardening",
            case_edit(
                "material = { E = 1000.0, nu = 0.3 }",
                "material = { E = 1000.0, nu = 0.3, yield_stress = -200.0, \
                 isotropic = { Q = 50.0, b = 10.0 }, kinematic = [{ C = 1.0, gamma = 0.0 }] }",
            ),
            Invalid("body[0].material.yield_stress"),
        ),
        (
            "thickness negative",
            case_edit("thickness = 1.0", "thickness = -5.0"),
            Invalid("analysis.thickness"),
        ),
        (
            "thickness infinite",
            case_edit("thickness = 1.0", "thickness = inf"),
            Invalid("analysis.thickness"),
        ),
        (
            "thickness NaN",
            case_edit("thickness = 1.0", "thickness = nan"),
            Invalid("analysis.thickness"),
        ),
        (
            "axisymmetric with thickness",
            case_edit(
                "type = \"plane_stress\"\nthickness = 1.0",
                "type = \"axisymmetric\"\nthickness = -5.0",
            ),
            Case,
        ),
        (
            "axisymmetric with an unknown key",
            case_edit(
                "type = \"plane_stress\"\nthickness = 1.0",
                "type = \"axisymmetric\"\nthicknes = 1.0",
            ),
            Case,
        ),
        (
            "E negative",
            case_edit("E = 1000.0", "E = -1000.0"),
            Invalid("body[0].material.E"),
        ),
        (
            "E infinite",
            case_edit("E = 1000.0", "E = inf"),
            Invalid("body[0].material.E"),
        ),
        (
            "nu = 0.5",
            case_edit("nu = 0.3", "nu = 0.5"),
            Invalid("body[0].material.nu"),
        ),
        (
            "hardening without yield stress",
            case_edit("nu = 0.3", "nu = 0.3, hardening = 10.0"),
            Invalid("body[0].material.hardening"),
        ),
        (
            "steps.count = 0",
            case_plus("[steps]\ncount = 0"),
            Invalid("steps.count"),
        ),
        (
            "steps.count = 10^12",
            case_plus("[steps]\ncount = 1000000000000"),
            Invalid("steps.count"),
        ),
        (
            "steps.count = i64::MAX",
            case_plus("[steps]\ncount = 9223372036854775807"),
            Invalid("steps.count"),
        ),
        (
            "steps.count negative",
            case_plus("[steps]\ncount = -3"),
            Case,
        ),
        (
            "steps.count a float",
            case_plus("[steps]\ncount = 1e12"),
            Case,
        ),
        (
            "NaN load factor",
            case_plus("[steps]\nfactors = [0.5, nan]"),
            Invalid("steps.factors"),
        ),
        (
            "count and factors",
            case_plus("[steps]\ncount = 2\nfactors = [1.0]"),
            Case,
        ),
        (
            "arc-length max_increments 10^9",
            case_plus("[steps]\ncontrol = \"arc_length\"\nmax_increments = 1000000000"),
            Invalid("steps.max_increments"),
        ),
        (
            "force_tolerance = inf",
            case_plus("[solver]\nforce_tolerance = inf"),
            Invalid("solver.force_tolerance"),
        ),
        (
            "force_tolerance = 1",
            case_plus("[solver]\nforce_tolerance = 1.0"),
            Invalid("solver.force_tolerance"),
        ),
        (
            "force_tolerance = 0",
            case_plus("[solver]\nforce_tolerance = 0.0"),
            Invalid("solver.force_tolerance"),
        ),
        (
            "displacement_tolerance = 0.5",
            case_plus("[solver]\ndisplacement_tolerance = 0.5"),
            Invalid("solver.displacement_tolerance"),
        ),
        (
            "displacement_tolerance NaN",
            case_plus("[solver]\ndisplacement_tolerance = nan"),
            Invalid("solver.displacement_tolerance"),
        ),
        (
            "max_cutbacks = 1000",
            case_plus("[solver]\nmax_cutbacks = 1000"),
            Invalid("solver.max_cutbacks"),
        ),
        (
            "max_iterations = 0",
            case_plus("[solver]\nmax_iterations = 0"),
            Invalid("solver.max_iterations"),
        ),
        (
            "max_iterations = 10^9",
            case_plus("[solver]\nmax_iterations = 1000000000"),
            Invalid("solver.max_iterations"),
        ),
        (
            "collapse_stiffness_ratio = 2",
            case_plus("[solver]\ncollapse_stiffness_ratio = 2.0"),
            Invalid("solver.collapse_stiffness_ratio"),
        ),
        (
            "traction with three components",
            case_edit("pressure = 1.0", "traction = [0.0, 1.0, 5.0]"),
            Invalid("load[0].traction"),
        ),
        (
            "traction with one component",
            case_edit("pressure = 1.0", "traction = [1.0]"),
            Invalid("load[0].traction"),
        ),
        (
            "force with three components",
            case_edit("pressure = 1.0", "force = [0.0, 1.0, 2.0]"),
            Invalid("load[0].force"),
        ),
        (
            "force with one component",
            case_edit("pressure = 1.0", "force = [1.0]"),
            Invalid("load[0].force"),
        ),
        (
            "pressure NaN",
            case_edit("pressure = 1.0", "pressure = nan"),
            Invalid("load[0].pressure"),
        ),
        (
            "traction infinite",
            case_edit("pressure = 1.0", "traction = [inf, 0.0]"),
            Invalid("load[0].traction"),
        ),
        (
            "two kinds of load",
            case_edit("pressure = 1.0", "pressure = 1.0\nforce = [1.0, 0.0]"),
            Case,
        ),
        (
            "support ux infinite",
            case_edit("ux = 0.0", "ux = -inf"),
            Invalid("support[0].ux"),
        ),
        (
            "support with no component",
            case_edit("ux = 0.0\nuy = 0.0\n", ""),
            Case,
        ),
        (
            "support factors of the wrong length",
            case_edit("uy = 0.0\n", "uy = 0.0\nfactors = [1.0, 2.0]\n"),
            Invalid("support[0].factors"),
        ),
        (
            "mesh size 0",
            case_edit("file = \"m.msh\"", "file = \"m.msh\"\nsize = 0.0"),
            Invalid("mesh.size"),
        ),
        (
            "file and geo",
            case_edit("file = \"m.msh\"", "file = \"m.msh\"\ngeo = \"m.geo\""),
            Case,
        ),
        (
            "geo with a NaN parameter",
            case_edit(
                "file = \"m.msh\"",
                "geo = \"m.geo\"\nparameters = { h = nan }",
            ),
            Invalid("mesh.parameters.h"),
        ),
        (
            "geo with an infinite parameter",
            case_edit(
                "file = \"m.msh\"",
                "geo = \"m.geo\"\nparameters = { h = inf }",
            ),
            Invalid("mesh.parameters.h"),
        ),
        (
            "geo parameter that is no identifier",
            case_edit(
                "file = \"m.msh\"",
                "geo = \"m.geo\"\nparameters = { \"-v 99\" = 1.0 }",
            ),
            Invalid("mesh.parameters.-v 99"),
        ),
        (
            "no body",
            CASE.replace(
                "[[body]]\ngroup = \"plate\"\nmaterial = { E = 1000.0, nu = 0.3 }\n",
                "",
            ),
            Case,
        ),
        (
            "body missing in the mesh",
            case_edit("group = \"plate\"", "group = \"plates\""),
            Group,
        ),
        (
            "support curve missing in the mesh",
            case_edit("group = \"bottom\"", "group = \"bottm\""),
            Group,
        ),
        (
            "rough joint with friction but no R",
            case_plus(&format!(
                "{PAIR}law = {{ type = \"rough_joint\", c_n = 1e-3, m = 0.5, S = 0.5, mu_m = 0.2 }}"
            )),
            Invalid("contact[0].law.R"),
        ),
        (
            "linear law with negative stiffness",
            case_plus(&format!(
                "{PAIR}law = {{ type = \"linear_coulomb\", normal_stiffness = -1.0, tangential_stiffness = 1.0 }}"
            )),
            Invalid("contact[0].law.normal_stiffness"),
        ),
        (
            "two contact pairs of one name",
            case_plus(&format!(
                "{PAIR}law = {{ type = \"linear_coulomb\", normal_stiffness = 1.0, tangential_stiffness = 1.0 }}\n\
                 {PAIR}law = {{ type = \"linear_coulomb\", normal_stiffness = 1.0, tangential_stiffness = 1.0 }}"
            )),
            Invalid("contact[1].name"),
        ),
        (
            "contact with curve and sides",
            case_plus(&format!(
                "{PAIR}curve = \"top\"\nlaw = {{ type = \"linear_coulomb\", normal_stiffness = 1.0, tangential_stiffness = 1.0 }}"
            )),
            Case,
        ),
        (
            "contact interference NaN",
            case_plus(&format!(
                "{PAIR}interference = nan\nlaw = {{ type = \"linear_coulomb\", normal_stiffness = 1.0, tangential_stiffness = 1.0 }}"
            )),
            Invalid("contact[0].interference"),
        ),
        (
            "hysteresis point with an infinite coordinate",
            case_plus(&format!(
                "{PAIR}hysteresis_points = [[0.5, 1.0], [inf, 1.0]]
law = {{ type = \"linear_coulomb\", normal_stiffness = 1.0, tangential_stiffness = 1.0 }}"
            )),
            Invalid("contact[0].hysteresis_points[1]"),
        ),
    ];
    let count = cases.len();
    for (label, case, expected) in cases {
        bad_case(label, &case, expected);
    }
    assert!(count >= 40);
}

/// A case whose contact pair is called `name` (a TOML string literal's content).
fn named_pair(name: &str) -> String {
    case_plus(&format!(
        "{PAIR}name = \"{name}\"\nlaw = {{ type = \"linear_coulomb\", normal_stiffness = 1.0, tangential_stiffness = 1.0 }}"
    ))
}

/// Whether a file whose name starts with `prefix` exists in `dir` or one of its ancestors.
fn escaped(dir: &Path, prefix: &str) -> bool {
    dir.ancestors().any(|d| {
        std::fs::read_dir(d).is_ok_and(|mut entries| {
            entries.any(|e| e.is_ok_and(|e| e.file_name().to_string_lossy().starts_with(prefix)))
        })
    })
}

#[test]
fn unsafe_names_and_paths_are_refused() {
    let long = "n".repeat(100);
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "traversal in a pair name",
            named_pair("x/../../../../ESCAPED"),
            "contact[0].name",
        ),
        (
            "absolute pair name",
            named_pair("/tmp/ESCAPED_ABS"),
            "contact[0].name",
        ),
        (
            "backslash in a pair name",
            named_pair("x\\\\..\\\\ESCAPED"),
            "contact[0].name",
        ),
        (
            "NUL in a pair name",
            named_pair("a\\u0000b"),
            "contact[0].name",
        ),
        (
            "line break in a pair name",
            named_pair("a\\nb"),
            "contact[0].name",
        ),
        (
            "control character in a pair name",
            named_pair("a\\u0007b"),
            "contact[0].name",
        ),
        ("reserved name CON", named_pair("CON"), "contact[0].name"),
        (
            "reserved name nul.txt",
            named_pair("nul.txt"),
            "contact[0].name",
        ),
        ("pair name ..", named_pair(".."), "contact[0].name"),
        ("pair name .", named_pair("."), "contact[0].name"),
        ("empty pair name", named_pair(""), "contact[0].name"),
        ("over-long pair name", named_pair(&long), "contact[0].name"),
        ("comma in a pair name", named_pair("a,b"), "contact[0].name"),
        (
            "traversal in a body group",
            case_edit("group = \"plate\"", "group = \"../ESCAPED\""),
            "body[0].group",
        ),
        (
            "slash in a support group",
            case_edit("group = \"bottom\"", "group = \"a/b\""),
            "support[0].group",
        ),
        (
            "quote in a load group",
            case_edit("group = \"top\"", "group = \"t\\\"op\""),
            "load[0].group",
        ),
    ];
    let count = cases.len();
    for (label, case, key) in cases {
        let (result, dir) = run(&case, Some(PLATE_MSH.as_bytes()));
        match result {
            Err(Error::InvalidParameter { key: k, .. }) if k == key => {}
            other => panic!("{label}: expected an invalid {key}, got {other:?}"),
        }
        assert!(!dir.path().join("out").exists(), "{label}: wrote output");
        assert!(!escaped(dir.path(), "ESCAPED"), "{label}: escaped");
    }
    assert!(count >= 12);
    // A derived pair name ("<side_a>-<side_b>") is checked too.
    let derived = case_plus(
        "[[contact]]\nside_a = \"bottom\"\nside_b = \"top\"\nlaw = { type = \"linear_coulomb\", normal_stiffness = 1.0, tangential_stiffness = 1.0 }\n\
         [[contact]]\nside_a = \"bottom\"\nside_b = \"top\"\nlaw = { type = \"linear_coulomb\", normal_stiffness = 1.0, tangential_stiffness = 1.0 }",
    );
    bad_case(
        "same sides twice",
        &derived,
        Expected::Invalid("contact[1].name"),
    );
}

/// The writers themselves refuse a path that leaves the output folder, whatever its origin.
#[test]
fn writers_refuse_paths_that_leave_the_output_folder() {
    use asperity::output::csv::{CsvTable, write_csv};
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a/b/out");
    let mut table: CsvTable = CsvTable::new(["x"]);
    table.rows.push(vec![1.0]);
    for name in [
        "contact_x/../../../../ESCAPED_0001.csv",
        "contact_\u{1}_0001.csv",
        &format!("{}.csv", "n".repeat(300)),
    ] {
        let path = out.join(name);
        assert!(
            matches!(write_csv(&path, &table), Err(Error::Io { .. })),
            "{name}"
        );
    }
    assert!(files(dir.path()).is_empty(), "{:?}", files(dir.path()));
    write_csv(&out.join("history.csv"), &table).unwrap();
}

/// The checks reject nothing that the shipped examples use (valid input behaves as before).
#[test]
fn shipped_case_files_pass_the_checks() {
    fn cases(dir: &Path, found: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                cases(&path, found);
            } else if path.extension().is_some_and(|e| e == "toml") {
                found.push(path);
            }
        }
    }
    let mut found = Vec::new();
    for dir in ["pipelines", "examples"] {
        cases(&Path::new(env!("CARGO_MANIFEST_DIR")).join(dir), &mut found);
    }
    assert!(found.len() >= 10, "{found:?}");
    for path in found {
        // Fit and sweep files (`asperity fit`, `asperity sweep`) live beside the cases; a
        // case is the TOML with the required `[mesh]` table.
        let table: toml::Table = toml::from_str(&std::fs::read_to_string(&path).unwrap())
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        if !table.contains_key("mesh") {
            continue;
        }
        if let Err(e) = Case::from_file(&path) {
            panic!("{}: {e}", path.display());
        }
    }
}

/// [`CASE`] with `[[step]]` tables (and whatever else `extra` holds) appended; its load is
/// called `top` after its group.
fn with_steps(extra: &str) -> String {
    format!("{CASE}{extra}\n")
}

/// `[[step]]`, `[[amplitude]]` and load names: each defect names its case-file key.
#[test]
fn load_history_errors_name_their_key() {
    use Expected::*;
    let amplitude = |time: &str, value: &str| {
        format!("[[amplitude]]\nname = \"a\"\ntime = {time}\nvalue = {value}\n")
    };
    let cases: Vec<(&str, String, Expected)> = vec![
        (
            "unknown load",
            with_steps("[[step]]\nloads = { topp = 1.0 }"),
            Invalid("step[0].loads.topp"),
        ),
        (
            "unknown support",
            with_steps("[[step]]\nloads = { top = 1.0 }\nsupports = { botom = 0.0 }"),
            Invalid("step[0].supports.botom"),
        ),
        (
            // named as unknown, not as a cyclic step without an amplitude
            "unknown load in a cyclic step",
            with_steps("[[step]]\ncycles = 2\nloads = { topp = 1.0 }"),
            Invalid("step[0].loads.topp"),
        ),
        (
            "unknown amplitude",
            with_steps("[[step]]\nloads = { top = \"wave\" }"),
            Invalid("step[0].loads.top"),
        ),
        (
            "amplitude times not increasing",
            with_steps(&format!(
                "{}[[step]]\nloads = {{ top = \"a\" }}",
                amplitude("[0.0, 0.5, 0.5, 1.0]", "[0.0, 1.0, 1.0, 0.0]")
            )),
            Invalid("amplitude[0].time"),
        ),
        (
            "amplitude times not from 0 to 1",
            with_steps(&format!(
                "{}[[step]]\nloads = {{ top = \"a\" }}",
                amplitude("[0.0, 0.5]", "[0.0, 1.0]")
            )),
            Invalid("amplitude[0].time"),
        ),
        (
            "amplitude lengths differ",
            with_steps(&format!(
                "{}[[step]]\nloads = {{ top = \"a\" }}",
                amplitude("[0.0, 1.0]", "[0.0, 1.0, 2.0]")
            )),
            Invalid("amplitude[0].value"),
        ),
        (
            "amplitude value NaN",
            with_steps(&format!(
                "{}[[step]]\nloads = {{ top = \"a\" }}",
                amplitude("[0.0, 1.0]", "[0.0, nan]")
            )),
            Invalid("amplitude[0].value"),
        ),
        (
            "inline amplitude starting after 0",
            with_steps("[[step]]\nloads = { top = { time = [0.1, 1.0], value = [0.0, 1.0] } }"),
            Invalid("step[0].loads.top.time"),
        ),
        (
            "ramp target NaN",
            with_steps("[[step]]\nloads = { top = nan }"),
            Invalid("step[0].loads.top"),
        ),
        (
            "amplitude jumps from the previous step's end value",
            with_steps(
                "[[step]]\nloads = { top = 1.0 }\n[[step]]\nloads = { top = { time = [0.0, 1.0], value = [0.5, 1.0] } }",
            ),
            Invalid("step[1].loads.top"),
        ),
        (
            "cyclic amplitude not ending where it starts",
            with_steps(
                "[[step]]\ncycles = 3\nloads = { top = { time = [0.0, 1.0], value = [0.0, 1.0] } }",
            ),
            Invalid("step[0].loads.top"),
        ),
        (
            "cyclic step without an amplitude",
            with_steps("[[step]]\ncycles = 3\nloads = { top = 1.0 }"),
            Invalid("step[0].cycles"),
        ),
        (
            "ramp in a cyclic step",
            with_steps(
                "[[step]]\nloads = { top = 1.0 }\n[[step]]\ncycles = 2\nloads = { top = 2.0 }\nsupports = { bottom = { time = [0.0, 1.0], value = [0.0, 0.0] } }",
            ),
            Invalid("step[1].loads.top"),
        ),
        (
            "[steps] with [[step]]",
            with_steps("[[step]]\nloads = { top = 1.0 }\n[steps]\ncount = 2"),
            Invalid("steps"),
        ),
        (
            "arc length with [[step]]",
            with_steps("[[step]]\nloads = { top = 1.0 }\n[steps]\ncontrol = \"arc_length\""),
            Invalid("steps.control"),
        ),
        (
            "per-load factors with [[step]]",
            case_edit("pressure = 1.0", "pressure = 1.0\nfactors = [1.0]")
                + "[[step]]\nloads = { top = 1.0 }\n",
            Invalid("load[0].factors"),
        ),
        (
            "load named in no step",
            with_steps("[[step]]\nsupports = { bottom = 0.0 }"),
            Invalid("load[0]"),
        ),
        (
            "non-zero support named in no step",
            with_steps(
                "[[support]]\nname = \"lift\"\ngroup = \"top\"\nux = 0.01\n[[step]]\nloads = { top = 1.0 }",
            ),
            Invalid("support[1]"),
        ),
        (
            "cycles = 0",
            with_steps("[[step]]\ncycles = 0\nloads = { top = 1.0 }"),
            Invalid("step[0].cycles"),
        ),
        (
            "increments = 0",
            with_steps("[[step]]\nincrements = 0\nloads = { top = 1.0 }"),
            Invalid("step[0].increments"),
        ),
        (
            "cycles_per_jump = 0",
            with_steps(
                "[[step]]\ncycles = 4\ncycles_per_jump = 0\nloads = { top = { time = [0.0, 0.5, 1.0], value = [0.0, 1.0, 0.0] } }",
            ),
            Invalid("step[0].cycles_per_jump"),
        ),
        (
            "cycles_per_jump above cycles",
            with_steps(
                "[[step]]\ncycles = 4\ncycles_per_jump = 5\nloads = { top = { time = [0.0, 0.5, 1.0], value = [0.0, 1.0, 0.0] } }",
            ),
            Invalid("step[0].cycles_per_jump"),
        ),
        (
            "too many simulated increments",
            with_steps(
                "[[step]]\ncycles = 1000000\nloads = { top = { time = [0.0, 0.5, 1.0], value = [0.0, 1.0, 0.0] } }",
            ),
            Invalid("step[0].increments"),
        ),
        (
            "two loads of one name",
            with_steps(
                "[[load]]\ngroup = \"top\"\ntraction = [1.0, 0.0]\n[[step]]\nloads = { top = 1.0 }",
            ),
            Invalid("load[1].name"),
        ),
        (
            // named by its own table, not as a "[[thermal]]" that does not exist
            "two temperatures of one name",
            with_steps(
                "[[temperature]]\ngroup = \"plate\"\nchange = 10.0\n\
                 [[temperature]]\ngroup = \"plate\"\nchange = 20.0\n\
                 [[step]]\nloads = { top = 1.0 }",
            ),
            Invalid("temperature[1].name"),
        ),
        (
            "two steps of one name",
            with_steps(
                "[[step]]\nname = \"s\"\nloads = { top = 1.0 }\n[[step]]\nname = \"s\"\nloads = { top = 0.0 }",
            ),
            Invalid("step[1].name"),
        ),
        (
            "unsafe step name",
            with_steps("[[step]]\nname = \"a/../b\"\nloads = { top = 1.0 }"),
            Invalid("step[0].name"),
        ),
        (
            "amplitude without [[step]]",
            with_steps(&amplitude("[0.0, 1.0]", "[0.0, 1.0]")),
            Invalid("amplitude[0]"),
        ),
        (
            "load history of the wrong type",
            with_steps("[[step]]\nloads = { top = true }"),
            Case,
        ),
        (
            "unknown step key",
            with_steps("[[step]]\ncycle = 3\nloads = { top = 1.0 }"),
            Case,
        ),
    ];
    let count = cases.len();
    for (label, case, expected) in cases {
        bad_case(label, &case, expected);
    }
    assert!(count >= 25);
    // The same case with a valid history runs.
    let (result, _dir) = run(
        &with_steps(
            "[[step]]\nincrements = 2\nloads = { top = 1.0 }\n[[step]]\ncycles = 2\nloads = { top = { time = [0.0, 0.5, 1.0], value = [1.0, -1.0, 1.0] } }",
        ),
        Some(PLATE_MSH.as_bytes()),
    );
    result.unwrap();
}

/// Two supports of one group that prescribe different values of a component are named by
/// their `name`s (the group alone would name both the same).
#[test]
fn conflicting_supports_are_named_by_their_names() {
    let case = case_plus(
        "[[support]]\nname = \"s1\"\ngroup = \"top\"\nux = 0.0\n\
         [[support]]\nname = \"s2\"\ngroup = \"top\"\nux = 0.05\n",
    );
    let (result, _dir) = run(&case, Some(PLATE_MSH.as_bytes()));
    let error = result.unwrap_err();
    assert!(
        matches!(&error, Error::ConflictingSupports { first, second, .. } if first == "s1" && second == "s2"),
        "{error}"
    );
    assert!(
        error.to_string().contains("supports 's1' and 's2'"),
        "{error}"
    );
}

/// An empty `kinematic` list is shown as a list, not as its length (a longer list than
/// five is refused when the case is read).
#[test]
fn an_empty_kinematic_list_is_shown_as_a_list() {
    let case = case_edit(
        "material = { E = 1000.0, nu = 0.3 }",
        "material = { E = 1000.0, nu = 0.3, yield_stress = 200.0, kinematic = [] }",
    );
    let (result, _dir) = run(&case, Some(PLATE_MSH.as_bytes()));
    let error = result.unwrap_err().to_string();
    assert!(error.contains("kinematic = []: give 1 to 5"), "{error}");
}

/// A `[mesh] parameters` name the `.geo` script never mentions (misspelt) is refused naming
/// the key, before gmsh runs: gmsh would mesh with the script's own value, silently.
#[test]
fn a_mesh_parameter_the_script_never_mentions_is_refused() {
    let scripts = tempfile::tempdir().unwrap();
    let geo = scripts.path().join("plate.geo");
    std::fs::write(
        &geo,
        "DefineConstant[ n = 4 ];\nPoint(1) = {0, 0, 0};\n// n_typos, nn: words that only contain the names\n",
    )
    .unwrap();
    let mesh = format!("[mesh]\ngeo = \"{}\"\n", geo.display());
    for (parameters, refused) in [
        ("n = 2", None),
        ("n_typo = 2", Some("mesh.parameters.n_typo")),
    ] {
        let case = CASE.replacen(
            "[mesh]\n",
            &format!("{mesh}parameters = {{ {parameters} }}\n#"),
            1,
        );
        let (result, _dir) = run(&case, None);
        match (refused, result) {
            (Some(key), Err(Error::InvalidParameter { key: k, .. })) => assert_eq!(k, key),
            (Some(_), other) => panic!("{parameters}: expected a refusal, got {other:?}"),
            // `n` passes the check: whatever gmsh then makes of this script is no refusal of it.
            (None, Err(Error::InvalidParameter { key, .. })) => {
                panic!("{parameters}: refused {key}")
            }
            (None, _) => {}
        }
    }
}
