//! The background writer of a run's files ([`RecordWriter`]): a converged step's result
//! files, the restart record of its increment and the indexes are committed together and
//! written in order on one thread while the next increment computes.

use std::path::{Path, PathBuf};
use std::sync::{Arc, mpsc};

use super::append::Append;
use super::atomic::{DropBehind, write_bytes, write_streamed};
use super::csv::{Cell, CsvTable, write_csv};
use super::pvd::{PvdEntry, write_pvd};
use super::restart::{ContinuumStates, OutputState, encode_record};
use super::vtm::{VtmBlock, write_vtm};
use super::vtu::encode_vtu;
use super::{Grid, GridView, SplitPlan};
use crate::solver::state::Progress;
use crate::{Error, Result};

/// A file handed to the [`RecordWriter`], encoded and written on its thread.
#[derive(Debug)]
pub enum Content {
    Vtu(Grid),
    /// Part `k` of a grid divided by a plan ([`GridView::part`]): the grid and the plan are
    /// shared by the files of its parts, each written without a copy of the grid.
    VtuPart(Arc<Grid>, Arc<SplitPlan>, usize),
    Csv(CsvTable),
    /// A table with text or empty cells.
    Table(CsvTable<Cell>),
    Pvd(Vec<PvdEntry>),
    /// A multiblock file naming a frame's VTU files.
    Vtm(Vec<VtmBlock>),
    /// A file's text, already formatted.
    Text(Vec<u8>),
    /// Rows to append to a growing file ([`super::append::AppendedFile`]).
    Append(Append),
    /// A restart record, already encoded (by [`RecordWriter::queue_record`]).
    Record(Vec<u8>),
}

impl Content {
    /// Bytes of memory the content holds (its arrays; names and small indexes left out).
    fn heap_bytes(&self) -> usize {
        match self {
            Content::Vtu(grid) => grid.heap_bytes(),
            Content::VtuPart(grid, plan, k) => (grid.heap_bytes() as f64 * plan.share(*k)) as usize,
            Content::Csv(table) => table.rows.len() * table.columns.len() * size_of::<f64>(),
            Content::Table(table) => table.rows.len() * table.columns.len() * size_of::<Cell>(),
            Content::Record(bytes) | Content::Text(bytes) => bytes.len(),
            Content::Append(append) => append.bytes.len(),
            Content::Pvd(_) | Content::Vtm(_) => 0,
        }
    }

    /// Writes the file, a VTU file through `buffer` (the writer thread's, reused); a large
    /// VTU file or record is dropped from the page cache behind the writer (`behind`).
    fn write(&self, path: &Path, buffer: &mut Vec<u8>, behind: &mut DropBehind) -> Result<()> {
        let vtu = |view: GridView, buffer: &mut Vec<u8>, behind: &mut DropBehind| {
            encode_vtu(path, view, buffer)?;
            write_streamed(path, buffer, behind)
        };
        match self {
            Content::Vtu(grid) => vtu(GridView::whole(grid), buffer, behind),
            Content::VtuPart(grid, plan, k) => vtu(GridView::part(grid, plan, *k), buffer, behind),
            Content::Csv(table) => write_csv(path, table),
            Content::Table(table) => write_csv(path, table),
            Content::Pvd(entries) => write_pvd(path, entries),
            Content::Vtm(blocks) => write_vtm(path, blocks),
            Content::Record(bytes) => write_streamed(path, bytes, behind),
            Content::Text(bytes) => write_bytes(path, bytes),
            Content::Append(append) => append.write(path),
        }
    }
}

/// Files that may wait for the writer thread before a commit waits for it: a few steps'
/// files (each step writes its VTU files and a table per contact pair) besides the record and
/// the tables that every commit rewrites.
const MAX_WAITING_FILES: usize = 32;

/// Bytes of rows that may wait to be appended before a commit waits for the writer thread.
const MAX_APPENDED: usize = 16 << 20;

/// Bytes of content (grids, tables, the record) that may wait for the writer thread before a
/// commit waits for it: a step's files at tens of thousands of unknowns (~10 MB) wait, a
/// million-unknown step's (~150 MB of grids) does not. Once the thread is slower than the
/// solver, a second such step waiting would add its size to the run's peak memory and save
/// nothing: the run goes at the thread's pace either way. (The next step's grids are made
/// while such a commit is written, before [`RecordWriter::make_room`] waits for it: the
/// thread would idle while they were made after it.)
const MAX_WAITING_BYTES: usize = 64 << 20;

