//! VTK XML unstructured grids (`.vtu`): written by hand with raw appended binary data, and
//! read back ([`read_vtu`]) for the tests.
//!
//! Layout of the files written here, chosen for ParaView ≥ 5 / VTK ≥ 9 and pyvista:
//! - `version="1.0"`, `header_type="UInt64"`, `byte_order="LittleEndian"`: VTK's current
//!   defaults.
//! - An XML head whose `<DataArray>`s are all `format="appended"` with an `offset`, then
//!   `<AppendedData encoding="raw">`, an underscore, and the arrays' bytes back to back, in
//!   the order of the head: each array is an 8-byte little-endian byte count followed by its
//!   values in little-endian order. No compression, no base64. The file is `</AppendedData>
//!   </VTKFile>`-terminated as VTK's own writer does.
//! - Points `Float64` with z = 0; connectivity and offsets `UInt64`; types `UInt8`.
//! - Point and cell arrays keep their type (`Float64` or `Int32`) and component count. The
//!   first 1-component array is tagged as the active `Scalars`, the first 3-component one
//!   as the active `Vectors`; a 6-component one is left generic because VTK's XML has no
//!   symmetric-tensor tag (`Tensors` means 9 components); ParaView recognises 6 components
//!   as a symmetric tensor in VTK's order xx, yy, zz, xy, yz, xz.
//!
//! Everything is validated before anything is written, so an invalid grid produces an error
//! naming the array and index, and no file.
//!
//! # Why raw appended data
//! The previous writer (vtkio: inline base64 of zlib-compressed blocks) spent ~0.5 s per
//! step on a 176k-unknown model (88k nodes), nearly all in zlib and base64 over every byte.
//! Results are doubles with noisy low bits, which compress poorly (zlib level 1 saved ~38 %,
//! mostly on the zero components), so the raw layout costs 1.6× the disk and writes at
//! memory/disk speed: 0.02 s for that step's 12 MB. VTK's reader, hence ParaView and
//! pyvista, reads it natively.

use std::collections::HashSet;
use std::fmt::Write as _;
use std::path::Path;

use super::atomic::{invalid_data, write_bytes};
use super::pvd::escape_attr;
use super::{Attachment, Field, FieldValues, Grid, GridView};
use crate::Result;

/// Bytes of the per-array size header (`header_type="UInt64"`).
const HEADER_BYTES: usize = 8;

/// Writes `grid` to `path` as a VTK XML unstructured grid with raw appended data
/// (atomically, creating the parent directory).
///
/// Fails, writing nothing, if the grid is inconsistent: an offset or cell type list of the
/// wrong length, a connectivity index out of range, a cell whose node count does not fit
/// its type, a field whose length is not `components × points` (or cells), a duplicate or
/// empty field name, or a NaN/infinite coordinate or value. The error names the array and
/// the first bad index.
pub fn write_vtu(path: &Path, grid: &Grid) -> Result<()> {
    write_vtu_with(path, GridView::whole(grid), &mut Vec::new())
}

/// [`write_vtu`] of what `view` holds of a grid (the whole grid or one part of it, read
/// through the part's indices: no copy of the grid), encoding the whole file into `buffer`
/// first (cleared; kept for the next file by a caller writing many), then writing it with
/// one call: no write buffer, no staging copy, and no fresh memory per file.
pub fn write_vtu_with(path: &Path, view: GridView, buffer: &mut Vec<u8>) -> Result<()> {
    encode_vtu(path, view, buffer)?;
    write_bytes(path, buffer)
}

/// The whole file [`write_vtu_with`] writes to `path`, encoded into `buffer` (cleared), or
/// why it cannot be written (naming `path`).
pub(crate) fn encode_vtu(path: &Path, view: GridView, buffer: &mut Vec<u8>) -> Result<()> {
    validate(&view).map_err(|msg| invalid_data(path, msg))?;
    let head = head(&view);
    buffer.clear();
    buffer.reserve(
        head.len()
            + arrays(view.grid)
                .map(|a| HEADER_BYTES + a.data_bytes(&view))
                .sum::<usize>(),
    );
    buffer.extend_from_slice(head.as_bytes());
    for array in arrays(view.grid) {
        array.encode_data(&view, buffer);
    }
    buffer.extend_from_slice(b"\n</AppendedData>\n</VTKFile>\n");
    Ok(())
}

