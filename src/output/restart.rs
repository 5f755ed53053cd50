//! The restart record `restart.bin`: everything a run needs to continue from its last
//! converged increment as if it had never stopped (`asperity run CASE --resume`).
//!
//! It holds the stepping loop's state ([`LoopState`]: step, pseudo-time, next increment
//! size, counters, force floor, stiffness history; under arc-length control its
//! [`ArcState`]: load factor, largest load factor, arc and its bounds, the last increment's
//! Δu over the free dofs), the run's counters, the displacements,
//! every integration point's committed state (strain, stress, plastic strain, equivalent
//! plastic strain, yield flag; at interface points relative displacement, contact stress,
//! plastic and accumulated slip, largest closure, friction, stiffness, contact status), and
//! the output's own state (the rows of `history.csv`, the entries of `results.pvd`, the step
//! records of `summary.json`), so that a resumed run rewrites those files exactly.
//!
//! Numbers are stored as their IEEE-754 bits (little-endian), never as text, so a resumed
//! run starts from bit-identical values. The record also stores the case file's text and the
//! program version: a record made by another case or program is refused, since continuing
//! it would mix two models. It is written atomically after the files of its increment, so
//! the record on disk always belongs to a state whose files are complete.

use std::io::{self, Read};
use std::path::{Path, PathBuf};
use std::sync::mpsc;

use super::Grid;
use super::atomic::write_bytes;
use super::csv::{Cell, CsvTable, write_csv};
use super::pvd::{PvdEntry, write_pvd};
use super::vtu::write_vtu_with;
use crate::contact::{ContactStatus, InterfaceState, PointHistory};
use crate::material::{PointState, Voigt};
use crate::solver::energy::{Energy, EnergyLedger};
use crate::solver::newton::ForceAverage;
use crate::solver::state::{
    ArcState, LoopState, Progress, Resume, RunStatistics, Solution, StiffnessHistory,
};
use crate::{Error, Result};

/// File name of the record in the output folder.
pub const RESTART_FILE: &str = "restart.bin";

/// First bytes of a record; the trailing digit is the format version.
const MAGIC: &[u8; 16] = b"asperity-rst-v3\n";

/// What a record holds besides the solver's state: the output's tables (rows of numbers,
/// e.g. `history.csv`) and the PVD series.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OutputState {
    pub tables: Vec<Vec<Vec<f64>>>,
    pub series: Vec<PvdEntry>,
}

/// The output's state as a record is written from it, borrowed from the output's own tables
/// (cloning every row for every record made the records of a long run cost quadratic time in
/// allocations).
#[derive(Clone, Debug, Default)]
pub struct OutputView<'a> {
    pub tables: Vec<&'a [Vec<f64>]>,
    pub series: &'a [PvdEntry],
}

impl OutputState {
    /// The state as a record is written from it.
    pub fn view(&self) -> OutputView<'_> {
        OutputView {
            tables: self.tables.iter().map(Vec::as_slice).collect(),
            series: &self.series,
        }
    }
}

/// A record read back: the run to continue and the output's state.
#[derive(Clone, Debug)]
pub struct Record {
    pub resume: Resume,
    pub output: OutputState,
}

/// A file handed to the [`RecordWriter`], encoded and written on its thread.
#[derive(Debug)]
pub enum Content {
    Vtu(Grid),
    Csv(CsvTable),
    /// A table with text or empty cells.
    Table(CsvTable<Cell>),
    Pvd(Vec<PvdEntry>),
    /// A file's text, already formatted (a [`super::csv::GrowingCsv`]).
    Text(Vec<u8>),
    /// A restart record, already encoded (by [`RecordWriter::queue_record`]).
    Record(Vec<u8>),
}

impl Content {
    /// Writes the file, a VTU file through `buffer` (the writer thread's, reused).
    fn write(&self, path: &Path, buffer: &mut Vec<u8>) -> Result<()> {
        match self {
            Content::Vtu(grid) => write_vtu_with(path, grid, buffer),
            Content::Csv(table) => write_csv(path, table),
            Content::Table(table) => write_csv(path, table),
            Content::Pvd(entries) => write_pvd(path, entries),
            Content::Record(bytes) | Content::Text(bytes) => write_bytes(path, bytes),
        }
    }
}

