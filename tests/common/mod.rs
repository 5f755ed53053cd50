//! Shared fixtures of the integration tests: programmatic quadratic meshes (so that the
//! tests need no gmsh and can distort meshes at will), the case builder ([`case`]) and
//! helpers to solve and measure.
#![allow(dead_code)]

mod case;
mod fixtures;

pub use case::*;
// Not every test uses the fixtures, and a test crate warns of a re-export it never uses.
#[allow(unused_imports)]
pub use fixtures::*;

use asperity::config::Case;
use asperity::mesh::{Cell, CellKind, Line3, Mesh, PhysicalGroup, PointElement};
use asperity::model::Model;
use asperity::solver::state::Solution;
use asperity::solver::stepping::run_steps;

/// `resume` written as a restart record at `path` for the case whose text is `case_text`
/// and read back for `model`, as `--resume` reads it.
pub fn through_record(
    path: &std::path::Path,
    case_text: &str,
    resume: &asperity::solver::state::Resume,
    model: &Model,
) -> asperity::output::restart::Record {
    let mut writer = asperity::output::writer::RecordWriter::default();
    use asperity::output::restart::{ContinuumStates, OutputState, read_record};
    let progress = asperity::solver::state::Progress {
        state: resume.state.clone(),
        stats: &resume.stats,
        solution: &resume.solution,
        last_increment: resume.last_increment.as_ref(),
    };
    let states = ContinuumStates::of(model);
    writer
        .write(path, case_text, &progress, &OutputState::default(), states)
        .unwrap();
    writer.finish().unwrap();
    read_record(path, case_text, &Solution::new(model), states).unwrap()
}

/// The `asperity` binary of this build.
pub fn asperity() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_asperity"))
}

/// Runs `asperity run <case> --out <out> <extra...>` and asserts that it succeeds, showing
/// what it printed when it does not.
pub fn run_cli(case: &std::path::Path, out: &std::path::Path, extra: &[&str]) {
    let output = asperity()
        .arg("run")
        .arg(case)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
}