/// One `<DataArray>` of the file.
#[derive(Clone, Copy)]
enum Array<'a> {
    Field(&'a Field, Attachment),
    Points,
    Connectivity,
    Offsets,
    Types,
}

/// The arrays of `grid` in file order: field data, point data, cell data, points, cells.
fn arrays(grid: &Grid) -> impl Iterator<Item = Array<'_>> {
    fn attached(fields: &[Field], at: Attachment) -> impl Iterator<Item = Array<'_>> {
        fields.iter().map(move |f| Array::Field(f, at))
    }
    attached(&grid.field_data, Attachment::None)
        .chain(attached(&grid.point_data, Attachment::Points))
        .chain(attached(&grid.cell_data, Attachment::Cells))
        .chain([
            Array::Points,
            Array::Connectivity,
            Array::Offsets,
            Array::Types,
        ])
}

impl Array<'_> {
    /// (Name, VTK type, components, number of values) in the file of `view`.
    fn describe<'g>(&'g self, view: &GridView<'g>) -> (&'g str, &'static str, usize, usize) {
        let cells = view.topology();
        match self {
            Array::Field(f, at) => {
                let n = f.components * view.tuple_count(f.len(), f.components, *at);
                match &f.values {
                    FieldValues::F64(_) => (&f.name, "Float64", f.components, n),
                    FieldValues::I32(_) => (&f.name, "Int32", f.components, n),
                    FieldValues::Str(_) => (&f.name, "String", f.components, n),
                }
            }
            Array::Points => ("Points", "Float64", 3, 3 * view.point_count()),
            Array::Connectivity => ("connectivity", "UInt64", 1, cells.connectivity.len()),
            Array::Offsets => ("offsets", "UInt64", 1, cells.offsets.len()),
            Array::Types => ("types", "UInt8", 1, cells.cell_types.len()),
        }
    }

    /// Bytes of the values (without the size header). Strings are written as VTK does,
    /// each followed by a NUL byte.
    fn data_bytes(&self, view: &GridView) -> usize {
        if let Array::Field(
            Field {
                values: FieldValues::Str(v),
                ..
            },
            _,
        ) = self
        {
            return v.iter().map(|s| s.len() + 1).sum();
        }
        let (_, ty, _, n) = self.describe(view);
        n * scalar_size(ty)
    }

    /// The `<DataArray .../>` tag pointing at `offset` in the appended data. Field data
    /// arrays state their `NumberOfTuples` (VTK cannot infer it from a point or cell count).
    fn tag(&self, view: &GridView, offset: usize, field_data: bool) -> String {
        let (name, ty, components, n) = self.describe(view);
        let mut tag = format!("<DataArray type=\"{ty}\" Name=\"{}\"", escape_attr(name));
        if components != 1 {
            let _ = write!(tag, " NumberOfComponents=\"{components}\"");
        }
        if field_data {
            let _ = write!(tag, " NumberOfTuples=\"{}\"", n / components);
        }
        if let Array::Field(f, _) = self {
            for (i, c) in f.component_names.iter().enumerate() {
                let _ = write!(tag, " ComponentName{i}=\"{}\"", escape_attr(c));
            }
        }
        let _ = writeln!(tag, " format=\"appended\" offset=\"{offset}\"/>");
        tag
    }

    /// Appends the array's size header and values (little-endian) to `out`.
    fn encode_data(&self, view: &GridView, out: &mut Vec<u8>) {
        out.extend_from_slice(&(self.data_bytes(view) as u64).to_le_bytes());
        let cells = view.topology();
        match self {
            Array::Field(f, at) => {
                let n = f.components;
                match &f.values {
                    FieldValues::F64(v) => encode_le(out, view, (v, n, *at), |x| x.to_le_bytes()),
                    FieldValues::I32(v) => encode_le(out, view, (v, n, *at), |x| x.to_le_bytes()),
                    FieldValues::Str(v) => v.iter().for_each(|s| {
                        out.extend_from_slice(s.as_bytes());
                        out.push(0);
                    }),
                }
            }
            Array::Points => {
                let points = (&view.grid.points[..], 1, Attachment::Points);
                encode_le(out, view, points, |&[x, y]| {
                    let mut b = [0u8; 24];
                    b[..8].copy_from_slice(&x.to_le_bytes());
                    b[8..16].copy_from_slice(&y.to_le_bytes());
                    b
                })
            }
            // The view's own cells: every value (attached to nothing the view selects).
            Array::Connectivity => {
                let connectivity = (&cells.connectivity[..], 1, Attachment::None);
                encode_le(out, view, connectivity, |x| x.to_le_bytes())
            }
            Array::Offsets => {
                let offsets = (&cells.offsets[..], 1, Attachment::None);
                encode_le(out, view, offsets, |x| x.to_le_bytes())
            }
            Array::Types => out.extend_from_slice(&cells.cell_types),
        }
    }
}

