//! Running Debian's `gmsh` command-line program to mesh a `.geo` script.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::error::MeshProblem;
use crate::{Error, Result};

/// Meshes `geo` in 2D into an MSH 4.1 file `out` with quadratic serendipity elements
/// (`-order 2`, `Mesh.SecondOrderIncomplete = 1`, so recombined quads become 8-node quads),
/// mesh size factor `size` (`-clscale`) and `-setnumber` values for the script's
/// `DefineConstant` parameters.
pub fn mesh_geo(
    geo: &Path,
    size: f64,
    parameters: &[(String, f64)],
    out: &Path,
) -> Result<PathBuf> {
    if !geo.is_file() {
        return Err(Error::mesh(
            geo,
            MeshProblem::NotFound,
            None,
            "the .geo script does not exist",
        ));
    }
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    let mut cmd = Command::new("gmsh");
    cmd.arg(geo)
        .args(["-2", "-order", "2", "-format", "msh41", "-v", "2"])
        .args(["-setnumber", "Mesh.SecondOrderIncomplete", "1"])
        .arg("-clscale")
        .arg(size.to_string());
    for (name, value) in parameters {
        cmd.arg("-setnumber").arg(name).arg(value.to_string());
    }
    cmd.arg("-o").arg(out);
    tracing::info!("meshing {} (size factor {size})", geo.display());
    let output = cmd.output().map_err(|e| {
        Error::External(format!(
            "cannot run gmsh ({e}); install it with `apt-get install gmsh` or run `make deps`"
        ))
    })?;
    let log = String::from_utf8_lossy(&output.stderr).to_string()
        + &String::from_utf8_lossy(&output.stdout);
    if !output.status.success() || log.contains("Error") || !out.is_file() {
        return Err(Error::External(format!(
            "gmsh failed on {}:\n{}",
            geo.display(),
            log.lines()
                .filter(|l| l.contains("Error") || l.contains("Warning"))
                .collect::<Vec<_>>()
                .join("\n")
        )));
    }
    Ok(out.to_path_buf())
}
