//! The restart record `restart.bin`: everything a run needs to continue from its last
//! converged increment as if it had never stopped (`asperity run CASE --resume`).
//!
//! It holds the stepping loop's state ([`LoopState`]: step, pseudo-time, next increment
//! size, counters, force floor, stiffness history), the run's counters, the displacements,
//! every integration point's committed state ([`PointState`], [`InterfaceState`] with its
//! fretting history; the continuum's left out when they follow from the displacements,
//! [`ContinuumStates`]), the energy ledger, and the output's own state: the length and checksum
//! of each file the run grows by appending ([`OutputState`]; `history.csv`, from which the
//! step records of `summary.json` are read back, the fretting tables and the energy marks), so
//! that a resumed run continues those files exactly, and the record stays the size of the
//! model however many frames the run has.
//!
//! The state types derive serde's traits and the record is their `postcard` encoding, which
//! stores every `f64` as its eight IEEE-754 bytes, never as text, so a resumed run starts from
//! bit-identical values. A fixed magic (with the format version) opens the record, followed by
//! the program version and the case file's text: a record made by another case or program is
//! refused before the rest is read, since continuing it would mix two models. It is written
//! atomically after the files of its increment and the rows appended at it
//! ([`super::writer::RecordWriter`]), so the record on disk always belongs to a state whose
//! files are complete.

use std::borrow::Cow;
use std::io;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::append::FileMark;
use crate::contact::InterfaceState;
use crate::material::PointState;
use crate::model::Model;
use crate::solver::energy::EnergyLedger;
use crate::solver::newton::LastIncrement;
use crate::solver::shakedown::BodyCycles;
use crate::solver::state::{
    InternalVariables, LoopState, Progress, Resume, RunStatistics, Solution,
};
use crate::{Error, Result};

/// First bytes of a record; the trailing digit is the format version (3: `postcard`; 4: the
/// growing files' lengths and checksums instead of their rows; 5: the continuum's internal
/// variables, the backstresses of kinematic hardening, and the energy ledger's thermal work;
/// 6: six-component stresses and strains and three-component interface states, for twist;
/// 7: the continuum's states left out when they follow from the displacements; 8: the
/// predictor's last converged increment).
const MAGIC: &[u8; 16] = b"asperity-rst-v8\n";
/// Bytes of [`MAGIC`] before the format version.
const MAGIC_NAME: usize = 14;

/// What a record holds besides the solver's state: the length and checksum of each file
/// the run grows by appending (`history.csv`, the fretting tables), by file name, at the
/// record's increment. A resumed run continues each file from there
/// ([`super::append::check`], [`super::append::truncate`]); the rows themselves stay in the
/// files, so that a record is the size of the model however many frames the run has.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OutputState {
    pub files: Vec<(String, FileMark)>,
}

/// First bytes of the file of energy marks (`restart_energy.bin`): the energy balance at
/// every cycle end so far, which `summary.json` lists and a resumed run reads back, kept out
/// of the record because it grows with the cycles.
pub const ENERGY_MARKS: &[u8] = b"asperity-energy-marks-v1\n";

/// The bytes of an energy mark's numbers (`crate::output::summary::EnergyMark::to_row`) in
/// the file of energy marks `path`, as `postcard` stores them (bit for bit).
pub fn encode_energy_mark(path: &Path, row: &[f64]) -> Result<Vec<u8>> {
    postcard::to_allocvec(row)
        .map_err(|e| Error::io(path, io::Error::new(io::ErrorKind::InvalidData, e)))
}

/// The rows of the energy marks' file `path` ([`ENERGY_MARKS`], then
/// [`encode_energy_mark`]s); a file of another content is an [`Error::Restart`].
pub fn read_energy_marks(path: &Path) -> Result<Vec<Vec<f64>>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let refuse = |reason: &str| Error::Restart {
        path: path.to_path_buf(),
        reason: reason.into(),
    };
    let mut rest = bytes
        .strip_prefix(ENERGY_MARKS)
        .ok_or_else(|| refuse("not an asperity file of energy marks"))?;
    let mut rows = Vec::new();
    while !rest.is_empty() {
        let (row, after) = postcard::take_from_bytes::<Vec<f64>>(rest)
            .map_err(|_| refuse("its energy marks are damaged"))?;
        rows.push(row);
        rest = after;
    }
    Ok(rows)
}

