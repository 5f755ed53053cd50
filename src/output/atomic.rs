//! Writing a file so that it is either complete or absent.
//!
//! A run can stop at any moment (an error in a later step, Ctrl-C, a killed job), and
//! ParaView or a post-processing script may read the output folder while the run is still
//! going. Writing straight into `step_0007.vtu` would expose a truncated file in both
//! cases; instead every writer of this module tree goes through [`write_atomically`], which
//! writes a hidden temporary file next to the target (`tempfile`'s [`NamedTempFile`]) and
//! persists it onto the target. Persisting renames within one directory (one filesystem),
//! which replaces the target in a single step on POSIX systems, so readers see either the
//! old file or the new one, never a mixture; a temporary file that is never persisted is
//! deleted when it is dropped, also when `write` fails or panics.

use std::io::{self, BufWriter, Write};
use std::path::Path;

use tempfile::NamedTempFile;

use crate::{Error, Result};

/// Writes `path` by calling `write` on a buffered temporary file in the same directory and
/// persisting that file onto `path` once `write` has succeeded and the data is flushed.
///
/// Creates the parent directory if it is missing. On any failure the temporary file is
/// removed and the error names `path`; an existing file at `path` is left untouched. The
/// file gets the permissions `File::create` would give it (0o666 less the umask), not the
/// owner-only ones of a temporary file.
///
/// Validation of the data should happen *before* calling this, so that a bad value does not
/// even create the temporary file; `write` may still fail (disk full, ...), in which case
/// the cleanup here applies.
pub(crate) fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<()> {
    super::paths::check_output_path(path)?;
    write_through(path, BUFFER, |file| Box::new(file), write, |_| ())
}

/// Bytes of the write buffer of [`write_atomically`].
const BUFFER: usize = 1 << 20;

/// Writes `bytes`, a whole file already in memory, to `path` as [`write_atomically`] does,
/// without the write buffer: one `write` call, no copy and no buffer to allocate.
pub(crate) fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    super::paths::check_output_path(path)?;
    write_through(
        path,
        0,
        |file| Box::new(file),
        |w| w.write_all(bytes),
        |_| (),
    )
}

/// [`write_bytes`] for a writer of many large files in a row (a run's frames, its restart
/// records): a file of [`STREAMED_BYTES`] or more is sent to the disk at once and kept in
/// `behind`, whose next [`DropBehind::release`] drops it from the page cache.
pub(crate) fn write_streamed(path: &Path, bytes: &[u8], behind: &mut DropBehind) -> Result<()> {
    super::paths::check_output_path(path)?;
    let large = bytes.len() >= STREAMED_BYTES;
    let keep = |file: &std::fs::File| {
        if large {
            behind.keep(file);
        }
    };
    write_through(path, 0, |file| Box::new(file), |w| w.write_all(bytes), keep)
}

/// Bytes from which [`write_streamed`] drops a file from the page cache behind it.
pub(crate) const STREAMED_BYTES: usize = 8 << 20;

/// Large files written in full, to drop from the page cache once they are on the disk
/// ("drop-behind", as `dd oflag=nocache` does). A run writes its frames once and reads them
/// never (4 GB at 3.84 M unknowns): kept in the page cache they would push out what the
/// machine caches for other work, and every frame would take fresh memory for its pages —
/// on a virtual machine whose free memory goes back to its host (free page reporting), each
/// fresh page is a fault in the host too, and writing into the page cache then ran at
/// 0.15–0.2 GB/s (dd, 1 GB) where writing into pages just dropped runs at several GB/s. Each
/// kept file's writeback is started when it is written (`sync_file_range`, without waiting),
/// and its pages are dropped at the next release — a commit later, when they are written —
/// so that the next files reuse them. Linux only; elsewhere nothing is kept or dropped.
#[derive(Debug, Default)]
pub(crate) struct DropBehind {
    files: Vec<std::fs::File>,
}

impl DropBehind {
    /// The most files kept open at once (one descriptor each).
    const MOST_KEPT: usize = 64;

    /// Starts writing `file` back to the disk and keeps a handle on it (at most
    /// [`Self::MOST_KEPT`]: a commit of more large files releases the earlier ones early).
    fn keep(&mut self, file: &std::fs::File) {
        if self.files.len() >= Self::MOST_KEPT {
            self.release();
        }
        #[cfg(target_os = "linux")]
        {
            use std::os::fd::AsRawFd;
            // SAFETY: a plain system call on an open file descriptor. Advice only: a failure
            // leaves the pages cached, which is no error.
            unsafe { libc::sync_file_range(file.as_raw_fd(), 0, 0, libc::SYNC_FILE_RANGE_WRITE) };
            if let Ok(handle) = file.try_clone() {
                self.files.push(handle);
            }
        }
        #[cfg(not(target_os = "linux"))]
        let _ = file;
    }

