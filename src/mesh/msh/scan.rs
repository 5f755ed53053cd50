//! A byte-level scanner of MSH 4.1 files beside mshio: the `$MeshFormat` header, the
//! `$Nodes`/`$Elements` section headers, node tags and `$PhysicalNames`. mshio 0.4 panics on
//! some malformed headers and drops dense node tags, so these parts are read here first (see
//! the parent module).

use std::collections::HashMap;

use super::Fault;
use crate::error::{MeshEntity, MeshProblem};

const HEADER: Option<MeshEntity> = Some(MeshEntity::Section("$MeshFormat"));

/// Whether the file looks cut short: a complete MSH file ends with a `$End...` line. Lets
/// the parse error say "truncated" rather than leave the user guessing.
pub(super) fn looks_truncated(bytes: &[u8]) -> bool {
    let body = trim(bytes);
    let last_line = body
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(body, |i| &body[i + 1..]);
    !last_line.starts_with(b"$End")
}

/// What we need of the `$MeshFormat` header.
#[derive(Debug)]
pub(super) struct Header {
    /// `None` for ascii files, otherwise the binary number layout.
    pub(super) binary: Option<Binary>,
    /// Offset just after `$EndMeshFormat`.
    pub(super) body_start: usize,
}

/// Number layout of a binary MSH file (ints are 4 bytes, doubles 8).
#[derive(Clone, Copy, Debug)]
pub(super) struct Binary {
    size_t: usize,
    little_endian: bool,
}

/// Reads and checks the `$MeshFormat` header. Doing this before mshio gives precise messages
/// (MSH 2.2, not an MSH file) and avoids mshio's panics on unusual `size_t` sizes.
pub(super) fn read_header(bytes: &[u8]) -> Result<Header, Fault> {
    let bad = |message: String| Fault::new(MeshProblem::Header, HEADER, message);
    let incomplete = || {
        Fault::new(
            MeshProblem::Truncated,
            HEADER,
            "the $MeshFormat header is incomplete (truncated file?)",
        )
    };
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(0);
    let line_end = |from: usize| {
        bytes[from..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| from + i)
    };
    let first_end = line_end(start);
    if trim(&bytes[start..first_end]) != b"$MeshFormat" {
        return Err(bad(
            "not a gmsh MSH file (it does not start with $MeshFormat)".into(),
        ));
    }
    let second = (first_end + 1).min(bytes.len());
    let second_end = line_end(second);
    let text = String::from_utf8_lossy(&bytes[second..second_end]);
    let fields: Vec<&str> = text.split_whitespace().collect();
    if fields.len() < 3 {
        return Err(incomplete());
    }
    let version = fields[0];
    if version != "4.1" {
        let kind = if version.starts_with('2') {
            format!("MSH {version}")
        } else {
            format!("MSH version {version}")
        };
        return Err(Fault::new(
            MeshProblem::Version,
            HEADER,
            format!(
                "{kind} is not supported: re-mesh with gmsh -format msh41 or \
                 Mesh.MshFileVersion = 4.1"
            ),
        ));
    }
    // gmsh writes sizeof(size_t), 8 (or 4 on 32-bit systems); mshio reads the value into
    // an i32 and an unchecked one could overflow there.
    let size_t = match fields[2] {
        "4" => 4,
        "8" => 8,
        other => {
            return Err(bad(format!(
                "invalid data size `{other}` in the $MeshFormat header (gmsh writes 8, or 4)"
            )));
        }
    };
    let mut pos = (second_end + 1).min(bytes.len());
    let binary = match fields[1] {
        "0" => None,
        "1" => {
            let one: [u8; 4] = bytes
                .get(pos..pos + 4)
                .and_then(|b| b.try_into().ok())
                .ok_or_else(incomplete)?;
            let little_endian = if i32::from_le_bytes(one) == 1 {
                true
            } else if i32::from_be_bytes(one) == 1 {
                false
            } else {
                return Err(bad(
                    "cannot detect the byte order of the binary MSH file".into()
                ));
            };
            pos += 4;
            Some(Binary {
                size_t,
                little_endian,
            })
        }
        other => {
            return Err(bad(format!(
                "invalid file type `{other}` in the $MeshFormat header (0 ascii, 1 binary)"
            )));
        }
    };
    let end = find_line(bytes, pos, b"$EndMeshFormat").ok_or_else(|| {
        Fault::new(
            MeshProblem::Truncated,
            HEADER,
            "the $MeshFormat header has no $EndMeshFormat (truncated file?)",
        )
    })?;
    Ok(Header {
        binary,
        body_start: end,
    })
}

