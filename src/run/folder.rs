//! The output folder of a run: the one place that names, creates, lists and removes the files
//! of a run.
//!
//! The folder is the user's folder too: it may hold their own files (measurements, notes, the
//! case itself). A run therefore keeps a manifest, `run_files.txt`, of every file it writes,
//! each name added *before* the file is first created, so that even a run killed at any
//! moment never leaves a file of its own unlisted. `--force` and `--resume` remove only files
//! that the manifest lists (and never an input of the run), and a run refuses to start where
//! it would overwrite a file that no manifest lists. Files are never written through a
//! symbolic link: the atomic writer replaces a link rather than following it, and claiming a
//! name that is a link is an error.

use std::collections::HashSet;
use std::fs::File;
use std::io::Write;
use std::path::{Component, Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use crate::output::atomic::write_text;
use crate::post::fretting::FrettingTable;
use crate::{Error, Result};

/// The manifest's file name.
pub const MANIFEST: &str = "run_files.txt";

/// The manifest's first line: it tells a manifest of asperity's from a user's file of the same
/// name.
const MANIFEST_HEADER: &str = "# asperity run files: written by asperity into this folder; --force and --resume remove only these";

/// A file of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunFile<'a> {
    /// `run.json`: what made the results.
    Info,
    /// `summary.json`.
    Summary,
    /// `results.pvd`, the series of the VTU files.
    Series,
    /// `history.csv`.
    History,
    /// `mesh.msh`, when the case meshes a `.geo` script.
    Mesh,
    /// `restart.bin`, the restart record.
    Restart,
    /// `restart_energy.bin`, the energy balance at every cycle end so far, which the restart
    /// record continues (for `summary.json`).
    RestartEnergy,
    /// `log.txt`.
    Log,
    /// `bodies_NNNN.vtu` of an output frame of a model of one body.
    Bodies(usize),
    /// `interface_NNNN.vtu` of an output frame of a model of one contact pair.
    Interface(usize),
    /// `frame_NNNN.vtm`, the multiblock file of an output frame that `results.pvd` lists:
    /// its bodies and contact pairs by name.
    Frame(usize),
    /// `bodies_NNNN_K.vtu`: body K (1-based) of an output frame, in a model of several bodies.
    Body(usize, usize),
    /// `interface_NNNN_K.vtu`: contact pair K (1-based) of an output frame, in a model of
    /// several pairs.
    Pair(usize, usize),
    /// `contact_<pair>_NNNN.csv` of an output frame.
    Contact(&'a str, usize),
    /// The fretting tables (`hysteresis_<pair>.csv`, `point_loops_<pair>.csv`, `cycles.csv`,
    /// `wear_<pair>.csv`).
    Fretting(FrettingTable<'a>),
}

/// The files a run writes once, with their names.
const SINGLE_FILES: [(RunFile<'static>, &str); 9] = [
    (RunFile::Info, "run.json"),
    (RunFile::Summary, "summary.json"),
    (RunFile::Series, "results.pvd"),
    (RunFile::History, "history.csv"),
    (RunFile::Mesh, "mesh.msh"),
    (RunFile::Restart, "restart.bin"),
    (RunFile::RestartEnergy, "restart_energy.bin"),
    (RunFile::Log, "log.txt"),
    (RunFile::Fretting(FrettingTable::Cycles), "cycles.csv"),
];

impl RunFile<'_> {
    /// The file's name in the output folder.
    pub fn name(&self) -> String {
        match *self {
            RunFile::Bodies(step) => format!("bodies_{step:04}.vtu"),
            RunFile::Interface(step) => format!("interface_{step:04}.vtu"),
            RunFile::Frame(step) => format!("frame_{step:04}.vtm"),
            RunFile::Body(step, k) => format!("bodies_{step:04}_{k}.vtu"),
            RunFile::Pair(step, k) => format!("interface_{step:04}_{k}.vtu"),
            RunFile::Contact(pair, step) => format!("contact_{pair}_{step:04}.csv"),
            RunFile::Fretting(FrettingTable::Hysteresis(pair)) => format!("hysteresis_{pair}.csv"),
            RunFile::Fretting(FrettingTable::PointLoops(pair)) => {
                format!("point_loops_{pair}.csv")
            }
            RunFile::Fretting(FrettingTable::Wear(pair)) => format!("wear_{pair}.csv"),
            single => SINGLE_FILES
                .iter()
                .find(|(file, _)| *file == single)
                .map(|(_, name)| (*name).to_string())
                .expect("every single file has a name"),
        }
    }
}

/// The output frame of a step file's name (`bodies_NNNN.vtu`, `interface_NNNN.vtu`, their
/// parts `bodies_NNNN_K.vtu`, `interface_NNNN_K.vtu`, `frame_NNNN.vtm`,
/// `contact_<pair>_NNNN.csv` for a pair that `is_pair` accepts; at least four digits).
fn step_of_file(name: &str, is_pair: impl Fn(&str) -> bool) -> Option<usize> {
    let is_number = |d: &str| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit());
    let digits = ["bodies_", "interface_"]
        .iter()
        .find_map(|p| {
            let rest = name.strip_prefix(p)?.strip_suffix(".vtu")?;
            match rest.split_once('_') {
                Some((digits, part)) => is_number(part).then_some(digits),
                None => Some(rest),
            }
        })
        .or_else(|| name.strip_prefix("frame_")?.strip_suffix(".vtm"))
        .or_else(|| {
            let rest = name.strip_prefix("contact_")?.strip_suffix(".csv")?;
            let (pair, digits) = rest.rsplit_once('_')?;
            is_pair(pair).then_some(digits)
        })?;
    if digits.len() >= 4 && is_number(digits) {
        digits.parse().ok()
    } else {
        None
    }
}

/// Whether a run with contact pairs `pairs` may write a file called `name` (`mesh.msh` too,
/// whether or not the run meshes a script).
fn is_run_file(name: &str, pairs: &[String]) -> bool {
    is_run_file_of(name, |pair| pairs.iter().any(|p| p == pair))
}

/// Whether `name` is a name a run writes, its per-pair files for a pair that `is_pair`
/// accepts.
fn is_run_file_of(name: &str, is_pair: impl Fn(&str) -> bool + Copy) -> bool {
    let per_pair = [
        FrettingTable::Hysteresis(""),
        FrettingTable::PointLoops(""),
        FrettingTable::Wear(""),
    ]
    .map(|t| RunFile::Fretting(t).name());
    name == MANIFEST
        || SINGLE_FILES.iter().any(|(_, n)| *n == name)
        || step_of_file(name, is_pair).is_some()
        || per_pair.iter().any(|empty| {
            let (prefix, suffix) = empty.split_once('.').expect("a table's name has a suffix");
            name.strip_prefix(prefix)
                .and_then(|rest| rest.strip_suffix(&format!(".{suffix}")))
                .is_some_and(|pair| !pair.is_empty() && is_pair(pair))
        })
}

/// Whether `name` is a name some run writes (any contact pair): what `--force` and
/// `--resume` may remove of what a manifest lists. A manifest edited to list another name
/// (a user's own file) does not make a run delete it.
fn is_any_run_file(name: &str) -> bool {
    is_run_file_of(name, |_| true)
}

/// The file whose temporary file `name` is (the atomic writer names them `.NAME.XXXXXX.tmp`).
fn temporary_of(name: &str) -> Option<&str> {
    let inner = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    Some(inner.rsplit_once('.')?.0)
}

/// How a run treats an output folder that holds the files of an earlier run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OutputMode {
    /// Refuse ([`Error::OutputExists`]): results are never overwritten by accident.
    #[default]
    Fresh,
    /// Remove the earlier run's files (those its manifest lists) first.
    Force,
    /// Continue the earlier run from its restart record; start over (removing its files) when
    /// it has none (it was stopped before its first increment converged).
    Resume,
}