/// Writes a run's committed files in the background: the files of a converged step (VTU,
/// CSV), the restart record of a converged increment (`case` is the case file's text, which
/// [`read_record`] compares with the case being resumed) and the indexes, in the order they
/// were queued, on one thread, one commit at a time.
///
/// The caller queues a commit's files ([`RecordWriter::queue`],
/// [`RecordWriter::queue_record`]), then [`RecordWriter::commit`]s them: when the writer
/// thread is idle, that hands them to it, so that encoding and writing a step's files (~10 MB
/// of VTU data and ~10 MB of record for a 60k-unknown model) overlaps the next increment
/// instead of adding to the run's time. When it is still writing an earlier commit, the new
/// files wait, merged with those of the commits that came after that one: a file queued
/// again (the record, `history.csv`, the growing tables, the indexes) keeps only its latest
/// content, so a thread that falls behind (thousands of short increments, each rewriting
/// tables that grow with the run) skips the versions that a later commit replaces instead of
/// making the run wait for each. The merged files keep their order (each file where its
/// latest commit put it, after the files of earlier commits), so the record and the indexes
/// still come after the step files they refer to. Within a commit the files are written in
/// order and the first error stops it, so a step's record and index entries are never on
/// disk without its files; that error (an [`Error::Io`] naming the file) is returned by a
/// later `commit` or by [`RecordWriter::finish`], which writes what waits and stops the run.
///
/// A run killed while commits are in flight or waiting has only complete files (each is
/// written atomically), the index lists only complete steps, and a resumed run repeats the
/// increments after the record on disk bit for bit, rewriting their files and index rows
/// identically.
/// Files that may wait for the writer thread before a commit waits for it: a few steps'
/// files (each step writes its VTU files and a table per contact pair) besides the record and
/// the tables that every commit rewrites.
const MAX_WAITING_FILES: usize = 32;

#[derive(Debug, Default)]
pub struct RecordWriter {
    /// The files of the next commit, in order.
    queued: Vec<(PathBuf, Content)>,
    /// Committed files waiting for the writer thread to finish the commit in flight, merged
    /// (the latest content of each path, in order).
    waiting: Vec<(PathBuf, Content)>,
    /// The writer thread, started at the first commit.
    worker: Option<Worker>,
    /// Whether a commit is being written (its outcome not yet received).
    in_flight: bool,
    /// A record buffer to encode into: reusing it spares the page faults of ~10 MB of
    /// fresh memory per record.
    spare: Vec<u8>,
}

/// The writer thread: commits go to it through one channel, their outcomes (the record's
/// buffer for reuse, or the error) come back through the other. One thread for the whole
/// run: spawning one per commit cost up to a millisecond on a busy machine.
#[derive(Debug)]
struct Worker {
    commits: mpsc::Sender<Vec<(PathBuf, Content)>>,
    outcomes: mpsc::Receiver<Result<Vec<u8>>>,
    thread: std::thread::JoinHandle<()>,
}

impl Worker {
    fn start() -> Self {
        let (commits, inbox) = mpsc::channel::<Vec<(PathBuf, Content)>>();
        let (outbox, outcomes) = mpsc::channel();
        let thread = std::thread::spawn(move || {
            let mut buffer = Vec::new();
            for files in inbox {
                if outbox.send(write_in_order(files, &mut buffer)).is_err() {
                    break;
                }
            }
        });
        Self {
            commits,
            outcomes,
            thread,
        }
    }

    /// Ends the thread once it has written what it was sent; passes on its panic.
    fn stop(self) {
        drop(self.commits);
        if let Err(panic) = self.thread.join() {
            std::panic::resume_unwind(panic);
        }
    }
}

impl RecordWriter {
    /// Adds `path` with `content` to the next commit.
    pub fn queue(&mut self, path: PathBuf, content: Content) {
        self.queued.push((path, content));
    }

    /// Encodes the record of the converged increment `progress` and adds it to the next
    /// commit.
    pub fn queue_record(
        &mut self,
        path: &Path,
        case: &str,
        progress: &Progress,
        output: &OutputView,
    ) -> Result<()> {
        let mut buffer = std::mem::take(&mut self.spare);
        encode_record(&mut buffer, case, progress, output).map_err(|e| Error::io(path, e))?;
        self.queue(path.to_path_buf(), Content::Record(buffer));
        Ok(())
    }