/// The node tags of one block of the `$Nodes` section, with the block's entity (to check
/// that they describe the same block as mshio's).
pub(super) struct NodeTags {
    pub(super) dim: i32,
    pub(super) entity: i32,
    pub(super) tags: Vec<u64>,
}

impl NodeTags {
    pub(super) fn len(&self) -> usize {
        self.tags.len()
    }
}

/// Reads `$PhysicalNames` (`count`, then lines `dim tag "name"`) into a map (dim, tag) → name.
/// The section is optional; it is ASCII even in binary files.
pub(super) fn read_physical_names(
    bytes: &[u8],
    from: usize,
) -> Result<HashMap<(u8, i32), String>, Fault> {
    let fault = |message: String| {
        Fault::new(
            MeshProblem::PhysicalNames,
            Some(MeshEntity::Section("$PhysicalNames")),
            message,
        )
    };
    let mut names = HashMap::new();
    let Some(start) = find_line(bytes, from, b"$PhysicalNames") else {
        return Ok(names);
    };
    let end = find_line(bytes, start, b"$EndPhysicalNames")
        .ok_or_else(|| fault("the $PhysicalNames section has no $EndPhysicalNames".into()))?;
    // `end` is just after the end tag line: cut the tag line off.
    let body = &bytes[start..end];
    let body = &body[..body.len() - trailing_line_len(body)];
    let text = String::from_utf8_lossy(body);
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let count: usize = lines.next().and_then(|l| l.parse().ok()).ok_or_else(|| {
        fault("the $PhysicalNames section does not start with the number of names".into())
    })?;
    let mut found = 0;
    for line in lines {
        let bad = || {
            fault(format!(
                "malformed $PhysicalNames line `{line}` (expected: dim tag \"name\")"
            ))
        };
        let mut fields = line.splitn(3, char::is_whitespace);
        let dim: u8 = fields.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
        let tag: i32 = fields
            .next()
            .and_then(|s| s.trim().parse().ok())
            .ok_or_else(bad)?;
        let name = fields.next().map(str::trim).ok_or_else(bad)?;
        let name = name
            .strip_prefix('"')
            .and_then(|n| n.strip_suffix('"'))
            .ok_or_else(bad)?;
        names.insert((dim, tag), name.to_string());
        found += 1;
    }
    if found != count {
        return Err(fault(format!(
            "the $PhysicalNames section announces {count} names but contains {found}"
        )));
    }
    Ok(names)
}

/// Length of the last line of `body` including its line break (the `$End...` tag line).
pub(super) fn trailing_line_len(body: &[u8]) -> usize {
    let without_break = body.strip_suffix(b"\n").unwrap_or(body);
    match without_break.iter().rposition(|&b| b == b'\n') {
        Some(i) => body.len() - i - 1,
        None => body.len(),
    }
}

/// Offset just after the first line, at or after `from`, that is exactly `tag` (optionally
/// surrounded by blanks). Section tags always start a line; in binary files a false match
/// inside binary data is astronomically unlikely, and the node tags read from the match are
/// cross-checked against mshio's node blocks anyway.
pub(super) fn find_line(bytes: &[u8], from: usize, tag: &[u8]) -> Option<usize> {
    let mut line_start = from.min(bytes.len());
    while line_start < bytes.len() {
        let line_end = bytes[line_start..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| line_start + i);
        if trim(&bytes[line_start..line_end]) == tag {
            return Some((line_end + 1).min(bytes.len()));
        }
        line_start = line_end + 1;
    }
    None
}

/// `line` without leading and trailing ASCII whitespace (including `\r`).
pub(super) fn trim(line: &[u8]) -> &[u8] {
    let start = line
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(line.len());
    let end = line
        .iter()
        .rposition(|b| !b.is_ascii_whitespace())
        .map_or(start, |i| i + 1);
    &line[start..end]
}

/// A minimal reader of MSH numbers, ascii (whitespace-separated tokens) or binary.
pub(super) struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    binary: Option<Binary>,
}

impl<'a> Cursor<'a> {
    /// A cursor at offset `pos` of `bytes`, reading ascii numbers, or binary ones laid out as
    /// `binary` says.
    pub(super) fn new(bytes: &'a [u8], pos: usize, binary: Option<Binary>) -> Self {
        Self { bytes, pos, binary }
    }

