//! `make bench` (twist part): what the circumferential displacement costs a frictional joint
//! (issue 25: "a frictional twist case costs at most 1.5× the same mesh without twist"). The
//! shrink fit of `examples/shrink_fit/shrink_fit.geo` (a solid shaft in a hub, linear Coulomb
//! interface with interference) is pulled apart until the whole fit slides, on the same mesh
//! and in the same steps:
//! (a) axisymmetric without twist: the hub's outer surface pushed axially;
//! (b) with `twist = true` and the same push, u_θ held on the shaft's base: the cost of the
//!     third unknown per node alone;
//! (c) with twist, the push and a rotation of the hub (slip at 45° to the axis): the
//!     frictional twist case, slip in both tangential directions.
//! Each run is timed whole (model built beforehand), best of [`RUNS`] (the small mesh's runs
//! take tens of milliseconds, where three left the ratio to the machine's noise); the ratios to (a) and the
//! best run's ratio to its floor (with the mesh reading and model building it would add) are
//! printed and appended with the machine and date to BENCHMARKS.md. `--quick`: the smaller
//! mesh only.

use std::path::Path;
use std::time::Instant;

mod common;

use asperity::mesh::{gmsh, msh};
use asperity::solver::stepping::run_steps;

/// Interface radius of the geometry (shrink_fit.geo's default b, mm).
const B: f64 = 10.0;
/// Axial travel of the hub's outer surface (mm): several times what it takes the whole fit
/// to slide.
const TRAVEL: f64 = 0.01;
const STEPS: usize = 8;
/// Timed runs of each case; the best counts.
const RUNS: usize = 7;

/// The fit pulled by `push` (mm) and turned by `rotation` (rad) at the hub's outer surface,
/// with (`twist`) or without the circumferential unknown.
fn case(twist: bool, rotation: f64) -> asperity::config::Case {
    let factors: Vec<f64> = (1..=STEPS).map(|k| k as f64 / STEPS as f64).collect();
    let mut base = vec![("uz", 0.0)];
    let mut drive = vec![("uz", TRAVEL)];
    if twist {
        base.push(("utheta", 0.0));
        drive.push(("rotation", rotation));
    }
    let mut builder = common::CaseBuilder::axisymmetric();
    if twist {
        builder = builder.set("analysis", "twist", true);
    }
    builder
        .body("shaft", common::elastic(210000.0, 0.3))
        .body("hub", common::elastic(210000.0, 0.3))
        .support("shaft_bottom", &base)
        .support_history("hub_outer", &drive, &factors)
        .contact(
            &[
                ("side_a", "shaft_outer".into()),
                ("side_b", "hub_bore".into()),
                ("interference", 0.01.into()),
            ],
            common::linear_coulomb(1e5, 1e5, 0.2),
        )
        .steps(STEPS as i64)
        .case()
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let variants = [
        ("no twist", case(false, 0.0)),
        ("twist, axial push", case(true, 0.0)),
        ("twist, push + rotation", case(true, TRAVEL / B)),
    ];
    let mut rows = Vec::new();
    for n in [20usize, 60] {
        let mesh_path = Path::new("build/bench").join(format!("shrink_fit-{n}.msh"));
        gmsh::mesh_geo(
            Path::new("examples/shrink_fit/shrink_fit.geo"),
            1.0,
            &[("n".into(), n as f64)],
            &mesh_path,
        )
        .expect("gmsh");
        let mut reference = None;
        for (name, case) in &variants {
            let t = Instant::now();
            let mesh = msh::read_msh(&mesh_path).expect("read");
            let t_read = t.elapsed().as_secs_f64();
            let model = common::model(mesh, case).expect("model");
            let t_setup = t.elapsed().as_secs_f64();
            let settings = common::settings(case);
            let mut best = (f64::INFINITY, None);
            for _ in 0..RUNS {
                let t = Instant::now();
                let (_, stats) = run_steps(&model, &settings, |_| Ok(0.0)).expect("solve");
                let seconds = t.elapsed().as_secs_f64();
                if seconds < best.0 {
                    best = (seconds, Some(stats));
                }
            }
            let (best, stats) = (best.0, best.1.expect("RUNS > 0"));
            let reference = *reference.get_or_insert(best);
            let row = format!(
                "| {} | {name} | {} | {} | {best:.3} | {:.2} | {:.2} |",
                model.dofs.free_count(),
                model.interface.elements.len(),
                stats.iterations,
                best / reference,
                common::floor_ratio(&stats, t_read, t_setup + best)
            );
            println!("{row}");
            rows.push(row);
        }
        if quick {
            break;
        }
    }
    common::append_table(
        "Twist: a frictional shrink fit pulled until it slides, same mesh with and without u_θ",
        &[
            "unknowns",
            "case",
            "interface elements",
            "Newton iterations",
            "whole run, best of 7 [s]",
            "ratio to no twist",
            "run / floor",
        ],
        &rows,
    );
}