/// Builds a structured quad8 (or tri6, `triangles = true`) mesh of the map
/// `(s, t) ∈ [0,1]² → geometry(s, t)` with `nx × ny` cells. Mid-side nodes are mapped
/// through the geometry too (so curved boundaries are followed). Interior corner nodes are
/// moved by `distortion` (a fraction of the cell size, deterministic pseudo-random) in the
/// parameter plane; mid-side nodes then sit at the middle of straight parameter edges.
///
/// Groups: surface "body"; curves "s0" (s = 0), "s1" (s = 1), "t0" (t = 0), "t1" (t = 1);
/// point "origin" (s = t = 0).
pub fn structured(
    nx: usize,
    ny: usize,
    distortion: f64,
    triangles: bool,
    geometry: impl Fn(f64, f64) -> [f64; 2],
) -> Mesh {
    // Parameter-plane corner grid with distortion of interior points.
    let mut grid = vec![[0.0; 2]; (nx + 1) * (ny + 1)];
    let mut seed = 12345u64;
    let mut rand = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 33) as f64 / (1u64 << 31) as f64) - 0.5
    };
    for j in 0..=ny {
        for i in 0..=nx {
            let (mut s, mut t) = (i as f64 / nx as f64, j as f64 / ny as f64);
            if i > 0 && i < nx && j > 0 && j < ny {
                s += distortion * rand() / nx as f64;
                t += distortion * rand() / ny as f64;
            }
            grid[j * (nx + 1) + i] = [s, t];
        }
    }
    let mut mesh = Mesh::default();
    let mut param: Vec<[f64; 2]> = Vec::new();
    let mut node_of = std::collections::HashMap::new();
    let mut node = |p: [f64; 2], mesh: &mut Mesh, param: &mut Vec<[f64; 2]>| -> u32 {
        let key = ((p[0] * 1e12).round() as i64, (p[1] * 1e12).round() as i64);
        *node_of.entry(key).or_insert_with(|| {
            mesh.nodes.push(geometry(p[0], p[1]));
            mesh.node_tags.push(mesh.nodes.len() as u64);
            param.push(p);
            (mesh.nodes.len() - 1) as u32
        })
    };
    let mid = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
    let mut tag = 0;
    for j in 0..ny {
        for i in 0..nx {
            let c = [
                grid[j * (nx + 1) + i],
                grid[j * (nx + 1) + i + 1],
                grid[(j + 1) * (nx + 1) + i + 1],
                grid[(j + 1) * (nx + 1) + i],
            ];
            let corner_sets: Vec<[usize; 3]> = if triangles {
                vec![[0, 1, 2], [0, 2, 3]]
            } else {
                vec![]
            };
            if triangles {
                for t in corner_sets {
                    let p = [c[t[0]], c[t[1]], c[t[2]]];
                    let mut nodes = [0u32; 8];
                    for k in 0..3 {
                        nodes[k] = node(p[k], &mut mesh, &mut param);
                        nodes[3 + k] = node(mid(p[k], p[(k + 1) % 3]), &mut mesh, &mut param);
                    }
                    tag += 1;
                    mesh.cells.push(Cell {
                        kind: CellKind::Tri6,
                        nodes,
                        entity: 1,
                        tag,
                    });
                }
            } else {
                let mut nodes = [0u32; 8];
                for k in 0..4 {
                    nodes[k] = node(c[k], &mut mesh, &mut param);
                    nodes[4 + k] = node(mid(c[k], c[(k + 1) % 4]), &mut mesh, &mut param);
                }
                tag += 1;
                mesh.cells.push(Cell {
                    kind: CellKind::Quad8,
                    nodes,
                    entity: 1,
                    tag,
                });
            }
        }
    }
    // Boundary lines: entity 1 s = 0, 2 s = 1, 3 t = 0, 4 t = 1.
    let mut lines = Vec::new();
    for (entity, count, at) in [
        (
            1,
            ny,
            Box::new(|k: usize| grid[k * (nx + 1)]) as Box<dyn Fn(usize) -> [f64; 2]>,
        ),
        (2, ny, Box::new(|k: usize| grid[k * (nx + 1) + nx])),
        (3, nx, Box::new(|k: usize| grid[k])),
        (4, nx, Box::new(|k: usize| grid[ny * (nx + 1) + k])),
    ] {
        for k in 0..count {
            let (a, b) = (at(k), at(k + 1));
            let nodes = [
                node(a, &mut mesh, &mut param),
                node(b, &mut mesh, &mut param),
                node(mid(a, b), &mut mesh, &mut param),
            ];
            tag += 1;
            lines.push(Line3 { nodes, entity, tag });
        }
    }
    mesh.lines = lines;
    let origin = node([0.0, 0.0], &mut mesh, &mut param);
    mesh.points.push(PointElement {
        node: origin,
        entity: 1,
        tag: tag + 1,
    });
    let group = |dim: u8, tag: i32, name: &str| PhysicalGroup {
        dim,
        tag,
        name: name.into(),
        entities: vec![tag],
    };
    mesh.groups = vec![
        PhysicalGroup {
            dim: 2,
            tag: 1,
            name: "body".into(),
            entities: vec![1],
        },
        group(1, 1, "s0"),
        group(1, 2, "s1"),
        group(1, 3, "t0"),
        group(1, 4, "t1"),
        PhysicalGroup {
            dim: 0,
            tag: 1,
            name: "origin".into(),
            entities: vec![1],
        },
    ];
    mesh.path = "generated".into();
    mesh
}

/// A rectangle [0, lx] × [0, ly].
pub fn rectangle(lx: f64, ly: f64, nx: usize, ny: usize, distortion: f64, triangles: bool) -> Mesh {
    structured(nx, ny, distortion, triangles, move |s, t| [s * lx, t * ly])
}

/// A quarter annulus a ≤ r ≤ b, 0 ≤ θ ≤ π/2: s runs radially, t in angle. Curves: "s0" the
/// bore, "s1" the outside, "t0" on the x axis (y = 0), "t1" on the y axis (x = 0).
pub fn quarter_annulus(a: f64, b: f64, nr: usize, nt: usize) -> Mesh {
    structured(nr, nt, 0.0, false, move |s, t| {
        let (r, th) = (a + s * (b - a), t * std::f64::consts::FRAC_PI_2);
        [r * th.cos(), r * th.sin()]
    })
}

/// Builds the model and solves all steps.
pub fn solve(mesh: Mesh, case: &Case) -> (Model, Solution) {
    let model = model(mesh, case).expect("model builds");
    let (solution, _) = run_steps(&model, &settings(case), |_| Ok(0.0)).expect("solves");
    (model, solution)
}

/// Solves `builder`'s case on the two-block mesh (`contact_pair.msh`, [`two_blocks`]), with
/// the run's statistics.
pub fn solve_two_blocks(
    builder: CaseBuilder,
) -> (Solution, asperity::solver::state::RunStatistics) {
    let case = builder.case();
    let mesh = asperity::mesh::msh::read_msh(&fixture("contact_pair.msh")).unwrap();
    let built = model(mesh, &case).unwrap();
    run_steps(&built, &settings(&case), |_| Ok(0.0)).expect("solves")
}

