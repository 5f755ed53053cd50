//! Running Debian's `gmsh` command-line program to mesh a `.geo` script.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use super::cache::{CacheKey, MeshCache};
use crate::error::MeshProblem;
use crate::{Error, Result};

/// Longest gmsh run: a 2D mesh of any size this program can solve takes seconds to a few
/// minutes; a gmsh that runs longer hangs (it does, e.g., on a NaN parameter) and is killed.
pub const GMSH_TIMEOUT: Duration = Duration::from_secs(600);

/// Most elements a `.geo` script is meshed into (estimated before meshing, see
/// [`estimate_elements`]). gmsh needs about 1 kB per element (a size factor of 10⁻⁶ on a
/// small model ran it up to 6 GB before this limit), and the solver far more: a run of
/// 1.1 million quad8 elements outgrew 23 GB.
pub const MAX_MESH_ELEMENTS: u64 = 1_000_000;

/// Ratio of the mesh size factors of successive probes in [`estimate_elements`]: each finer
/// probe has about 16 times the elements of the previous one (in 2D the count goes as the
/// inverse square of the element size).
const PROBE_STEP: f64 = 4.0;

/// The coarsest probe's size factor is at least this (4096 times fewer elements than the
/// script's own mesh at factor 1), so that the first probe is cheap whatever the script.
const COARSEST_PROBE: f64 = 64.0;

/// A probe with at least this many elements is refined enough that its count scales as the
/// inverse square of the size factor; coarser probes are dominated by the geometry (every
/// curve needs an element) and would overestimate.
const RELIABLE_PROBE: u64 = 4000;

/// Meshes `geo` in 2D into an MSH 4.1 file `out` with quadratic serendipity elements
/// (`-order 2`, `Mesh.SecondOrderIncomplete = 1`, so recombined quads become 8-node quads),
/// mesh size factor `size` (`-clscale`) and `-setnumber` values for the script's
/// `DefineConstant` parameters. The number of elements is estimated first
/// ([`estimate_elements`]); a mesh above [`MAX_MESH_ELEMENTS`] is refused before it is made.
///
/// With a mesh cache ([`MeshCache::from_env`]), a mesh gmsh made before from the same script,
/// gmsh version, size factor and parameters is copied to `out` instead (see [`cache`](super::cache)).
pub fn mesh_geo(geo: &Path, size: f64, parameters: &[(String, f64)], out: &Path) -> Result<Meshed> {
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
    // An earlier mesh at `out` must not pass for this one when gmsh writes none.
    match std::fs::remove_file(out) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(Error::io(out, e)),
        _ => {}
    }
    let cached = MeshCache::from_env().and_then(|cache| {
        let key = cache_key(geo, size, parameters)?;
        Some((cache, key))
    });
    if let Some((cache, key)) = &cached
        && cache.fetch(key, out)
    {
        tracing::info!(
            "mesh of {} (size factor {size}) from the mesh cache",
            geo.display()
        );
        return Ok(Meshed {
            path: out.to_path_buf(),
            gmsh_seconds: 0.0,
            cached: true,
        });
    }
    let start = Instant::now();
    make_mesh(geo, size, parameters, out)?;
    let gmsh_seconds = start.elapsed().as_secs_f64();
    if let Some((cache, key)) = &cached {
        cache.store(key, out);
    }
    Ok(Meshed {
        path: out.to_path_buf(),
        gmsh_seconds,
        cached: false,
    })
}

/// A mesh [`mesh_geo`] made or found in the cache.
#[derive(Clone, Debug)]
pub struct Meshed {
    /// The MSH file.
    pub path: PathBuf,
    /// Seconds spent in gmsh (its element-count probes and the mesh itself; 0 from the cache).
    pub gmsh_seconds: f64,
    /// Whether the mesh came from the cache.
    pub cached: bool,
}