    /// Drops the pages of the files kept since the last release from the page cache (the
    /// kernel keeps those still being written) and closes them.
    pub(crate) fn release(&mut self) {
        for file in self.files.drain(..) {
            #[cfg(target_os = "linux")]
            {
                use std::os::fd::AsRawFd;
                // SAFETY: as in `keep`.
                unsafe { libc::posix_fadvise(file.as_raw_fd(), 0, 0, libc::POSIX_FADV_DONTNEED) };
            }
            #[cfg(not(target_os = "linux"))]
            let _ = file;
        }
    }
}

/// [`write_atomically`] with a write buffer of `buffer` bytes (0: none) and the temporary
/// file reached through `sink` (the file itself; in tests, a writer that fails like a full
/// disk).
fn write_through(
    path: &Path,
    buffer: usize,
    sink: impl for<'f> FnOnce(&'f std::fs::File) -> Box<dyn Write + 'f>,
    write: impl FnOnce(&mut dyn Write) -> io::Result<()>,
    written: impl FnOnce(&std::fs::File),
) -> Result<()> {
    let file_name = path.file_name().ok_or_else(|| {
        Error::io(
            path,
            io::Error::new(io::ErrorKind::InvalidInput, "the path has no file name"),
        )
    })?;
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;

    let result = (|| -> io::Result<()> {
        // Hidden (leading dot) so that file browsers and `*.vtu` globs skip it, and in the
        // same directory so that persisting it cannot cross filesystems.
        let mut prefix = std::ffi::OsString::from(".");
        prefix.push(file_name);
        prefix.push(".");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let tmp = builder.tempfile_in(dir)?;
        let mut writer = BufWriter::with_capacity(buffer, sink(tmp.as_file()));
        write(&mut writer)?;
        // `into_inner` flushes and reports flush errors, which dropping a `BufWriter` would
        // silently swallow (a full disk would then yield a truncated file and `Ok`).
        drop(
            writer
                .into_inner()
                .map_err(io::IntoInnerError::into_error)?,
        );
        written(tmp.as_file());
        // The rename makes the complete file visible at once, so a killed run never leaves a
        // partial file. No fsync: a killed process's writes are in the page cache and reach
        // the disk anyway, and one fsync per file cost 5-20 ms (a third of the wall time of
        // a small frictional run, six files a step). Durability against power loss is the
        // filesystem's (ext4 flushes a file's data before a rename over an existing one), as
        // for CalculiX's and Abaqus' result files.
        persist(tmp, path)
    })();
    result.map_err(|e| Error::io(path, e))
}

/// Writes `text` to `path` atomically ([`write_bytes`]).
pub(crate) fn write_text(path: &Path, text: &str) -> Result<()> {
    write_bytes(path, text.as_bytes())
}

/// Renames `tmp` onto `path`; on failure `tmp` is dropped, which deletes it.
fn persist(tmp: NamedTempFile, path: &Path) -> io::Result<()> {
    tmp.persist(path).map(drop).map_err(|e| e.error)
}