impl OutputMode {
    /// The mode of the command line's `--force` and `--resume` (exclusive).
    pub fn from_flags(force: bool, resume: bool) -> Self {
        match (force, resume) {
            (true, _) => OutputMode::Force,
            (false, true) => OutputMode::Resume,
            (false, false) => OutputMode::Fresh,
        }
    }
}

/// What a run needs to know to take over a folder: the files it may write (its contact
/// pairs' names) and the files it must never remove or overwrite (its inputs).
#[derive(Clone, Debug, Default)]
pub struct FolderPlan {
    /// The names of the case's contact pairs (they are part of file names).
    pub pairs: Vec<String>,
    /// The case file, its mesh file or `.geo` script.
    pub inputs: Vec<PathBuf>,
    /// Whether the run meshes a `.geo` script into `mesh.msh`.
    pub meshes: bool,
}

impl FolderPlan {
    /// Whether the run may write a file called `name`.
    fn writes(&self, name: &str) -> bool {
        is_run_file(name, &self.pairs) && (self.meshes || name != RunFile::Mesh.name())
    }
}

/// The manifest: the names a run listed as its own, and the open file new names are
/// appended to.
#[derive(Debug)]
struct Manifest {
    listed: HashSet<String>,
    file: File,
}

/// The output folder of one run.
#[derive(Debug)]
pub struct OutputFolder {
    dir: PathBuf,
    manifest: Mutex<Manifest>,
    /// Whether the folder holds a restart record of an earlier run that this run continues.
    resumable: bool,
}