/// The cache key of `geo` at `size` with `parameters` for the installed gmsh, or `None`
/// (a script that reads other files, or one that is not text, or no gmsh version).
fn cache_key(geo: &Path, size: f64, parameters: &[(String, f64)]) -> Option<CacheKey> {
    let script = std::fs::read_to_string(geo).ok()?;
    let version = Command::new("gmsh").arg("--version").output().ok()?;
    let version = [version.stdout, version.stderr].concat();
    CacheKey::new(
        &script,
        &String::from_utf8_lossy(&version),
        size,
        parameters,
    )
}

/// Estimates the element count, refuses a mesh over the limit, and meshes (see
/// [`mesh_geo`]).
fn make_mesh(geo: &Path, size: f64, parameters: &[(String, f64)], out: &Path) -> Result<()> {
    let estimate = estimate_elements(geo, size, parameters)?;
    if let Some(Estimate {
        elements,
        probe,
        probe_elements,
        growth,
    }) = estimate
        && elements > MAX_MESH_ELEMENTS
    {
        // A count that grew with the finer probes as a 2D mesh does (at least 4 of the 16
        // times per probe step) follows the size factor; one that hardly grew does not.
        let follows_size = growth >= PROBE_STEP;
        let wanted = probe * (probe_elements as f64 / MAX_MESH_ELEMENTS as f64).sqrt();
        return Err(too_large(
            geo,
            format!(
                "mesh.size = {size} would make about {elements:.1e} elements (extrapolated from \
                 the script meshed at size factor {probe}: {probe_elements} elements)"
            ),
            follows_size.then_some(wanted),
        ));
    }
    tracing::info!("meshing {} (size factor {size})", geo.display());
    let mut cmd = gmsh(geo, size, parameters, out);
    cmd.args(["-order", "2"])
        .args(["-setnumber", "Mesh.SecondOrderIncomplete", "1"]);
    run(cmd, geo, out)?;
    // The estimate bounds a count that follows the size factor; the mesh itself is counted
    // too (and is neither solved nor cached beyond the limit).
    let elements = element_count(out)?;
    if elements > MAX_MESH_ELEMENTS {
        let _ = std::fs::remove_file(out);
        return Err(too_large(
            geo,
            format!("the mesh gmsh made at mesh.size = {size} has {elements} elements"),
            None,
        ));
    }
    Ok(())
}

/// The error of a mesh over [`MAX_MESH_ELEMENTS`]: `what` says how many elements, and `size`,
/// when the count follows the size factor, the factor that would meet the limit.
fn too_large(geo: &Path, what: String, size: Option<f64>) -> Error {
    let advice = match size {
        Some(size) => format!("increase mesh.size (to about {size:.2e}) or coarsen the script"),
        None => "its element counts do not follow mesh.size (transfinite or fixed counts): \
                 lower the counts the script sets (its [mesh] parameters) or coarsen it"
            .into(),
    };
    Error::mesh(
        geo,
        MeshProblem::TooLarge,
        None,
        format!("{what}, more than the limit of {MAX_MESH_ELEMENTS}; {advice}"),
    )
}