/// Appends the tuples `view` holds of `values` (`n` components each, attached as `at`),
/// converted by `bytes` (independent of the host's byte order).
fn encode_le<T, const N: usize>(
    out: &mut Vec<u8>,
    view: &GridView,
    (values, n, at): (&[T], usize, Attachment),
    bytes: impl Fn(&T) -> [u8; N],
) {
    view.for_each_tuple(values, n, at, |tuple| {
        for v in tuple {
            out.extend_from_slice(&bytes(v));
        }
    });
}

/// Size in bytes of a VTK scalar type written or read here.
fn scalar_size(ty: &str) -> usize {
    match ty {
        "Int8" | "UInt8" => 1,
        "Int16" | "UInt16" => 2,
        "Int32" | "UInt32" | "Float32" => 4,
        _ => 8,
    }
}

/// The XML up to and including the `_` that starts the appended data.
fn head(view: &GridView) -> String {
    let grid = view.grid;
    let mut offset = 0;
    let mut tags = Vec::new();
    for (i, a) in arrays(grid).enumerate() {
        tags.push(a.tag(view, offset, i < grid.field_data.len()));
        offset += HEADER_BYTES + a.data_bytes(view);
    }
    let (field_tags, rest) = tags.split_at(grid.field_data.len());
    let (point_tags, rest) = rest.split_at(grid.point_data.len());
    let (cell_tags, rest) = rest.split_at(grid.cell_data.len());
    let mut head = String::from("<?xml version=\"1.0\"?>\n");
    let _ = write!(
        head,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">\n<UnstructuredGrid>\n",
    );
    if !field_tags.is_empty() {
        head.push_str("<FieldData>\n");
        field_tags.iter().for_each(|t| head.push_str(t));
        head.push_str("</FieldData>\n");
    }
    let _ = writeln!(
        head,
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        view.point_count(),
        view.cell_count(),
    );
    for (tag, fields, tags) in [
        ("PointData", &grid.point_data, point_tags),
        ("CellData", &grid.cell_data, cell_tags),
    ] {
        let _ = writeln!(head, "<{tag}{}>", active_attributes(fields));
        tags.iter().for_each(|t| head.push_str(t));
        let _ = writeln!(head, "</{tag}>");
    }
    head.push_str("<Points>\n");
    head.push_str(&rest[0]);
    head.push_str("</Points>\n<Cells>\n");
    rest[1..].iter().for_each(|t| head.push_str(t));
    head.push_str("</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_");
    head
}

/// The `Scalars="..." Vectors="..."` attributes of a `PointData`/`CellData` element: the
/// first 1- and 3-component arrays, which ParaView colours by / glyphs by default.
fn active_attributes(fields: &[Field]) -> String {
    let mut out = String::new();
    for (attr, n) in [("Scalars", 1), ("Vectors", 3)] {
        if let Some(f) = fields.iter().find(|f| f.components == n) {
            let _ = write!(out, " {attr}=\"{}\"", escape_attr(&f.name));
        }
    }
    out
}

