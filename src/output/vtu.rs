//! VTK XML unstructured grids (`.vtu`), written and read with `vtkio`.
//!
//! Layout of the files written here, chosen for ParaView ≥ 5 / VTK ≥ 9 and pyvista:
//! - `version="1.0"`, `header_type="UInt64"`, little-endian: VTK's current defaults.
//! - Every array `format="binary"`, i.e. base64 inline in the XML, compressed with zlib in
//!   32 KiB blocks (`compressor="vtkZLibDataCompressor"`). Appended raw data would be smaller
//!   and faster, but vtkio only writes inline data.
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
//! # Why the arrays are encoded one by one
//! vtkio's one-call path (`Vtk` → `VTKFile` → XML) compresses all arrays on one thread and
//! feeds the zlib encoder one number at a time: 2.3 s (release) for a 500k-point quad8 grid
//! with 11 point-field components, nearly all of it per-number overhead. Its
//! `xml::DataArray` encoder and XML serializer are public, though, so [`write_vtu`] encodes
//! each array with them on the rayon pool and writes the few enclosing tags itself (1.1–1.4 s
//! on 2 cores; the largest array bounds it from below). The arrays are byte-for-byte what
//! vtkio writes, and [`read_vtu`] (vtkio's reader) checks the frame in the tests.

use std::collections::HashSet;
use std::fmt::Write as _;
use std::path::Path;

use rayon::prelude::*;
use vtkio::model::{Attribute, ByteOrder, CellType, DataSet, IOBuffer, Vtk};
use vtkio::xml::{self, Compressor, EncodingInfo, ScalarType};

use super::atomic::{invalid_data, write_atomically};
use super::pvd::escape_attr;
use super::{Field, FieldValues, Grid};
use crate::Result;

/// zlib level: 1 (fastest). Level 6 took twice as long for the same size on FE results
/// (doubles with noisy low bits barely compress; the gain comes from zero components, which
/// every level catches), and output must not slow down a run.
const COMPRESSION_LEVEL: u32 = 1;

/// Writes `grid` to `path` as a compressed VTK XML unstructured grid (atomically, creating
/// the parent directory).
///
/// Fails, writing nothing, if the grid is inconsistent: an offset or cell type list of the
/// wrong length, a connectivity index out of range, a cell whose node count does not fit
/// its type, a field whose length is not `components × points` (or cells), a duplicate or
/// empty field name, or a NaN/infinite coordinate or value. The error names the array and
/// the first bad index.
pub fn write_vtu(path: &Path, grid: &Grid) -> Result<()> {
    validate(grid).map_err(|msg| invalid_data(path, msg))?;

    let compressor = if COMPRESSION_LEVEL == 0 {
        Compressor::None
    } else {
        Compressor::ZLib
    };
    let encoding = EncodingInfo {
        byte_order: ByteOrder::LittleEndian,
        header_type: ScalarType::UInt64,
        compressor,
        compression_level: COMPRESSION_LEVEL,
    };
    // All arrays, in file order. Each is encoded independently, so they go to the rayon
    // pool; the biggest (stress, points, connectivity) then overlap.
    let arrays: Vec<Array> = grid
        .point_data
        .iter()
        .chain(&grid.cell_data)
        .map(Array::Field)
        .chain([
            Array::Points,
            Array::Connectivity,
            Array::Offsets,
            Array::Types,
        ])
        .collect();
    let encoded = arrays
        .par_iter()
        .map(|a| a.encode(grid, encoding))
        .collect::<std::result::Result<Vec<String>, String>>()
        .map_err(|msg| invalid_data(path, format!("vtkio could not encode {msg}")))?;
    let (point_arrays, rest) = encoded.split_at(grid.point_data.len());
    let (cell_arrays, rest) = rest.split_at(grid.cell_data.len());
    let [points, connectivity, offsets, types] = rest else {
        unreachable!("4 geometry arrays")
    };

    let mut head = String::from("<?xml version=\"1.0\"?>\n");
    let _ = write!(
        head,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\"{}>\n<UnstructuredGrid>\n\
         <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
        if compressor == Compressor::ZLib {
            " compressor=\"vtkZLibDataCompressor\""
        } else {
            ""
        },
        grid.points.len(),
        grid.cell_count(),
    );
    write_atomically(path, |w| {
        w.write_all(head.as_bytes())?;
        for (tag, fields, arrays) in [
            ("PointData", &grid.point_data, point_arrays),
            ("CellData", &grid.cell_data, cell_arrays),
        ] {
            w.write_all(format!("<{tag}{}>\n", active_attributes(fields)).as_bytes())?;
            for a in arrays {
                w.write_all(a.as_bytes())?;
                w.write_all(b"\n")?;
            }
            w.write_all(format!("</{tag}>\n").as_bytes())?;
        }
        w.write_all(b"<Points>\n")?;
        w.write_all(points.as_bytes())?;
        w.write_all(b"\n</Points>\n<Cells>\n")?;
        for a in [connectivity, offsets, types] {
            w.write_all(a.as_bytes())?;
            w.write_all(b"\n")?;
        }
        w.write_all(b"</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")
    })
}