/// The element count of a mesh of `geo` at size factor `size`, extrapolated from a coarser
/// probe mesh ([`Estimate`]), or `None` when the probes could not bound it below the limit
/// before reaching `size` itself (the caller then meshes at `size`).
///
/// Why probes: gmsh reports no element count before meshing, and the count cannot be read
/// off the script (transfinite counts, size fields, `Ceil` of the size factor and absolute
/// size limits all enter). So the script is meshed, first order, at size factors
/// `size` × 4^k from the first one above `COARSEST_PROBE` down to `size` × 4, each probe
/// at most about 16 times the previous one. In 2D a count grows at most as 1/factor², so
/// the count at `size` is at most the probe's × 16^k: below the limit, the mesh is
/// accepted. It is refused only when a probe of at least `RELIABLE_PROBE` elements,
/// extrapolated with the growth actually observed from the previous probe (a script with
/// fixed transfinite counts does not grow at all), still exceeds the limit. The probes cost
/// a small fraction of the mesh they predict: a 10⁻⁶ factor on a small model is refused
/// after a few probes of at most a few thousand elements. A probe gmsh cannot make (a script
/// written for fine sizes) is skipped, unless it ran out of memory or time: the mesh at
/// `size` would too, and that failure is the error.
pub fn estimate_elements(
    geo: &Path,
    size: f64,
    parameters: &[(String, f64)],
) -> Result<Option<Estimate>> {
    let steps = (COARSEST_PROBE / size).log(PROBE_STEP).ceil().max(0.0) as i32;
    let dir = tempfile::tempdir().map_err(|e| Error::io(std::env::temp_dir(), e))?;
    let out = dir.path().join("probe.msh");
    let mut previous: Option<u64> = None;
    let most_growth = PROBE_STEP * PROBE_STEP;
    for k in (1..=steps).rev() {
        let probe = size * PROBE_STEP.powi(k);
        // A script may not mesh at a coarse factor (a count that rounds to zero, a division
        // by it): such a probe tells nothing, and only the mesh at `size` itself must succeed.
        let meshed = attempt(gmsh(geo, probe, parameters, &out), geo, &out);
        let count = match meshed {
            Ok(()) => element_count(&out),
            Err(Failure {
                error: stop @ Error::Interrupted { .. },
                ..
            }) => return Err(stop),
            // A finer probe, and the mesh itself, would need more memory or time still.
            Err(Failure {
                error,
                exhausted: true,
            }) => {
                return Err(Error::External(format!(
                    "{error}\n(meshing a coarser probe at size factor {probe}, to estimate \
                     the element count at mesh.size = {size}: the mesh itself would need \
                     more; lower the script's counts or raise mesh.size)"
                )));
            }
            Err(Failure { error, .. }) => Err(error),
        };
        let count = match count {
            Ok(count) => count,
            Err(_) => {
                previous = None;
                continue;
            }
        };
        let extrapolate = |growth: f64| (count as f64 * growth.powi(k)).min(u64::MAX as f64) as u64;
        let estimate = |elements, growth| Estimate {
            elements,
            probe,
            probe_elements: count,
            growth,
        };
        let bound = extrapolate(most_growth);
        if bound <= MAX_MESH_ELEMENTS {
            return Ok(Some(estimate(bound, most_growth)));
        }
        if let Some(before) = previous
            && count >= RELIABLE_PROBE
        {
            let growth = (count as f64 / before.max(1) as f64).clamp(1.0, most_growth);
            let elements = extrapolate(growth);
            if elements > MAX_MESH_ELEMENTS {
                return Ok(Some(estimate(elements, growth)));
            }
        }
        previous = Some(count);
    }
    Ok(None)
}

/// An element count extrapolated from a probe mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Estimated number of elements at the requested size factor (an upper bound when it is
    /// below [`MAX_MESH_ELEMENTS`]).
    pub elements: u64,
    /// Size factor of the probe it was extrapolated from.
    pub probe: f64,
    /// Number of elements of the probe.
    pub probe_elements: u64,
    /// The growth of the count per probe step it was extrapolated with (16 for a 2D mesh
    /// that follows the size factor, about 1 for fixed transfinite counts).
    pub growth: f64,
}

/// The address space a gmsh run may take: meshing the limit's million elements (second
/// order) takes about 1.5 GB; a script whose fixed counts reach a billion elements would
/// take the machine's whole memory before the element limit could refuse it, and is stopped
/// here instead (gmsh aborts when an allocation fails).
pub const GMSH_MEMORY_BYTES: u64 = 8 << 30;

