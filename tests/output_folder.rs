//! The output folder is the user's folder too (README "Output folder"): a run removes or
//! overwrites only what its manifest (`run_files.txt`) lists as written by asperity, never an
//! input of the run, never writes through a symbolic link, resolves relative folders one way,
//! and stops cleanly on Ctrl-C.
use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{fixture, held_block};

/// `asperity ARGS` in `cwd`: the exit code and the output.
fn asperity_in(cwd: &Path, args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("runs");
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out.status.code(), text)
}

/// `asperity run CASE --out OUT [flags]` in `dir`.
fn run(dir: &Path, case: &Path, out: &Path, flags: &[&str]) -> (Option<i32>, String) {
    let mut args = vec![
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(flags);
    asperity_in(dir, &args)
}

/// `asperity run CASE --out OUT` started in the background, its output piped.
fn spawn_run(case: &Path, out: &Path) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args([
            "run",
            case.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Sends `signal` (`-INT`, `-TERM`) to `child`.
fn signal(child: &std::process::Child, signal: &str) {
    let status = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

/// The held block of `tests/fixtures/two_bodies_ascii.msh` in `steps` steps, as `dir/case.toml`.
fn block_case(dir: &Path, steps: i64) -> PathBuf {
    held_block().steps(steps).write(&dir.join("case.toml"))
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A user's files whose names look like results (`wear_*.csv`, `contact_*_NNNN.csv` of a pair
/// the case does not have, `*.vtu`) survive `--force` and a `--resume` that starts over; the
/// run's own files of the earlier run are gone.
#[test]
fn force_and_resume_remove_only_what_the_manifest_lists() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let case = block_case(dir.path(), 3);
    let (code, text) = run(dir.path(), &case, &out, &[]);
    assert_eq!(code, Some(0), "{text}");
    let manifest = read(&out.join("run_files.txt"));
    assert!(
        manifest.lines().any(|l| l == "bodies_0003.vtu"),
        "{manifest}"
    );
    let mine = [
        "wear_measurements.csv",
        "contact_measured_0001.csv",
        "hysteresis_bench.csv",
        "photo.vtu",
        "notes.txt",
    ];
    for name in mine {
        std::fs::write(out.join(name), "mine").unwrap();
    }
    // A folder named like a writer's temporary file is no writer's: left in place.
    std::fs::create_dir(out.join(".log.txt.QQQQQQ.tmp")).unwrap();
    let case = block_case(dir.path(), 2);
    let (code, text) = run(dir.path(), &case, &out, &["--force"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(
        !out.join("bodies_0003.vtu").exists(),
        "a stale step file survived --force"
    );
    // No restart record (removed by hand): --resume starts over, removing only the run's files.
    std::fs::remove_file(out.join("restart.bin")).unwrap();
    let (code, text) = run(dir.path(), &case, &out, &["--resume"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("no restart record"), "{text}");
    for name in mine {
        assert_eq!(read(&out.join(name)), "mine", "{name} was touched");
    }
    assert!(out.join("bodies_0002.vtu").is_file());
    assert!(out.join(".log.txt.QQQQQQ.tmp").is_dir());
}

/// A manifest edited to list a user's own file (a name no run writes) does not make --force
/// delete it: the run leaves it in place and says so.
#[test]
fn force_keeps_a_file_a_manifest_lists_that_no_run_writes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let case = block_case(dir.path(), 2);
    let (code, text) = run(dir.path(), &case, &out, &[]);
    assert_eq!(code, Some(0), "{text}");
    std::fs::write(out.join("mynotes.txt"), "mine").unwrap();
    // Paths added by hand are no files of the folder: ignored with a warning, not kept.
    let victim = dir.path().join("victim.txt");
    std::fs::write(&victim, "mine").unwrap();
    let manifest = out.join("run_files.txt");
    let added = format!("mynotes.txt\n../victim.txt\n{}\n", victim.display());
    std::fs::write(&manifest, read(&manifest) + &added).unwrap();
    let (code, text) = run(dir.path(), &case, &out, &["--force"]);
    assert_eq!(code, Some(0), "{text}");
    assert_eq!(read(&out.join("mynotes.txt")), "mine");
    assert!(
        text.contains("'mynotes.txt', which is no name a run writes"),
        "{text}"
    );
    assert!(text.contains("2 entries are no plain file names"), "{text}");
    assert_eq!(read(&victim), "mine");
    assert!(!read(&manifest).contains("victim"), "{}", read(&manifest));
}

/// The case reads its mesh from the output folder under the name of the mesh a run writes
/// (`mesh.msh`): `--force` keeps it, whether or not an earlier run listed it.
#[test]
fn force_never_removes_an_input_of_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::copy(fixture("two_bodies_ascii.msh"), out.join("mesh.msh")).unwrap();
    let case = held_block()
        .mesh_file(&out.join("mesh.msh"))
        .steps(1)
        .write(&dir.path().join("case.toml"));
    for flags in [&[][..], &["--force"], &["--force"]] {
        let (code, text) = run(dir.path(), &case, &out, flags);
        assert_eq!(code, Some(0), "{flags:?}: {text}");
        assert!(
            out.join("mesh.msh").is_file(),
            "{flags:?} removed the input mesh"
        );
    }
    // Listed as the run's by a manifest (the mesh an earlier run meshed), still an input.
    let manifest = out.join("run_files.txt");
    let listed = read(&manifest) + "mesh.msh\n";
    std::fs::write(&manifest, listed).unwrap();
    let (code, text) = run(dir.path(), &case, &out, &["--force"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(
        out.join("mesh.msh").is_file(),
        "--force removed the listed input mesh"
    );
}

/// An input of the run (its mesh, its case file) lying in the output folder under the name of
/// a file the run writes (`cycles.csv`, `history.csv`, `summary.json`) is refused before
/// anything is written, with or without `--force` and whether or not a manifest lists the
/// name: the run would replace its own input.
#[test]
fn an_input_under_a_run_files_name_is_never_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let mesh = std::fs::read(fixture("two_bodies_ascii.msh")).unwrap();
    std::fs::write(out.join("cycles.csv"), &mesh).unwrap();
    let case = held_block()
        .mesh_file(&out.join("cycles.csv"))
        .steps(1)
        .write(&dir.path().join("case.toml"));
    for flags in [&[][..], &["--force"]] {
        let (code, text) = run(dir.path(), &case, &out, flags);
        assert_eq!(code, Some(2), "{flags:?}: {text}");
        assert!(
            text.contains("cycles.csv") && text.contains("input"),
            "{text}"
        );
        assert_eq!(std::fs::read(out.join("cycles.csv")).unwrap(), mesh);
        assert_eq!(
            common::file_names(&out),
            ["cycles.csv"],
            "{flags:?} wrote files"
        );
    }
    // The case file itself, named like a result of an earlier run that listed it.
    let mesh_case = held_block()
        .mesh_file(&fixture("two_bodies_ascii.msh"))
        .steps(1)
        .write(&dir.path().join("case.toml"));
    let earlier = dir.path().join("earlier");
    let (code, text) = run(dir.path(), &mesh_case, &earlier, &[]);
    assert_eq!(code, Some(0), "{text}");
    let text_of_case = read(&mesh_case);
    for name in ["history.csv", "summary.json"] {
        let case_there = earlier.join(name);
        std::fs::write(&case_there, &text_of_case).unwrap();
        let (code, text) = run(dir.path(), &case_there, &earlier, &["--force"]);
        assert_eq!(code, Some(2), "{name}: {text}");
        assert_eq!(read(&case_there), text_of_case, "{name} was replaced");
    }
}

/// `--resume` with another case file (a restart record of another case) is refused before
/// anything of the earlier run is touched: its summary, run.json, log and manifest keep their
/// bytes.
#[test]
fn a_refused_resume_leaves_the_earlier_run_as_it_was() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let case = block_case(dir.path(), 2);
    let (code, text) = run(dir.path(), &case, &out, &[]);
    assert_eq!(code, Some(0), "{text}");
    let snapshot = |out: &Path| -> Vec<(String, Vec<u8>)> {
        common::file_names(out)
            .into_iter()
            .map(|name| {
                let bytes = std::fs::read(out.join(&name)).unwrap();
                (name, bytes)
            })
            .collect()
    };
    let before = snapshot(&out);
    assert!(before.iter().any(|(name, _)| name == "restart.bin"));
    let other = held_block().steps(3).write(&dir.path().join("other.toml"));
    let (code, text) = run(dir.path(), &other, &out, &["--resume"]);
    assert_eq!(code, Some(3), "{text}");
    assert!(text.contains("case file changed"), "{text}");
    assert!(
        snapshot(&out) == before,
        "the refused resume changed the folder"
    );
}

/// A file the run would write but that no manifest lists (a log of the user's, results of
/// another program) is refused, before anything is written, with --force too; it is left
/// untouched.
#[test]
fn files_the_run_did_not_write_are_never_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("log.txt"), "my notes").unwrap();
    let case = block_case(dir.path(), 1);
    for flags in [&[][..], &["--force"], &["--resume"]] {
        let (code, text) = run(dir.path(), &case, &out, flags);
        assert_eq!(code, Some(2), "{flags:?}: {text}");
        assert!(
            text.contains("log.txt") && text.contains("run_files.txt"),
            "{text}"
        );
        assert_eq!(read(&out.join("log.txt")), "my notes");
        assert_eq!(
            common::file_names(&out),
            ["log.txt"],
            "{flags:?} wrote files"
        );
    }
    // A file of the manifest's name that is not a manifest is not taken for one.
    std::fs::remove_file(out.join("log.txt")).unwrap();
    std::fs::write(out.join("run_files.txt"), "bodies_0001.vtu\n").unwrap();
    std::fs::write(out.join("bodies_0001.vtu"), "mine").unwrap();
    let (code, text) = run(dir.path(), &case, &out, &["--force"]);
    assert_eq!(code, Some(2), "{text}");
    assert_eq!(read(&out.join("bodies_0001.vtu")), "mine");
}

/// Symbolic links in the output folder are never followed: a `log.txt` pointing outside and
/// a dangling `mesh.msh` that gmsh would create outside are refused, their targets untouched.
#[cfg(unix)]
#[test]
fn symbolic_links_are_never_written_through() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let outside = dir.path().join("precious.txt");
    std::fs::write(&outside, "keep").unwrap();
    std::os::unix::fs::symlink(&outside, out.join("log.txt")).unwrap();
    let case = block_case(dir.path(), 1);
    for flags in [&[][..], &["--force"]] {
        let (code, text) = run(dir.path(), &case, &out, flags);
        assert_eq!(code, Some(2), "{flags:?}: {text}");
        assert_eq!(read(&outside), "keep");
    }
    // A link put in place of a file the run listed is removed by --force (the link, not its
    // target) and a file written in its place.
    std::fs::remove_file(out.join("log.txt")).unwrap();
    let (code, text) = run(dir.path(), &case, &out, &[]);
    assert_eq!(code, Some(0), "{text}");
    std::fs::remove_file(out.join("log.txt")).unwrap();
    std::os::unix::fs::symlink(&outside, out.join("log.txt")).unwrap();
    let (code, text) = run(dir.path(), &case, &out, &["--force"]);
    assert_eq!(code, Some(0), "{text}");
    assert_eq!(read(&outside), "keep");
    assert!(!out.join("log.txt").symlink_metadata().unwrap().is_symlink());
    // --resume appends to the log and the growing tables: a link in their place is refused
    // before anything is written (exit 2), as is one in place of a file it replaces.
    for name in ["log.txt", "history.csv", "summary.json"] {
        let kept = out.join("kept");
        std::fs::rename(out.join(name), &kept).unwrap();
        std::os::unix::fs::symlink(&outside, out.join(name)).unwrap();
        let (code, text) = run(dir.path(), &case, &out, &["--resume"]);
        assert_eq!(code, Some(2), "{name}: {text}");
        assert!(text.contains("symbolic link"), "{text}");
        assert_eq!(read(&outside), "keep");
        std::fs::remove_file(out.join(name)).unwrap();
        std::fs::rename(&kept, out.join(name)).unwrap();
    }

    // An output folder that is a link to nothing is named as such.
    let dangling = dir.path().join("dangling");
    std::os::unix::fs::symlink(dir.path().join("nothing"), &dangling).unwrap();
    let (code, text) = run(dir.path(), &case, &dangling, &[]);
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains("symbolic link to nothing"), "{text}");

    let geo_out = dir.path().join("geo_out");
    std::fs::create_dir(&geo_out).unwrap();
    let target = dir.path().join("elsewhere.msh");
    std::os::unix::fs::symlink(&target, geo_out.join("mesh.msh")).unwrap();
    let geo_case = held_block()
        .mesh_geo(&dir.path().join("unused.geo"), 1.0)
        .steps(1)
        .write(&dir.path().join("geo_case.toml"));
    std::fs::write(dir.path().join("unused.geo"), "Point(1) = {0, 0, 0};\n").unwrap();
    let (code, text) = run(dir.path(), &geo_case, &geo_out, &["--force"]);
    assert_eq!(code, Some(2), "{text}");
    assert!(!target.exists(), "gmsh wrote through the dangling link");
}

/// A snapshot of an output folder made of hard links (`cp -al`, `rsync --link-dest`) is not
/// changed by a `--resume` of the folder, which cuts back and appends to its growing files in
/// place: they get copies of their own first.
#[cfg(unix)]
#[test]
fn resume_leaves_a_hard_linked_snapshot_as_it_was() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let case = block_case(dir.path(), 2);
    let (code, text) = run(dir.path(), &case, &out, &[]);
    assert_eq!(code, Some(0), "{text}");
    let snap = dir.path().join("snap");
    std::fs::create_dir(&snap).unwrap();
    let names = common::file_names(&out);
    let before: Vec<Vec<u8>> = names
        .iter()
        .map(|name| {
            std::fs::hard_link(out.join(name), snap.join(name)).unwrap();
            std::fs::read(snap.join(name)).unwrap()
        })
        .collect();
    let (code, text) = run(dir.path(), &case, &out, &["--resume"]);
    assert_eq!(code, Some(0), "{text}");
    assert_ne!(
        read(&out.join("log.txt")).len(),
        before[names.iter().position(|n| n == "log.txt").unwrap()].len()
    );
    for (name, bytes) in names.iter().zip(&before) {
        assert!(
            std::fs::read(snap.join(name)).unwrap() == *bytes,
            "{name} changed"
        );
    }
}

