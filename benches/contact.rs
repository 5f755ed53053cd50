//! `make bench` (second part): what the unsymmetric tangent of sliding friction costs. A
//! block is pressed onto a base and pushed along it until every interface point slips
//! (friction, Buczkowski & Kleiber (1994), Eq. 21, makes the tangent unsymmetric there). On
//! that tangent the bench times (a) the symmetric path: numeric Cholesky of the symmetric
//! part + one solve, and (b) the unsymmetric path: the same factorisation used as BiCGSTAB
//! preconditioner on the true tangent, and reports the Krylov iterations. Every whole run
//! (reading the mesh, the model, the solver) is given with its ratio to its floor. Figures go
//! to BENCHMARKS.md.

use std::path::Path;
use std::time::Instant;

mod common;

use asperity::assembly::{AssemblyInput, GlobalSystem};
use asperity::config::Case;
use asperity::mesh::{gmsh, msh};
use asperity::model::Model;
use asperity::solver::linear::CholeskySolver;
use asperity::solver::newton::Problem;
use asperity::solver::state::RunStatistics;
use asperity::solver::stepping::run_steps;

/// The block on the base, pressed and pushed along in two steps, with the linear Coulomb law.
fn case() -> Case {
    common::block_on_base(210000.0, 0.3, &[], common::linear_coulomb(1e5, 1e5, 0.3))
        .pressed_and_pushed(10.0, 0.05, &[0.0, 1.0])
        .case()
}

/// The sliding block with the paper's law (slip hardening, power-law compliance), solved by
/// `algorithm`.
fn rough(algorithm: &str) -> Case {
    common::block_on_base(210000.0, 0.3, &[], common::sliding_rough_joint())
        .pressed_and_pushed(10.0, 0.01, &[0.0, 0.25, 0.5, 0.75, 1.0])
        .set("solver", "max_iterations", 200)
        .set("solver", "contact_algorithm", algorithm)
        .case()
}

/// Iterations and time of each global contact algorithm on the sliding block with the
/// paper's law.
fn algorithms(n: usize, mesh_path: &Path) -> Vec<String> {
    ["newton", "two_step", "elastic_contact"]
        .iter()
        .map(|algorithm| {
            let case = rough(algorithm);
            let (model, stats, t_read, t_run) = whole_run(mesh_path, &case);
            format!(
                "| {} | {algorithm} | {} | {} | {} | {t_run:.3} | {:.2} |",
                model.dofs.free_count(),
                stats.steps,
                stats.iterations,
                stats.unsymmetric_solves,
                common::floor_ratio(&stats, t_read, t_run)
            )
        })
        .inspect(|row| println!("{row} (n = {n})"))
        .collect()
}

/// Reads `mesh_path`, builds the model of `case` and solves it (writing nothing): the model,
/// the run's statistics, and the seconds spent reading the mesh and in all.
fn whole_run(mesh_path: &Path, case: &Case) -> (Model, RunStatistics, f64, f64) {
    let t = Instant::now();
    let mesh = msh::read_msh(mesh_path).expect("read");
    let t_read = t.elapsed().as_secs_f64();
    let model = common::model(mesh, case).expect("model");
    let (_, stats) = run_steps(&model, &common::settings(case), |_| Ok(0.0)).expect("solve");
    (model, stats, t_read, t.elapsed().as_secs_f64())
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let mut algorithm_rows = Vec::new();
    let case = case();
    let mut rows = Vec::new();
    for n in [40usize, 128] {
        let mesh_path = Path::new("build/bench").join(format!("sliding-{n}.msh"));
        gmsh::mesh_geo(
            Path::new("geo/sliding_block.geo"),
            1.0,
            &[("n".into(), n as f64)],
            &mesh_path,
        )
        .expect("gmsh");
        algorithm_rows.extend(algorithms(n, &mesh_path));
        let t = Instant::now();
        let mesh = msh::read_msh(&mesh_path).expect("read");
        let t_read = t.elapsed().as_secs_f64();
        let model = common::model(mesh, &case).expect("model");
        let settings = common::settings(&case);
        let (mut solution, stats) = run_steps(&model, &settings, |_| Ok(0.0)).expect("solve");
        let t_run = t.elapsed().as_secs_f64();
        let slipping = solution
            .interface_committed
            .iter()
            .filter(|s| s.has_unsymmetric_tangent())
            .count();
        // The tangent at the converged sliding state, and its preconditioner, as the solver
        // builds them.
        let mut system = GlobalSystem::new(model.pattern.clone(), model.dofs.dof_count());
        let (u, mut problem) = solution.split(&model);
        let input = AssemblyInput {
            dofs: &model.dofs,
            u,
            tangent: true,
            algorithm: settings.contact_algorithm,
        };
        let symmetric = problem.assemble(&mut system, &input);
        assert!(!symmetric, "the block slips, so its tangent is unsymmetric");
        let mut linear = CholeskySolver::new(&model.pattern).expect("symbolic");
        let rhs: Vec<f64> = (0..model.dofs.free_count())
            .map(|i| ((i % 7) as f64 - 3.0) * 1e-3)
            .collect();
        let mut x = rhs.clone();
        linear
            .solve_unsymmetric(
                system.matrix(),
                system.preconditioner_matrix(),
                &mut x,
                1e-12,
            )
            .expect("warm-up");
        let t = Instant::now();
        let mut x = rhs.clone();
        let iterations = linear
            .solve_unsymmetric(
                system.matrix(),
                system.preconditioner_matrix(),
                &mut x,
                1e-12,
            )
            .expect("unsymmetric");
        let t_unsym = t.elapsed().as_secs_f64();
        // Symmetric path on the same pattern: what an iteration without slipping points costs
        // (numeric Cholesky + one solve of a symmetric matrix of this pattern).
        let t = Instant::now();
        linear
            .factorize(system.preconditioner_matrix())
            .expect("factor");
        let mut y = rhs.clone();
        linear.solve_in_place(&mut y);
        let t_sym = t.elapsed().as_secs_f64();
        let row = format!(
            "| {} | {} | {slipping} | {} | {} | {:.2} | {:.2} | {:.4} | {:.4} | {iterations} | {:.2} |",
            model.dofs.free_count(),
            model.interface.elements.len(),
            stats.iterations,
            stats.unsymmetric_solves,
            t_run,
            common::floor_ratio(&stats, t_read, t_run),
            t_sym,
            t_unsym,
            t_unsym / t_sym
        );
        println!("{row}");
        rows.push(row);
        if quick {
            break;
        }
    }
    common::append_table(
        "Sliding block, unsymmetric friction tangent (plane strain)",
        &[
            "unknowns",
            "interface elements",
            "slipping points",
            "Newton iterations (2 steps)",
            "unsymmetric solves",
            "whole run [s]",
            "run / floor",
            "symmetric factorise+solve [s]",
            "unsymmetric solve [s]",
            "BiCGSTAB iterations",
            "ratio",
        ],
        &rows,
    );
    common::append_table(
        "Global contact algorithms, sliding block with the paper's law (5 steps of push-along)",
        &[
            "unknowns",
            "algorithm",
            "steps",
            "Newton iterations",
            "unsymmetric solves",
            "whole run [s]",
            "run / floor",
        ],
        &algorithm_rows,
    );
}
