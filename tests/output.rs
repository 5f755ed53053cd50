//! Output writers: VTU round trip through the raw appended-data reader, validation failures that must leave
//! no file behind, the PVD collection, CSV tables, and the `summary.json` of converged and
//! failed runs.

use std::fs;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};

use asperity::Error;
use asperity::config::Case;
use asperity::output::csv::{CsvTable, write_csv};
use asperity::output::pvd::{PvdEntry, write_pvd};
use asperity::output::vtu::{read_vtu, write_vtu};
use asperity::output::{Field, FieldValues, Grid};

use crate::common;

/// What a writer refused to write into `path`: the message of an [`Error::Io`] of invalid
/// data about that file.
fn refused(err: Error, path: &Path) -> String {
    match err {
        Error::Io { path: p, source } if p == path && source.kind() == ErrorKind::InvalidData => {
            source.to_string()
        }
        other => panic!(
            "expected invalid data for {}, got {other:?}",
            path.display()
        ),
    }
}

/// One 8-node quad (VTK 23) on [0,2]×[0,1], a 6-node triangle (22) on top of it sharing the
/// edge y = 1, and a quadratic edge (21) along y = 0: the three cell kinds asperity writes.
fn mixed_grid() -> Grid {
    let mut points = vec![
        // quad8: corners then mid-sides, VTK/gmsh order
        [0.0, 0.0],
        [2.0, 0.0],
        [2.0, 1.0],
        [0.0, 1.0],
        [1.0, 0.0],
        [2.0, 0.5],
        [1.0, 1.0],
        [0.0, 0.5],
    ];
    // tri6 apex and its two new mid-side nodes
    points.extend([[1.0, 2.0], [1.5, 1.5], [0.5, 1.5]]);
    let n = points.len();
    let mut grid = Grid {
        points,
        ..Grid::default()
    };
    grid.push_cell(23, 0..8);
    grid.push_cell(22, [3, 2, 8, 6, 9, 10]);
    grid.push_cell(21, [0, 1, 4]);

    // Values that are not round in binary, to catch any precision loss.
    let f = |i: usize, k: usize| (i as f64 + 0.1) * (k as f64 + 1.0 / 3.0) * 1e-3 - 0.7;
    let displacement = (0..n).flat_map(|i| [f(i, 0), f(i, 1), 0.0]).collect();
    let stress = (0..n)
        .flat_map(|i| (0..6).map(move |k| f(i, k) * 1e3))
        .collect();
    let von_mises = (0..n).map(|i| f(i, 7).abs() * 1e2).collect();
    grid.point_data = vec![
        Field {
            name: "displacement".into(),
            components: 3,
            component_names: Vec::new(),
            values: FieldValues::F64(displacement),
        },
        Field {
            name: "stress".into(),
            components: 6,
            component_names: Vec::new(),
            values: FieldValues::F64(stress),
        },
        Field {
            name: "von_mises".into(),
            components: 1,
            component_names: Vec::new(),
            values: FieldValues::F64(von_mises),
        },
    ];
    grid.cell_data = vec![
        Field {
            name: "body".into(),
            components: 1,
            component_names: Vec::new(),
            values: FieldValues::I32(vec![1, 2, -1]),
        },
        Field {
            name: "area".into(),
            components: 1,
            component_names: Vec::new(),
            values: FieldValues::F64(vec![2.0, 0.5, 0.0]),
        },
    ];
    grid
}

fn dir_names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn vtu_round_trip_is_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sub/step_0001.vtu");
    let grid = mixed_grid();
    write_vtu(&path, &grid).unwrap();
    assert_eq!(
        dir_names(path.parent().unwrap()),
        vec!["step_0001.vtu"],
        "no temporary left"
    );

    let bytes = fs::read(&path).unwrap();
    let text = String::from_utf8_lossy(&bytes);
    assert!(
        text.contains("<AppendedData encoding=\"raw\">"),
        "raw appended data"
    );
    assert!(!text.contains("compressor"), "not compressed");
    assert!(
        text.contains("NumberOfComponents=\"6\""),
        "stress keeps 6 components"
    );

    let back = read_vtu(&path).unwrap();
    // Bit-exact: the file stores Float64, so equality is the right check.
    assert_eq!(back, grid);
    assert_eq!(back.cell_types, vec![23, 22, 21]);
}

#[test]
fn vtu_overwrites_an_existing_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.vtu");
    let mut grid = mixed_grid();
    write_vtu(&path, &grid).unwrap();
    grid.cell_data.clear();
    write_vtu(&path, &grid).unwrap();
    assert_eq!(read_vtu(&path).unwrap(), grid);
}

/// Arrays whose byte size is a multiple of 32 KiB (here 4096 f64 scalars, 8192 i32), the
/// corner case of block-compressed formats and of the 64 KiB staging buffer of the writer.
fn block_multiple_grid() -> Grid {
    let n = 4096;
    let mut grid = Grid {
        points: (0..n).map(|i| [i as f64, (i % 7) as f64]).collect(),
        ..Grid::default()
    };
    for i in 0..n as u64 / 2 {
        grid.push_cell(3, [2 * i, 2 * i + 1]);
    }
    grid.point_data.push(Field {
        name: "s".into(),
        components: 1,
        component_names: Vec::new(),
        values: FieldValues::F64((0..n).map(|i| i as f64 * 0.1).collect()),
    });
    grid.cell_data.push(Field {
        name: "id".into(),
        components: 4,
        component_names: Vec::new(),
        values: FieldValues::I32((0..2 * n).collect()),
    });
    grid
}