    /// Commits the queued files: hands them to the writer thread if it is idle, else merges
    /// them into the files waiting for it. Returns the error of a finished commit.
    pub fn commit(&mut self) -> Result<()> {
        let files = std::mem::take(&mut self.queued);
        self.merge(files);
        if self.in_flight && !self.poll()? {
            if self.waiting.len() <= MAX_WAITING_FILES {
                return Ok(());
            }
            // Files that no later commit replaces (each step's VTU and contact tables) pile
            // up while the thread is behind: wait for it rather than hold them all in memory.
            self.wait()?;
        }
        self.send_waiting();
        Ok(())
    }

    /// Adds `files` to the waiting ones: a path already waiting is replaced (its superseded
    /// record buffer kept for reuse) and takes its new place in the order.
    fn merge(&mut self, files: Vec<(PathBuf, Content)>) {
        for (path, content) in files {
            let earlier = self.waiting.iter().position(|(p, _)| *p == path);
            if let Some((_, Content::Record(bytes))) = earlier.map(|i| self.waiting.remove(i)) {
                self.keep_spare(bytes);
            }
            self.waiting.push((path, content));
        }
    }

    /// Hands the waiting files, if any, to the writer thread (started at the first commit).
    fn send_waiting(&mut self) {
        let files = std::mem::take(&mut self.waiting);
        if files.is_empty() {
            return;
        }
        let worker = self.worker.get_or_insert_with(Worker::start);
        if worker.commits.send(files).is_err() {
            // The thread is gone, which only a panic does.
            if let Some(worker) = self.worker.take() {
                worker.stop();
            }
        }
        self.in_flight = true;
    }

    /// A record buffer for the next encoding, if larger than the one kept.
    fn keep_spare(&mut self, mut bytes: Vec<u8>) {
        if bytes.capacity() > self.spare.capacity() {
            bytes.clear();
            self.spare = bytes;
        }
    }

    /// Queues and commits the record of a converged increment.
    pub fn write(
        &mut self,
        path: &Path,
        case: &str,
        state: &LoopState,
        stats: &RunStatistics,
        solution: &Solution,
        output: &OutputView,
    ) -> Result<()> {
        let progress = Progress {
            state: state.clone(),
            stats,
            solution,
        };
        self.queue_record(path, case, &progress, output)?;
        self.commit()
    }

    /// Writes everything committed: waits for the commit in flight, then for the files
    /// waiting behind it; reports the first error.
    pub fn finish(&mut self) -> Result<()> {
        let start = std::time::Instant::now();
        self.wait()?;
        self.send_waiting();
        self.wait()?;
        tracing::debug!(
            seconds = start.elapsed().as_secs_f64(),
            "waited for the background writer"
        );
        Ok(())
    }

    /// Whether the commit in flight is done (then its outcome is taken: its error returned,
    /// its record buffer kept), without waiting.
    fn poll(&mut self) -> Result<bool> {
        let Some(worker) = self.worker.as_ref().filter(|_| self.in_flight) else {
            return Ok(true);
        };
        match worker.outcomes.try_recv() {
            Ok(outcome) => self.take_outcome(Some(outcome)).map(|()| true),
            Err(mpsc::TryRecvError::Empty) => Ok(false),
            Err(mpsc::TryRecvError::Disconnected) => self.take_outcome(None).map(|()| true),
        }
    }

    /// Waits for the commit in flight, if any, and takes its outcome.
    fn wait(&mut self) -> Result<()> {
        let Some(worker) = self.worker.as_ref().filter(|_| self.in_flight) else {
            return Ok(());
        };
        let outcome = worker.outcomes.recv().ok();
        self.take_outcome(outcome)
    }

    /// The outcome of the commit in flight (None: the thread panicked). After an error the
    /// waiting files are dropped: their record and indexes may refer to the files that failed.
    fn take_outcome(&mut self, outcome: Option<Result<Vec<u8>>>) -> Result<()> {
        self.in_flight = false;
        match outcome {
            Some(Err(e)) => {
                self.waiting.clear();
                return Err(e);
            }
            Some(Ok(spare)) => self.keep_spare(spare),
            None => {
                if let Some(worker) = self.worker.take() {
                    worker.stop();
                }
            }
        }
        Ok(())
    }
}