/// One `<DataArray>` of the file.
enum Array<'a> {
    Field(&'a Field),
    Points,
    Connectivity,
    Offsets,
    Types,
}

impl Array<'_> {
    /// The `<DataArray ...>...</DataArray>` element, encoded and serialized by vtkio. The
    /// error names the array.
    fn encode(&self, grid: &Grid, encoding: EncodingInfo) -> std::result::Result<String, String> {
        let (name, components, data) = match self {
            Array::Field(f) => (
                f.name.as_str(),
                f.components,
                match &f.values {
                    FieldValues::F64(v) => IOBuffer::F64(v.clone()),
                    FieldValues::I32(v) => IOBuffer::I32(v.clone()),
                },
            ),
            Array::Points => (
                "Points",
                3,
                IOBuffer::F64(grid.points.iter().flat_map(|&[x, y]| [x, y, 0.0]).collect()),
            ),
            Array::Connectivity => ("connectivity", 1, IOBuffer::U64(grid.connectivity.clone())),
            Array::Offsets => ("offsets", 1, IOBuffer::U64(grid.offsets.clone())),
            Array::Types => ("types", 1, IOBuffer::U8(grid.cell_types.clone())),
        };
        let array = xml::DataArray::from_io_buffer(data, encoding)
            .map_err(|e| format!("array `{name}`: {e}"))?
            .with_name(name)
            .with_num_comp(components as u32);
        xml::se::to_string(&array).map_err(|e| format!("array `{name}`: {e}"))
    }
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

/// Reads a `.vtu` file as written by [`write_vtu`] (single piece, 2D points; z is dropped).
///
/// Point and cell arrays of type `Float64`/`Float32` become [`FieldValues::F64`], integer
/// arrays [`FieldValues::I32`] (failing if a value does not fit).
///
/// Note that vtkio silently skips arrays it cannot decode; with files written by
/// [`write_vtu`] that does not happen, and the tests check every array comes back.
pub fn read_vtu(path: &Path) -> Result<Grid> {
    let bad = |msg: String| invalid_data(path, msg);
    let vtk = Vtk::import(path).map_err(|e| match e {
        vtkio::Error::IO(e) => crate::Error::io(path, e),
        e => bad(format!("not a readable VTK file: {e}")),
    })?;
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        return Err(bad("not an UnstructuredGrid file".into()));
    };
    let [piece] = <[_; 1]>::try_from(pieces)
        .map_err(|p| bad(format!("expected 1 piece, found {}", p.len())))?;
    let piece = piece
        .into_loaded_piece_data(None)
        .map_err(|e| bad(format!("cannot load the piece: {e}")))?;

    let coords: Vec<f64> = piece
        .points
        .cast_into()
        .ok_or_else(|| bad("points are not numbers".into()))?;
    let points = coords.chunks_exact(3).map(|p| [p[0], p[1]]).collect();
    let (connectivity, offsets) = piece.cells.cell_verts.into_xml();
    let cell_types = piece.cells.types.iter().map(|&t| t as u8).collect();
    let fields = |attrs: Vec<Attribute>| -> Result<Vec<Field>> {
        attrs
            .into_iter()
            .filter_map(|a| match a {
                Attribute::DataArray(d) => Some(d),
                Attribute::Field { .. } => None,
            })
            .map(|d| {
                let values = match &d.data {
                    IOBuffer::F64(_) | IOBuffer::F32(_) => d.data.cast_into().map(FieldValues::F64),
                    _ => d.data.cast_into().map(FieldValues::I32),
                }
                .ok_or_else(|| bad(format!("array `{}` has an unsupported type", d.name)))?;
                Ok(Field {
                    name: d.name,
                    components: d.elem.num_comp() as usize,
                    values,
                })
            })
            .collect()
    };
    Ok(Grid {
        points,
        connectivity,
        offsets,
        cell_types,
        point_data: fields(piece.data.point)?,
        cell_data: fields(piece.data.cell)?,
    })
}

/// Number of nodes of the fixed-size VTK cell types; `None` for variable ones (poly-line,
/// polygon, ...) which are not checked.
fn nodes_of(cell: CellType) -> Option<u64> {
    use CellType::*;
    Some(match cell {
        Vertex => 1,
        Line => 2,
        Triangle => 3,
        Pixel | Quad | Tetra => 4,
        Pyramid => 5,
        Wedge => 6,
        Voxel | Hexahedron => 8,
        QuadraticEdge => 3,
        QuadraticTriangle | QuadraticLinearQuad => 6,
        BiquadraticTriangle => 7,
        QuadraticQuad => 8,
        BiquadraticQuad => 9,
        QuadraticTetra => 10,
        QuadraticHexahedron => 20,
        _ => return None,
    })
}