#[test]
fn vtu_arrays_of_32k_multiple_size_round_trip() {
    let grid = block_multiple_grid();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.vtu");
    write_vtu(&path, &grid).unwrap();
    assert_eq!(read_vtu(&path).unwrap(), grid);
}

#[test]
fn vtu_empty_grid_round_trips() {
    // A model without contact pairs still writes its (empty) interface grid.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("empty.vtu");
    let grid = Grid {
        point_data: vec![Field {
            name: "u".into(),
            components: 3,
            component_names: Vec::new(),
            values: FieldValues::F64(vec![]),
        }],
        ..Grid::default()
    };
    write_vtu(&path, &grid).unwrap();
    assert_eq!(read_vtu(&path).unwrap(), grid);
}

#[test]
fn vtu_nan_is_an_error_naming_the_field_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.vtu");
    let mut grid = mixed_grid();
    if let FieldValues::F64(v) = &mut grid.point_data[1].values {
        v[17] = f64::NAN;
    }
    let err = refused(write_vtu(&path, &grid).unwrap_err(), &path);
    assert!(err.contains("`stress`"), "{err}");
    assert!(err.contains("index 17"), "{err}");
    assert!(
        dir_names(dir.path()).is_empty(),
        "{:?}",
        dir_names(dir.path())
    );

    // An existing file is left as it was.
    write_vtu(&path, &mixed_grid()).unwrap();
    let before = fs::read(&path).unwrap();
    assert!(write_vtu(&path, &grid).is_err());
    assert_eq!(fs::read(&path).unwrap(), before);
    assert_eq!(dir_names(dir.path()), vec!["bad.vtu"]);
}

#[test]
fn vtu_infinite_coordinate_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut grid = mixed_grid();
    grid.points[4][1] = f64::INFINITY;
    let path = dir.path().join("x.vtu");
    let err = refused(write_vtu(&path, &grid).unwrap_err(), &path);
    assert!(err.contains("points") && err.contains("point 4"), "{err}");
    assert!(dir_names(dir.path()).is_empty());
}

#[test]
fn vtu_inconsistent_grids_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.vtu");
    let expect_err = |grid: &Grid, needle: &str| {
        let err = refused(write_vtu(&path, grid).unwrap_err(), &path);
        assert!(err.contains(needle), "expected `{needle}` in: {err}");
        assert!(dir_names(dir.path()).is_empty());
    };

    let mut g = mixed_grid();
    if let FieldValues::F64(v) = &mut g.point_data[0].values {
        v.pop();
    }
    expect_err(&g, "point field `displacement` has 32 values, expected 33");

    let mut g = mixed_grid();
    g.cell_data[0].values = FieldValues::I32(vec![1, 2]);
    expect_err(&g, "cell field `body` has 2 values, expected 3");

    let mut g = mixed_grid();
    g.connectivity[9] = 11;
    expect_err(&g, "connectivity: index 9 refers to point 11");

    let mut g = mixed_grid();
    g.cell_types[1] = 23;
    expect_err(&g, "cell 1: type 23");

    let mut g = mixed_grid();
    g.cell_types[2] = 200;
    expect_err(&g, "unknown VTK cell type 200");

    let mut g = mixed_grid();
    g.offsets.pop();
    expect_err(&g, "offsets");

    let mut g = mixed_grid();
    g.point_data[2].name = "stress".into();
    expect_err(&g, "`stress` appears twice");
}

/// Minimal XML reading for the test: the attributes of every `<DataSet .../>` element.
fn datasets(xml: &str) -> Vec<Vec<(String, String)>> {
    xml.split("<DataSet ")
        .skip(1)
        .map(|rest| {
            let tag = &rest[..rest.find("/>").expect("DataSet is self-closing")];
            tag.split('"')
                .collect::<Vec<_>>()
                .chunks(2)
                .filter(|kv| kv.len() == 2)
                .map(|kv| {
                    (
                        kv[0].trim().trim_end_matches('=').to_string(),
                        kv[1].to_string(),
                    )
                })
                .collect()
        })
        .collect()
}

