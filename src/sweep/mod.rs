//! Parameter sweeps as independent jobs (`asperity sweep plan|run|collect`).
//!
//! A sweep file names a base case, the keys to vary (dotted paths into the case, [`keys`])
//! with a list of values or a range, how to combine them (`grid`: every combination; `zip`:
//! element by element; `latin_hypercube`: `samples` points, one in each of `samples` equal
//! strata of every range, strata paired by seeded random permutations), and the quantities to
//! collect (dotted paths into `summary.json`, e.g. `steps.-1.reactions.top.y`).
//!
//! `plan` writes `runs/NNNN/case.toml` per run (checked by parsing it into a
//! [`Case`] and building its model spec), `manifest.json`, `jobs.txt` (one command per line,
//! for GNU parallel) and `array.sbatch` (a Slurm job array, the task id selecting the run).
//! Every job is `asperity sweep run STUDY --task K`, which skips a run whose `summary.json`
//! exists, so a sweep is restartable by any of the three means; a run that fails leaves a
//! `summary.json` with its error. `collect` gathers the runs into `sweep.csv` and plots.
//!
//! Before anything is written, `plan` counts the runs (at most [`MAX_RUNS`]) and checks what
//! reaches file names and job files: quantity names follow the rules of contact pair names,
//! `[slurm]` values Slurm's syntax, and paths hold no control character ([`Slurm`]).

mod jobs;
pub mod keys;
mod run;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use rand::Rng;
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use toml::Value;

use crate::config::{Case, check_name};
use crate::model::ModelSpec;
use crate::output::atomic::write_atomically;
use crate::{Error, Result};

pub use jobs::Slurm;
pub use run::{Collected, collect, run_local, run_task};

/// The most runs a sweep may have. A plan is counted before anything is allocated or
/// written, so that a typing slip (a range of 10⁸ points, 10¹² samples, a 100⁶ grid) is an
/// error naming the key instead of an exhausted memory; 100 000 runs is already more folders
/// than a file browser or a cluster's array limit handles comfortably (Slurm's default
/// `MaxArraySize` is 1001 tasks).
pub const MAX_RUNS: usize = 100_000;

/// A sweep file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// The base case (relative to the sweep file).
    pub base: PathBuf,
    #[serde(default)]
    pub method: Method,
    /// Latin hypercube: number of runs.
    pub samples: Option<usize>,
    /// Latin hypercube: seed of the permutations and of the points within strata.
    #[serde(default)]
    pub seed: u64,
    #[serde(rename = "vary")]
    pub keys: Vec<Vary>,
    /// Quantities to collect: name = dotted path into `summary.json`.
    #[serde(default)]
    pub quantities: BTreeMap<String, String>,
    #[serde(default)]
    pub slurm: Slurm,
}

/// How the keys' values are combined into runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    #[default]
    Grid,
    Zip,
    LatinHypercube,
}

/// One varied key.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Vary {
    pub key: String,
    /// Explicit values.
    pub values: Option<Vec<Value>>,
    /// `{ from, to, count }`: `count` values from `from` to `to` (geometric with `log = true`).
    pub range: Option<Range>,
}

#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    pub from: f64,
    pub to: f64,
    /// Values of a grid or zip (a Latin hypercube takes `samples`).
    pub count: Option<usize>,
    #[serde(default)]
    pub log: bool,
}

/// `manifest.json` of a study folder.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Manifest {
    pub sweep: PathBuf,
    pub base: PathBuf,
    pub method: Method,
    pub keys: Vec<String>,
    pub quantities: BTreeMap<String, String>,
    pub runs: Vec<RunEntry>,
}

/// One run of the manifest.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunEntry {
    pub id: usize,
    /// Folder relative to the study (`runs/0003`), holding `case.toml` and the results.
    pub dir: PathBuf,
    /// The value of each key, in the order of `keys`.
    pub values: Vec<Value>,
}