/// A record read back: the run to continue and the output's state.
#[derive(Clone, Debug)]
pub struct Record {
    pub resume: Resume,
    pub output: OutputState,
}

/// Whether a record holds the continuum's integration-point states. At a million unknowns
/// they are 97 % of a record (232 of 238 MB), whose encoding on the solver's thread and
/// writing cost more than a tenth of an elastic run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContinuumStates {
    /// Stored: states with a history (plasticity) or a temperature field.
    Stored,
    /// Left out: they follow from the displacements
    /// ([`Model::states_follow_displacements`]); a resumed run evaluates them again.
    FromDisplacements,
}

impl ContinuumStates {
    /// What the records of `model` hold.
    pub fn of(model: &Model) -> Self {
        if model.states_follow_displacements() {
            Self::FromDisplacements
        } else {
            Self::Stored
        }
    }
}

/// What is checked before the rest of a record is read, whose layout another version may
/// have changed.
#[derive(Serialize, Deserialize)]
struct Header<'a> {
    /// The version of the program that wrote the record.
    version: &'a str,
    /// The text of the case file.
    case: &'a str,
}

/// The rest of a record: borrowed from the run when written (the big tables are not copied
/// for each record), owned when read back. The trial states are not stored: a resumed run
/// starts them from the committed ones.
#[derive(Serialize, Deserialize)]
struct Body<'a> {
    state: Cow<'a, LoopState>,
    stats: Cow<'a, RunStatistics>,
    u: Cow<'a, [f64]>,
    /// Empty when they follow from the displacements ([`ContinuumStates::FromDisplacements`]).
    committed: Cow<'a, [PointState]>,
    interface_committed: Cow<'a, [InterfaceState]>,
    /// The continuum's committed internal variables (empty without kinematic hardening).
    internal_committed: Cow<'a, [f64]>,
    /// The bodies' cycle trackers and shakedown verdicts.
    body_cycles: Cow<'a, BodyCycles>,
    energy: Cow<'a, EnergyLedger>,
    output: Cow<'a, OutputState>,
    /// The predictor's last converged increment (`None` with the predictor off).
    last_increment: Option<StoredIncrement<'a>>,
}

/// A [`LastIncrement`] as a record stores it: its displacements only when they are not the
/// record's (they always are after a converged increment), and the external forces and their
/// change, which only loaded dofs carry, by their nonzero entries. At a million unknowns this
/// keeps the predictor's part of a record at the 8 MB of Δu instead of 32 MB.
#[derive(Serialize, Deserialize)]
struct StoredIncrement<'a> {
    ready: bool,
    /// `None`: the record's displacements.
    u: Option<Cow<'a, [f64]>>,
    du: Cow<'a, [f64]>,
    f_ext: NonZeros,
    df: NonZeros,
}

/// The nonzero entries of a vector of `len` entries, by index (bit for bit).
#[derive(Serialize, Deserialize)]
struct NonZeros {
    len: usize,
    entries: Vec<(usize, f64)>,
}

impl NonZeros {
    fn of(v: &[f64]) -> Self {
        let entries = v.iter().copied().enumerate();
        Self {
            len: v.len(),
            // A signed zero is kept: -0.0 is not the zero the vector is filled with.
            entries: entries.filter(|(_, x)| x.to_bits() != 0).collect(),
        }
    }

    /// The vector, or `None` if an index is outside it (a damaged record).
    fn to_vec(&self) -> Option<Vec<f64>> {
        let mut v = vec![0.0; self.len];
        for &(i, x) in &self.entries {
            *v.get_mut(i)? = x;
        }
        Some(v)
    }
}

impl<'a> StoredIncrement<'a> {
    fn of(last: &'a LastIncrement, u: &[f64]) -> Self {
        let same = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
        Self {
            ready: last.ready,
            u: (last.u.len() != u.len() || !same(&last.u, u)).then(|| Cow::Borrowed(&last.u[..])),
            du: Cow::Borrowed(&last.du),
            f_ext: NonZeros::of(&last.f_ext),
            df: NonZeros::of(&last.df),
        }
    }