#[test]
fn pvd_lists_timesteps_and_parts() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.pvd");
    let entries = vec![
        PvdEntry {
            time: 0.5,
            part: 0,
            name: "bodies".into(),
            file: "vtu/bodies_1.vtu".into(),
        },
        PvdEntry {
            time: 0.5,
            part: 1,
            name: "interface".into(),
            file: dir.path().join("vtu/interface_1.vtu"),
        },
        PvdEntry {
            time: 1.0 / 3.0 + 1.0,
            part: 0,
            name: "bodies".into(),
            file: "vtu/bodies_2.vtu".into(),
        },
        PvdEntry {
            time: 1.0 / 3.0 + 1.0,
            part: 1,
            name: "interface".into(),
            file: "vtu/interface_2.vtu".into(),
        },
    ];
    write_pvd(&path, &entries).unwrap();
    assert_eq!(dir_names(dir.path()), vec!["run.pvd"]);

    let xml = fs::read_to_string(&path).unwrap();
    assert!(
        xml.contains("<VTKFile type=\"Collection\" version=\"0.1\""),
        "{xml}"
    );
    assert!(
        xml.contains("<Collection>")
            && xml.contains("</Collection>")
            && xml.trim_end().ends_with("</VTKFile>")
    );
    let sets = datasets(&xml);
    assert_eq!(sets.len(), 4, "{xml}");
    let get = |i: usize, key: &str| {
        sets[i]
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.clone())
            .unwrap()
    };
    let files: Vec<String> = (0..4).map(|i| get(i, "file")).collect();
    assert_eq!(
        files,
        [
            "vtu/bodies_1.vtu",
            "vtu/interface_1.vtu",
            "vtu/bodies_2.vtu",
            "vtu/interface_2.vtu"
        ]
    );
    for (i, e) in entries.iter().enumerate() {
        // Times round-trip exactly.
        assert_eq!(get(i, "timestep").parse::<f64>().unwrap(), e.time);
        assert_eq!(get(i, "part"), e.part.to_string());
        assert_eq!(get(i, "name"), e.name);
    }
}

#[test]
fn pvd_rejects_nan_time() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("r.pvd");
    let err = write_pvd(&path, &[PvdEntry::new(f64::NAN, PathBuf::from("a.vtu"))]).unwrap_err();
    // The message names the entry whose time is not a number.
    let err = refused(err, &path);
    assert!(err.contains("a.vtu"), "{err}");
    assert!(dir_names(dir.path()).is_empty());
}

#[test]
fn csv_writes_header_and_exact_values() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("history.csv");
    let mut table = CsvTable::new(["step", "load, N", "u_y"]);
    table.rows.push(vec![1.0, 0.1, -1.0 / 3.0]);
    table.rows.push(vec![2.0, 1e-300, 6.02e23]);
    write_csv(&path, &table).unwrap();
    let text = fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "step,\"load, N\",u_y");
    for row in &table.rows {
        let parsed: Vec<f64> = lines
            .next()
            .unwrap()
            .split(',')
            .map(|s| s.parse().unwrap())
            .collect();
        assert_eq!(&parsed, row);
    }
    assert!(lines.next().is_none());
}

#[test]
fn csv_rejects_ragged_rows_and_non_finite_values() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.csv");
    let mut table = CsvTable::new(["a", "b"]);
    table.rows = vec![vec![1.0, 2.0], vec![3.0]];
    let err = refused(write_csv(&path, &table).unwrap_err(), &path);
    assert!(
        err.contains("row 1 has 1 values but the table has 2 columns"),
        "{err}"
    );
    table.rows = vec![vec![1.0, 2.0], vec![3.0, f64::NEG_INFINITY]];
    let err = refused(write_csv(&path, &table).unwrap_err(), &path);
    assert!(err.contains("column `b`, row 1"), "{err}");
    assert!(dir_names(dir.path()).is_empty());
}

/// The shrink fit of `examples/shrink_fit/shrink_fit.toml` (axisymmetric, one contact pair, one step).
fn shrink_fit() -> Case {
    Case::from_file(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/shrink_fit/shrink_fit.toml"),
    )
    .unwrap()
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&fs::read_to_string(path).unwrap()).unwrap()
}

/// The last row of a CSV file by column name.
fn last_row(path: &Path) -> std::collections::HashMap<String, f64> {
    let text = fs::read_to_string(path).unwrap();
    let header = text.lines().next().unwrap().split(',');
    let values = text.lines().last().unwrap().split(',');
    header
        .zip(values)
        .map(|(h, v)| (h.to_string(), v.parse().unwrap()))
        .collect()
}