impl Manifest {
    /// Reads `study/manifest.json`.
    pub fn read(study: &Path) -> Result<Self> {
        let path = study.join(MANIFEST);
        let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
        let manifest: Self = serde_json::from_str(&text).map_err(|e| Error::Case {
            path: path.clone(),
            message: format!("not a sweep manifest: {e}"),
        })?;
        check_quantity_names(&path, &manifest.quantities)?;
        Ok(manifest)
    }
}

/// Quantity names become file names (`<name>.png` in the study) and `sweep.csv` columns, so
/// they follow the rules of contact pair names ([`check_name`]: no `/`, `..`, comma, line
/// break, ...); the error names `quantities.<name>` of `file` (the sweep file or a manifest).
fn check_quantity_names(file: &Path, quantities: &BTreeMap<String, String>) -> Result<()> {
    for name in quantities.keys() {
        check_name(name).map_err(|reason| {
            invalid(
                file,
                format!("quantities.{name:?}"),
                "",
                format!("the name of a quantity becomes the file name {name}.png: {reason}"),
            )
        })?;
    }
    Ok(())
}

/// An error of sweep file `path` at `key`.
fn invalid(path: &Path, key: String, value: impl ToString, reason: impl Into<String>) -> Error {
    Error::InvalidParameter {
        path: path.to_path_buf(),
        key,
        value: value.to_string(),
        reason: reason.into(),
    }
}

/// Plans sweep file `path` into the folder `study`; `exe` is the asperity executable the job
/// files call.
pub fn plan(path: &Path, study: &Path, exe: &Path) -> Result<Manifest> {
    let text = crate::config::read_input(path)?;
    let sweep: SweepFile = toml::from_str(&text).map_err(|e| Error::toml(path, &e))?;
    if sweep.keys.is_empty() {
        return Err(invalid(path, "vary".into(), "[]", "no [[vary]] key"));
    }
    // Everything that reaches a file name, a case file's header or a job file is checked
    // before anything is written.
    let sweep_path = jobs::job_path(path, "sweep file", path)?;
    let exe = jobs::job_path(path, "asperity executable", exe)?;
    let absolute_study = std::path::absolute(study).map_err(|e| Error::io(study, e))?;
    jobs::study_path(path, &absolute_study)?;
    sweep.slurm.check(path)?;
    check_quantity_names(path, &sweep.quantities)?;
    for (i, vary) in sweep.keys.iter().enumerate() {
        if vary.key.chars().any(char::is_control) {
            return Err(invalid(
                path,
                format!("vary[{i}].key"),
                format!("{:?}", vary.key),
                "a key holds no control character (line break, tab, ...)",
            ));
        }
        // The later value would silently win, and sweep.csv would have two such columns.
        if let Some(j) = sweep.keys[..i].iter().position(|k| k.key == vary.key) {
            return Err(invalid(
                path,
                format!("vary[{i}].key"),
                &vary.key,
                format!("varied already by vary[{j}]: vary a key once (its values in one list)"),
            ));
        }
    }
    let base = path.parent().unwrap_or(Path::new("")).join(&sweep.base);
    let base = base.canonicalize().map_err(|e| Error::io(&base, e))?;
    let base_text = crate::config::read_input(&base)?;
    let mut tree: Value = toml::from_str(&base_text).map_err(|e| Error::toml(&base, &e))?;
    absolute_mesh_paths(&mut tree, base.parent().unwrap_or(Path::new("/")));
    let points = points(&sweep, path)?;
    // Every run's case is made and checked before the study folder is made or touched.
    let mut cases = Vec::with_capacity(points.len());
    for (id, values) in points.into_iter().enumerate() {
        let dir = PathBuf::from(format!("runs/{id:04}"));
        let mut t = tree.clone();
        for (i, (vary, v)) in sweep.keys.iter().zip(&values).enumerate() {
            keys::set(&mut t, &vary.key, v.clone())
                .map_err(|reason| invalid(path, format!("vary[{i}].key"), &vary.key, reason))?;
        }
        let text = toml::to_string(&t).map_err(|e| Error::External(e.to_string()))?;
        check_run(&text, &absolute_study.join(&dir).join("case.toml")).map_err(|e| {
            invalid(
                path,
                format!("vary ({})", describe(&sweep.keys, &values)),
                "",
                format!("run {id} is not a valid case: {e}"),
            )
        })?;
        cases.push((RunEntry { id, dir, values }, text));
    }
    check_study_folder(study, cases.iter().map(|(run, _)| run.dir.as_path()))?;
    std::fs::create_dir_all(study).map_err(|e| Error::io(study, e))?;
    let study = study.canonicalize().map_err(|e| Error::io(study, e))?;
    // Once more after symbolic links are resolved: they name the folder in the job files.
    let study_text = jobs::study_path(path, &study)?;
    let mut runs = Vec::with_capacity(cases.len());
    for (run, text) in cases {
        let header = comment(&format!(
            "run {} of sweep {sweep_path}: {}",
            run.id,
            describe(&sweep.keys, &run.values)
        ));
        write_atomically(&study.join(&run.dir).join("case.toml"), |w| {
            w.write_all(format!("{header}{text}").as_bytes())
        })?;
        runs.push(run);
    }
    let manifest = Manifest {
        sweep: path.to_path_buf(),
        base,
        method: sweep.method,
        keys: sweep.keys.iter().map(|k| k.key.clone()).collect(),
        quantities: sweep.quantities.clone(),
        runs,
    };
    let json =
        serde_json::to_string_pretty(&manifest).map_err(|e| Error::External(e.to_string()))?;
    write_atomically(&study.join(MANIFEST), |w| w.write_all(json.as_bytes()))?;
    jobs::write_jobs(study_text, manifest.runs.len(), exe, &sweep.slurm)?;
    Ok(manifest)
}