    /// The increment read back for a record whose displacements are `u`, or `None` if its
    /// vectors are not all of `u`'s length (a damaged record; checked before anything of
    /// the stated length is allocated).
    fn into_last(self, u: &[f64]) -> Option<LastIncrement> {
        let n = u.len();
        let own_u = self.u.as_ref().is_none_or(|v| v.len() == n);
        if !(own_u && self.du.len() == n && self.f_ext.len == n && self.df.len == n) {
            return None;
        }
        Some(LastIncrement {
            ready: self.ready,
            u: self.u.map_or_else(|| u.to_vec(), Cow::into_owned),
            du: self.du.into_owned(),
            f_ext: self.f_ext.to_vec()?,
            df: self.df.to_vec()?,
        })
    }
}

/// Encodes the record of the converged increment `progress` into `buffer` (cleared first);
/// `case` is the case file's text, which [`read_record`] compares with the case being resumed;
/// `states` says whether the continuum's states are stored.
pub(super) fn encode_record(
    buffer: &mut Vec<u8>,
    case: &str,
    progress: &Progress,
    output: &OutputState,
    states: ContinuumStates,
) -> io::Result<()> {
    let Progress {
        state,
        stats,
        solution,
        last_increment,
    } = progress;
    let header = Header {
        version: env!("CARGO_PKG_VERSION"),
        case,
    };
    let body = Body {
        state: Cow::Borrowed(state),
        stats: Cow::Borrowed(stats),
        u: Cow::Borrowed(&solution.u),
        committed: Cow::Borrowed(match states {
            ContinuumStates::Stored => solution.point_states(),
            ContinuumStates::FromDisplacements => &[],
        }),
        interface_committed: Cow::Borrowed(&solution.interface_committed),
        internal_committed: Cow::Borrowed(&solution.internal.committed),
        body_cycles: Cow::Borrowed(&solution.internal.cycles),
        energy: Cow::Borrowed(&solution.energy),
        output: Cow::Borrowed(output),
        last_increment: last_increment.map(|last| StoredIncrement::of(last, &solution.u)),
    };
    // Encoded into memory first (a record is mostly integration-point states: ~10 MB for a
    // 60k-unknown model), then written with one call; the buffer is reused from record to
    // record, sparing the page faults of fresh memory. The first buffer is made the record's
    // size (a counting pass): grown by doubling, it cost twice its size in fresh pages and
    // copies (14 MB: 35 ms of the elasto-plastic punch's main thread, 20 ms now).
    buffer.clear();
    let record = (header, body);
    if buffer.capacity() == 0 {
        let size = postcard::experimental::serialized_size(&record)
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e))?;
        buffer.reserve(MAGIC.len() + size);
    }
    buffer.extend_from_slice(MAGIC);
    let encoded = postcard::to_extend(&record, std::mem::take(buffer));
    *buffer = encoded.map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e))?;
    Ok(())
}

/// Checks, before a resumed run writes or meshes anything, that the record at `path` is one
/// of this program version for the case whose text is `case`, reading no more than its header
/// can take (the magic, the version, a case text of at most
/// [`crate::config::MAX_INPUT_BYTES`]).
pub fn check_record(path: &Path, case: &str) -> Result<()> {
    use std::io::Read;
    let limit = (MAGIC.len() + 1024) as u64 + crate::config::MAX_INPUT_BYTES;
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut bytes = Vec::new();
    file.take(limit)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    checked_header(path, &bytes, case).map(drop)
}

/// Why postcard could not read a record.
fn damage(e: postcard::Error) -> String {
    match e {
        postcard::Error::DeserializeUnexpectedEnd => "the record is truncated".into(),
        e => format!("the record is damaged ({e})"),
    }
}

/// The bytes after a record's header, once the magic, the program version and the case text
/// are checked against this program and `case`.
fn checked_header<'b>(path: &Path, bytes: &'b [u8], case: &str) -> Result<&'b [u8]> {
    let refuse = |reason: String| Error::Restart {
        path: path.to_path_buf(),
        reason,
    };
    let Some(rest) = bytes.strip_prefix(MAGIC) else {
        return Err(refuse(if MAGIC.starts_with(bytes) {
            "the record is truncated".into()
        } else if bytes.starts_with(&MAGIC[..MAGIC_NAME]) {
            "the record has another format (of another version of asperity); run without \
             --resume"
                .into()
        } else {
            "not an asperity restart record".into()
        }));
    };
    let (header, rest) =
        postcard::take_from_bytes::<Header>(rest).map_err(|e| refuse(damage(e)))?;
    if header.version != env!("CARGO_PKG_VERSION") {
        return Err(refuse(format!(
            "it was written by asperity {}, this is {}",
            header.version,
            env!("CARGO_PKG_VERSION")
        )));
    }
    if header.case != case {
        return Err(refuse(
            "the case file changed since the record was written; run without --resume".into(),
        ));
    }
    Ok(rest)
}