/// The largest |a_i − b_i| and the largest |b_i|: a difference and its scale.
pub fn largest_difference(a: &[f64], b: &[f64]) -> (f64, f64) {
    let largest = |v: &mut dyn Iterator<Item = f64>| v.fold(0.0_f64, |m, x| m.max(x.abs()));
    (
        largest(&mut a.iter().zip(b).map(|(x, y)| x - y)),
        largest(&mut b.iter().copied()),
    )
}

/// Displacement of node `n`.
pub fn displacement(solution: &Solution, n: usize) -> [f64; 2] {
    [solution.u[2 * n], solution.u[2 * n + 1]]
}

/// Least-squares slope of log(err) against log(h).
pub fn fitted_rate(h: &[f64], err: &[f64]) -> f64 {
    let x: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let y: Vec<f64> = err.iter().map(|v| v.ln()).collect();
    let (mx, my) = (
        x.iter().sum::<f64>() / x.len() as f64,
        y.iter().sum::<f64>() / y.len() as f64,
    );
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    sxy / sxx
}

/// Tensor-product quad8 mesh with corner coordinates `xs` × `ys` (mid-side nodes at the
/// middle), surface group `surface`. Each boundary line is its own entity, so curve groups
/// can be made afterwards with [`add_curve_group`].
pub fn tensor(xs: &[f64], ys: &[f64], surface: &str) -> Mesh {
    let (nx, ny) = (xs.len() - 1, ys.len() - 1);
    let x0 = xs[0];
    let y0 = ys[0];
    let (lx, ly) = (xs[nx] - x0, ys[ny] - y0);
    // Map the parameter grid onto the given coordinates (piecewise linear per cell).
    let interp = |v: &[f64], s: f64| {
        let n = v.len() - 1;
        let k = ((s * n as f64).floor() as usize).min(n - 1);
        let t = s * n as f64 - k as f64;
        v[k] + t * (v[k + 1] - v[k])
    };
    let _ = (lx, ly);
    let mut mesh = structured(nx, ny, 0.0, false, |s, t| [interp(xs, s), interp(ys, t)]);
    // Re-number line entities one per line; keep the surface and rename it.
    for (i, l) in mesh.lines.iter_mut().enumerate() {
        l.entity = 1000 + i as i32;
    }
    mesh.points.clear();
    mesh.groups = vec![PhysicalGroup {
        dim: 2,
        tag: 1,
        name: surface.into(),
        entities: vec![1],
    }];
    mesh
}

/// Adds a physical curve `name` of the boundary lines whose three nodes satisfy `on`.
pub fn add_curve_group(mesh: &mut Mesh, name: &str, on: impl Fn([f64; 2]) -> bool) {
    let entities: Vec<i32> = mesh
        .lines
        .iter()
        .filter(|l| l.nodes.iter().all(|&n| on(mesh.nodes[n as usize])))
        .map(|l| l.entity)
        .collect();
    assert!(!entities.is_empty(), "group {name} would be empty");
    let tag = mesh.groups.iter().map(|g| g.tag).max().unwrap_or(0) + 1;
    mesh.groups.push(PhysicalGroup {
        dim: 1,
        tag,
        name: name.into(),
        entities,
    });
}

/// Adds a physical point `name` at the node nearest to `at`.
pub fn add_point_group(mesh: &mut Mesh, name: &str, at: [f64; 2]) {
    let d = |p: [f64; 2]| (p[0] - at[0]).powi(2) + (p[1] - at[1]).powi(2);
    let node = (0..mesh.nodes.len())
        .min_by(|&a, &b| d(mesh.nodes[a]).total_cmp(&d(mesh.nodes[b])))
        .unwrap() as u32;
    let entity = 900_000 + mesh.points.len() as i32;
    mesh.points.push(PointElement {
        node,
        entity,
        tag: 0,
    });
    let tag = mesh.groups.iter().map(|g| g.tag).max().unwrap_or(0) + 1;
    mesh.groups.push(PhysicalGroup {
        dim: 0,
        tag,
        name: name.into(),
        entities: vec![entity],
    });
}

