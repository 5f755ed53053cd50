//! VTK XML unstructured grids (`.vtu`), written and read with `vtkio`.
//!
//! Layout of the files written here, chosen for ParaView ≥ 5 / VTK ≥ 9 and pyvista:
//! - `version="1.0"`, `header_type="UInt64"`, little-endian: VTK's current defaults.
//! - Every array `format="binary"`, i.e. base64 inline in the XML, compressed with zlib in
//!   32 KiB blocks (`compressor="vtkZLibDataCompressor"`). Appended raw data would be smaller
//!   and faster, but vtkio only writes inline data.
//! - Points `Float64` with z = 0; connectivity and offsets `UInt64`; types `UInt8`.
//! - Point and cell arrays keep their type (`Float64` or `Int32`) and component count. A
//!   3-component array is tagged as the active `Vectors`; a 6-component one is left generic
//!   because VTK's XML has no symmetric-tensor tag (`Tensors` means 9 components); ParaView
//!   recognises 6 components as a symmetric tensor in VTK's order xx, yy, zz, xy, yz, xz.
//!
//! Everything is validated before anything is written, so an invalid grid produces an error
//! naming the array and index, and no file.

use std::collections::HashSet;
use std::path::Path;

use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, ElementType, IOBuffer,
    UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};
use vtkio::xml::Compressor;

use super::atomic::{invalid_data, write_atomically};
use super::{Field, FieldValues, Grid};
use crate::Result;

/// zlib level: 1 (fastest) compresses FE results almost as well as the default 6 at a
/// fraction of the time (doubles do not compress much either way), and output must not
/// slow down a run.
const COMPRESSION_LEVEL: u32 = 6;

/// Writes `grid` to `path` as a compressed VTK XML unstructured grid (atomically, creating
/// the parent directory).
///
/// Fails, writing nothing, if the grid is inconsistent: an offset or cell type list of the
/// wrong length, a connectivity index out of range, a cell whose node count does not fit
/// its type, a field whose length is not `components × points` (or cells), a duplicate or
/// empty field name, or a NaN/infinite coordinate or value. The error names the array and
/// the first bad index.
pub fn write_vtu(path: &Path, grid: &Grid) -> Result<()> {
    let t0 = std::time::Instant::now();
    let types = validate(grid).map_err(|msg| invalid_data(path, msg))?;

    eprintln!("validate {:?}", t0.elapsed());
    let vtk = Vtk {
        version: Version::new_xml(1, 0),
        title: String::new(),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::inline(UnstructuredGridPiece {
            points: IOBuffer::F64(grid.points.iter().flat_map(|&[x, y]| [x, y, 0.0]).collect()),
            cells: Cells {
                cell_verts: VertexNumbers::XML {
                    connectivity: grid.connectivity.clone(),
                    offsets: grid.offsets.clone(),
                },
                types,
            },
            data: Attributes {
                point: grid.point_data.iter().map(attribute).collect(),
                cell: grid.cell_data.iter().map(attribute).collect(),
            },
        }),
    };

    let to_err =
        |e: vtkio::xml::Error| invalid_data(path, format!("vtkio could not encode the grid: {e}"));
    let xml = vtk
        .try_into_xml_format(Compressor::ZLib, COMPRESSION_LEVEL)
        .map_err(to_err)?;
    // Serialize into memory, not into the file: vtkio's XML writer uses `Write::write`
    // without checking for short writes and drops its `BufWriter` without reporting flush
    // errors, both harmless for a `Vec` but silent truncation risks for a file.
    eprintln!("encode {:?}", t0.elapsed());
    let mut bytes = Vec::new();
    xml.write(&mut bytes).map_err(to_err)?;
    eprintln!("xml {:?}", t0.elapsed());
    let r = write_atomically(path, |w| w.write_all(&bytes));
    eprintln!("file {:?}", t0.elapsed());
    r
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

/// Converts a [`Field`] to a vtkio attribute; see the module docs for the tagging.
fn attribute(field: &Field) -> Attribute {
    let elem = match field.components {
        1 => ElementType::Scalars {
            num_comp: 1,
            lookup_table: None,
        },
        3 => ElementType::Vectors,
        n => ElementType::Generic(n as u32),
    };
    let data = match &field.values {
        FieldValues::F64(v) => IOBuffer::F64(v.clone()),
        FieldValues::I32(v) => IOBuffer::I32(v.clone()),
    };
    Attribute::DataArray(DataArray {
        name: field.name.clone(),
        elem,
        data,
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

/// Checks `grid` as documented on [`write_vtu`] and returns the vtkio cell types.
fn validate(grid: &Grid) -> std::result::Result<Vec<CellType>, String> {
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
    let mut types = Vec::with_capacity(n_cells);
    let mut start = 0u64;
    for (i, (&end, &t)) in grid.offsets.iter().zip(&grid.cell_types).enumerate() {
        let cell = cell_type(t).ok_or_else(|| format!("cell {i}: unknown VTK cell type {t}"))?;
        if end < start || end > grid.connectivity.len() as u64 {
            return Err(format!(
                "offsets: cell {i} ends at {end}, outside {start}..={}",
                grid.connectivity.len()
            ));
        }
        if let Some(n) = nodes_of(cell) {
            if end - start != n {
                return Err(format!(
                    "cell {i}: type {t} ({cell:?}) needs {n} nodes, got {}",
                    end - start
                ));
            }
        }
        types.push(cell);
        start = end;
    }
    if start != grid.connectivity.len() as u64 {
        return Err(format!(
            "offsets: the last cell ends at {start} but connectivity has {} entries",
            grid.connectivity.len()
        ));
    }
    check_fields("point", &grid.point_data, n_points)?;
    check_fields("cell", &grid.cell_data, n_cells)?;
    Ok(types)
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
        if let FieldValues::F64(v) = &f.values {
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(format!(
                    "{kind} field `{name}` has the non-finite value {} at index {i} ({kind} {}, component {})",
                    v[i],
                    i / f.components,
                    i % f.components
                ));
            }
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