#[test]
fn a_converged_run_writes_its_summary() {
    let dir = tempfile::tempdir().unwrap();
    let case = shrink_fit();
    let run = asperity::run::run(&case, dir.path(), false).unwrap();
    let s = read_json(&dir.path().join("summary.json"));
    println!("{s:#}");
    assert_eq!(s["program"], "asperity");
    assert_eq!(s["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(s["case"], case.path.display().to_string());
    assert_eq!(s["status"], "converged");
    assert!(s["error"].is_null());
    assert_eq!(s["analysis"], "axisymmetric");
    assert_eq!(s["model"]["nodes"], run.nodes);
    assert_eq!(s["model"]["elements"], run.cells);
    assert_eq!(s["model"]["unknowns"], run.dofs);
    assert!(s["model"]["interface_elements"].as_u64().unwrap() > 0);
    assert!(s["model"]["thickness"].is_null());
    let steps = s["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 1);
    assert_eq!(steps[0]["load_factor"], 1.0);
    assert_eq!(steps[0]["cutbacks"], 0);
    // Reactions and resultants are those of history.csv.
    let history = last_row(&dir.path().join("history.csv"));
    for support in ["shaft_ends", "hub_ends", "axis"] {
        for c in ["x", "y"] {
            let column = &history[&format!("reaction_{support}_{c}")];
            assert_eq!(steps[0]["reactions"][support][c], *column);
            assert_eq!(s["reactions"][support][c], *column);
        }
    }
    for quantity in [
        "normal_force",
        "tangential_force",
        "force_on_b_x",
        "force_on_b_y",
    ] {
        assert_eq!(
            steps[0]["contact"]["fit"][quantity],
            history[&format!("fit_{quantity}")]
        );
    }
    assert_eq!(s["final_residual"], history["residual"]);
    assert_eq!(steps[0]["iterations"], history["iterations"]);
    let totals = &s["totals"];
    assert_eq!(totals["steps"], 1);
    assert_eq!(totals["increments"], run.stats.increments);
    assert_eq!(totals["iterations"], run.stats.iterations);
    assert_eq!(totals["unsymmetric_solves"], run.stats.unsymmetric_solves);
    assert_eq!(totals["krylov_iterations"], run.stats.krylov_iterations);
    for phase in [
        "mesh",
        "model",
        "symbolic",
        "assembly",
        "factorisation",
        "solve",
        "output",
        "total",
    ] {
        assert!(s["seconds"][phase].as_f64().unwrap() >= 0.0, "{phase}");
    }
}

#[test]
fn a_failed_run_writes_its_summary_with_the_converged_steps() {
    let dir = tempfile::tempdir().unwrap();
    let case = shrink_fit();
    let folder = asperity::run::folder::OutputFolder::scratch(dir.path()).unwrap();
    let (mesh, mesh_seconds) = asperity::run::mesh_case(&case, &folder).unwrap();
    let err = asperity::run::run_mesh(&case, mesh, mesh_seconds, &folder, false, |_, _| {
        Err(asperity::Error::io(
            "evaluation",
            std::io::Error::other("stopped by the test"),
        ))
    })
    .unwrap_err();
    let s = read_json(&dir.path().join("summary.json"));
    assert_eq!(s["status"], "failed");
    assert_eq!(s["error"], err.to_string());
    assert!(
        matches!(&err, Error::Io { path, .. } if path == Path::new("evaluation")),
        "{err}"
    );
    assert!(s["model"]["nodes"].as_u64().unwrap() > 0);
    // The step converged and its files were written before the evaluation failed.
    assert_eq!(s["steps"].as_array().unwrap().len(), 1);
    assert_eq!(s["totals"]["steps"], 1);
    assert!(s["totals"]["unsymmetric_solves"].is_null());
    assert!(s["seconds"]["assembly"].is_null());
    assert!(s["seconds"]["total"].as_f64().unwrap() >= 0.0);

    // A mesh that cannot be read: no model, and the error.
    let out = dir.path().join("no_mesh");
    let mut case = case;
    case.mesh.file = Some(dir.path().join("missing.msh"));
    let err = asperity::run::mesh_case(
        &case,
        &asperity::run::folder::OutputFolder::scratch(&out).unwrap(),
    )
    .unwrap_err();
    let s = read_json(&out.join("summary.json"));
    assert_eq!(s["status"], "failed");
    assert_eq!(s["error"], err.to_string());
    assert!(s["model"].is_null() && s["analysis"].is_null());
    assert_eq!(s["steps"].as_array().unwrap().len(), 0);
}

/// Times writing a 500k-point grid of quad8 cells with the fields of a real run. Run with
/// `cargo test --release --test suite -- --ignored --nocapture output::vtu_timing`.
#[test]
#[ignore]
fn vtu_timing_500k_points() {
    // Structured quad8 mesh: (2m+1)(2n+1) - mn nodes; m = n = 408 gives ~500k.
    let (m, n) = (408usize, 408usize);
    let mut grid = Grid::default();
    let mut id = vec![vec![u64::MAX; 2 * n + 1]; 2 * m + 1];
    for (i, row) in id.iter_mut().enumerate() {
        for (j, slot) in row.iter_mut().enumerate() {
            if i % 2 == 1 && j % 2 == 1 {
                continue;
            }
            *slot = grid.points.len() as u64;
            grid.points
                .push([i as f64 * 0.01, j as f64 * 0.01 + (i as f64).sin() * 1e-3]);
        }
    }
    for i in 0..m {
        for j in 0..n {
            let (a, b) = (2 * i, 2 * j);
            grid.push_cell(
                23,
                [
                    id[a][b],
                    id[a + 2][b],
                    id[a + 2][b + 2],
                    id[a][b + 2],
                    id[a + 1][b],
                    id[a + 2][b + 1],
                    id[a + 1][b + 2],
                    id[a][b + 1],
                ],
            );
        }
    }
    let np = grid.points.len();
    let nc = grid.cell_count();
    // Like real plane results: smooth in-plane values (incompressible doubles), but
    // displacement z and the out-of-plane shears are zero and the plastic strain is zero
    // outside a small zone; `ASPERITY_TIMING_DENSE=1` makes every value non-zero instead.
    let dense = std::env::var("ASPERITY_TIMING_DENSE").is_ok_and(|v| v == "1");
    let wave = |k: usize| (k as f64 * 0.001).sin() * 123.456;
    let field = |name: &str, comps: usize, zero: &dyn Fn(usize, usize) -> bool| Field {
        name: name.into(),
        components: comps,
        component_names: Vec::new(),
        values: FieldValues::F64(
            (0..np * comps)
                .map(|k| {
                    if !dense && zero(k / comps, k % comps) {
                        0.0
                    } else {
                        wave(k)
                    }
                })
                .collect(),
        ),
    };
    grid.point_data = vec![
        field("displacement", 3, &|_, c| c == 2),
        field("stress", 6, &|_, c| c >= 4),
        field("von_mises", 1, &|_, _| false),
        field("eq_plastic_strain", 1, &|p, _| p > np / 20),
    ];
    grid.cell_data = vec![Field {
        name: "body".into(),
        components: 1,
        component_names: Vec::new(),
        values: FieldValues::I32(vec![1; nc]),
    }];

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.vtu");
    let t = std::time::Instant::now();
    write_vtu(&path, &grid).unwrap();
    let dt = t.elapsed();
    let size = fs::metadata(&path).unwrap().len();
    println!(
        "write_vtu: {np} points, {nc} cells, {:.1} MB in {:.3} s",
        size as f64 / 1e6,
        dt.as_secs_f64()
    );
    let t = std::time::Instant::now();
    let back = read_vtu(&path).unwrap();
    println!("read_vtu: {:.3} s", t.elapsed().as_secs_f64());
    assert_eq!(back, grid);
}

/// Writes sample files for checking by hand in ParaView or pyvista (`pyvista.read`,
/// `pyvista.get_reader`): `ASPERITY_SAMPLE_DIR=/tmp/samples cargo test --test suite --
/// --ignored write_samples`.
#[test]
#[ignore]
fn write_samples() {
    let Some(dir) = std::env::var_os("ASPERITY_SAMPLE_DIR").map(PathBuf::from) else {
        return;
    };
    let grid = mixed_grid();
    let mut entries = Vec::new();
    for step in 1..=2 {
        let mut g = grid.clone();
        for f in &mut g.point_data {
            if let FieldValues::F64(v) = &mut f.values {
                v.iter_mut().for_each(|x| *x *= step as f64);
            }
        }
        let bodies = format!("vtu/bodies_{step}.vtu");
        write_vtu(&dir.join(&bodies), &g).unwrap();
        let mut edge = Grid {
            points: g.points.clone(),
            ..Grid::default()
        };
        edge.push_cell(21, [0, 1, 4]);
        edge.cell_data.push(Field {
            name: "p_N".into(),
            components: 1,
            component_names: Vec::new(),
            values: FieldValues::F64(vec![-(step as f64)]),
        });
        let interface = format!("vtu/interface_{step}.vtu");
        write_vtu(&dir.join(&interface), &edge).unwrap();
        let time = step as f64 * 0.5;
        entries.push(PvdEntry {
            time,
            part: 0,
            name: "bodies".into(),
            file: bodies.into(),
        });
        entries.push(PvdEntry {
            time,
            part: 1,
            name: "interface".into(),
            file: interface.into(),
        });
    }
    write_pvd(&dir.join("run.pvd"), &entries).unwrap();
    write_vtu(&dir.join("block_multiple.vtu"), &block_multiple_grid()).unwrap();
    write_vtu(&dir.join("empty.vtu"), &Grid::default()).unwrap();
    let mut table = CsvTable::new(["time", "load, N", "u_y"]);
    table.rows = vec![vec![0.5, 1e-300, -1.0 / 3.0], vec![1.0, 6.02e23, 0.1]];
    write_csv(&dir.join("history.csv"), &table).unwrap();
}

/// The step grids of ParaView output on a block pressed and pushed on a base (plane strain)
/// and on the same model in axisymmetry: every new field checked against an independent
/// relation (equilibrium, Hooke's law, the displacement of the bodies), and the grid's field
/// data and component names through a write/read round trip.
mod step_grids {
    use super::common::*;
    use super::*;
    use asperity::post::interface::{InterfaceOutput, contact_extent, resultants};
    use asperity::post::{BodyPoints, StepInfo, reactions, step_grids};
    use asperity::solver::stepping::run_steps;

    const E: f64 = 200_000.0;
    const NU: f64 = 0.3;

    /// A block [1, 3] × [1, 2] on a base [0, 4] × [0, 1], coincident nodes on the contact; the
    /// curve groups are the parts of the bodies' horizontal edges under the block: `ground`
    /// (y = 0), `base_top`, `block_bottom` (y = 1) and `block_top` (y = 2).
    fn mesh() -> asperity::mesh::Mesh {
        let body = |name: &str, [x0, x1]: [f64; 2], y0: f64, curves: [(&str, f64); 2]| {
            let nx = (2.0 * (x1 - x0)) as usize;
            let mut m = tensor(&uniform(x0, x1, nx), &uniform(y0, y0 + 1.0, 2), name);
            for (group, y) in curves {
                add_curve_group(&mut m, group, |x| x[1] == y && (1.0..=3.0).contains(&x[0]));
            }
            m
        };
        let base = body(
            "base",
            [0.0, 4.0],
            0.0,
            [("ground", 0.0), ("base_top", 1.0)],
        );
        let block = body(
            "block",
            [1.0, 3.0],
            1.0,
            [("block_bottom", 1.0), ("block_top", 2.0)],
        );
        merge(base, block, false)
    }

    fn field<'g>(fields: &'g [Field], name: &str) -> &'g Field {
        fields
            .iter()
            .find(|f| f.name == name)
            .unwrap_or_else(|| panic!("no field `{name}`"))
    }

    fn f64s(f: &Field) -> &[f64] {
        match &f.values {
            FieldValues::F64(v) => v,
            other => panic!("`{}` is not Float64: {other:?}", f.name),
        }
    }

    /// Σ over the tuples of a 3-component field: (x, y).
    fn sum_xy(f: &Field) -> [f64; 2] {
        let v = f64s(f);
        [0, 1].map(|c| v.iter().skip(c).step_by(3).sum())
    }

    fn close(a: f64, b: f64, scale: f64) -> bool {
        (a - b).abs() <= 1e-10 * scale
    }

    /// Runs the pressed-and-pushed block (p = 10 MPa on the 2 mm top, pushed until it slides)
    /// and checks every step's grids.
    fn check(case: CaseBuilder) {
        let case = case.pressed_and_pushed(10.0, 0.01, &[0.0, 1.0, 2.0]).case();
        let model = model(mesh(), &case).unwrap();
        let points = BodyPoints::new(&model);
        let interface = InterfaceOutput::new(&model);
        let dir = tempfile::tempdir().unwrap();
        let mut slid = false;
        run_steps(&model, &settings(&case), |step| {
            let info = StepInfo {
                step: step.step,
                time: 0.25 * step.step as f64,
                load_factor: step.load_factor,
            };
            let (bodies, contact) = step_grids(&model, &points, &interface, step, info);
            let contact = contact.expect("the model has a contact pair");
            let states = &step.solution.interface_committed;

            // Reaction forces: summed over the grid they are the supports' reactions.
            let total: [f64; 2] = reactions(&model, step.internal_force, step.external_force)
                .iter()
                .fold([0.0; 2], |a, r| [a[0] + r[0], a[1] + r[1]]);
            let rf = sum_xy(field(&bodies.point_data, "reaction_force"));
            let scale = total[1].abs().max(1.0);
            assert!(close(rf[0], total[0], scale) && close(rf[1], total[1], scale));

            // Contact force vectors add up to the pair's resultant on body B, whose normal
            // part carries the pressure on the block (10 MPa × 2 mm × 1 mm, the top is the
            // only other load on the block and is vertical).
            let r = resultants(&model, states)[0];
            let normal = sum_xy(field(&contact.point_data, "contact_normal_force"));
            let shear = sum_xy(field(&contact.point_data, "contact_shear_force"));
            for c in 0..2 {
                assert!(close(normal[c] + shear[c], r[2 + c], 20.0), "{c}");
            }
            assert!(close(normal[1], 20.0, 20.0), "{normal:?}");
            assert!(
                normal[0].abs() < 1e-10 * 20.0,
                "a flat contact has no normal x force"
            );
            // Sliding as a whole: the shear force is μ N (Coulomb, μ = 0.3).
            let extent = contact_extent(&model, states)[0];
            if extent.stick_length == 0.0 && extent.slip_length > 0.0 {
                slid = true;
                assert!(close(shear[0].abs(), 0.3 * 20.0, 20.0), "{shear:?}");
            }
            let length = extent.stick_length + extent.slip_length + extent.open_length;
            assert!(close(length, 2.0, 1.0), "the pair is 2 mm long: {extent:?}");
            // Pressed flat: all of it is closed; 2 mm × the unit thickness.
            assert!(close(extent.area, 2.0, 1.0), "{extent:?}");

            // Interface displacement = the body displacement at the same nodes (side B).
            let u = f64s(field(&contact.point_data, "displacement"));
            for (k, &n) in interface.nodes().iter().enumerate() {
                let n = n as usize;
                assert_eq!(
                    &u[3 * k..3 * k + 3],
                    &[step.solution.u[2 * n], step.solution.u[2 * n + 1], 0.0]
                );
            }

            // Hooke's law between the nodal stress and strain tensors (both recovered by the
            // same linear map, so it holds at the nodes exactly): σ = λ tr ε I + 2G ε with the
            // tensor shear ε_xy (plane strain and axisymmetry: all four components).
            let (lambda, g) = (
                E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU)),
                E / (2.0 * (1.0 + NU)),
            );
            let sigma = f64s(field(&bodies.point_data, "stress"));
            let eps = f64s(field(&bodies.point_data, "strain"));
            for (s, e) in sigma.chunks(6).zip(eps.chunks(6)) {
                let tr = e[0] + e[1] + e[2];
                for i in 0..3 {
                    assert!(
                        close(s[i], lambda * tr + 2.0 * g * e[i], 10.0),
                        "{s:?} {e:?}"
                    );
                }
                assert!(close(s[3], 2.0 * g * e[3], 10.0), "shear: {s:?} {e:?}");
            }

            // Field data and component names survive the file.
            for (name, grid) in [("bodies", &bodies), ("interface", &contact)] {
                let path = dir.path().join(format!("{name}_{}.vtu", step.step));
                write_vtu(&path, grid).unwrap();
                let back = read_vtu(&path).unwrap();
                assert_eq!(&back, grid);
                let time = f64s(field(&back.field_data, "TimeValue"));
                assert_eq!(time, [0.25 * step.step as f64]);
                let lf = f64s(field(&back.field_data, "load_factor"));
                assert_eq!(lf, [step.load_factor]);
                let k = &field(&back.field_data, "step").values;
                assert_eq!(k, &FieldValues::I32(vec![step.step as i32]));
            }
            Ok(0.0)
        })
        .unwrap();
        assert!(slid, "the last step slides");
        // Names of the indices in the cell data.
        let names = |grid: &Grid, key: &str| field(&grid.field_data, key).values.clone();
        let state = asperity::solver::state::Solution::new(&model);
        let bodies = asperity::post::body_grid(&model, &points, &state.u, state.point_states());
        assert_eq!(
            names(&bodies, "body_names"),
            FieldValues::Str(vec!["base".into(), "block".into()])
        );
        let contact = interface.grid(&model, &state.interface_committed);
        assert_eq!(
            names(&contact, "pair_names"),
            FieldValues::Str(vec!["joint".into()])
        );
        for tensor in ["stress", "strain"] {
            let names = &field(&bodies.point_data, tensor).component_names;
            assert_eq!(names, &["xx", "yy", "zz", "xy", "yz", "xz"]);
        }
    }

    fn case(builder: CaseBuilder) -> CaseBuilder {
        let faces = [
            ("side_a", "base_top".into()),
            ("side_b", "block_bottom".into()),
            ("name", "joint".into()),
        ];
        builder
            .body("base", elastic(E, NU))
            .body("block", elastic(E, NU))
            .support("ground", &[("ux", 0.0), ("uy", 0.0)])
            .contact(&faces, linear_coulomb(1e4, 1e3, 0.3))
    }

    #[test]
    fn plane_strain() {
        check(case(CaseBuilder::plane_strain()));
    }

    /// The contact extent of pair `joint` as quantities: area, stick, slip and open lengths,
    /// max slip.
    const EXTENT: [&str; 5] = [
        "a:contact_area:pair=joint",
        "st:stick_length:pair=joint",
        "sl:slip_length:pair=joint",
        "op:open_length:pair=joint",
        "ms:max_slip:pair=joint",
    ];

    /// The quantities of `[[quantity]]`/`[[history]]` (`name:kind:keys`) on `step`.
    fn quantities(
        model: &asperity::model::Model,
        step: &asperity::solver::state::StepResult,
        specs: &[&str],
    ) -> Vec<f64> {
        let specs: Vec<_> = specs
            .iter()
            .map(|s| asperity::config::parse_quantity(s).unwrap())
            .collect();
        asperity::post::quantities::evaluate(&specs, model, step).unwrap()
    }

    /// The pushed block (plane stress, thickness 0.5) slides as a whole at the last step: the
    /// pair slips over its full 2 mm, its contact area is 2 mm × 0.5 mm, and the largest slip
    /// is at least the mean slip. With Coulomb's τ = μ p and the elastic tangential gap τ/k_T
    /// at every sliding point, the mean slip is |ḡ_x| − μ p̄ / k_T (ḡ_x the mean relative
    /// displacement, p̄ the mean pressure, both length-weighted on a flat contact); it is at
    /// most the 0.02 mm pushed.
    #[test]
    fn contact_extent_quantities_of_a_sliding_block() {
        let case = case(CaseBuilder::plane_stress(0.5))
            .pressed_and_pushed(10.0, 0.01, &[0.0, 1.0, 2.0])
            .case();
        let model = model(mesh(), &case).unwrap();
        let tag = model.mesh.node_tags[7];
        let mut last = Vec::new();
        run_steps(&model, &settings(&case), |step| {
            let node = format!("n:node_displacement:node={tag},component=y");
            let mut specs = EXTENT.to_vec();
            specs.extend([
                "g:relative_displacement:pair=joint,component=x",
                "p:contact_pressure:pair=joint,statistic=mean",
                &node,
            ]);
            last = quantities(&model, step, &specs);
            assert_eq!(last[7], step.solution.u[2 * 7 + 1], "node {tag}");
            let unknown =
                asperity::config::parse_quantity("n:node_displacement:node=999999,component=x")
                    .unwrap();
            let e = asperity::post::quantities::evaluate(&[unknown], &model, step).unwrap_err();
            assert!(
                matches!(&e, Error::Quantity { name, reason } if name == "n" && reason.contains("no node 999999")),
                "{e}"
            );
            Ok(0.0)
        })
        .unwrap();
        let e = asperity::config::parse_quantity("n:node_displacement:node=7.5,component=x")
            .unwrap_err();
        assert!(e.contains("node = '7.5' is not a node tag"), "{e}");
        let [area, stick, slip, open, max_slip, g, p, _] = last[..] else {
            unreachable!()
        };
        assert!(close(area, 1.0, 1.0), "area {area}");
        assert_eq!((stick, open), (0.0, 0.0));
        assert!(close(slip, 2.0, 1.0), "slip length {slip}");
        let mean_slip = g.abs() - 0.3 * p / 1e3;
        assert!(mean_slip > 0.0, "{g} {p}");
        assert!(
            max_slip >= mean_slip * (1.0 - 1e-9) && max_slip <= 0.02,
            "max slip {max_slip}, mean {mean_slip}"
        );
    }

    /// The same bodies as rings about the y axis, pressed: the contact area is the annulus
    /// π (3² − 1²), its normal force the pressure on the top annulus, and the tensors are
    /// named in cylindrical components.
    #[test]
    fn axisymmetric() {
        let case = case(CaseBuilder::axisymmetric())
            .pressure("block_top", 10.0)
            .steps(1)
            .case();
        let model = model(mesh(), &case).unwrap();
        let points = BodyPoints::new(&model);
        let interface = InterfaceOutput::new(&model);
        let annulus = std::f64::consts::PI * (3.0f64.powi(2) - 1.0);
        run_steps(&model, &settings(&case), |step| {
            let info = StepInfo {
                step: step.step,
                time: 1.0,
                load_factor: step.load_factor,
            };
            let (bodies, contact) = step_grids(&model, &points, &interface, step, info);
            let extent = contact_extent(&model, &step.solution.interface_committed)[0];
            assert!(close(extent.area, annulus, annulus), "{extent:?}");
            assert!(close(extent.stick_length, 2.0, 1.0), "{extent:?}");
            // All of it closed and sticking under the pressure alone (no shear load, no slip).
            let q = quantities(&model, step, &EXTENT);
            assert!(close(q[0], annulus, annulus), "{q:?}");
            assert!(close(q[1], 2.0, 1.0), "{q:?}");
            assert_eq!(q[2..], [0.0; 3], "{q:?}");
            let normal = sum_xy(field(&contact.unwrap().point_data, "contact_normal_force"));
            assert!(
                close(normal[1], 10.0 * annulus, 10.0 * annulus),
                "{normal:?}"
            );
            for tensor in ["stress", "strain"] {
                let names = &field(&bodies.point_data, tensor).component_names;
                assert_eq!(names, &["rr", "zz", "θθ", "rz", "zθ", "rθ"]);
            }
            Ok(0.0)
        })
        .unwrap();
    }
}