/// Reads a `.vtu` file as written by [`write_vtu`]: one piece, every array
/// `format="appended"` in raw appended data with `UInt64` headers, uncompressed,
/// little-endian. 2D points (z is dropped).
///
/// Point, cell and field data arrays of type `Float64` become [`FieldValues::F64`], `Int32`
/// ones [`FieldValues::I32`], `String` ones (field data only) [`FieldValues::Str`];
/// component names are kept. Every size header is checked against the array's declared length,
/// so a file whose layout differs from the head fails with an error naming the array.
pub fn read_vtu(path: &Path) -> Result<Grid> {
    let bytes = std::fs::read(path).map_err(|e| crate::Error::io(path, e))?;
    parse_vtu(&bytes).map_err(|msg| invalid_data(path, msg))
}

/// An XML start tag: its name and attributes (values unescaped).
struct Tag {
    name: String,
    attrs: Vec<(String, String)>,
}

impl Tag {
    fn get(&self, key: &str) -> std::result::Result<&str, String> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
            .ok_or_else(|| format!("<{}> has no `{key}` attribute", self.name))
    }
}

/// The start tags (`<Name a="b" ...>` or `<Name .../>`) of the XML `text`; closing tags,
/// the declaration and comments are skipped.
fn start_tags(text: &str) -> std::result::Result<Vec<Tag>, String> {
    let mut tags = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find('<') {
        let end = rest[i..].find('>').ok_or("unterminated XML tag")? + i;
        let body = &rest[i + 1..end];
        rest = &rest[end + 1..];
        if body.starts_with(['/', '?', '!']) {
            continue;
        }
        let body = body.strip_suffix('/').unwrap_or(body);
        let name_end = body.find(char::is_whitespace).unwrap_or(body.len());
        let mut tag = Tag {
            name: body[..name_end].to_string(),
            attrs: Vec::new(),
        };
        let mut a = body[name_end..].trim_start();
        while !a.is_empty() {
            let eq = a.find('=').ok_or("attribute without `=`")?;
            let key = a[..eq].trim().to_string();
            let v = a[eq + 1..].trim_start();
            let quote = v.chars().next().ok_or("attribute without value")?;
            let close = v[1..].find(quote).ok_or("unterminated attribute value")?;
            tag.attrs.push((key, unescape(&v[1..1 + close])));
            a = v[close + 2..].trim_start();
        }
        tags.push(tag);
    }
    Ok(tags)
}

/// Inverse of [`escape_attr`].
fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