/// Writes `files` in order, stopping at the first error; returns the record's buffer.
fn write_in_order(files: Vec<(PathBuf, Content)>, buffer: &mut Vec<u8>) -> Result<Vec<u8>> {
    let mut spare = Vec::new();
    for (path, content) in files {
        content.write(&path, buffer)?;
        if let Content::Record(mut bytes) = content {
            bytes.clear();
            spare = bytes;
        }
    }
    Ok(spare)
}

impl Drop for RecordWriter {
    /// A run that stops with an error still leaves its last commit complete (files queued
    /// but not committed are dropped: they belong to a step whose commit never came).
    fn drop(&mut self) {
        if !std::thread::panicking()
            && let Err(e) = self.finish()
        {
            tracing::warn!("{e}");
        }
        // Not `stop`: a panic of the thread must not become a second one while this thread
        // unwinds.
        if let Some(Worker {
            commits, thread, ..
        }) = self.worker.take()
        {
            drop(commits);
            let _ = thread.join();
        }
    }
}

/// Encodes a record into `buffer` (cleared first).
fn encode_record(
    buffer: &mut Vec<u8>,
    case: &str,
    &Progress {
        ref state,
        stats,
        solution,
    }: &Progress,
    output: &OutputView,
) -> io::Result<()> {
    // Encoded into memory first (a record is mostly integration-point states: ~10 MB for a
    // 60k-unknown model), then written with one call: encoding value by value through the
    // file writer cost more than the write itself.
    buffer.clear();
    buffer.reserve(record_size_estimate(solution));
    let mut e = Encoder(buffer);
    e.bytes(MAGIC)?;
    e.text(env!("CARGO_PKG_VERSION"))?;
    e.text(case)?;
    encode_state(&mut e, state)?;
    encode_stats(&mut e, stats)?;
    e.floats(&solution.u)?;
    e.len(solution.committed.len())?;
    for s in &solution.committed {
        encode_point(&mut e, s)?;
    }
    e.len(solution.interface_committed.len())?;
    for s in &solution.interface_committed {
        encode_interface(&mut e, s)?;
    }
    encode_energy(&mut e, &solution.energy)?;
    e.len(output.tables.len())?;
    for table in &output.tables {
        e.len(table.len())?;
        for row in table.iter() {
            e.floats(row)?;
        }
    }
    e.len(output.series.len())?;
    for entry in output.series {
        e.f64(entry.time)?;
        e.u64(u64::from(entry.part))?;
        e.text(&entry.name)?;
        e.text(&entry.file.to_string_lossy())?;
    }
    Ok(())
}

/// Bytes of a record's solution part, to size its buffer once (states as at most 64
/// values each).
fn record_size_estimate(solution: &Solution) -> usize {
    8 * (solution.u.len() + 64 * (solution.committed.len() + solution.interface_committed.len()))
}

/// Reads the record at `path` for the case whose text is `case` and a model whose solution
/// has the sizes of `template` (from [`Solution::new`]). A record of another case, program
/// version or model size, or a damaged one, is an [`Error::Restart`].
pub fn read_record(path: &Path, case: &str, template: &Solution) -> Result<Record> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let refuse = |reason: String| Error::Restart {
        path: path.to_path_buf(),
        reason,
    };
    let mut d = Decoder(&bytes[..]);
    let damaged = |e: io::Error| refuse(format!("the record is damaged ({e})"));
    let mut magic = [0u8; 16];
    d.0.read_exact(&mut magic).map_err(damaged)?;
    if &magic != MAGIC {
        return Err(refuse(
            "not an asperity restart record of this format".into(),
        ));
    }
    let version = d.text().map_err(damaged)?;
    if version != env!("CARGO_PKG_VERSION") {
        return Err(refuse(format!(
            "it was written by asperity {version}, this is {}",
            env!("CARGO_PKG_VERSION")
        )));
    }
    if d.text().map_err(damaged)? != case {
        return Err(refuse(
            "the case file changed since the record was written; run without --resume".into(),
        ));
    }
    let record = decode_rest(&mut d, template).map_err(damaged)?;
    if !d.0.is_empty() {
        return Err(refuse("the record has trailing bytes".into()));
    }
    Ok(record)
}

