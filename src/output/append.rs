//! Files that grow by appending (`history.csv`, the fretting tables): each frame adds a few
//! rows, so a run writes only those instead of the whole file again (which made the output
//! cost of a run quadratic in its frames).
//!
//! An [`AppendedFile`] holds only the bytes not yet handed to the background writer, and
//! counts every byte it was given: the file's length and its CRC-32 so far, its
//! [`FileMark`]. The restart record keeps the marks of a run's growing files instead of their
//! rows, so it stays the size of the model however long the run. A resumed run
//! restores each file to its mark: it checks the checksum of the file's first `length`
//! bytes and cuts off what came after (rows of frames after the record, or the partial last
//! line of a run killed while appending), so it continues the file exactly where the record
//! left it.

use std::fs::{File, OpenOptions};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::paths::check_output_path;
use crate::{Error, Result};

/// What a restart record keeps of a growing file: its length in bytes and the CRC-32 of
/// those bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileMark {
    pub length: u64,
    pub crc: u32,
}

/// A file written by appending: the bytes not yet handed to the writer, and the length and
/// running checksum of everything appended.
#[derive(Clone, Debug, Default)]
pub struct AppendedFile {
    pending: Vec<u8>,
    /// Bytes handed to the writer (the offset of the pending ones).
    handed: u64,
    crc: crc32fast::Hasher,
}

impl AppendedFile {
    /// A file continued after the bytes that `mark` describes.
    pub fn continued(mark: FileMark) -> Self {
        Self {
            pending: Vec::new(),
            handed: mark.length,
            crc: crc32fast::Hasher::new_with_initial_len(mark.crc, mark.length),
        }
    }

    /// Appends `bytes`.
    pub fn push(&mut self, bytes: &[u8]) {
        self.crc.update(bytes);
        self.pending.extend_from_slice(bytes);
    }

    /// The bytes appended since the last [`Self::take`].
    pub fn pending(&self) -> &[u8] {
        &self.pending
    }

    /// Hands over the pending bytes with their offset in the file (`None` when there are
    /// none).
    pub fn take(&mut self) -> Option<Append> {
        if self.pending.is_empty() {
            return None;
        }
        let bytes = std::mem::take(&mut self.pending);
        let offset = self.handed;
        self.handed += bytes.len() as u64;
        Some(Append { offset, bytes })
    }

    /// The length and checksum of everything appended (taken or not).
    pub fn mark(&self) -> FileMark {
        FileMark {
            length: self.handed + self.pending.len() as u64,
            crc: self.crc.clone().finalize(),
        }
    }
}

/// Bytes to write at `offset` of a file, which must be exactly that long: the file is
/// created by the append at offset 0 and only ever grows by the next append.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Append {
    pub offset: u64,
    pub bytes: Vec<u8>,
}

impl Append {
    /// Adds the bytes of the append that follows this one.
    pub fn extend(&mut self, next: Append) -> std::result::Result<(), Append> {
        if next.offset != self.offset + self.bytes.len() as u64 {
            return Err(next);
        }
        self.bytes.extend_from_slice(&next.bytes);
        Ok(())
    }

    /// Writes the bytes at their offset of `path` with one call; at offset 0 the file is
    /// created anew (a run starts its tables). A file of another length than the offset
    /// (changed by another program) or a link is an error naming `path`.
    pub fn write(&self, path: &Path) -> Result<()> {
        check_output_path(path)?;
        let write = || -> io::Result<()> {
            refuse_link(path)?;
            let start = self.offset == 0;
            let mut file = OpenOptions::new()
                .write(true)
                .create(start)
                .truncate(start)
                .open(path)?;
            let length = file.metadata()?.len();
            if length != self.offset {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    format!(
                        "the file has {length} bytes where the run wrote {}: another program \
                         changed it",
                        self.offset
                    ),
                ));
            }
            file.seek(SeekFrom::Start(self.offset))?;
            file.write_all(&self.bytes)
        };
        write().map_err(|e| Error::io(path, e))
    }
}

/// A symbolic link is never written through.
fn refuse_link(path: &Path) -> io::Result<()> {
    match path.symlink_metadata() {
        Ok(m) if m.file_type().is_symlink() => Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "it is a symbolic link; a run never writes through one",
        )),
        _ => Ok(()),
    }
}