impl OutputFolder {
    /// Takes over `dir` for a run in `mode`: refuses a folder with an earlier run's files
    /// (`Fresh`), removes them (`Force`, and `Resume` without a restart record), or removes
    /// only the temporary files a killed run left (`Resume`). Only files that the folder's
    /// manifest lists are removed, never an input of the run; a file the run would write that
    /// no manifest lists, or an input under the name of a file the run writes, is an error
    /// ([`Error::OutputForeign`]), before anything is created.
    pub fn open(dir: &Path, mode: OutputMode, plan: &FolderPlan) -> Result<Self> {
        let dir = &normalized(dir);
        if dir.exists() && !dir.is_dir() {
            return Err(foreign(dir, dir, "the output folder is a file"));
        }
        if !dir.exists() && is_link(dir) {
            return Err(foreign(
                dir,
                dir,
                "the output folder is a symbolic link to nothing (a folder that does not \
                 exist): remove the link or make its folder",
            ));
        }
        let listed = read_manifest(dir)?;
        let entries = entries(dir)?;
        let inputs: Vec<PathBuf> = plan.inputs.iter().filter_map(|p| canonical(p)).collect();
        let is_input = |path: &Path| canonical(path).is_some_and(|c| inputs.contains(&c));
        for name in &entries {
            let path = dir.join(name);
            if plan.writes(name) && is_input(&path) {
                return Err(foreign(
                    dir,
                    &path,
                    "this is an input of the run (its case file, mesh or .geo script), and the \
                     run writes a file of this name, which would replace it: rename the input \
                     or choose another output folder",
                ));
            }
            // Only `--force` removes a link in its place (a link is never written through).
            if plan.writes(name) && mode != OutputMode::Force && is_link(&path) {
                return Err(foreign(
                    dir,
                    &path,
                    "it is a symbolic link, and a run never writes through one: remove it, \
                     or run with --force, which removes the link (not what it points to)",
                ));
            }
            // The manifest itself was checked by `read_manifest`.
            let unlisted = name != MANIFEST && !listed.contains(name);
            if plan.writes(name) && unlisted {
                return Err(foreign(
                    dir,
                    &path,
                    "the run would write a file of this name, but no manifest of asperity's \
                     (run_files.txt) lists it as written by asperity: move it away or choose \
                     another output folder",
                ));
            }
        }
        // The run's own files, less its inputs (a case may read the mesh an earlier run wrote).
        let ours: Vec<&String> = entries
            .iter()
            .filter(|n| listed.contains(*n) && n.as_str() != MANIFEST && !is_input(&dir.join(n)))
            .filter(|n| {
                let run_file = is_any_run_file(n);
                if !run_file {
                    tracing::warn!(
                        "{}: {MANIFEST} lists '{n}', which is no name a run writes: left in place",
                        dir.display()
                    );
                }
                run_file
            })
            .collect();
        let resumable = listed.contains(RunFile::Restart.name().as_str())
            && dir.join(RunFile::Restart.name()).is_file();
        let remove = |names: &[&String]| -> Result<()> {
            for name in names {
                let path = dir.join(name);
                std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
            }
            Ok(())
        };
        // Temporary files only: a folder of that name is no writer's (left in place).
        let temporaries: Vec<&String> = entries
            .iter()
            .filter(|n| temporary_of(n).is_some_and(|t| listed.contains(t) && is_any_run_file(t)))
            .filter(|n| dir.join(n).symlink_metadata().is_ok_and(|m| !m.is_dir()))
            .collect();
        // A log alone holds no results (a sweep's pool opens it before the run starts).
        let log = RunFile::Log.name();
        let results: Vec<&&String> = ours.iter().filter(|n| ***n != log).collect();
        let fresh_manifest = match mode {
            OutputMode::Fresh if !results.is_empty() => {
                return Err(Error::OutputExists {
                    dir: dir.to_path_buf(),
                    files: results.len(),
                    example: results[0].to_string(),
                });
            }
            OutputMode::Fresh => true,
            OutputMode::Resume if resumable => {
                remove(&temporaries)?;
                for name in &ours {
                    unshare(&dir.join(name))?;
                }
                false
            }
            OutputMode::Force | OutputMode::Resume => {
                if mode == OutputMode::Resume && !results.is_empty() {
                    tracing::warn!(
                        "{}: no restart record (the run stopped before its first increment \
                         converged); starting from the beginning",
                        dir.join(RunFile::Restart.name()).display()
                    );
                }
                remove(&ours)?;
                remove(&temporaries)?;
                true
            }
        };
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let manifest = open_manifest(dir, listed, !fresh_manifest)?;
        Ok(Self {
            dir: dir.to_path_buf(),
            manifest: Mutex::new(manifest),
            resumable: resumable && mode == OutputMode::Resume,
        })
    }