/// Everything after the header.
fn decode_rest(d: &mut Decoder, template: &Solution) -> io::Result<Record> {
    let state = decode_state(d)?;
    let stats = decode_stats(d)?;
    let mut solution = template.clone();
    let u = d.floats()?;
    expect_len("displacements", u.len(), solution.u.len())?;
    solution.u = u;
    expect_len("integration points", d.len()?, solution.committed.len())?;
    for s in &mut solution.committed {
        *s = decode_point(d)?;
    }
    let n = d.len()?;
    expect_len("interface points", n, solution.interface_committed.len())?;
    for s in &mut solution.interface_committed {
        *s = decode_interface(d)?;
    }
    solution.energy = decode_energy(d)?;
    solution.trial.clone_from(&solution.committed);
    solution
        .interface_trial
        .clone_from(&solution.interface_committed);
    let mut output = OutputState::default();
    for _ in 0..d.len()? {
        let rows = d.len()?;
        output
            .tables
            .push((0..rows).map(|_| d.floats()).collect::<io::Result<_>>()?);
    }
    for _ in 0..d.len()? {
        output.series.push(PvdEntry {
            time: d.f64()?,
            part: u32::try_from(d.u64()?).map_err(|_| corrupt("part number"))?,
            name: d.text()?,
            file: d.text()?.into(),
        });
    }
    Ok(Record {
        resume: Resume {
            state,
            stats,
            solution,
        },
        output,
    })
}

fn expect_len(what: &str, found: usize, expected: usize) -> io::Result<()> {
    if found == expected {
        Ok(())
    } else {
        Err(corrupt(&format!(
            "{found} {what}, the model has {expected}"
        )))
    }
}

fn corrupt(what: &str) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, what.to_string())
}

fn encode_state(e: &mut Encoder, s: &LoopState) -> io::Result<()> {
    // Destructured so that a new field cannot be forgotten here.
    let LoopState {
        step,
        time,
        size,
        cutbacks,
        increments,
        iterations,
        force_floor,
        stiffness: StiffnessHistory { first, last },
        force_average: ForceAverage { sum, count },
        ref arc,
    } = *s;
    for n in [step, cutbacks, increments, iterations, count] {
        e.len(n)?;
    }
    for v in [time, size, force_floor, sum] {
        e.f64(v)?;
    }
    e.option(first)?;
    e.option(last)?;
    e.bytes(&[u8::from(arc.is_some())])?;
    let Some(ArcState {
        load_factor,
        largest_load_factor,
        radius,
        min_radius,
        max_radius,
        previous_increment,
    }) = arc
    else {
        return Ok(());
    };
    e.floats(&[*load_factor, *largest_load_factor, *min_radius, *max_radius])?;
    e.option(*radius)?;
    e.floats(previous_increment)
}

fn decode_state(d: &mut Decoder) -> io::Result<LoopState> {
    let [step, cutbacks, increments, iterations, count] =
        [d.len()?, d.len()?, d.len()?, d.len()?, d.len()?];
    let [time, size, force_floor, sum] = [d.f64()?, d.f64()?, d.f64()?, d.f64()?];
    let stiffness = StiffnessHistory {
        first: d.option()?,
        last: d.option()?,
    };
    let arc = if d.flag()? {
        let f = d.floats()?;
        let [load_factor, largest_load_factor, min_radius, max_radius] = f[..] else {
            return Err(corrupt("arc-length state"));
        };
        Some(ArcState {
            load_factor,
            largest_load_factor,
            radius: d.option()?,
            min_radius,
            max_radius,
            previous_increment: d.floats()?,
        })
    } else {
        None
    };
    Ok(LoopState {
        step,
        time,
        size,
        cutbacks,
        increments,
        iterations,
        force_floor,
        stiffness,
        force_average: ForceAverage { sum, count },
        arc,
    })
}