/// The names a plan writes in its study folder (`runs` holds the runs' folders).
const PLAN_FILES: [&str; 4] = [MANIFEST, jobs::JOBS, jobs::ARRAY, "runs"];

/// A study folder's plan: its runs and their values ([`Manifest`]).
pub(super) const MANIFEST: &str = "manifest.json";

/// Refuses ([`Error::OutputForeign`], before anything is written) a study folder whose
/// files of a plan's names are not a sweep's: a `manifest.json` that is no sweep manifest,
/// or `jobs.txt`, `array.sbatch` or `runs` without one. A folder holding a sweep's plan may
/// be planned again: its runs whose case changes are run again ([`run::run_task`]).
fn check_study_folder<'a>(study: &Path, runs: impl Iterator<Item = &'a Path>) -> Result<()> {
    if !study.exists() {
        return Ok(());
    }
    // A linked `runs` or run folder would take the runs' cases (and results) elsewhere.
    for dir in std::iter::once(Path::new("runs")).chain(runs) {
        crate::run::folder::refuse_linked_folder(
            study,
            &study.join(dir),
            "it is a symbolic link, and a plan never writes through one: remove it or choose \
             another study folder",
        )?;
    }
    let foreign = |file: &str, reason: &str| Error::OutputForeign {
        dir: study.to_path_buf(),
        file: study.join(file),
        reason: reason.to_string(),
    };
    if !study.is_dir() {
        return Err(foreign("", "the study folder is a file"));
    }
    if study.join(MANIFEST).exists() {
        return Manifest::read(study).map(drop).map_err(|_| {
            foreign(
                MANIFEST,
                "not the manifest of a sweep: move it away or choose another study folder",
            )
        });
    }
    match PLAN_FILES[1..]
        .iter()
        .find(|name| study.join(name).exists())
    {
        Some(name) => Err(foreign(
            name,
            "a sweep plan writes a file of this name, but the folder holds no sweep's \
             manifest.json: move it away or choose another study folder",
        )),
        None => Ok(()),
    }
}