/// [`read_vtu`] on the file's bytes.
fn parse_vtu(bytes: &[u8]) -> std::result::Result<Grid, String> {
    const MARK: &[u8] = b"<AppendedData encoding=\"raw\">";
    let at = bytes
        .windows(MARK.len())
        .position(|w| w == MARK)
        .ok_or("no raw <AppendedData> element")?;
    let head = std::str::from_utf8(&bytes[..at]).map_err(|e| format!("XML head: {e}"))?;
    let underscore = bytes[at + MARK.len()..]
        .iter()
        .position(|&b| b == b'_')
        .ok_or("no `_` starting the appended data")?;
    let data = &bytes[at + MARK.len() + underscore + 1..];

    let tags = start_tags(head)?;
    let file = tags
        .iter()
        .find(|t| t.name == "VTKFile")
        .ok_or("no <VTKFile>")?;
    for (key, want) in [
        ("type", "UnstructuredGrid"),
        ("byte_order", "LittleEndian"),
        ("header_type", "UInt64"),
    ] {
        if file.get(key)? != want {
            return Err(format!("<VTKFile> {key} is not {want}"));
        }
    }
    if file.attrs.iter().any(|(k, _)| k == "compressor") {
        return Err("compressed data is not supported".into());
    }
    let pieces: Vec<&Tag> = tags.iter().filter(|t| t.name == "Piece").collect();
    let [piece] = pieces[..] else {
        return Err(format!("expected 1 piece, found {}", pieces.len()));
    };
    let count = |key| -> std::result::Result<usize, String> {
        piece
            .get(key)?
            .parse()
            .map_err(|e| format!("Piece {key}: {e}"))
    };
    let (n_points, n_cells) = (count("NumberOfPoints")?, count("NumberOfCells")?);

    let mut grid = Grid::default();
    let mut section = "";
    for tag in &tags {
        if tag.name != "DataArray" {
            section = match tag.name.as_str() {
                s @ ("FieldData" | "PointData" | "CellData" | "Points" | "Cells") => s,
                _ => section,
            };
            continue;
        }
        let name = tag.get("Name")?.to_string();
        let ty = tag.get("type")?;
        let components: usize = match tag.get("NumberOfComponents") {
            Ok(c) => c
                .parse()
                .map_err(|e| format!("array `{name}` components: {e}"))?,
            Err(_) => 1,
        };
        if tag.get("format")? != "appended" {
            return Err(format!("array `{name}` is not appended"));
        }
        let offset: usize = tag
            .get("offset")?
            .parse()
            .map_err(|e| format!("array `{name}` offset: {e}"))?;
        let component_names: Vec<String> = (0..components)
            .map_while(|i| tag.get(&format!("ComponentName{i}")).ok().map(String::from))
            .collect();
        let tuples = match section {
            "PointData" | "Points" => n_points,
            "FieldData" => tag
                .get("NumberOfTuples")?
                .parse()
                .map_err(|e| format!("array `{name}` NumberOfTuples: {e}"))?,
            _ if name == "connectivity" => usize::MAX, // checked against the header below
            _ => n_cells,
        };
        let raw = array_bytes(data, offset, &name)?;
        if (section, ty) == ("FieldData", "String") {
            let strings = string_values(raw, &name)?;
            if strings.len() != tuples * components {
                return Err(format!(
                    "array `{name}`: {} strings for {tuples} × {components}",
                    strings.len()
                ));
            }
            grid.field_data.push(Field {
                name,
                components,
                component_names,
                values: FieldValues::Str(strings),
            });
            continue;
        }
        let size = scalar_size(ty);
        if raw.len() % size != 0
            || (tuples != usize::MAX && raw.len() != tuples * components * size)
        {
            return Err(format!(
                "array `{name}`: {} bytes do not hold {tuples} × {components} {ty}",
                raw.len()
            ));
        }
        let f64s = || -> Vec<f64> {
            raw.chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
                .collect()
        };
        let u64s = || -> Vec<u64> {
            raw.chunks_exact(8)
                .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
                .collect()
        };
        match (section, ty) {
            ("Points", "Float64") if components == 3 => {
                grid.points = f64s().chunks_exact(3).map(|p| [p[0], p[1]]).collect();
            }
            ("Cells", "UInt64") if name == "connectivity" => grid.connectivity = u64s(),
            ("Cells", "UInt64") if name == "offsets" => grid.offsets = u64s(),
            ("Cells", "UInt8") if name == "types" => grid.cell_types = raw.to_vec(),
            ("FieldData" | "PointData" | "CellData", "Float64" | "Int32") => {
                let values = if ty == "Float64" {
                    FieldValues::F64(f64s())
                } else {
                    FieldValues::I32(
                        raw.chunks_exact(4)
                            .map(|b| i32::from_le_bytes(b.try_into().expect("4 bytes")))
                            .collect(),
                    )
                };
                let field = Field {
                    name,
                    components,
                    component_names,
                    values,
                };
                match section {
                    "FieldData" => grid.field_data.push(field),
                    "PointData" => grid.point_data.push(field),
                    _ => grid.cell_data.push(field),
                }
            }
            _ => return Err(format!("unexpected {ty} array `{name}` in <{section}>")),
        }
    }
    if grid.points.len() != n_points || grid.cell_types.len() != n_cells {
        return Err("points or cell types missing or of the wrong length".into());
    }
    Ok(grid)
}