/// `asperity run` on the `asperity init` template (a block pressed and pushed on a
/// foundation, four steps): the written VTU files carry the nodal reaction forces (summed,
/// the supports' reactions of `summary.json`), the interface displacement (the side-B body
/// displacement at the same point) and the step's FieldData.
#[test]
fn run_writes_reactions_interface_displacement_and_field_data() {
    use std::process::Command;
    let dir = tempfile::tempdir().unwrap();
    let exe = env!("CARGO_BIN_EXE_asperity");
    let init = Command::new(exe)
        .args(["-q", "init", dir.path().to_str().unwrap()])
        .output()
        .unwrap();
    assert!(init.status.success());
    let case = dir.path().join("case.toml");
    let text = fs::read_to_string(&case).unwrap();
    fs::write(&case, text.replacen("size = 1.0", "size = 2.0", 1)).unwrap();
    let run = Command::new(exe)
        .args(["-q", "run", case.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let out = dir.path().join("out");
    let summary: serde_json::Value =
        serde_json::from_slice(&fs::read(out.join("summary.json")).unwrap()).unwrap();
    let steps = summary["steps"].as_array().unwrap();
    for s in steps {
        let k = s["step"].as_u64().unwrap() as usize;
        // The template's two bodies, each in its own file; its one pair.
        let bodies: Vec<Grid> = common::frame_files(&out, k, "bodies")
            .iter()
            .map(|path| read_vtu(path).unwrap())
            .collect();
        assert_eq!(bodies.len(), 2);
        let interface = read_vtu(&out.join(format!("interface_{k:04}.vtu"))).unwrap();
        let get = |fields: &[Field], name: &str| -> Vec<f64> {
            match &fields.iter().find(|f| f.name == name).unwrap().values {
                FieldValues::F64(v) => v.clone(),
                FieldValues::I32(v) => v.iter().map(|&i| i as f64).collect(),
                other => panic!("{name}: {other:?}"),
            }
        };
        for grid in bodies.iter().chain([&interface]) {
            assert_eq!(get(&grid.field_data, "TimeValue"), [k as f64]);
            assert_eq!(get(&grid.field_data, "step"), [k as f64]);
            assert_eq!(
                get(&grid.field_data, "load_factor"),
                [s["load_factor"].as_f64().unwrap()]
            );
        }
        // Σ RF over the bodies = Σ of the supports' reactions.
        let reactions = s["reactions"].as_object().unwrap();
        for (c, key) in ["x", "y"].iter().enumerate() {
            let total: f64 = reactions.values().map(|r| r[key].as_f64().unwrap()).sum();
            let sum: f64 = bodies
                .iter()
                .flat_map(|b| get(&b.point_data, "reaction_force"))
                .skip(c)
                .step_by(3)
                .sum();
            let scale = reactions
                .values()
                .map(|r| r[key].as_f64().unwrap().abs())
                .fold(1.0, f64::max);
            assert!(
                (sum - total).abs() <= 1e-9 * scale,
                "{key}: {sum} vs {total}"
            );
        }
        // Each interface point moves with a body point at the same place (side B).
        let u_face = get(&interface.point_data, "displacement");
        assert_eq!(u_face.len(), 3 * interface.points.len());
        assert!(u_face.iter().any(|&v| v != 0.0), "a loaded interface moves");
        for (i, x) in interface.points.iter().enumerate() {
            let found = bodies.iter().any(|body| {
                let u_body = get(&body.point_data, "displacement");
                body.points
                    .iter()
                    .enumerate()
                    .any(|(j, y)| y == x && u_body[3 * j..3 * j + 3] == u_face[3 * i..3 * i + 3])
            });
            assert!(
                found,
                "interface point {x:?}: no body point with its displacement"
            );
        }
    }
    assert_eq!(steps.len(), 4);
}