/// `key = value, ...` of one run.
fn describe(keys: &[Vary], values: &[Value]) -> String {
    keys.iter()
        .zip(values)
        .map(|(k, v)| format!("{} = {v}", k.key))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `text` as TOML comment lines: a value TOML writes over several lines (a string with a line
/// break) stays inside the comment, and control characters, which a TOML comment may not
/// hold, are replaced.
fn comment(text: &str) -> String {
    text.lines()
        .map(|line| format!("# {}\n", line.replace(|c: char| c.is_control(), "\u{fffd}")))
        .collect()
}

/// A run's case must parse and give a model spec (the law and material parameters valid).
fn check_run(text: &str, path: &Path) -> Result<()> {
    let case = Case::from_toml(text, path)?;
    ModelSpec::new(&case).map(|_| ())
}

/// Makes `mesh.file` and `mesh.geo` absolute (relative to the base case's folder `dir`), so
/// the run's case can live in another folder; drops `output.dir` (runs write to their own).
fn absolute_mesh_paths(tree: &mut Value, dir: &Path) {
    if let Some(Value::Table(mesh)) = tree.get_mut("mesh") {
        for key in ["file", "geo"] {
            if let Some(Value::String(p)) = mesh.get_mut(key) {
                *p = dir.join(&*p).display().to_string();
            }
        }
    }
    if let Some(Value::Table(output)) = tree.get_mut("output") {
        output.remove("dir");
    }
}

/// The values of every run (one vector per run, one value per key).
fn points(sweep: &SweepFile, path: &Path) -> Result<Vec<Vec<Value>>> {
    let mut columns = Vec::with_capacity(sweep.keys.len());
    for (i, k) in sweep.keys.iter().enumerate() {
        let key = |field: &str| format!("vary[{i}].{field}");
        let values = match (&k.values, k.range, sweep.method) {
            (Some(v), None, Method::Grid | Method::Zip) if !v.is_empty() => v.clone(),
            (None, Some(r), m) => {
                if !(r.from.is_finite() && r.to.is_finite())
                    || (r.log && (r.from <= 0.0 || r.to <= 0.0))
                {
                    return Err(invalid(
                        path,
                        key("range"),
                        format!("{} .. {}", r.from, r.to),
                        "must be finite (and positive with log = true)",
                    ));
                }
                if m == Method::LatinHypercube {
                    Vec::new() // sampled below
                } else {
                    let n = r.count.filter(|n| *n >= 1).ok_or_else(|| {
                        invalid(
                            path,
                            key("range.count"),
                            "",
                            "a grid or zip range needs `count` ≥ 1",
                        )
                    })?;
                    check_run_count(path, key("range.count"), Some(n), n)?;
                    (0..n)
                        .map(|j| {
                            Value::Float(r.at(if n == 1 {
                                0.0
                            } else {
                                j as f64 / (n - 1) as f64
                            }))
                        })
                        .collect()
                }
            }
            (_, _, Method::LatinHypercube) => {
                return Err(invalid(
                    path,
                    key("range"),
                    "",
                    "a Latin hypercube needs `range = { from, to }` for every key",
                ));
            }
            _ => {
                return Err(invalid(
                    path,
                    key("values"),
                    "",
                    "give a non-empty `values` list or a `range`, not both",
                ));
            }
        };
        columns.push(values);
    }
    Ok(match sweep.method {
        Method::Grid => {
            let sizes: Vec<String> = columns.iter().map(|c| c.len().to_string()).collect();
            let runs = columns
                .iter()
                .try_fold(1usize, |runs, c| runs.checked_mul(c.len()));
            check_run_count(path, "vary".into(), runs, sizes.join(" × "))?;
            grid(&columns)
        }
        Method::Zip => {
            let n = columns[0].len();
            if let Some(i) = columns.iter().position(|c| c.len() != n) {
                return Err(invalid(
                    path,
                    format!("vary[{i}]"),
                    columns[i].len(),
                    format!("zip needs every key to have the same number of values ({n})"),
                ));
            }
            check_run_count(path, "vary".into(), Some(n), n)?;
            (0..n)
                .map(|j| columns.iter().map(|c| c[j].clone()).collect())
                .collect()
        }
        Method::LatinHypercube => {
            let n = sweep.samples.filter(|n| *n >= 1).ok_or_else(|| {
                invalid(
                    path,
                    "samples".into(),
                    "",
                    "a Latin hypercube needs `samples` ≥ 1",
                )
            })?;
            check_run_count(path, "samples".into(), Some(n), n)?;
            let ranges: Vec<Range> = sweep
                .keys
                .iter()
                .map(|k| k.range.expect("checked"))
                .collect();
            latin_hypercube(&ranges, n, sweep.seed)
        }
    })
}

/// Refuses a plan of `runs` runs (`None`: more than `usize::MAX`) above [`MAX_RUNS`]; `key`
/// and `value` of sweep file `path` are what gives that many.
fn check_run_count(
    path: &Path,
    key: String,
    runs: Option<usize>,
    value: impl ToString,
) -> Result<()> {
    match runs {
        Some(n) if n <= MAX_RUNS => Ok(()),
        _ => Err(invalid(
            path,
            key,
            value,
            format!(
                "the plan would have {} runs, more than the {MAX_RUNS} runs a sweep may have \
                 (asperity::sweep::MAX_RUNS); use fewer values or split the sweep",
                runs.map_or(format!("more than {}", usize::MAX), |n| n.to_string())
            ),
        )),
    }
}

/// Every combination of the values of `columns` (the first key varying slowest).
fn grid(columns: &[Vec<Value>]) -> Vec<Vec<Value>> {
    columns.iter().fold(vec![Vec::new()], |acc, col| {
        acc.iter()
            .flat_map(|prefix| {
                col.iter().map(move |v| {
                    let mut p = prefix.clone();
                    p.push(v.clone());
                    p
                })
            })
            .collect()
    })
}

impl Range {
    /// The value at fraction `s` ∈ [0, 1] of the range.
    fn at(&self, s: f64) -> f64 {
        if self.log {
            self.from * (self.to / self.from).powf(s)
        } else {
            self.from + s * (self.to - self.from)
        }
    }
}

/// `n` points of a Latin hypercube over `ranges`: for each key, one uniform point in each of
/// the n strata [j/n, (j+1)/n), the strata shuffled independently per key (ChaCha8, seeded:
/// the same seed gives the same points on every platform).
pub fn latin_hypercube(ranges: &[Range], n: usize, seed: u64) -> Vec<Vec<Value>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let columns: Vec<Vec<f64>> = ranges
        .iter()
        .map(|r| {
            let mut strata: Vec<usize> = (0..n).collect();
            strata.shuffle(&mut rng);
            strata
                .into_iter()
                .map(|j| r.at((j as f64 + rng.random::<f64>()) / n as f64))
                .collect()
        })
        .collect();
    (0..n)
        .map(|j| columns.iter().map(|c| Value::Float(c[j])).collect())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latin_hypercube_has_one_point_per_stratum_and_is_seeded() {
        let r = [
            Range {
                from: 0.0,
                to: 1.0,
                count: None,
                log: false,
            },
            Range {
                from: 1.0,
                to: 100.0,
                count: None,
                log: true,
            },
        ];
        let a = latin_hypercube(&r, 10, 7);
        assert_eq!(a, latin_hypercube(&r, 10, 7));
        assert_ne!(a, latin_hypercube(&r, 10, 8));
        for (k, range) in r.iter().enumerate() {
            let mut strata: Vec<usize> = a
                .iter()
                .map(|p| {
                    let v = p[k].as_float().unwrap();
                    let s = if range.log {
                        (v / range.from).ln() / (range.to / range.from).ln()
                    } else {
                        v
                    };
                    (s * 10.0).floor() as usize
                })
                .collect();
            strata.sort();
            assert_eq!(strata, (0..10).collect::<Vec<_>>());
        }
    }
}