/// Why `path` cannot be continued at `mark`, or `None` when its first `mark.length` bytes
/// have the mark's checksum.
pub fn check(path: &Path, mark: FileMark) -> Result<Option<String>> {
    let mut file = match File::open(path) {
        Ok(file) => file,
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            return Ok((mark.length > 0).then(|| "the file is missing".into()));
        }
        Err(e) => return Err(Error::io(path, e)),
    };
    let length = file.metadata().map_err(|e| Error::io(path, e))?.len();
    if length < mark.length {
        return Ok(Some(format!(
            "it has {length} bytes, fewer than the {} the restart record counts: it was \
             changed after the record was written",
            mark.length
        )));
    }
    let mut crc = crc32fast::Hasher::new();
    let mut buffer = vec![0; 1 << 16];
    let mut left = mark.length;
    while left > 0 {
        let chunk = &mut buffer[..left.min(1 << 16) as usize];
        file.read_exact(chunk).map_err(|e| Error::io(path, e))?;
        crc.update(chunk);
        left -= chunk.len() as u64;
    }
    Ok((crc.finalize() != mark.crc).then(|| {
        format!(
            "its first {} bytes differ from those the restart record counts: it was changed \
             after the record was written",
            mark.length
        )
    }))
}

/// Cuts `path` to the length of `mark` (checked with [`check`]): what a run appended after
/// its record, or the partial last line of a run killed while appending.
pub fn truncate(path: &Path, mark: FileMark) -> Result<()> {
    if mark.length == 0 && !path.exists() {
        return Ok(());
    }
    let cut = || -> io::Result<()> {
        refuse_link(path)?;
        OpenOptions::new()
            .write(true)
            .open(path)?
            .set_len(mark.length)
    };
    cut().map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn appends_continue_a_file_that_is_checked_and_cut_back_to_its_mark() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        let mut file = AppendedFile::default();
        file.push(b"x,y\n");
        file.push(b"1,2\n");
        file.take().unwrap().write(&path).unwrap();
        assert!(file.take().is_none());
        let mark = file.mark();
        assert_eq!(mark.length, 8);
        assert_eq!(mark.crc, crc32fast::hash(b"x,y\n1,2\n"));
        // Rows after the mark and a partial line are cut off; the file goes on from there.
        let mut later = file.clone();
        later.push(b"3,4\n");
        later.take().unwrap().write(&path).unwrap();
        std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .unwrap()
            .write_all(b"5,")
            .unwrap();
        assert_eq!(check(&path, mark).unwrap(), None);
        truncate(&path, mark).unwrap();
        let mut resumed = AppendedFile::continued(mark);
        resumed.push(b"3,4\n");
        resumed.take().unwrap().write(&path).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"x,y\n1,2\n3,4\n");
        assert_eq!(resumed.mark(), later.mark());
        // A changed byte, a shorter or missing file are found.
        std::fs::write(&path, b"x,y\n1,3\n").unwrap();
        assert!(check(&path, mark).unwrap().unwrap().contains("differ"));
        std::fs::write(&path, b"x,y\n").unwrap();
        assert!(check(&path, mark).unwrap().unwrap().contains("fewer"));
        std::fs::remove_file(&path).unwrap();
        assert!(check(&path, mark).unwrap().unwrap().contains("missing"));
    }

    #[test]
    fn an_append_to_a_file_of_another_length_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("h.csv");
        std::fs::write(&path, b"x\n1\n2\n").unwrap();
        let append = Append {
            offset: 4,
            bytes: b"3\n".to_vec(),
        };
        let err = append.write(&path).unwrap_err().to_string();
        assert!(err.contains("h.csv") && err.contains("6 bytes"), "{err}");
        let mut first = Append {
            offset: 0,
            bytes: b"x\n".to_vec(),
        };
        assert!(first.extend(append.clone()).is_err());
        first
            .extend(Append {
                offset: 2,
                bytes: b"1\n".to_vec(),
            })
            .unwrap();
        assert_eq!(first.bytes, b"x\n1\n");
        // The first append starts the file anew (a folder reused by a study's level).
        first.write(&path).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"x\n1\n");
    }
}