/// Builds the [`Error::Io`] used for data that cannot be written (wrong lengths, NaN, ...):
/// the file is what the user sees, so the error names it, and the message names the
/// offending array and index.
pub(crate) fn invalid_data(path: &Path, message: impl Into<String>) -> Error {
    Error::io(
        path,
        io::Error::new(io::ErrorKind::InvalidData, message.into()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    fn names(dir: &Path) -> Vec<std::ffi::OsString> {
        let mut names: Vec<_> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn failed_write_leaves_nothing_behind_and_keeps_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        fs::write(&path, "old").unwrap();
        let err = write_atomically(&path, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("boom"))
        })
        .unwrap_err();
        assert!(err.to_string().contains("boom"), "{err}");
        assert_eq!(fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(names(dir.path()), vec![std::ffi::OsString::from("a.txt")]);
    }

    /// A file that takes `room` bytes and then fails as a full disk does.
    struct FullDisk<'f> {
        file: &'f std::fs::File,
        room: usize,
    }

    impl Write for FullDisk<'_> {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if self.room == 0 {
                return Err(io::Error::from(io::ErrorKind::StorageFull));
            }
            let n = buf.len().min(self.room);
            self.room -= n;
            self.file.write(&buf[..n])
        }
        fn flush(&mut self) -> io::Result<()> {
            self.file.flush()
        }
    }

    #[test]
    fn a_full_disk_is_an_error_naming_the_file_and_leaves_the_old_one() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("history.csv");
        fs::write(&path, "old").unwrap();
        // Larger than the buffer, so the disk fills both during writing and at the flush.
        for (room, size) in [(0, 10), (5, 10), (1000, 3 << 20)] {
            let err = write_through(
                &path,
                BUFFER,
                |file| Box::new(FullDisk { file, room }),
                |w| w.write_all(&vec![b'x'; size]),
                |_| (),
            )
            .unwrap_err();
            assert!(
                matches!(&err, Error::Io { path: p, source } if p == &path
                && source.kind() == io::ErrorKind::StorageFull),
                "{err}"
            );
            assert!(err.to_string().contains("history.csv"), "{err}");
            assert_eq!(fs::read_to_string(&path).unwrap(), "old");
            assert_eq!(
                names(dir.path()),
                vec![std::ffi::OsString::from("history.csv")]
            );
        }
    }

    #[test]
    fn creates_missing_parent_directories_and_replaces_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x/y/b.txt");
        write_atomically(&path, |w| w.write_all(b"old")).unwrap();
        write_atomically(&path, |w| w.write_all(b"new")).unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "new");
        assert_eq!(
            names(&dir.path().join("x/y")),
            vec![std::ffi::OsString::from("b.txt")]
        );
    }

    /// The share of `path`'s pages in the page cache (`mincore` on a mapping of it).
    #[cfg(target_os = "linux")]
    fn cached_share(path: &Path) -> f64 {
        use std::os::fd::AsRawFd;
        let file = fs::File::open(path).unwrap();
        let len = file.metadata().unwrap().len() as usize;
        let page = 4096;
        let mut resident = vec![0u8; len.div_ceil(page)];
        // SAFETY: a read-only shared mapping of an open file, unmapped before returning;
        // `mincore` writes one byte per page into `resident`, which has one per page.
        unsafe {
            let map = libc::mmap(
                std::ptr::null_mut(),
                len,
                libc::PROT_READ,
                libc::MAP_SHARED,
                file.as_raw_fd(),
                0,
            );
            assert_ne!(map, libc::MAP_FAILED);
            assert_eq!(libc::mincore(map, len, resident.as_mut_ptr()), 0);
            libc::munmap(map, len);
        }
        resident.iter().filter(|&&r| r & 1 == 1).count() as f64 / resident.len() as f64
    }

    /// A large file written through `write_streamed` is dropped from the page cache at the
    /// next release (once on the disk), with the same bytes; a small one is not kept.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_large_streamed_file_leaves_the_page_cache_at_the_next_release() {
        // On the repository's disk: a tmpfs `/tmp` keeps its files in memory.
        let target = Path::new(env!("CARGO_MANIFEST_DIR")).join("target");
        fs::create_dir_all(&target).unwrap();
        let dir = tempfile::tempdir_in(&target).unwrap();
        let path = dir.path().join("bodies_0001.vtu");
        let bytes: Vec<u8> = (0..STREAMED_BYTES + 12345)
            .map(|i| (i % 251) as u8)
            .collect();
        let mut behind = DropBehind::default();
        write_streamed(&path, &bytes, &mut behind).unwrap();
        assert_eq!(behind.files.len(), 1);
        fs::File::open(&path).unwrap().sync_data().unwrap();
        assert!(cached_share(&path) > 0.9, "{}", cached_share(&path));
        behind.release();
        assert!(behind.files.is_empty());
        assert!(cached_share(&path) < 0.1, "{}", cached_share(&path));
        assert!(fs::read(&path).unwrap() == bytes);
        let small = dir.path().join("history.csv");
        write_streamed(&small, b"step\n1\n", &mut behind).unwrap();
        assert!(behind.files.is_empty());
        assert_eq!(fs::read(&small).unwrap(), b"step\n1\n");
    }

    #[cfg(unix)]
    #[test]
    fn the_file_gets_the_permissions_of_a_created_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let created = dir.path().join("created.txt");
        fs::write(&created, "x").unwrap();
        let path = dir.path().join("atomic.txt");
        write_atomically(&path, |w| w.write_all(b"x")).unwrap();
        let mode = |p: &Path| fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&path), mode(&created));
    }
}
