//! `make bench`: times mesh reading, model set-up, assembly, ordering + symbolic
//! factorisation, numeric factorisation and solve of a plane-strain elastic block at about
//! 10k, 100k and 1M unknowns, then the whole run (reading, model, solver) and its ratio to
//! its floor, and appends the figures (machine and date) to BENCHMARKS.md.
//! Pass `--quick` to stop after the smallest size.

use std::path::Path;
use std::time::Instant;

mod common;

use asperity::assembly::{AssemblyInput, GlobalSystem};
use asperity::contact::ContactAlgorithm;
use asperity::material::PointState;
use asperity::mesh::{gmsh, msh};
use asperity::solver::linear::CholeskySolver;
use asperity::solver::stepping::run_steps;

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let dir = Path::new("build/bench");
    let case = common::CaseBuilder::plane_strain()
        .body("block", common::elastic(210000.0, 0.3))
        .support("bottom", &[("uy", 0.0)])
        .support("left", &[("ux", 0.0)])
        .pressure("top", 10.0)
        .case();
    let mut rows = Vec::new();
    for n in [41usize, 129, 408] {
        let mesh_path = dir.join(format!("block-{n}.msh"));
        let t = Instant::now();
        gmsh::mesh_geo(
            Path::new("geo/block.geo"),
            1.0,
            &[("n".into(), n as f64)],
            &mesh_path,
        )
        .expect("gmsh");
        let t_gmsh = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mesh = msh::read_msh(&mesh_path).expect("read");
        let t_read = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let model = common::model(mesh, &case).expect("model");
        let t_model = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut linear = CholeskySolver::new(&model.pattern).expect("symbolic");
        let t_symbolic = t.elapsed().as_secs_f64();
        let states = model.continuum.cells.len() * 9;
        let committed = vec![PointState::default(); states];
        let mut trial = committed.clone();
        let u = vec![0.0; model.dofs.dof_count()];
        let mut system = GlobalSystem::new(model.pattern.clone(), model.dofs.dof_count());
        let t = Instant::now();
        let input = AssemblyInput {
            dofs: &model.dofs,
            u: &u,
            tangent: true,
            algorithm: ContactAlgorithm::default(),
        };
        system.assemble(
            &input,
            &model.continuum,
            &model.continuum_coloring,
            &committed,
            &mut trial,
        );
        let t_assembly = t.elapsed().as_secs_f64();
        let t = Instant::now();
        linear.factorize(system.matrix()).expect("factorise");
        let t_factor = t.elapsed().as_secs_f64();
        // Second numeric factorisation: the cost of every later Newton iteration.
        let t = Instant::now();
        linear.factorize(system.matrix()).expect("refactorise");
        let t_refactor = t.elapsed().as_secs_f64();
        let mut rhs = vec![0.0; model.dofs.free_count()];
        let mut load = vec![0.0; model.dofs.dof_count()];
        model.external_force(1.0, &mut load);
        model.dofs.gather_free(&load, &mut rhs);
        let t = Instant::now();
        linear.solve_in_place(&mut rhs);
        let t_solve = t.elapsed().as_secs_f64();
        let factor_mb = linear.factor_nnz() as f64 * 8.0 / 1e6;
        // Freed before the whole run makes its own (the factor at 1M unknowns is 1.3 GB); the
        // row reads the run's model, the same.
        drop((linear, system, model, committed, trial));
        // The whole run, as `asperity run` makes it (without its files), and its floor.
        let t = Instant::now();
        let mesh = msh::read_msh(&mesh_path).expect("read");
        let t_run_read = t.elapsed().as_secs_f64();
        let model = common::model(mesh, &case).expect("model");
        let (_, stats) = run_steps(&model, &common::settings(&case), |_| Ok(0.0)).expect("solve");
        let t_run = t.elapsed().as_secs_f64();
        let row = format!(
            "| {} | {} | {} | {:.2} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.1} | {:.3} | {:.2} |",
            model.dofs.free_count(),
            model.continuum.cells.len(),
            model.pattern.nnz(),
            t_gmsh,
            t_read,
            t_model,
            t_assembly,
            t_symbolic,
            t_factor,
            t_refactor,
            t_solve,
            factor_mb,
            t_run,
            common::floor_ratio(&stats, t_run_read, t_run),
        );
        println!("{row}");
        rows.push(row);
        if quick {
            break;
        }
    }
    append_to_benchmarks(&rows);
}

fn append_to_benchmarks(rows: &[String]) {
    common::append_table(
        "Elastic block (plane strain, quad8)",
        &[
            "unknowns",
            "elements",
            "matrix nnz",
            "gmsh [s]",
            "read [s]",
            "model [s]",
            "assembly [s]",
            "AMD+symbolic [s]",
            "factorise [s]",
            "refactorise [s]",
            "solve [s]",
            "factor [MB]",
            "whole run [s]",
            "run / floor",
        ],
        rows,
    );
}