/// Checks `grid` as documented on [`write_vtu`].
fn validate(grid: &Grid) -> std::result::Result<(), String> {
    let n_points = grid.points.len();
    let n_cells = grid.cell_types.len();
    if u32::try_from(n_points).is_err() || u32::try_from(n_cells).is_err() {
        return Err(format!(
            "{n_points} points / {n_cells} cells exceed VTK's 32-bit counts"
        ));
    }
    if let Some(i) = grid
        .points
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(format!(
            "points: coordinate of point {i} is not finite: {:?}",
            grid.points[i]
        ));
    }
    if grid.offsets.len() != n_cells {
        return Err(format!(
            "offsets: {} entries for {n_cells} cell types",
            grid.offsets.len()
        ));
    }
    if let Some(i) = grid.connectivity.iter().position(|&p| p >= n_points as u64) {
        return Err(format!(
            "connectivity: index {i} refers to point {} but there are {n_points} points",
            grid.connectivity[i]
        ));
    }
    let mut start = 0u64;
    for (i, (&end, &t)) in grid.offsets.iter().zip(&grid.cell_types).enumerate() {
        let cell = cell_type(t).ok_or_else(|| format!("cell {i}: unknown VTK cell type {t}"))?;
        if end < start || end > grid.connectivity.len() as u64 {
            return Err(format!(
                "offsets: cell {i} ends at {end}, outside {start}..={}",
                grid.connectivity.len()
            ));
        }
        if let Some(n) = nodes_of(cell)
            && end - start != n
        {
            return Err(format!(
                "cell {i}: type {t} ({cell:?}) needs {n} nodes, got {}",
                end - start
            ));
        }
        start = end;
    }
    if start != grid.connectivity.len() as u64 {
        return Err(format!(
            "offsets: the last cell ends at {start} but connectivity has {} entries",
            grid.connectivity.len()
        ));
    }
    check_fields("point", &grid.point_data, n_points)?;
    check_fields("cell", &grid.cell_data, n_cells)
}

/// Checks names, lengths and finiteness of the `kind` ("point" or "cell") arrays.
fn check_fields(kind: &str, fields: &[Field], count: usize) -> std::result::Result<(), String> {
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
        let len = match &f.values {
            FieldValues::F64(v) => v.len(),
            FieldValues::I32(v) => v.len(),
        };
        if len != f.components * count {
            return Err(format!(
                "{kind} field `{name}` has {len} values, expected {} ({} components × {count} {kind}s)",
                f.components * count,
                f.components
            ));
        }
        if let FieldValues::F64(v) = &f.values
            && let Some(i) = v.iter().position(|x| !x.is_finite())
        {
            return Err(format!(
                "{kind} field `{name}` has the non-finite value {} at index {i} \
                 ({kind} {}, component {})",
                v[i],
                i / f.components,
                i % f.components
            ));
        }
    }
    Ok(())
}

/// `CellType` from its VTK number. vtkio derives `num_traits::FromPrimitive` for this, but
/// this crate does not depend on `num-traits`; comparing discriminants needs no dependency.
fn cell_type(t: u8) -> Option<CellType> {
    use CellType::*;
    const ALL: &[CellType] = &[
        Vertex,
        PolyVertex,
        Line,
        PolyLine,
        Triangle,
        TriangleStrip,
        Polygon,
        Pixel,
        Quad,
        Tetra,
        Voxel,
        Hexahedron,
        Wedge,
        Pyramid,
        QuadraticEdge,
        QuadraticTriangle,
        QuadraticQuad,
        QuadraticTetra,
        QuadraticHexahedron,
        QuadraticWedge,
        QuadraticPyramid,
        BiquadraticQuad,
        TriquadraticHexahedron,
        QuadraticLinearQuad,
        QuadraticLinearWedge,
        BiquadraticQuadraticWedge,
        BiquadraticQuadraticHexahedron,
        BiquadraticTriangle,
        CubicLine,
        ConvexPointSet,
        Polyhedron,
        ParametricCurve,
        ParametricSurface,
        ParametricTriSurface,
        ParametricQuadSurface,
        ParametricTetraRegion,
        ParametricHexRegion,
        HigherOrderEdge,
        HigherOrderTriangle,
        HigherOrderQuad,
        HigherOrderPolygon,
        HigherOrderTetrahedron,
        HigherOrderWedge,
        HigherOrderPyramid,
        HigherOrderHexahedron,
        LagrangeCurve,
        LagrangeTriangle,
        LagrangeQuadrilateral,
        LagrangeTetrahedron,
        LagrangeHexahedron,
        LagrangeWedge,
        LagrangePyramid,
        BezierCurve,
        BezierTriangle,
        BezierQuadrilateral,
        BezierTetrahedron,
        BezierHexahedron,
        BezierWedge,
        BezierPyramid,
    ];
    ALL.iter().copied().find(|&c| c as u8 == t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_type_numbers_match_vtk() {
        assert_eq!(cell_type(21), Some(CellType::QuadraticEdge));
        assert_eq!(cell_type(22), Some(CellType::QuadraticTriangle));
        assert_eq!(cell_type(23), Some(CellType::QuadraticQuad));
        assert_eq!(cell_type(30), Some(CellType::QuadraticLinearQuad));
        assert_eq!(cell_type(9), Some(CellType::Quad));
        assert_eq!(cell_type(0), None);
        assert_eq!(cell_type(15), None);
        for t in 0..=u8::MAX {
            if let Some(c) = cell_type(t) {
                assert_eq!(c as u8, t);
            }
        }
    }
}
