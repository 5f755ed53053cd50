//! The run's progress bar and its log sinks: stderr lines that do not tear the bar, and
//! `log.txt` in the output folder.

use std::fs::File;
use std::io::Write;
use std::sync::{Arc, Mutex, MutexGuard};

use tracing_subscriber::fmt::MakeWriter;

use indicatif::ProgressBar;

use super::folder::{OutputFolder, RunFile};
use crate::{Error, Result};

pub use crate::stop::{request_stop, stop_requested};

/// The progress bar of the run in progress, if it is drawn: [`LogToStderr`] writes log lines
/// through it.
static ACTIVE_BAR: Mutex<Option<ProgressBar>> = Mutex::new(None);

/// stderr for log lines (`tracing_subscriber`'s `with_writer(|| LogToStderr)`): while a run
/// draws its progress bar on the terminal, each line is written with the bar hidden and the
/// bar redrawn below it ([`ProgressBar::suspend`]), so that lines and bar do not interleave.
/// Without a bar (stderr not a terminal, `-q`, no run) it is plain stderr.
pub struct LogToStderr;

impl Write for LogToStderr {
    fn write(&mut self, line: &[u8]) -> std::io::Result<usize> {
        let bar = ACTIVE_BAR.lock().unwrap_or_else(|e| e.into_inner()).clone();
        write_log_line(bar.as_ref(), &mut std::io::stderr(), line)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        std::io::stderr().flush()
    }
}

/// Writes a log `line` to `out`, with `bar` (when there is one) hidden meanwhile.
pub fn write_log_line(
    bar: Option<&ProgressBar>,
    out: &mut impl Write,
    line: &[u8],
) -> std::io::Result<usize> {
    match bar {
        Some(bar) => bar.suspend(|| out.write_all(line))?,
        None => out.write_all(line)?,
    }
    Ok(line.len())
}

/// The run's progress bar, registered for [`LogToStderr`] while it lives; dropping it (at the
/// end of the run, also a failed one) clears it from the terminal.
pub(super) struct RunBar(pub(super) ProgressBar);

impl RunBar {
    /// Clears the bar from the terminal; log lines go straight to stderr again.
    pub(super) fn finish(&self) {
        *ACTIVE_BAR.lock().unwrap_or_else(|e| e.into_inner()) = None;
        self.0.finish_and_clear();
    }
}

impl Drop for RunBar {
    fn drop(&mut self) {
        self.finish();
    }
}

pub(super) fn progress_bar(enabled: bool, steps: usize) -> RunBar {
    if !enabled {
        return RunBar(ProgressBar::hidden());
    }
    let bar = ProgressBar::new(steps as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} step {pos}/{len} [{elapsed_precise}] {wide_bar} {msg}",
        )
        .expect("valid progress template"),
    );
    *ACTIVE_BAR.lock().unwrap_or_else(|e| e.into_inner()) = Some(bar.clone());
    RunBar(bar)
}

/// The run's `log.txt`: a log sink that records nothing until [`LogFile::open`] is called with
/// the output folder (known only once the case is read), then the same lines as stderr, at
/// INFO level or more detailed, whatever `-q` says.
#[derive(Clone, Default)]
pub struct LogFile(Arc<Mutex<Option<File>>>);

impl LogFile {
    /// Starts writing the folder's `log.txt` (created, or truncated unless `append`).
    /// A resumed run appends to the log of the run it continues.
    pub fn open(&self, folder: &OutputFolder, append: bool) -> Result<()> {
        let path = folder.path(RunFile::Log)?;
        let file = File::options()
            .write(true)
            .create(true)
            .append(append)
            .truncate(!append)
            .open(&path)
            .map_err(|e| Error::io(&path, e))?;
        *self.lock() = Some(file);
        Ok(())
    }

    fn lock(&self) -> MutexGuard<'_, Option<File>> {
        // A panic while logging leaves the file usable: it only ever holds whole lines.
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// One event's write into [`LogFile`] (the fmt layer writes a whole line at once).
pub struct LogFileWriter<'a>(MutexGuard<'a, Option<File>>);

impl Write for LogFileWriter<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self.0.as_mut() {
            Some(f) => f.write(buf),
            None => Ok(buf.len()),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.0.as_mut().map_or(Ok(()), Write::flush)
    }
}

impl<'a> MakeWriter<'a> for LogFile {
    type Writer = LogFileWriter<'a>;

    fn make_writer(&'a self) -> Self::Writer {
        LogFileWriter(self.lock())
    }
}