/// The counters and timings of the run so far (the symbolic factorisation's are measured
/// again by the resumed run).
fn encode_stats(e: &mut Encoder, s: &RunStatistics) -> io::Result<()> {
    for n in [
        s.steps,
        s.increments,
        s.iterations,
        s.cutbacks,
        s.unsymmetric_solves,
        s.krylov_iterations,
    ] {
        e.len(n)?;
    }
    e.floats(&[
        s.assembly_seconds,
        s.factorization_seconds,
        s.solve_seconds,
        s.output_seconds,
        s.last_residual,
    ])
}

fn decode_stats(d: &mut Decoder) -> io::Result<RunStatistics> {
    let mut s = RunStatistics {
        steps: d.len()?,
        increments: d.len()?,
        iterations: d.len()?,
        cutbacks: d.len()?,
        unsymmetric_solves: d.len()?,
        krylov_iterations: d.len()?,
        ..RunStatistics::default()
    };
    let f = d.floats()?;
    let [a, b, c, o, r] = f[..] else {
        return Err(corrupt("run statistics"));
    };
    (
        s.assembly_seconds,
        s.factorization_seconds,
        s.solve_seconds,
        s.output_seconds,
        s.last_residual,
    ) = (a, b, c, o, r);
    Ok(s)
}

fn encode_point(e: &mut Encoder, s: &PointState) -> io::Result<()> {
    let PointState {
        strain,
        stress,
        plastic_strain,
        equivalent_plastic_strain,
        yielding,
    } = s;
    for v in [strain, stress, plastic_strain] {
        for x in v.iter() {
            e.f64(*x)?;
        }
    }
    e.f64(*equivalent_plastic_strain)?;
    e.bytes(&[u8::from(*yielding)])
}

fn decode_point(d: &mut Decoder) -> io::Result<PointState> {
    let mut voigt =
        || -> io::Result<Voigt> { Ok(Voigt::new(d.f64()?, d.f64()?, d.f64()?, d.f64()?)) };
    Ok(PointState {
        strain: voigt()?,
        stress: voigt()?,
        plastic_strain: voigt()?,
        equivalent_plastic_strain: d.f64()?,
        yielding: d.flag()?,
    })
}

fn encode_interface(e: &mut Encoder, s: &InterfaceState) -> io::Result<()> {
    let InterfaceState {
        relative,
        stress,
        plastic_slip,
        accumulated_slip,
        max_closure,
        friction,
        stiffness,
        status,
        unsymmetric,
        history,
    } = s;
    encode_history(e, history)?;
    let [r0, r1] = *relative;
    let [s0, s1] = *stress;
    let [k0, k1] = *stiffness;
    for v in [
        r0,
        r1,
        s0,
        s1,
        *plastic_slip,
        *accumulated_slip,
        *max_closure,
        *friction,
        k0,
        k1,
    ] {
        e.f64(v)?;
    }
    e.bytes(&[*status as u8, u8::from(*unsymmetric)])
}

fn decode_interface(d: &mut Decoder) -> io::Result<InterfaceState> {
    let history = decode_history(d)?;
    let mut v = [0.0; 10];
    for x in &mut v {
        *x = d.f64()?;
    }
    let status = match d.byte()? {
        0 => ContactStatus::Open,
        1 => ContactStatus::Stick,
        2 => ContactStatus::Slip,
        _ => return Err(corrupt("contact status")),
    };
    Ok(InterfaceState {
        relative: [v[0], v[1]],
        stress: [v[2], v[3]],
        plastic_slip: v[4],
        accumulated_slip: v[5],
        max_closure: v[6],
        friction: v[7],
        stiffness: [v[8], v[9]],
        status,
        unsymmetric: d.flag()?,
        history,
    })
}

fn encode_energy(e: &mut Encoder, ledger: &EnergyLedger) -> io::Result<()> {
    let EnergyLedger {
        total,
        previous_force,
        weights: _,
    } = ledger;
    let Energy {
        external_work,
        elastic_energy,
        interface_energy,
        plastic_dissipation,
        friction_dissipation,
        wear_work,
        numerical_dissipation,
    } = total;
    e.floats(&[
        *external_work,
        *elastic_energy,
        *interface_energy,
        *plastic_dissipation,
        *friction_dissipation,
        *wear_work,
        *numerical_dissipation,
    ])?;
    e.floats(previous_force)
}