/// Puts two meshes into one. With `conforming`, nodes of `b` that coincide with nodes of `a`
/// are merged (one conforming mesh); otherwise they stay distinct (coincident contact nodes).
pub fn merge(a: Mesh, b: Mesh, conforming: bool) -> Mesh {
    let mut m = a;
    // Entities of `b` are shifted past every entity of `a`, so merges can be nested.
    let max_entity = m
        .cells
        .iter()
        .map(|c| c.entity)
        .chain(m.lines.iter().map(|l| l.entity))
        .chain(m.points.iter().map(|p| p.entity));
    let offset_entity = max_entity.max().unwrap_or(0) + 1;
    let mut map = Vec::with_capacity(b.nodes.len());
    let lookup: std::collections::HashMap<(i64, i64), u32> = if conforming {
        m.nodes
            .iter()
            .enumerate()
            .map(|(i, p)| {
                (
                    ((p[0] * 1e9).round() as i64, (p[1] * 1e9).round() as i64),
                    i as u32,
                )
            })
            .collect()
    } else {
        Default::default()
    };
    for p in &b.nodes {
        let key = ((p[0] * 1e9).round() as i64, (p[1] * 1e9).round() as i64);
        map.push(*lookup.get(&key).unwrap_or(&{
            m.nodes.push(*p);
            m.node_tags.push(m.nodes.len() as u64);
            (m.nodes.len() - 1) as u32
        }));
    }
    let tag0 = m.cells.len() as u64 + m.lines.len() as u64 + 1;
    for (k, c) in b.cells.iter().enumerate() {
        let mut c = *c;
        for n in c.nodes.iter_mut().take(c.kind.node_count()) {
            *n = map[*n as usize];
        }
        c.entity += offset_entity;
        c.tag = tag0 + k as u64;
        m.cells.push(c);
    }
    for l in &b.lines {
        m.lines.push(Line3 {
            nodes: l.nodes.map(|n| map[n as usize]),
            entity: l.entity + offset_entity,
            tag: l.tag + tag0,
        });
    }
    for p in &b.points {
        m.points.push(PointElement {
            node: map[p.node as usize],
            entity: p.entity + offset_entity,
            tag: p.tag + tag0,
        });
    }
    let tag_offset = m.groups.iter().map(|g| g.tag).max().unwrap_or(0);
    for g in b.groups {
        m.groups.push(PhysicalGroup {
            tag: g.tag + tag_offset,
            entities: g.entities.iter().map(|e| e + offset_entity).collect(),
            ..g
        });
    }
    m
}

/// Points 0 = v[0] < ... < v[n] = `length` with `n` intervals whose sizes grow (ratio > 1)
/// or shrink geometrically from `start` to the end.
pub fn graded(start: f64, length: f64, n: usize, ratio: f64) -> Vec<f64> {
    let weights: Vec<f64> = (0..n).map(|i| ratio.powi(i as i32)).collect();
    let total: f64 = weights.iter().sum();
    let mut v = vec![start];
    for w in weights {
        let last = *v.last().unwrap();
        v.push(last + length * w / total);
    }
    v
}

/// Uniform points from `a` to `b` with `n` intervals.
pub fn uniform(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|i| a + (b - a) * i as f64 / n as f64).collect()
}

/// The mesh of [`block_on_base`] (coincident nodes on the contact): the base [0, `base_width`]
/// × [0, 1] with curves "ground" (y = 0) and "base_top" (y = 1 under the block), and the block
/// `block_x` × [1, `block_top`] with curves "block_bottom" and "block_top"; `columns` quad8
/// across the base and the block, `rows` up each.
pub fn block_on_base_mesh(
    base_width: f64,
    block_x: [f64; 2],
    block_top: f64,
    columns: [usize; 2],
    rows: usize,
) -> Mesh {
    let mut base = tensor(
        &uniform(0.0, base_width, columns[0]),
        &uniform(0.0, 1.0, rows),
        "base",
    );
    add_curve_group(&mut base, "ground", |x| x[1] == 0.0);
    add_curve_group(&mut base, "base_top", |x| {
        x[1] == 1.0 && (block_x[0]..=block_x[1]).contains(&x[0])
    });
    let mut block = tensor(
        &uniform(block_x[0], block_x[1], columns[1]),
        &uniform(1.0, block_top, rows),
        "block",
    );
    add_curve_group(&mut block, "block_bottom", |x| x[1] == 1.0);
    add_curve_group(&mut block, "block_top", |x| x[1] == block_top);
    merge(base, block, false)
}

/// The sliding block of the allocation, criteria and wear tests: the block
/// [0.5, 2.5] × [1, 1.75] on the base [0, 3] × [0, 1], 6 and 4 columns, 2 rows.
pub fn sliding_block_mesh() -> Mesh {
    block_on_base_mesh(3.0, [0.5, 2.5], 1.75, [6, 4], 2)
}

/// The shrink fit of a solid shaft (radius B) in a hub (outer radius C), both of length L,
/// axisymmetric with the ends held axially (plane strain), the faces overlapping by DELTA:
/// the mesh (programmatic, 6 quad8 through each wall) and the case, with the pair called
/// "fit". Closed form in docs/theory.md ("Lamé cylinders and the shrink fit").
pub mod shrink_fit {
    use super::*;
    use toml::{Table, Value};