/// `path` as gmsh's command line reads it as a file: a relative path starting with `-`
/// (a script called `-info`) would be taken for an option, `./-info` is not.
fn not_an_option(path: &Path) -> std::path::PathBuf {
    if path.as_os_str().as_encoded_bytes().starts_with(b"-") {
        Path::new(".").join(path)
    } else {
        path.to_path_buf()
    }
}

/// The gmsh command meshing `geo` in 2D at size factor `size` into `out` (MSH 4.1, binary),
/// its address space capped at [`GMSH_MEMORY_BYTES`].
///
/// Binary because it pays at every size: at 1 M unknowns gmsh took 1.75 s instead of 2.94 s
/// (writing 27 instead of 32 MB of text it formats number by number) and the reader 0.23 s
/// instead of 0.53 s; at 3.8 M unknowns gmsh 7.3 s instead of 10.4 s (BENCHMARKS.md).
fn gmsh(geo: &Path, size: f64, parameters: &[(String, f64)], out: &Path) -> Command {
    let mut cmd = Command::new("gmsh");
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        let limit = libc::rlimit {
            rlim_cur: GMSH_MEMORY_BYTES as libc::rlim_t,
            rlim_max: GMSH_MEMORY_BYTES as libc::rlim_t,
        };
        // SAFETY: between fork and exec the closure only calls setrlimit, which is
        // async-signal-safe, on a limit made before the fork.
        unsafe {
            cmd.pre_exec(move || {
                if libc::setrlimit(libc::RLIMIT_AS, &limit) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
    }
    cmd.arg(not_an_option(geo))
        .args(["-2", "-format", "msh41", "-bin", "-v", "2"])
        .arg("-clscale")
        .arg(size.to_string());
    for (name, value) in parameters {
        cmd.arg("-setnumber").arg(name).arg(value.to_string());
    }
    cmd.arg("-o").arg(out);
    cmd
}

/// Runs gmsh (`cmd`, meshing `geo` into `out`); its failure is an error with gmsh's own
/// `Error` lines, or, when it printed none (killed, crashed), how it ended and its last
/// lines of output.
fn run(cmd: Command, geo: &Path, out: &Path) -> Result<()> {
    attempt(cmd, geo, out).map_err(|failure| failure.error)
}

/// A failed gmsh run: its error, and whether gmsh ran out of memory or time, which a finer
/// mesh of the same script would too.
struct Failure {
    error: Error,
    exhausted: bool,
}

/// [`run`], telling a run out of memory or time apart.
fn attempt(mut cmd: Command, geo: &Path, out: &Path) -> std::result::Result<(), Failure> {
    let failure = |error, exhausted| Failure { error, exhausted };
    let child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| {
            failure(
                Error::External(format!(
                    "cannot run gmsh ({e}); install it with `apt-get install gmsh` or run \
                     `make deps`"
                )),
                false,
            )
        })?;
    let (status, log) = wait_with_timeout(child, GMSH_TIMEOUT).map_err(|e| match e {
        // Ctrl-C or SIGTERM while gmsh runs: it is stopped, and the run with it.
        Some(e) if e.kind() == std::io::ErrorKind::Interrupted => failure(
            Error::Interrupted {
                step: 0,
                dir: out.parent().unwrap_or(Path::new(".")).to_path_buf(),
                resume: None,
            },
            false,
        ),
        Some(e) => failure(
            Error::External(format!("gmsh on {}: {e}", geo.display())),
            false,
        ),
        None => failure(
            Error::External(format!(
                "gmsh did not finish meshing {} within {} s and was stopped; check the script \
                 (and its parameters) in the gmsh GUI",
                geo.display(),
                GMSH_TIMEOUT.as_secs()
            )),
            true,
        ),
    })?;
    let mut errors: Vec<&str> = Vec::new();
    for line in log.lines().map(str::trim_end) {
        if line.trim_start().starts_with("Error") && !errors.contains(&line) {
            errors.push(line);
        }
    }
    if status.success() && errors.is_empty() && out.is_file() {
        return Ok(());
    }
    let reason = if !errors.is_empty() {
        errors.join("\n")
    } else {
        let lines: Vec<&str> = log.lines().filter(|l| !l.trim().is_empty()).collect();
        let tail = lines[lines.len().saturating_sub(5)..].join("\n");
        let ended = if status.success() {
            "gmsh wrote no mesh".to_string()
        } else {
            ended_by(status)
        };
        if tail.is_empty() {
            format!("{ended}, and printed nothing")
        } else {
            format!("{ended}; its last output:\n{tail}")
        }
    };
    Err(failure(
        Error::External(format!("gmsh failed on {}:\n{reason}", geo.display())),
        out_of_memory(status, &log),
    ))
}

/// Whether gmsh ended for want of memory: killed by SIGKILL (the kernel's out-of-memory
/// killer), or aborted on a failed allocation (its address space is capped).
fn out_of_memory(status: ExitStatus, log: &str) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        match status.signal() {
            Some(9) => return true,
            Some(6) => return log.contains("std::bad_alloc"),
            _ => {}
        }
    }
    false
}