    /// A folder of a run that is never resumed nor refused (a convergence study's level, a
    /// fit's temporary run): created if missing, its manifest continued.
    pub fn scratch(dir: &Path) -> Result<Self> {
        let dir = &normalized(dir);
        let listed = read_manifest(dir)?;
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let manifest = open_manifest(dir, listed, true)?;
        Ok(Self {
            dir: dir.to_path_buf(),
            manifest: Mutex::new(manifest),
            resumable: false,
        })
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Whether the run continues an earlier one from its restart record.
    pub fn resumable(&self) -> bool {
        self.resumable
    }

    /// The path of `file`, listed in the manifest as the run's own before it is first written.
    /// A symbolic link of that name is an error: a run never writes through a link.
    pub fn path(&self, file: RunFile) -> Result<PathBuf> {
        let name = file.name();
        let path = self.dir.join(&name);
        let mut manifest = self.lock();
        if manifest.listed.contains(&name) {
            return Ok(path);
        }
        if is_link(&path) {
            return Err(foreign(
                &self.dir,
                &path,
                "it is a symbolic link; a run never writes through one",
            ));
        }
        let manifest_path = self.dir.join(MANIFEST);
        writeln!(manifest.file, "{name}").map_err(|e| Error::io(&manifest_path, e))?;
        manifest.listed.insert(name);
        Ok(path)
    }

    /// Removes the step files of output frames from `first` on (written after the restart
    /// record a run resumes from); every listed name is the run's own, whatever its pair.
    pub fn remove_steps_from(&self, first: usize) -> Result<()> {
        let manifest = self.lock();
        for name in &manifest.listed {
            if step_of_file(name, |_| true).is_some_and(|s| s >= first) {
                let path = self.dir.join(name);
                match std::fs::remove_file(&path) {
                    Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                        return Err(Error::io(&path, e));
                    }
                    _ => {}
                }
            }
        }
        Ok(())
    }