    pub const B: f64 = 10.0;
    pub const C: f64 = 20.0;
    pub const L: f64 = 10.0;
    pub const DELTA: f64 = 0.01;
    pub const E: f64 = 200_000.0;
    pub const NU: f64 = 0.3;

    /// Plane-strain compliance C = b (C_s + C_h) of the solid shaft in the hub: the contact
    /// pressure of rigid faces is δ / C.
    pub fn compliance() -> f64 {
        let (e, nu) = (E / (1.0 - NU * NU), NU / (1.0 - NU));
        let cs = (1.0 - nu) / e;
        let ch = ((C * C + B * B) / (C * C - B * B) + nu) / e;
        B * (cs + ch)
    }

    /// Shaft and hub: one conforming mesh with the curve "fit" between them, or two meshes
    /// with coincident faces "shaft_outer" and "hub_bore". Also the curves "shaft_ends",
    /// "hub_ends" and the point "hub_corner" at (C, 0).
    pub fn mesh(conforming: bool) -> Mesh {
        let zs = uniform(0.0, L, 4);
        let mut shaft = tensor(&uniform(0.0, B, 6), &zs, "shaft");
        add_curve_group(&mut shaft, "shaft_ends", |x| x[1] == 0.0 || x[1] == L);
        let mut hub = tensor(&uniform(B, C, 6), &zs, "hub");
        add_curve_group(&mut hub, "hub_ends", |x| x[1] == 0.0 || x[1] == L);
        if conforming {
            add_curve_group(&mut shaft, "fit", |x| (x[0] - B).abs() < 1e-12);
        } else {
            add_curve_group(&mut shaft, "shaft_outer", |x| (x[0] - B).abs() < 1e-12);
            add_curve_group(&mut hub, "hub_bore", |x| (x[0] - B).abs() < 1e-12);
        }
        add_point_group(&mut hub, "hub_corner", [C, 0.0]);
        merge(shaft, hub, conforming)
    }

    /// The case on [`mesh`]`(conforming)` with the interface `law`.
    pub fn case(conforming: bool, law: Table) -> Case {
        let faces: Vec<(&str, Value)> = if conforming {
            vec![
                ("curve", "fit".into()),
                ("body_a", "shaft".into()),
                ("body_b", "hub".into()),
            ]
        } else {
            vec![
                ("side_a", "shaft_outer".into()),
                ("side_b", "hub_bore".into()),
            ]
        };
        let mut keys = vec![("name", "fit".into()), ("interference", DELTA.into())];
        keys.extend(faces);
        CaseBuilder::axisymmetric()
            .body("shaft", elastic(E, NU))
            .body("hub", elastic(E, NU))
            .support("shaft_ends", &[("uz", 0.0)])
            .support("hub_ends", &[("uz", 0.0)])
            .contact(&keys, law)
            .case()
    }
}

/// A perfectly plastic thick cylinder a = 10 ≤ r ≤ b = 20 mm (axisymmetric, σ_Y = 100 MPa,
/// u_z = 0 on both ends) under its limit pressure p_L = (2/√3) σ_Y ln(b/a) as the reference
/// load of arc-length control, which follows it to the limit point (the path of
/// `pipelines/thick_cylinder_riks.toml` on a coarse mesh; the arc adapts, shrinks and is cut
/// back on the plateau). Groups: surface "wall", curves "bore" and "ends".
pub fn plastic_cylinder_under_arc_length() -> (Mesh, CaseBuilder) {
    let (a, b, h, sigma_y) = (10.0, 20.0, 2.5, 100.0);
    let mut mesh = tensor(&uniform(a, b, 6), &uniform(0.0, h, 1), "wall");
    add_curve_group(&mut mesh, "bore", |x| (x[0] - a).abs() < 1e-12);
    add_curve_group(&mut mesh, "ends", |x| x[1] == 0.0 || x[1] == h);
    let p_limit = 2.0 / 3f64.sqrt() * sigma_y * (b / a).ln();
    let mut material = elastic(210_000.0, 0.3);
    material.insert("yield_stress".into(), sigma_y.into());
    let case = CaseBuilder::axisymmetric()
        .body("wall", material)
        .support("ends", &[("uz", 0.0)])
        .pressure("bore", p_limit)
        .set("steps", "control", "arc_length")
        .set("steps", "initial_increment", 0.2)
        .set("steps", "max_load_factor", 1.5)
        .set("steps", "max_increments", 200);
    (mesh, case)
}