/// Reads the record at `path` for the case whose text is `case` and a model whose solution
/// has the sizes of `template` (from [`Solution::new`]) and whose records hold `states`. A
/// record of another case, program version or model size, or a damaged one, is an
/// [`Error::Restart`]. Continuum states left out are `template`'s, for the run to evaluate.
pub fn read_record(
    path: &Path,
    case: &str,
    template: &Solution,
    states: ContinuumStates,
) -> Result<Record> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let rest = checked_header(path, &bytes, case)?;
    let refuse = |reason: String| Error::Restart {
        path: path.to_path_buf(),
        reason,
    };
    let damaged = |e: postcard::Error| refuse(damage(e));
    let (mut body, rest) = postcard::take_from_bytes::<Body>(rest).map_err(damaged)?;
    if !rest.is_empty() {
        return Err(refuse("the record has trailing bytes".into()));
    }
    let sizes = [
        ("displacements", body.u.len(), template.u.len()),
        (
            "integration points",
            body.committed.len(),
            match states {
                ContinuumStates::Stored => template.point_states().len(),
                ContinuumStates::FromDisplacements => 0,
            },
        ),
        (
            "interface points",
            body.interface_committed.len(),
            template.interface_committed.len(),
        ),
        (
            "internal variables",
            body.internal_committed.len(),
            template.internal.committed.len(),
        ),
    ];
    if let Some((what, found, expected)) = sizes.into_iter().find(|(_, f, e)| f != e) {
        return Err(refuse(format!(
            "the record is damaged ({found} {what}, the model has {expected})"
        )));
    }
    // The predictor's vectors are over all dofs, as the displacements are.
    let last_increment = body.last_increment.take().map(|stored| {
        stored.into_last(&body.u).ok_or_else(|| {
            refuse("the record is damaged (its last increment is not of the model's dofs)".into())
        })
    });
    let last_increment = last_increment.transpose()?;
    Ok(body.into_record(template, last_increment))
}

