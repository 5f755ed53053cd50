//! Running Debian's `gmsh` command-line program to mesh a `.geo` script.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use crate::error::MeshProblem;
use crate::{Error, Result};

/// Longest gmsh run: a 2D mesh of any size this program can solve takes seconds to a few
/// minutes; a gmsh that runs longer hangs (it does, e.g., on a NaN parameter) and is killed.
pub const GMSH_TIMEOUT: Duration = Duration::from_secs(600);

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
    let child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| {
            Error::External(format!(
                "cannot run gmsh ({e}); install it with `apt-get install gmsh` or run `make deps`"
            ))
        })?;
    let (status, log) = wait_with_timeout(child, GMSH_TIMEOUT).map_err(|e| match e {
        Some(e) => Error::External(format!("gmsh on {}: {e}", geo.display())),
        None => Error::External(format!(
            "gmsh did not finish meshing {} within {} s and was stopped; check the script \
             (and its parameters) in the gmsh GUI",
            geo.display(),
            GMSH_TIMEOUT.as_secs()
        )),
    })?;
    if !status.success() || log.contains("Error") || !out.is_file() {
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

/// Waits for `child` at most `timeout`, collecting its stderr and stdout (read on threads so
/// that a full pipe cannot stall it). On time-out the child is killed and the error is `None`.
fn wait_with_timeout(
    mut child: Child,
    timeout: Duration,
) -> std::result::Result<(ExitStatus, String), Option<std::io::Error>> {
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut text = Vec::new();
            if let Some(mut pipe) = pipe {
                let _ = pipe.read_to_end(&mut text);
            }
            String::from_utf8_lossy(&text).into_owned()
        })
    };
    let stderr = drain(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let stdout = drain(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().map_err(Some)? {
            break status;
        }
        if start.elapsed() > timeout {
            let _ = child.kill();
            let _ = child.wait();
            return Err(None);
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let log = stderr.join().unwrap_or_default() + &stdout.join().unwrap_or_default();
    Ok((status, log))
}
