//! A model whose solver storage cannot fit in the memory the run may take stops with a clear
//! error (exit code 3, the bytes needed and the limit named) before the factor is allocated,
//! instead of a failed allocation (signal 6) or the kernel's out-of-memory kill part way
//! through the run. The limit here is the address-space limit (`ulimit -v`), the one a test
//! can set for a child process alone; the machine's and the cgroup's are read the same way
//! (`asperity::memory`).

use std::path::{Path, PathBuf};
use std::process::Command;

use asperity::mesh::gmsh::mesh_geo;

/// Address-space limit of the run, in KiB. The run below maps about 0.3 GB before the check
/// and its factor needs 0.38 GB: it reaches the check under limits from 0.37 GB on and is
/// refused there up to 0.74 GB (measured with two threads); 0.56 GB is in the middle.
const LIMIT_KIB: u64 = 550_000;

/// The tapered press fit of `make bench-calculix` (its case file, a linear Coulomb joint) at
/// 244 k unknowns.
fn case(dir: &Path) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let geo = root.join("geo/bench_tapered_joint.geo");
    let mesh = mesh_geo(&geo, 0.0774, &[], &dir.join("mesh.msh")).expect("gmsh meshes the taper");
    let bench = std::fs::read_to_string(root.join("benches/calculix/cases/tapered_press_fit.toml"))
        .unwrap();
    let geo_line = "geo = \"../../../geo/bench_tapered_joint.geo\"";
    assert!(
        bench.contains(geo_line),
        "the bench case meshes the taper's .geo"
    );
    let text = bench.replace(
        geo_line,
        &format!("file = {:?}", mesh.path.display().to_string()),
    );
    let path = dir.join("case.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_factor_beyond_the_address_space_limit_is_refused_before_it_is_allocated() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("memory_limit");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let case = case(&dir);
    let out = dir.join("out");
    let run = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {LIMIT_KIB} && exec \"$0\" run \"$1\" --out \"$2\" -q"
        ))
        .arg(env!("CARGO_BIN_EXE_asperity"))
        .arg(&case)
        .arg(&out)
        .env("RAYON_NUM_THREADS", "2")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(3), "{stderr}");
    for words in [
        "the linear solver needs 0.38 GB of memory for the 244344 unknowns (the sparse factor of \
         the bodies' stiffness 0.36 GB, the dense system of the 1659 interface unknowns 0.02 GB)",
        "ulimit -v",
        "mesh.size",
    ] {
        assert!(stderr.contains(words), "`{words}` not in: {stderr}");
    }
    // The folder says why, and no increment was written.
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.contains("\"failed\""), "{summary}");
    assert!(!has_frames(&out), "a frame was written");
}

/// Whether `dir` or a folder below it holds a VTU file.
fn has_frames(dir: &Path) -> bool {
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .any(|entry| {
            let path = entry.path();
            path.extension().is_some_and(|e| e == "vtu") || (path.is_dir() && has_frames(&path))
        })
}