fn decode_energy(d: &mut Decoder) -> io::Result<EnergyLedger> {
    let v = d.floats()?;
    expect_len("energy totals", v.len(), 7)?;
    Ok(EnergyLedger {
        total: Energy {
            external_work: v[0],
            elastic_energy: v[1],
            interface_energy: v[2],
            plastic_dissipation: v[3],
            friction_dissipation: v[4],
            wear_work: v[5],
            numerical_dissipation: v[6],
        },
        previous_force: d.floats()?,
        weights: Default::default(),
    })
}

fn encode_history(e: &mut Encoder, h: &PointHistory) -> io::Result<()> {
    let PointHistory {
        dissipation,
        wear,
        gap_wear,
        cycle_start_dissipation,
        cycle_start_wear,
        cycle_slip,
        cycle_slip_range,
        cycle_max_shear,
        cycle_elastic_closure,
        last_cycle_dissipation,
        last_cycle_slip_amplitude,
        last_cycle_max_shear,
        last_cycle_wear,
    } = h;
    e.floats(&[
        *dissipation,
        wear[0],
        wear[1],
        *gap_wear,
        *cycle_start_dissipation,
        cycle_start_wear[0],
        cycle_start_wear[1],
        *cycle_slip,
        cycle_slip_range[0],
        cycle_slip_range[1],
        *cycle_max_shear,
        *cycle_elastic_closure,
        *last_cycle_dissipation,
        *last_cycle_slip_amplitude,
        *last_cycle_max_shear,
        last_cycle_wear[0],
        last_cycle_wear[1],
    ])
}

fn decode_history(d: &mut Decoder) -> io::Result<PointHistory> {
    let v = d.floats()?;
    expect_len("interface point history", v.len(), 17)?;
    Ok(PointHistory {
        dissipation: v[0],
        wear: [v[1], v[2]],
        gap_wear: v[3],
        cycle_start_dissipation: v[4],
        cycle_start_wear: [v[5], v[6]],
        cycle_slip: v[7],
        cycle_slip_range: [v[8], v[9]],
        cycle_max_shear: v[10],
        cycle_elastic_closure: v[11],
        last_cycle_dissipation: v[12],
        last_cycle_slip_amplitude: v[13],
        last_cycle_max_shear: v[14],
        last_cycle_wear: [v[15], v[16]],
    })
}

/// Little-endian binary writer.
/// Appends the record's values to a byte buffer; writing into memory cannot fail, so every
/// method returns `Ok`.
struct Encoder<'b>(&'b mut Vec<u8>);

impl Encoder<'_> {
    fn bytes(&mut self, b: &[u8]) -> io::Result<()> {
        self.0.extend_from_slice(b);
        Ok(())
    }
    fn u64(&mut self, v: u64) -> io::Result<()> {
        self.bytes(&v.to_le_bytes())
    }
    fn len(&mut self, n: usize) -> io::Result<()> {
        self.u64(n as u64)
    }
    fn f64(&mut self, v: f64) -> io::Result<()> {
        self.bytes(&v.to_bits().to_le_bytes())
    }
    fn floats(&mut self, v: &[f64]) -> io::Result<()> {
        self.len(v.len())?;
        v.iter().try_for_each(|x| self.f64(*x))
    }
    fn option(&mut self, v: Option<f64>) -> io::Result<()> {
        self.bytes(&[u8::from(v.is_some())])?;
        self.f64(v.unwrap_or(0.0))
    }
    fn text(&mut self, s: &str) -> io::Result<()> {
        self.len(s.len())?;
        self.bytes(s.as_bytes())
    }
}

/// Reader of what [`Encoder`] wrote; lengths are checked against the bytes left before
/// anything is allocated, so a damaged record cannot ask for a huge allocation.
struct Decoder<'b>(&'b [u8]);