    fn lock(&self) -> MutexGuard<'_, Manifest> {
        // The manifest only ever holds whole lines: a panic elsewhere leaves it usable.
        self.manifest.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// `dir` with its `.` components removed and each `name/..` pair collapsed, as a shell's `cd`
/// reads them: `cases/../results` is `results`, `../results` stays. The folder a user names
/// is then the folder written to, however it was spelled (`--out a/../b`, an `[output] dir`
/// relative to a case file in another folder), and no written path holds a `..` after a
/// folder name, which the last check before writing refuses
/// ([`crate::output::paths::check_output_path`]).
fn normalized(dir: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for component in dir.components() {
        match component {
            Component::CurDir => {}
            Component::ParentDir
                if matches!(out.components().next_back(), Some(Component::Normal(_))) =>
            {
                out.pop();
            }
            // `/..` is `/`.
            Component::ParentDir if out.components().next_back() == Some(Component::RootDir) => {}
            other => out.push(other),
        }
    }
    if out.as_os_str().is_empty() {
        out.push(".");
    }
    out
}

/// The error of a file in `dir` that the run must not touch.
fn foreign(dir: &Path, file: &Path, reason: &str) -> Error {
    Error::OutputForeign {
        dir: dir.to_path_buf(),
        file: file.to_path_buf(),
        reason: reason.to_string(),
    }
}

/// Whether `path` is a symbolic link (not followed).
pub fn is_link(path: &Path) -> bool {
    path.symlink_metadata()
        .is_ok_and(|m| m.file_type().is_symlink())
}

/// Refuses a folder `dir` inside `parent` (a study's level or run folder) that is a symbolic
/// link: what would be written into it would land where the link points. `what` names it
/// and says what to do ("a level's folder ...").
pub fn refuse_linked_folder(parent: &Path, dir: &Path, what: &str) -> Result<()> {
    if is_link(dir) {
        return Err(Error::OutputForeign {
            dir: parent.to_path_buf(),
            file: dir.to_path_buf(),
            reason: what.to_string(),
        });
    }
    Ok(())
}

/// Gives the file `path` a copy of its own when another name shares it (a hard link, such as
/// a snapshot made with `cp -al` or `rsync --link-dest`): a resumed run cuts back and appends
/// to its growing files in place, which must not change the snapshot.
fn unshare(path: &Path) -> Result<()> {
    use std::os::unix::fs::MetadataExt;
    let shared = path
        .symlink_metadata()
        .is_ok_and(|m| m.is_file() && m.nlink() > 1);
    if !shared {
        return Ok(());
    }
    let mut source = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    crate::output::atomic::write_atomically(path, |w| std::io::copy(&mut source, w).map(drop))
}

/// `path` with symbolic links resolved, if it exists.
fn canonical(path: &Path) -> Option<PathBuf> {
    std::fs::canonicalize(path).ok()
}

/// The names of the entries of `dir` (none if it does not exist).
fn entries(dir: &Path) -> Result<Vec<String>> {
    let read = match std::fs::read_dir(dir) {
        Ok(read) => read,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(Error::io(dir, e)),
    };
    let mut names = Vec::new();
    for entry in read {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        if let Some(name) = entry.file_name().to_str() {
            names.push(name.to_string());
        }
    }
    names.sort();
    Ok(names)
}

/// The names the manifest of `dir` lists (none without a manifest). A file of the manifest's
/// name that is not asperity's manifest (a link, another header) is an error.
fn read_manifest(dir: &Path) -> Result<HashSet<String>> {
    let path = dir.join(MANIFEST);
    match path.symlink_metadata() {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(HashSet::new()),
        Err(e) => return Err(Error::io(&path, e)),
        Ok(m) if !m.is_file() => {
            return Err(foreign(dir, &path, "it is not a regular file"));
        }
        Ok(_) => {}
    }
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let mut lines = text.lines();
    if lines.next() != Some(MANIFEST_HEADER) {
        return Err(foreign(
            dir,
            &path,
            "it has the name of asperity's run manifest but is not one",
        ));
    }
    // Only plain names of the folder's own files: a path (`../x`, `/x`, `a/b`) is no file a
    // run wrote here and is dropped, never acted on.
    let (names, paths): (Vec<&str>, Vec<&str>) =
        lines.filter(|l| !l.is_empty()).partition(|line| {
            let mut parts = Path::new(line).components();
            matches!(
                (parts.next(), parts.next()),
                (Some(std::path::Component::Normal(_)), None)
            )
        });
    if let Some(first) = paths.first() {
        tracing::warn!(
            "{}: {} entries are no plain file names (such as '{first}'): ignored",
            path.display(),
            paths.len()
        );
    }
    Ok(names.into_iter().map(str::to_string).collect())
}

/// Opens the manifest of `dir`, which lists `listed`, for appending: `continued`, or as a new
/// one.
fn open_manifest(dir: &Path, listed: HashSet<String>, continued: bool) -> Result<Manifest> {
    let path = dir.join(MANIFEST);
    let listed = if continued && path.is_file() {
        listed
    } else {
        // A new manifest keeps the listed files that are still there (a log, an input).
        let mut kept: Vec<String> = listed
            .into_iter()
            .filter(|name| dir.join(name).is_file())
            .collect();
        kept.sort();
        let lines: String = kept.iter().map(|name| format!("{name}\n")).collect();
        write_text(&path, &format!("{MANIFEST_HEADER}\n{lines}"))?;
        kept.into_iter().collect()
    };
    let file = File::options()
        .append(true)
        .open(&path)
        .map_err(|e| Error::io(&path, e))?;
    Ok(Manifest { listed, file })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pairs() -> Vec<String> {
        vec!["fit".into(), "a_b".into()]
    }

    #[test]
    fn any_run_file_takes_every_pair_but_no_other_name() {
        for name in [
            "contact_other_0001.csv",
            "wear_x.csv",
            "log.txt",
            "frame_0001.vtm",
        ] {
            assert!(is_any_run_file(name), "{name}");
        }
        for name in [
            "mynotes.txt",
            "hysteresis_.csv",
            "wear_x.txt",
            "bodies_1.vtu",
        ] {
            assert!(!is_any_run_file(name), "{name}");
        }
    }

    #[test]
    fn run_files_are_told_from_the_users_files() {
        let pairs = pairs();
        for name in [
            "bodies_0001.vtu",
            "interface_12345.vtu",
            "bodies_0001_2.vtu",
            "interface_0003_1.vtu",
            "frame_0004.vtm",
            "contact_fit_0007.csv",
            "contact_a_b_0007.csv",
            "hysteresis_fit.csv",
            "wear_a_b.csv",
            "cycles.csv",
            "log.txt",
            "run_files.txt",
        ] {
            assert!(is_run_file(name, &pairs), "{name}");
        }
        for name in [
            "wear_measurements.csv",
            "contact_other_0001.csv",
            "bodies_01.vtu",
            "bodies_0001.vtu.bak",
            "bodies_0001_x.vtu",
            "frame_01.vtm",
            "notes.txt",
        ] {
            assert!(!is_run_file(name, &pairs), "{name}");
        }
        assert_eq!(
            step_of_file("contact_a_b_0012.csv", |p| pairs.iter().any(|q| q == p)),
            Some(12)
        );
        assert_eq!(step_of_file("bodies_0012_3.vtu", |_| false), Some(12));
        assert_eq!(step_of_file("frame_0012.vtm", |_| false), Some(12));
        assert_eq!(
            temporary_of(".bodies_0001.vtu.a1B2c3.tmp"),
            Some("bodies_0001.vtu")
        );
    }

    #[test]
    fn folders_are_normalised_as_a_shell_reads_them() {
        for (given, expected) in [
            ("a/../b", "b"),
            ("cases/../results", "results"),
            ("../results", "../results"),
            ("./out/./x/", "out/x"),
            ("a/b/../../..", ".."),
            ("a/..", "."),
            ("/tmp/a/../b", "/tmp/b"),
            ("/..", "/"),
        ] {
            assert_eq!(normalized(Path::new(given)), Path::new(expected), "{given}");
        }
    }

    #[test]
    fn names_round_trip_through_the_classification() {
        let pairs = pairs();
        let files = [
            RunFile::Info,
            RunFile::Summary,
            RunFile::Series,
            RunFile::History,
            RunFile::Mesh,
            RunFile::Restart,
            RunFile::RestartEnergy,
            RunFile::Log,
            RunFile::Bodies(3),
            RunFile::Interface(3),
            RunFile::Contact("fit", 3),
            RunFile::Fretting(FrettingTable::Hysteresis("fit")),
            RunFile::Fretting(FrettingTable::PointLoops("a_b")),
            RunFile::Fretting(FrettingTable::Cycles),
            RunFile::Fretting(FrettingTable::Wear("fit")),
        ];
        for file in files {
            assert!(is_run_file(&file.name(), &pairs), "{file:?}");
        }
    }
}