/// A relative `[output] dir` is relative to the case file, whatever the working directory;
/// `--out a/../b` is the folder `b` (relative to the working directory); neither fails after
/// creating files.
#[test]
fn relative_output_folders_resolve_one_way() {
    let dir = tempfile::tempdir().unwrap();
    let cases = dir.path().join("cases");
    std::fs::create_dir(&cases).unwrap();
    let case = held_block()
        .steps(1)
        .set("output", "dir", "../results")
        .write(&cases.join("case.toml"));
    let elsewhere = dir.path().join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    let (code, text) = asperity_in(&elsewhere, &["run", case.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{text}");
    assert!(dir.path().join("results/history.csv").is_file(), "{text}");
    assert!(!elsewhere.join("results").exists());

    let (code, text) = asperity_in(
        dir.path(),
        &["run", case.to_str().unwrap(), "--out", "a/../b"],
    );
    assert_eq!(code, Some(0), "{text}");
    assert!(dir.path().join("b/history.csv").is_file(), "{text}");
}

/// Ctrl-C (SIGINT) stops the run after its current increment: exit 130, the converged steps'
/// files complete, `summary.json` and `run.json` with status "interrupted", and the message
/// says how to resume; `--resume` then finishes with the files of an uninterrupted run.
#[cfg(unix)]
#[test]
fn ctrl_c_stops_cleanly_and_the_run_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let steps = 4000;
    let case = block_case(dir.path(), steps);
    let out = dir.path().join("out");
    let child = spawn_run(&case, &out);
    let start = Instant::now();
    while !out.join("restart.bin").is_file() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no step converged"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    signal(&child, "-INT");
    let output = child.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{text}");
    // The command to continue with, its paths quoted for the shell (as pasted).
    let command = format!(
        "`asperity run '{}' --out '{}' --resume`",
        case.display(),
        out.display()
    );
    assert!(text.contains(&command), "{text}");
    let summary: serde_json::Value =
        serde_json::from_str(&read(&out.join("summary.json"))).unwrap();
    assert_eq!(summary["status"], "interrupted", "{summary}");
    let info: serde_json::Value = serde_json::from_str(&read(&out.join("run.json"))).unwrap();
    assert_eq!(info["status"], "interrupted");
    let done = summary["steps"].as_array().unwrap().len();
    assert!(done < steps as usize, "the run was not interrupted");
    let history = read(&out.join("history.csv"));
    assert_eq!(
        history.lines().count(),
        done + 2,
        "header, step 0 and each converged step"
    );

    let (code, text) = run(dir.path(), &case, &out, &["--resume"]);
    assert_eq!(code, Some(0), "{text}");
    let reference = dir.path().join("reference");
    let (code, text) = run(dir.path(), &case, &reference, &[]);
    assert_eq!(code, Some(0), "{text}");
    for name in ["history.csv", "results.pvd", "bodies_4000.vtu"] {
        assert_eq!(
            std::fs::read(out.join(name)).unwrap(),
            std::fs::read(reference.join(name)).unwrap(),
            "{name} differs from the uninterrupted run's"
        );
    }
}

/// SIGTERM while gmsh meshes (a script that loops for minutes): gmsh is stopped and the run
/// ends at once with exit code 130 and an interrupted summary, instead of waiting for gmsh.
#[cfg(unix)]
#[test]
fn sigterm_while_gmsh_meshes_stops_gmsh_and_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let geo = dir.path().join("slow.geo");
    std::fs::write(
        &geo,
        "x = 0;\nFor i In {1:2000000000}\n  x = x + 1;\nEndFor\n\
         Point(1) = {0, 0, 0};\nPoint(2) = {1, 0, 0};\nPoint(3) = {1, 1, 0};\n\
         Line(1) = {1, 2};\nLine(2) = {2, 3};\nLine(3) = {3, 1};\n\
         Curve Loop(1) = {1, 2, 3};\nPlane Surface(1) = {1};\n\
         Physical Surface(\"plate\") = {1};\nPhysical Curve(\"bottom\") = {1};\n",
    )
    .unwrap();
    let case = held_block()
        .mesh_geo(&geo, 1.0)
        .steps(1)
        .write(&dir.path().join("case.toml"));
    let out = dir.path().join("out");
    let child = spawn_run(&case, &out);
    std::thread::sleep(Duration::from_millis(1500));
    let signalled = Instant::now();
    signal(&child, "-TERM");
    let output = child.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&output.stderr);
    // gmsh is polled every few milliseconds; the bound leaves room for a loaded machine.
    assert!(
        signalled.elapsed() < Duration::from_secs(10),
        "took {:?} after SIGTERM",
        signalled.elapsed()
    );
    assert_eq!(output.status.code(), Some(130), "{text}");
    let summary: serde_json::Value =
        serde_json::from_str(&read(&out.join("summary.json"))).unwrap();
    assert_eq!(summary["status"], "interrupted", "{summary}");
}