impl Decoder<'_> {
    fn take<const N: usize>(&mut self) -> io::Result<[u8; N]> {
        let mut b = [0u8; N];
        self.0.read_exact(&mut b)?;
        Ok(b)
    }
    fn byte(&mut self) -> io::Result<u8> {
        Ok(self.take::<1>()?[0])
    }
    fn flag(&mut self) -> io::Result<bool> {
        match self.byte()? {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(corrupt("flag")),
        }
    }
    fn u64(&mut self) -> io::Result<u64> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    /// A count of items of at least one byte each.
    fn len(&mut self) -> io::Result<usize> {
        let n = self.u64()?;
        usize::try_from(n)
            .ok()
            .filter(|&n| n <= self.0.len())
            .ok_or_else(|| corrupt("a count larger than the record"))
    }
    fn f64(&mut self) -> io::Result<f64> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn floats(&mut self) -> io::Result<Vec<f64>> {
        let n = self.len()?;
        if n > self.0.len() / 8 {
            return Err(corrupt("an array longer than the record"));
        }
        (0..n).map(|_| self.f64()).collect()
    }
    fn option(&mut self) -> io::Result<Option<f64>> {
        let present = self.flag()?;
        let v = self.f64()?;
        Ok(present.then_some(v))
    }
    fn text(&mut self) -> io::Result<String> {
        let n = self.len()?;
        let (s, rest) = self.0.split_at(n);
        self.0 = rest;
        String::from_utf8(s.to_vec()).map_err(|_| corrupt("text"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(x: f64) -> Content {
        Content::Csv(CsvTable {
            columns: vec!["x".into()],
            rows: vec![vec![x]],
        })
    }

    /// A folder where a file should go makes its rename fail, as a full or read-only disk
    /// would make a write fail.
    #[test]
    fn a_failed_write_stops_its_commit_and_a_later_commit_or_finish_reports_it_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = |name: &str| dir.path().join(name);
        std::fs::create_dir(path("b.csv")).unwrap();
        std::fs::write(path("b.csv").join("keep"), "x").unwrap();
        let mut writer = RecordWriter::default();
        for name in ["a.csv", "b.csv", "c.csv"] {
            writer.queue(path(name), table(1.0));
        }
        writer.commit().unwrap();
        writer.queue(path("d.csv"), table(2.0));
        // The next commit reports the failure if the thread is done by then; else its files
        // wait and `finish` reports it (and drops them).
        let err = match writer.commit() {
            Err(e) => e,
            Ok(()) => writer.finish().unwrap_err(),
        };
        assert!(
            matches!(&err, Error::Io { path: p, .. } if p == &path("b.csv")),
            "{err}"
        );
        assert!(err.to_string().contains("b.csv"), "{err}");
        // The files before the failure are complete; none after it, in that commit or the
        // refused one, was written.
        assert_eq!(std::fs::read_to_string(path("a.csv")).unwrap(), "x\n1\n");
        assert!(!path("c.csv").exists() && !path("d.csv").exists());
        writer.finish().unwrap();
    }

    #[test]
    fn commits_waiting_for_the_thread_keep_the_latest_content_of_each_file_in_order() {
        let name = |n: &str| PathBuf::from(n);
        let mut writer = RecordWriter::default();
        let batch = |step: &str, x: f64| {
            vec![
                (name(step), table(x)),
                (name("restart.bin"), Content::Record(vec![x as u8])),
                (name("results.pvd"), table(x)),
            ]
        };
        writer.merge(batch("bodies_0001.vtu", 1.0));
        writer.merge(batch("bodies_0002.vtu", 2.0));
        let order: Vec<&str> = writer
            .waiting
            .iter()
            .map(|(p, _)| p.to_str().unwrap())
            .collect();
        // Both steps' files, then the latest record and index: the index still comes last.
        assert_eq!(
            order,
            [
                "bodies_0001.vtu",
                "bodies_0002.vtu",
                "restart.bin",
                "results.pvd"
            ]
        );
        assert!(matches!(&writer.waiting[2].1, Content::Record(b) if b == &[2]));
        writer.waiting.clear();
    }

    #[test]
    fn commits_are_written_in_order_and_finish_waits_for_the_last() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("history.csv");
        let mut writer = RecordWriter::default();
        for x in 0..20 {
            writer.queue(path.clone(), table(f64::from(x)));
            writer.commit().unwrap();
        }
        writer.finish().unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "x\n19\n");
    }

    #[test]
    fn a_nan_found_in_the_background_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("contact_joint_0003.csv");
        let mut writer = RecordWriter::default();
        writer.queue(path.clone(), table(f64::NAN));
        writer.commit().unwrap();
        let err = writer.finish().unwrap_err();
        assert!(err.to_string().contains("contact_joint_0003.csv"), "{err}");
        assert!(!path.exists());
    }
}