impl Body<'_> {
    /// The record of a body read back for a model whose solution has the sizes of
    /// `template`, with the predictor's `last_increment`; trial states start from the
    /// committed ones.
    fn into_record(self, template: &Solution, last_increment: Option<LastIncrement>) -> Record {
        let committed = if self.committed.is_empty() {
            template.committed.clone()
        } else {
            self.committed.into_owned()
        };
        // States that follow the displacements are kept once, in the trial array, which the
        // resumed run evaluates at the record's displacements.
        let trial = if template.states_follow_displacements {
            template.trial.clone()
        } else {
            committed.clone()
        };
        let interface_committed = self.interface_committed.into_owned();
        // Every field named, so that a new one cannot be forgotten here.
        let solution = Solution {
            u: self.u.into_owned(),
            trial,
            committed,
            states_follow_displacements: template.states_follow_displacements,
            interface_trial: interface_committed.clone(),
            interface_committed,
            internal: InternalVariables {
                layout: template.internal.layout.clone(),
                trial: self.internal_committed.to_vec(),
                committed: self.internal_committed.into_owned(),
                cycles: self.body_cycles.into_owned(),
            },
            energy: self.energy.into_owned(),
            // Output of the last cycle end only, not a state to continue from.
            jump_use: template.jump_use.clone(),
            // Recomputed from the model at the record's time when the run continues.
            thermal: Default::default(),
        };
        Record {
            resume: Resume {
                state: self.state.into_owned(),
                stats: self.stats.into_owned(),
                solution,
                last_increment,
            },
            output: self.output.into_owned(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::state::LoopState;

    fn solution() -> Solution {
        Solution {
            u: vec![1.0 / 3.0, -0.0],
            committed: vec![PointState::default(); 2],
            trial: vec![PointState::default(); 2],
            states_follow_displacements: false,
            interface_committed: vec![InterfaceState::default()],
            interface_trial: vec![InterfaceState::default()],
            internal: Default::default(),
            energy: EnergyLedger::default(),
            jump_use: vec![],
            thermal: Default::default(),
        }
    }

    fn record(case: &str) -> Vec<u8> {
        record_with(case, None)
    }

    fn record_with(case: &str, last_increment: Option<&LastIncrement>) -> Vec<u8> {
        let (stats, solution) = (RunStatistics::default(), solution());
        let progress = Progress {
            state: LoopState::start(),
            stats: &stats,
            solution: &solution,
            last_increment,
        };
        let mut buffer = Vec::new();
        let output = OutputState::default();
        encode_record(
            &mut buffer,
            case,
            &progress,
            &output,
            ContinuumStates::Stored,
        )
        .unwrap();
        buffer
    }

    /// The reason `bytes` are refused as the record of case "case".
    fn refusal(bytes: &[u8]) -> String {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("restart.bin");
        std::fs::write(&path, bytes).unwrap();
        match read_record(&path, "case", &solution(), ContinuumStates::Stored) {
            Err(Error::Restart { path: p, reason }) if p == path => reason,
            other => panic!("not refused: {other:?}"),
        }
    }

    /// The predictor's last increment comes back bit for bit (a resumed run extrapolates its
    /// first increment as the uninterrupted run does), whether its displacements are the
    /// record's (left out) or not; vectors of another size are refused.
    #[test]
    fn the_predictors_last_increment_comes_back_bit_for_bit() {
        let last = LastIncrement {
            ready: true,
            u: vec![0.1 + 0.2, -0.0],
            f_ext: vec![-0.0, 3.0],
            du: vec![f64::MIN_POSITIVE, 1.0 / 7.0],
            df: vec![0.0, -2.5],
        };
        let bits = |l: &LastIncrement| {
            [&l.u, &l.f_ext, &l.du, &l.df]
                .map(|v| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
        };
        let at_record = LastIncrement {
            u: solution().u,
            ..last.clone()
        };
        for last in [last.clone(), at_record] {
            let back = read_record_bytes(&record_with("case", Some(&last)));
            assert_eq!(
                back.resume.last_increment.as_ref().map(bits),
                Some(bits(&last))
            );
        }
        let without = read_record_bytes(&record("case"));
        assert!(without.resume.last_increment.is_none());

        let short = LastIncrement {
            du: vec![1.0],
            ..last.clone()
        };
        let long_loads = LastIncrement {
            f_ext: vec![1.0; 3],
            ..last
        };
        for wrong in [short, long_loads] {
            let reason = refusal(&record_with("case", Some(&wrong)));
            assert!(
                reason.contains("last increment is not of the model's dofs"),
                "{reason}"
            );
        }
    }

    fn read_record_bytes(bytes: &[u8]) -> Record {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("restart.bin");
        std::fs::write(&path, bytes).unwrap();
        read_record(&path, "case", &solution(), ContinuumStates::Stored).unwrap()
    }

    #[test]
    fn a_foreign_older_truncated_or_extended_record_or_one_of_another_program_is_refused() {
        let good = record("case");
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("restart.bin");
        std::fs::write(&path, &good).unwrap();
        let back = read_record(&path, "case", &solution(), ContinuumStates::Stored)
            .unwrap()
            .resume
            .solution;
        let bits = |s: &Solution| s.u.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back), bits(&solution()));

        assert_eq!(refusal(b"x,y\n1,2\n"), "not an asperity restart record");
        let mut older = good.clone();
        for version in [b'2', b'4'] {
            older[14] = version;
            assert!(refusal(&older).contains("another format"));
        }
        for cut in [0, 10, MAGIC.len(), good.len() / 2, good.len() - 1] {
            assert_eq!(
                refusal(&good[..cut]),
                "the record is truncated",
                "cut at {cut}"
            );
        }
        assert!(refusal(&[&good[..], &[0]].concat()).contains("trailing bytes"));
        assert!(refusal(&record("other case")).contains("case file changed"));

        // The header of another program version, followed by this version's body.
        let ours = postcard::to_allocvec(&Header {
            version: env!("CARGO_PKG_VERSION"),
            case: "case",
        })
        .unwrap();
        let theirs = postcard::to_allocvec(&Header {
            version: "0.0.1",
            case: "case",
        })
        .unwrap();
        let body = &good[MAGIC.len() + ours.len()..];
        let reason = refusal(&[&MAGIC[..], &theirs, body].concat());
        assert!(reason.contains("written by asperity 0.0.1"), "{reason}");
    }
}