/// How a failed gmsh ended: its exit code, or the signal that killed it (SIGKILL is what the
/// kernel's out-of-memory killer sends).
fn ended_by(status: ExitStatus) -> String {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(signal) = status.signal() {
            let hint = match signal {
                9 => " (as the system does when memory runs out)".to_string(),
                6 => format!(
                    " (as gmsh does when an allocation fails: its memory is capped at {} GiB, \
                     which a mesh within the element limit never needs)",
                    GMSH_MEMORY_BYTES >> 30
                ),
                _ => String::new(),
            };
            return format!("gmsh was killed by signal {signal}{hint}");
        }
    }
    match status.code() {
        Some(code) => format!("gmsh exited with status {code}"),
        None => "gmsh ended abnormally".to_string(),
    }
}

/// The number of elements of the MSH 4.1 file `path` (ASCII or binary: a script may set
/// `Mesh.Binary`), of every dimension, from its `$Elements` header `numEntityBlocks
/// numElements minTag maxTag` (the file streamed up to it: a gmsh mesh of a million
/// elements is hundreds of MB). Another MSH version (a script that sets
/// `Mesh.MshFileVersion`) is an error saying so.
fn element_count(path: &Path) -> Result<u64> {
    use std::io::BufRead;
    let problem = |problem, message: String| Error::mesh(path, problem, None, message);
    let unreadable = || {
        problem(
            MeshProblem::MissingSection,
            "gmsh's mesh has no readable $Elements header".into(),
        )
    };
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut reader = std::io::BufReader::new(file);
    let mut line = Vec::new();
    // Reads up to the next line break; false at the end of the file.
    let next_line = |reader: &mut std::io::BufReader<std::fs::File>, line: &mut Vec<u8>| {
        line.clear();
        reader
            .read_until(b'\n', line)
            .map(|n| n > 0)
            .map_err(|e| Error::io(path, e))
    };
    while next_line(&mut reader, &mut line)? && line.trim_ascii() != b"$MeshFormat" {}
    if !next_line(&mut reader, &mut line)? {
        return Err(unreadable());
    }
    let format = String::from_utf8_lossy(line.trim_ascii()).into_owned();
    let mut fields = format.split_whitespace();
    let (version, binary, size) = (fields.next(), fields.next(), fields.next());
    if version != Some("4.1") {
        return Err(problem(
            MeshProblem::Version,
            format!(
                "gmsh wrote MSH format '{format}' (does the script set Mesh.MshFileVersion?): \
                 asperity reads MSH 4.1; remove that setting from the script"
            ),
        ));
    }
    // Binary: the int 1 in the file's byte order follows the format line.
    let little_endian = if binary == Some("1") {
        let mut one = [0u8; 4];
        reader
            .read_exact(&mut one)
            .map_err(|e| Error::io(path, e))?;
        Some(i32::from_le_bytes(one) == 1)
    } else {
        None
    };
    while next_line(&mut reader, &mut line)? {
        if line.trim_ascii() != b"$Elements" {
            continue;
        }
        return match little_endian {
            None => {
                next_line(&mut reader, &mut line)?;
                std::str::from_utf8(&line)
                    .ok()
                    .and_then(|h| h.split_whitespace().nth(1)?.parse().ok())
                    .ok_or_else(unreadable)
            }
            Some(little) => {
                // numEntityBlocks and numElements, each a size_t of `size` bytes (8).
                if size != Some("8") {
                    return Err(unreadable());
                }
                let mut header = [0u8; 16];
                reader
                    .read_exact(&mut header)
                    .map_err(|e| Error::io(path, e))?;
                let bytes: [u8; 8] = header[8..].try_into().expect("8 bytes");
                Ok(if little {
                    u64::from_le_bytes(bytes)
                } else {
                    u64::from_be_bytes(bytes)
                })
            }
        };
    }
    Err(unreadable())
}

