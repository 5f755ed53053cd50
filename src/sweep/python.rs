//! Plots by the Python scripts of `pipelines/` (matplotlib in the repository's `.venv`), found
//! as `asperity converge` finds `plot_convergence.py`.

use std::path::{Path, PathBuf};

/// The environment variable naming the `pipelines/` folder (as for `asperity converge`).
const PIPELINES_VAR: &str = "ASPERITY_PIPELINES";

/// `pipelines/<script>` and the Python to run it with: `$ASPERITY_PIPELINES`, else the
/// `pipelines/` folder of the first ancestor of the executable that has the script (the
/// repository of a `target/release/asperity`); `.venv/bin/python` beside it, else `python3`.
pub(crate) fn python_script(script: &str) -> std::result::Result<(PathBuf, PathBuf), String> {
    let pipelines = match std::env::var_os(PIPELINES_VAR) {
        Some(dir) => PathBuf::from(dir),
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
    let path = pipelines.join(script);
    if !path.is_file() {
        return Err(format!("{} does not exist", path.display()));
    }
    let venv = pipelines
        .parent()
        .map(|root| root.join(".venv/bin/python"))
        .filter(|p| p.is_file());
    Ok((path, venv.unwrap_or_else(|| PathBuf::from("python3"))))
}

/// Runs `pipelines/<script> <out>`; returns what happened, with the command to run by hand
/// when it could not.
pub(crate) fn run_python(script: &str, out: &Path, made: &str) -> String {
    let manual = format!(
        "run `.venv/bin/python pipelines/{script} {}` after `make venv`",
        out.display()
    );
    let (path, python) = match python_script(script) {
        Ok(found) => found,
        Err(why) => return format!("skipped {made}: {why}; {manual}"),
    };
    match std::process::Command::new(&python)
        .arg(&path)
        .arg(out)
        .output()
    {
        Ok(o) if o.status.success() => format!("{made} in {}", out.display()),
        Ok(o) => format!(
            "skipped {made}: {} failed: {}; {manual}",
            path.display(),
            String::from_utf8_lossy(&o.stderr)
                .trim()
                .lines()
                .last()
                .unwrap_or_default()
        ),
        Err(e) => format!(
            "skipped {made}: cannot run {}: {e}; {manual}",
            python.display()
        ),
    }
}
