//! The mesh cache end to end: a second run of the same `.geo` case takes its mesh from the
//! cache (no time in gmsh) and gives the same results; another size factor is meshed anew.

use crate::common;

use std::path::Path;

fn run(case: &Path, out: &Path, cache: &Path) -> serde_json::Value {
    let output = common::asperity()
        .env("ASPERITY_MESH_CACHE", cache)
        .args(["run", "-q", "--force"])
        .arg(case)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn a_repeated_run_reads_its_mesh_from_the_cache() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    // The script is copied next to the case: the key is its text, not its path.
    let geo = dir.path().join("pair.geo");
    std::fs::copy(common::fixture("contact_pair.geo"), &geo).unwrap();
    let case = |size: f64| {
        common::two_blocks(0.2)
            .support("lid", &[("ux", 0.01), ("uy", -0.01)])
            .mesh_geo(&geo, size)
            .write(&dir.path().join("case.toml"))
    };
    let first = run(&case(0.5), &dir.path().join("a"), &cache);
    let second = run(&case(0.5), &dir.path().join("b"), &cache);
    assert!(first["seconds"]["gmsh"].as_f64().unwrap() > 0.0);
    assert_eq!(second["seconds"]["gmsh"].as_f64(), Some(0.0));
    // gmsh writes binary MSH 4.1 (faster to write and to read than its text).
    let msh = std::fs::read(dir.path().join("a").join("mesh.msh")).unwrap();
    assert!(
        msh.starts_with(b"$MeshFormat\n4.1 1 8\n"),
        "not binary MSH 4.1"
    );
    for file in ["mesh.msh", "history.csv"] {
        assert_eq!(
            std::fs::read(dir.path().join("a").join(file)).unwrap(),
            std::fs::read(dir.path().join("b").join(file)).unwrap(),
            "{file}"
        );
    }
    // Another size factor is another mesh.
    let third = run(&case(0.4), &dir.path().join("c"), &cache);
    assert!(third["seconds"]["gmsh"].as_f64().unwrap() > 0.0);
    let entries = std::fs::read_dir(&cache).unwrap().count();
    assert_eq!(entries, 4, "two meshes, each a .msh and a .key");
}