/// Waits for `child` at most `timeout`, collecting its stderr and stdout (read on threads so
/// that a full pipe cannot stall it). On time-out the child is killed and the error is `None`;
/// on a stop request ([`crate::stop`]) it is killed and the error is of kind `Interrupted`.
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
        if crate::stop::stop_requested() {
            let _ = child.kill();
            let _ = child.wait();
            return Err(Some(std::io::Error::from(std::io::ErrorKind::Interrupted)));
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::process::ExitStatusExt;

    /// The wait status of a process killed by `signal`.
    fn killed(signal: i32) -> ExitStatus {
        ExitStatus::from_raw(signal)
    }

    #[test]
    fn element_counts_are_read_from_ascii_and_binary_headers() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.msh");
        let write = |bytes: &[u8]| std::fs::write(&path, bytes).unwrap();
        write(b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Elements\n3 1234 1 1234\n");
        assert_eq!(element_count(&path).unwrap(), 1234);
        let mut binary = b"$MeshFormat\n4.1 1 8\n".to_vec();
        binary.extend(1i32.to_le_bytes());
        binary.extend(b"\n$EndMeshFormat\n$Nodes\n");
        binary.extend([0x0a, 0x24, 0xff, 0x00]); // binary data with line breaks
        binary.extend(b"\n$EndNodes\n$Elements\n");
        for n in [3u64, 98_765, 1, 98_765] {
            binary.extend(n.to_le_bytes());
        }
        write(&binary);
        assert_eq!(element_count(&path).unwrap(), 98_765);
        write(b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Elements\n7\n");
        let error = element_count(&path).unwrap_err().to_string();
        assert!(
            error.contains("'2.2 0 8'") && error.contains("MshFileVersion"),
            "{error}"
        );
    }

    #[test]
    fn a_script_named_like_an_option_is_passed_as_a_file() {
        assert_eq!(not_an_option(Path::new("-info")), Path::new("./-info"));
        assert_eq!(not_an_option(Path::new("a/-b.geo")), Path::new("a/-b.geo"));
        assert_eq!(
            not_an_option(Path::new("/x/-b.geo")),
            Path::new("/x/-b.geo")
        );
    }

    #[test]
    fn only_a_failed_allocation_or_the_kernels_kill_is_out_of_memory() {
        let bad_alloc = "terminate called after throwing an instance of 'std::bad_alloc'";
        assert!(out_of_memory(killed(9), ""));
        assert!(out_of_memory(killed(6), bad_alloc));
        // an assertion of gmsh's own, a crash, an error exit: a finer mesh may still succeed
        assert!(!out_of_memory(killed(6), "Assertion `n > 0' failed."));
        assert!(!out_of_memory(killed(11), bad_alloc));
        assert!(!out_of_memory(ExitStatus::from_raw(1 << 8), bad_alloc));
    }
}