/// Writes a run's committed files in the background: the files of a converged step (VTU,
/// CSV), the restart record of a converged increment (`case` is the case file's text, which
/// [`read_record`](super::restart::read_record) compares with the case being resumed) and
/// the indexes, in the order they were queued, on one thread, one commit at a time.
///
/// The caller queues a commit's files ([`RecordWriter::queue`],
/// [`RecordWriter::queue_record`]), then [`RecordWriter::commit`]s them: when the writer
/// thread is idle, that hands them to it, so that encoding and writing a step's files (~10 MB
/// of VTU data and ~10 MB of record for a 60k-unknown model) overlaps the next increment
/// instead of adding to the run's time. When it is still writing an earlier commit, the new
/// files wait, merged with those of the commits that came after that one: a file queued
/// again (the record, the series) keeps only its latest content, and the rows appended to a
/// growing table ([`Content::Append`]) are joined into one append, so a thread that falls
/// behind (thousands of short increments) skips the versions that a later commit replaces
/// instead of making the run wait for each. The merged files keep their order (each file
/// where its latest commit put it, after the files of earlier commits), so the record and the
/// indexes still come after the step files and rows they refer to. Within a commit the files
/// are written in order and the first error stops it, so a step's record and index entries
/// are never on disk without its files; that error (an [`Error::Io`] naming the file) is
/// returned by a later `commit` or by [`RecordWriter::finish`], which writes what waits and
/// stops the run; nothing is written after it.
///
/// A run killed while commits are in flight or waiting has only complete files (each is
/// written atomically; a growing table may end in a partial row, past the length its record
/// counts), the index lists only complete steps, and a resumed run cuts the tables back to
/// the record and repeats the increments after it bit for bit, rewriting their files and
/// rows identically.
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
    /// Bytes of memory the commit in flight holds.
    in_flight_bytes: usize,
    /// A record buffer to encode into: reusing it spares the page faults of ~10 MB of
    /// fresh memory per record.
    spare: Vec<u8>,
    /// Whether a commit failed: nothing is written after it (its error was reported).
    failed: bool,
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
            let mut behind = DropBehind::default();
            for files in inbox {
                // The last commit's large files have had the time of an increment to reach
                // the disk: their pages are dropped for this commit's to reuse.
                behind.release();
                if outbox
                    .send(write_in_order(files, &mut buffer, &mut behind))
                    .is_err()
                {
                    break;
                }
            }
            behind.release();
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

    /// Drops the files queued since the last commit.
    pub fn discard_queued(&mut self) {
        self.queued.clear();
    }

    /// Encodes the record of the converged increment `progress` (with the continuum's
    /// `states` or without) and adds it to the next commit.
    pub fn queue_record(
        &mut self,
        path: &Path,
        case: &str,
        progress: &Progress,
        output: &OutputState,
        states: ContinuumStates,
    ) -> Result<()> {
        let mut buffer = std::mem::take(&mut self.spare);
        encode_record(&mut buffer, case, progress, output, states)
            .map_err(|e| Error::io(path, e))?;
        self.queue(path.to_path_buf(), Content::Record(buffer));
        Ok(())
    }

    /// Commits the queued files: hands them to the writer thread if it is idle, else merges
    /// them into the files waiting for it. Returns the error of a finished commit.
    pub fn commit(&mut self) -> Result<()> {
        let files = std::mem::take(&mut self.queued);
        if self.failed {
            // The error was reported; later files may refer to the ones that failed.
            return Ok(());
        }
        self.merge(files);
        if self.in_flight && !self.poll()? {
            if self.waiting.len() <= MAX_WAITING_FILES
                && self.waiting_appends() <= MAX_APPENDED
                && self.waiting_bytes() <= MAX_WAITING_BYTES
            {
                return Ok(());
            }
            // Files that no later commit replaces (each step's VTU and contact tables) and
            // rows appended to the growing tables pile up while the thread is behind: wait
            // for it rather than hold them all in memory.
            self.wait()?;
        }
        self.send_waiting();
        Ok(())
    }

    /// Adds `files` to the waiting ones: a path already waiting is replaced (its superseded
    /// record buffer kept for reuse), or for an append extended by the new bytes, and takes
    /// its new place in the order.
    fn merge(&mut self, files: Vec<(PathBuf, Content)>) {
        for (path, mut content) in files {
            let earlier = self.waiting.iter().position(|(p, _)| *p == path);
            match (earlier.map(|i| self.waiting.remove(i)), content) {
                (Some((_, Content::Record(bytes))), new) => {
                    self.keep_spare(bytes);
                    content = new;
                }
                (Some((_, Content::Append(mut first))), Content::Append(next)) => {
                    content = match first.extend(next) {
                        Ok(()) => Content::Append(first),
                        // Not the continuation: written as it is, at its offset the writer
                        // checks (and refuses).
                        Err(next) => {
                            self.waiting.push((path.clone(), Content::Append(first)));
                            Content::Append(next)
                        }
                    };
                }
                (_, new) => content = new,
            }
            self.waiting.push((path, content));
        }
    }

    /// Bytes waiting to be appended to growing files.
    fn waiting_appends(&self) -> usize {
        let appends = self
            .waiting
            .iter()
            .filter_map(|(_, content)| match content {
                Content::Append(append) => Some(append.bytes.len()),
                _ => None,
            });
        appends.sum()
    }

    /// Bytes of memory the waiting files hold.
    fn waiting_bytes(&self) -> usize {
        self.waiting.iter().map(|(_, c)| c.heap_bytes()).sum()
    }

    /// Hands the waiting files, if any, to the writer thread (started at the first commit).
    fn send_waiting(&mut self) {
        let files = std::mem::take(&mut self.waiting);
        if files.is_empty() {
            return;
        }
        self.in_flight_bytes = files.iter().map(|(_, c)| c.heap_bytes()).sum();
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

    /// To be called before queueing a step's files: waits for the commit in flight if it
    /// holds more than `MAX_WAITING_BYTES` (64 MiB: a million-unknown step's grids), so that
    /// no more than one such step is in memory besides the one being queued, then hands the
    /// thread the files waiting behind it. Smaller commits are left to overlap the next ones.
    pub fn make_room(&mut self) -> Result<()> {
        if self.in_flight && self.in_flight_bytes > MAX_WAITING_BYTES && !self.poll()? {
            self.wait()?;
            self.send_waiting();
        }
        Ok(())
    }

    /// Queues and commits the record of a converged increment.
    pub fn write(
        &mut self,
        path: &Path,
        case: &str,
        progress: &Progress,
        output: &OutputState,
        states: ContinuumStates,
    ) -> Result<()> {
        self.queue_record(path, case, progress, output, states)?;
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
                self.failed = true;
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
fn write_in_order(
    files: Vec<(PathBuf, Content)>,
    buffer: &mut Vec<u8>,
    behind: &mut DropBehind,
) -> Result<Vec<u8>> {
    let mut spare = Vec::new();
    for (path, content) in files {
        content.write(&path, buffer, behind)?;
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

    /// A commit larger than [`MAX_WAITING_BYTES`] never waits behind another, and
    /// `make_room` returns only once such a commit is written: at most one is in memory.
    #[test]
    fn a_large_commit_is_written_before_the_next_large_step_is_made() {
        let dir = tempfile::tempdir().unwrap();
        let large = || Content::Record(vec![7; MAX_WAITING_BYTES + 1]);
        let mut writer = RecordWriter::default();
        writer.queue(dir.path().join("a.bin"), large());
        writer.commit().unwrap();
        assert!(writer.in_flight && writer.in_flight_bytes > MAX_WAITING_BYTES);
        writer.queue(dir.path().join("b.bin"), large());
        writer.commit().unwrap();
        // The second did not wait behind the first: the first was written, the second sent.
        assert!(writer.waiting.is_empty());
        assert_eq!(
            std::fs::metadata(dir.path().join("a.bin")).unwrap().len() as usize,
            MAX_WAITING_BYTES + 1
        );
        writer.make_room().unwrap();
        assert!(!writer.in_flight && writer.waiting.is_empty());
        assert!(dir.path().join("b.bin").exists());
        writer.finish().unwrap();
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