/// The NUL-terminated strings of a `String` array's bytes.
fn string_values(raw: &[u8], name: &str) -> std::result::Result<Vec<String>, String> {
    let Some(body) = raw.strip_suffix(&[0]) else {
        return Err(format!("string array `{name}` does not end with NUL"));
    };
    if body.is_empty() && raw.len() == 1 {
        return Ok(vec![String::new()]);
    }
    body.split(|&b| b == 0)
        .map(|s| String::from_utf8(s.to_vec()).map_err(|e| format!("string array `{name}`: {e}")))
        .collect()
}

/// The values of the appended array at `offset`: after its 8-byte size header.
fn array_bytes<'d>(
    data: &'d [u8],
    offset: usize,
    name: &str,
) -> std::result::Result<&'d [u8], String> {
    let header = data
        .get(offset..offset + HEADER_BYTES)
        .ok_or_else(|| format!("array `{name}`: offset {offset} is past the data"))?;
    let len = u64::from_le_bytes(header.try_into().expect("8 bytes")) as usize;
    data.get(offset + HEADER_BYTES..offset + HEADER_BYTES + len)
        .ok_or_else(|| format!("array `{name}`: {len} bytes run past the data"))
}

/// Number of nodes of the fixed-size VTK cell types; `None` for variable ones (poly-line,
/// polygon, ...) which are not checked. VTK's numbering (vtkCellType.h).
fn nodes_of(cell: u8) -> Option<u64> {
    Some(match cell {
        1 => 1,       // vertex
        3 => 2,       // line
        5 => 3,       // triangle
        8..=10 => 4,  // pixel, quad, tetra
        14 => 5,      // pyramid
        13 => 6,      // wedge
        11 | 12 => 8, // voxel, hexahedron
        21 => 3,      // quadratic edge
        22 | 30 => 6, // quadratic triangle, quadratic-linear quad
        34 => 7,      // biquadratic triangle
        23 => 8,      // quadratic quad
        28 => 9,      // biquadratic quad
        24 => 10,     // quadratic tetra
        25 => 20,     // quadratic hexahedron
        _ => return None,
    })
}

/// Whether `t` is a VTK cell type number (vtkCellType.h; the same set vtkio knew).
fn known_cell_type(t: u8) -> bool {
    matches!(t, 1..=14 | 21..=35 | 41 | 42 | 51..=56 | 60..=81)
}
/// Checks `grid` as documented on [`write_vtu`].
fn validate(view: &GridView) -> std::result::Result<(), String> {
    let grid = view.grid;
    if !view.fits() {
        return Err(format!(
            "the grid's {} points and {} cells are not those its division into files was made for",
            grid.points.len(),
            grid.cell_count()
        ));
    }
    let cells = view.topology();
    let n_points = view.point_count();
    let n_cells = cells.cell_types.len();
    if u32::try_from(n_points).is_err() || u32::try_from(n_cells).is_err() {
        return Err(format!(
            "{n_points} points / {n_cells} cells exceed VTK's 32-bit counts"
        ));
    }
    if let Some((i, p)) = first_bad(view, &grid.points, 1, Attachment::Points, |p| {
        p.iter().all(|c| c.is_finite())
    }) {
        return Err(format!(
            "points: coordinate of point {i} is not finite: {:?}",
            p[0]
        ));
    }
    if cells.offsets.len() != n_cells {
        return Err(format!(
            "offsets: {} entries for {n_cells} cell types",
            cells.offsets.len()
        ));
    }
    if let Some(i) = cells
        .connectivity
        .iter()
        .position(|&p| p >= n_points as u64)
    {
        return Err(format!(
            "connectivity: index {i} refers to point {} but there are {n_points} points",
            cells.connectivity[i]
        ));
    }
    let mut start = 0u64;
    for (i, (&end, &t)) in cells.offsets.iter().zip(&cells.cell_types).enumerate() {
        if !known_cell_type(t) {
            return Err(format!("cell {i}: unknown VTK cell type {t}"));
        }
        if end < start || end > cells.connectivity.len() as u64 {
            return Err(format!(
                "offsets: cell {i} ends at {end}, outside {start}..={}",
                cells.connectivity.len()
            ));
        }
        if let Some(n) = nodes_of(t)
            && end - start != n
        {
            return Err(format!(
                "cell {i}: type {t} needs {n} nodes, got {}",
                end - start
            ));
        }
        start = end;
    }
    if start != cells.connectivity.len() as u64 {
        return Err(format!(
            "offsets: the last cell ends at {start} but connectivity has {} entries",
            cells.connectivity.len()
        ));
    }
    check_fields(view, "point", &grid.point_data, Attachment::Points)?;
    check_fields(view, "cell", &grid.cell_data, Attachment::Cells)?;
    check_fields(view, "field-data", &grid.field_data, Attachment::None)
}

