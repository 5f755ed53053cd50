//! The plots of `asperity converge`, `sweep collect` and `fit`: Python scripts of the
//! repository's `pipelines/` folder (matplotlib, in the repository's `.venv`), run on an output
//! folder. A plot is never required: when the script or a Python with matplotlib is missing,
//! or the script fails, the command says why and gives the command to make the plot by hand.
//!
//! One module below `study`, `sweep` and `fit`, which all make plots this way, and importing
//! nothing of the crate.

use std::path::{Path, PathBuf};

/// The environment variable naming the `pipelines/` folder (for an installed binary).
const PIPELINES_VAR: &str = "ASPERITY_PIPELINES";

/// Where `pipelines/<script>` is: in `$ASPERITY_PIPELINES` if set, else in the `pipelines/`
/// folder of the first ancestor of the running executable that has the script (the
/// repository of a `target/release/asperity`). Returns the script and the Python to run it
/// with: the `.venv/bin/python` beside that `pipelines/` folder if there is one, else
/// `python3`.
fn find(script: &str) -> Result<(PathBuf, PathBuf), String> {
    let pipelines = match std::env::var_os(PIPELINES_VAR) {
        Some(dir) => {
            let dir = PathBuf::from(dir);
            if !dir.join(script).is_file() {
                return Err(format!("{PIPELINES_VAR}={} has no {script}", dir.display()));
            }
            dir
        }
        None => {
            let exe = std::env::current_exe().map_err(|e| format!("no executable path: {e}"))?;
            exe.ancestors()
                .skip(1)
                .map(|a| a.join("pipelines"))
                .find(|p| p.join(script).is_file())
                .ok_or_else(|| {
                    format!(
                        "pipelines/{script} not found above {} (set {PIPELINES_VAR})",
                        exe.display()
                    )
                })?
        }
    };
    let venv = pipelines
        .parent()
        .map(|root| root.join(".venv/bin/python"))
        .filter(|p| p.is_file());
    Ok((
        pipelines.join(script),
        venv.unwrap_or_else(|| PathBuf::from("python3")),
    ))
}

/// Runs `pipelines/<script> <out>`, which makes `made` (e.g. "convergence.png"). The script
/// is found in `$ASPERITY_PIPELINES` if set, else in the `pipelines/` folder of the first
/// ancestor of the executable that has it, and run with the `.venv/bin/python` beside that
/// folder, else `python3`, if that Python has matplotlib. The error is the sentence to show
/// instead: `skipped <made>: <why>;` and the command to run by hand.
pub fn run_script(script: &str, out: &Path, made: &str) -> Result<(), String> {
    let how = |python: &str, script: &str| {
        format!(
            "to make it, run `{python} {script} {}` in the repository (after `make venv`)",
            out.display()
        )
    };
    let (path, python) = find(script).map_err(|why| {
        format!(
            "skipped {made}: {why}; {}",
            how(".venv/bin/python", &format!("pipelines/{script}"))
        )
    })?;
    let manual = how(&python.display().to_string(), &path.display().to_string());
    let has_matplotlib = std::process::Command::new(&python)
        .args(["-c", "import matplotlib"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_matplotlib {
        return Err(format!(
            "skipped {made}: {} has no matplotlib; {manual}",
            python.display()
        ));
    }
    match std::process::Command::new(&python)
        .arg(&path)
        .arg(out)
        .output()
    {
        Ok(o) if o.status.success() => Ok(()),
        Ok(o) => Err(format!(
            "skipped {made}: {} failed: {}; {manual}",
            path.display(),
            String::from_utf8_lossy(&o.stderr)
                .trim()
                .lines()
                .last()
                .unwrap_or_default()
        )),
        Err(e) => Err(format!(
            "skipped {made}: cannot run {}: {e}; {manual}",
            python.display()
        )),
    }
}