    pub(super) fn is_binary(&self) -> bool {
        self.binary.is_some()
    }

    /// Bytes left after the cursor.
    pub(super) fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    /// Size of a binary `size_t` (8 for ascii files, where it does not matter).
    pub(super) fn size_t_bytes(&self) -> usize {
        self.binary.map_or(8, |b| b.size_t)
    }

    /// Next whitespace-separated ascii token.
    fn token(&mut self) -> Option<&[u8]> {
        let rest = self.bytes.get(self.pos..)?;
        let start = rest.iter().position(|b| !b.is_ascii_whitespace())?;
        let len = rest[start..]
            .iter()
            .position(u8::is_ascii_whitespace)
            .unwrap_or(rest.len() - start);
        self.pos += start + len;
        Some(&rest[start..start + len])
    }

    /// Next `n` raw bytes (binary files).
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let slice = self.bytes.get(self.pos..self.pos.checked_add(n)?)?;
        self.pos += n;
        Some(slice)
    }

    pub(super) fn size_t(&mut self) -> Option<u64> {
        match self.binary {
            None => std::str::from_utf8(self.token()?).ok()?.parse().ok(),
            Some(b) => {
                let raw = self.take(b.size_t)?;
                let mut buf = [0u8; 8];
                if b.little_endian {
                    buf[..raw.len()].copy_from_slice(raw);
                    Some(u64::from_le_bytes(buf))
                } else {
                    buf[8 - raw.len()..].copy_from_slice(raw);
                    Some(u64::from_be_bytes(buf))
                }
            }
        }
    }

    pub(super) fn int(&mut self) -> Option<i64> {
        match self.binary {
            None => std::str::from_utf8(self.token()?).ok()?.parse().ok(),
            Some(b) => {
                let raw: [u8; 4] = self.take(4)?.try_into().ok()?;
                Some(i64::from(if b.little_endian {
                    i32::from_le_bytes(raw)
                } else {
                    i32::from_be_bytes(raw)
                }))
            }
        }
    }

    pub(super) fn skip_doubles(&mut self, n: usize) -> Option<()> {
        match self.binary {
            None => {
                for _ in 0..n {
                    self.token()?;
                }
            }
            Some(_) => {
                self.take(n.checked_mul(8)?)?;
            }
        }
        Some(())
    }
}

/// Map from gmsh node tag to node index. A flat vector when the tags are dense enough (the
/// common case: one array read per element node instead of a hash lookup), a hash map
/// otherwise (e.g. a few nodes with huge tags).
pub(super) enum TagIndex {
    Dense { min: u64, index: Vec<u32> },
    Sparse(HashMap<u64, u32>),
}

impl TagIndex {
    const NONE: u32 = u32::MAX;

    pub(super) fn new(tags: &[u64]) -> Result<Self, Fault> {
        let duplicate = |t: u64| {
            Fault::new(
                MeshProblem::DuplicateNode,
                Some(MeshEntity::Node(t)),
                format!("node tag {t} appears twice in the $Nodes section"),
            )
        };
        let (Some(&min), Some(&max)) = (tags.iter().min(), tags.iter().max()) else {
            return Ok(TagIndex::Dense {
                min: 0,
                index: Vec::new(),
            });
        };
        let span = max - min;
        if span <= 2 * tags.len() as u64 + 1024 {
            let mut index = vec![Self::NONE; span as usize + 1];
            for (i, &t) in tags.iter().enumerate() {
                let slot = &mut index[(t - min) as usize];
                if *slot != Self::NONE {
                    return Err(duplicate(t));
                }
                *slot = i as u32;
            }
            Ok(TagIndex::Dense { min, index })
        } else {
            let mut index = HashMap::with_capacity(tags.len());
            for (i, &t) in tags.iter().enumerate() {
                if index.insert(t, i as u32).is_some() {
                    return Err(duplicate(t));
                }
            }
            Ok(TagIndex::Sparse(index))
        }
    }

    pub(super) fn get(&self, tag: u64) -> Option<u32> {
        match self {
            TagIndex::Dense { min, index } => {
                let i = *index.get(usize::try_from(tag.checked_sub(*min)?).ok()?)?;
                (i != Self::NONE).then_some(i)
            }
            TagIndex::Sparse(map) => map.get(&tag).copied(),
        }
    }
}