/// The first tuple (its index in `view`'s file, and the tuple) of `values` (`n` components
/// each, attached as `at`) that `view` holds and that fails `good`.
fn first_bad<'v, T>(
    view: &GridView<'v>,
    values: &'v [T],
    n: usize,
    at: Attachment,
    good: impl Fn(&T) -> bool,
) -> Option<(usize, &'v [T])> {
    let (mut index, mut bad) = (0, None);
    view.for_each_tuple(values, n, at, |tuple| {
        if bad.is_none() {
            if tuple.iter().all(&good) {
                index += 1;
            } else {
                bad = Some(tuple);
            }
        }
    });
    bad.map(|tuple| (index, tuple))
}

/// Checks names, lengths, component names and values of the `kind` arrays `fields`
/// attached as `at` ("point" or "cell": as many tuples as the grid's points or cells;
/// "field-data": any whole number of tuples), the values only of the tuples `view` holds
/// (a non-finite value is named by its index in the file). Strings are allowed in field
/// data only and must not contain NUL (VTK's separator).
fn check_fields(
    view: &GridView,
    kind: &str,
    fields: &[Field],
    at: Attachment,
) -> std::result::Result<(), String> {
    let count = match at {
        Attachment::Points => Some(view.grid.points.len()),
        Attachment::Cells => Some(view.grid.cell_count()),
        Attachment::None => None,
    };
    let mut names = HashSet::new();
    for f in fields {
        let name = &f.name;
        if name.is_empty() {
            return Err(format!("a {kind} field has an empty name"));
        }
        if !names.insert(name.as_str()) {
            return Err(format!("{kind} field `{name}` appears twice"));
        }
        if f.components == 0 {
            return Err(format!("{kind} field `{name}` has 0 components"));
        }
        if !f.component_names.is_empty() && f.component_names.len() != f.components {
            return Err(format!(
                "{kind} field `{name}` has {} component names for {} components",
                f.component_names.len(),
                f.components
            ));
        }
        let len = f.len();
        let count = count.unwrap_or(len / f.components);
        if len != f.components * count || (kind == "field-data" && len == 0) {
            return Err(format!(
                "{kind} field `{name}` has {len} values, expected {} ({} components × {count} {kind}s)",
                f.components * count,
                f.components
            ));
        }
        if let FieldValues::Str(v) = &f.values {
            if kind != "field-data" {
                return Err(format!("{kind} field `{name}`: strings only in field data"));
            }
            if let Some(i) = v.iter().position(|s| s.contains('\0')) {
                return Err(format!("field-data `{name}`: string {i} contains NUL"));
            }
        }
        if let FieldValues::F64(v) = &f.values
            && let Some((tuple, values)) = first_bad(view, v, f.components, at, |x| x.is_finite())
        {
            let component = values.iter().position(|x| !x.is_finite()).unwrap_or(0);
            return Err(format!(
                "{kind} field `{name}` has the non-finite value {} at index {} \
                 ({kind} {tuple}, component {component})",
                values[component],
                tuple * f.components + component,
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Grid {
        let mut g = Grid {
            points: vec![[0.0, 0.0], [1.0, 0.0], [0.5, 0.1]],
            ..Grid::default()
        };
        g.push_cell(21, [0, 1, 2]);
        g.point_data.push(Field {
            name: "a&b".into(),
            components: 1,
            component_names: Vec::new(),
            values: FieldValues::F64(vec![0.1, -2.5, 1e-300]),
        });
        g.cell_data.push(Field {
            name: "pair".into(),
            components: 1,
            component_names: Vec::new(),
            values: FieldValues::I32(vec![-7]),
        });
        g
    }

    /// The appended block is exactly the arrays of the head, in order, each a UInt64 byte
    /// count and little-endian values, at the offsets the head names.
    #[test]
    fn appended_layout_matches_the_head() {
        let g = grid();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("g.vtu");
        write_vtu(&path, &g).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let mark = b"<AppendedData encoding=\"raw\">\n_";
        let at = bytes.windows(mark.len()).position(|w| w == mark).unwrap();
        let head = std::str::from_utf8(&bytes[..at]).unwrap();
        let data = &bytes[at + mark.len()..];
        let tags = start_tags(head).unwrap();
        let arrays: Vec<&Tag> = tags.iter().filter(|t| t.name == "DataArray").collect();
        let names: Vec<&str> = arrays.iter().map(|t| t.get("Name").unwrap()).collect();
        assert_eq!(
            names,
            ["a&b", "pair", "Points", "connectivity", "offsets", "types"]
        );
        // (bytes, first value's bytes) of each array.
        let expect: [(usize, Vec<u8>); 6] = [
            (24, 0.1f64.to_le_bytes().to_vec()),
            (4, (-7i32).to_le_bytes().to_vec()),
            (72, 0.0f64.to_le_bytes().to_vec()),
            (24, 0u64.to_le_bytes().to_vec()),
            (8, 3u64.to_le_bytes().to_vec()),
            (1, vec![21]),
        ];
        let mut offset = 0;
        for (tag, (len, first)) in arrays.iter().zip(expect) {
            assert_eq!(tag.get("offset").unwrap(), offset.to_string());
            assert_eq!(tag.get("format").unwrap(), "appended");
            let n = u64::from_le_bytes(data[offset..offset + 8].try_into().unwrap());
            assert_eq!(n as usize, len, "{}", tag.get("Name").unwrap());
            assert_eq!(&data[offset + 8..offset + 8 + first.len()], &first[..]);
            offset += 8 + len;
        }
        assert_eq!(&data[offset..], b"\n</AppendedData>\n</VTKFile>\n");
        // Points carry z = 0: the third point is (0.5, 0.1, 0).
        let points = &data[24 + 8 + 4 + 8 + 8..];
        let z = |k: usize| f64::from_le_bytes(points[8 * k..8 * k + 8].try_into().unwrap());
        assert_eq!([z(6), z(7), z(8)], [0.5, 0.1, 0.0]);
        assert_eq!(parse_vtu(&bytes).unwrap(), g);
    }

    #[test]
    fn damaged_files_are_errors_naming_the_array() {
        let g = grid();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("g.vtu");
        write_vtu(&path, &g).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        // Truncated inside the points.
        let err = parse_vtu(&bytes[..bytes.len() - 80]).unwrap_err();
        assert!(
            err.contains("run past") || err.contains("past the data"),
            "{err}"
        );
        // A size header that disagrees with the head.
        let mut bad = bytes.clone();
        let mark = b"encoding=\"raw\">\n_";
        let at = bad.windows(mark.len()).position(|w| w == mark).unwrap() + mark.len();
        bad[at] = 16;
        let err = parse_vtu(&bad).unwrap_err();
        assert!(err.contains("`a&b`"), "{err}");
    }

    #[test]
    fn cell_type_numbers() {
        assert_eq!(nodes_of(21), Some(3));
        assert_eq!(nodes_of(22), Some(6));
        assert_eq!(nodes_of(23), Some(8));
        assert!(known_cell_type(30) && !known_cell_type(0) && !known_cell_type(15));
    }
}
