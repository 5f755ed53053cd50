//! An arc-length run of elastic bodies, whose point states follow the displacements and are
//! kept once, that stops after a failed attempt (the arc halved below `min_arc_length`)
//! leaves the converged state's point states in its solution, not the failed attempt's.

use crate::common;

use asperity::mesh::msh::read_msh;
use asperity::run::newton_settings;
use asperity::solver::stepping::run_steps;
use common::{fixture, model};

/// The largest nodal displacement increment (Euclidean, per node) from `a` to `b`.
fn largest_move(a: &[f64], b: &[f64]) -> f64 {
    a.chunks_exact(2)
        .zip(b.chunks_exact(2))
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max)
}

#[test]
fn a_stopped_arc_length_run_leaves_the_converged_point_states() {
    let case = |limit: f64, min_arc: f64| {
        common::two_blocks(0.3)
            .pressure("lid", 1.0)
            .set("steps", "control", "arc_length")
            .set("steps", "initial_increment", 0.1)
            .set("steps", "max_increments", 2)
            .set("steps", "min_arc_length", min_arc)
            .set("steps", "max_arc_length", 1.5)
            .set("solver", "max_displacement_increment", limit)
            .case()
    };
    let run = |limit: f64, min_arc: f64| {
        let case = case(limit, min_arc);
        let built = model(read_msh(&fixture("contact_pair.msh")).unwrap(), &case).unwrap();
        assert!(built.states_follow_displacements());
        let mut steps = Vec::new();
        let (solution, _) = run_steps(&built, &newton_settings(&case.solver), |step| {
            steps.push((
                step.solution.u.clone(),
                step.solution.point_states().to_vec(),
            ));
            Ok(0.0)
        })
        .unwrap();
        (built, steps, solution)
    };
    // Two increments with no plausibility limit in the way: the second arc is longer (1.5
    // times the first, the largest allowed).
    let (built, free, _) = run(1e3, 1e-4);
    assert_eq!(free.len(), 2);
    let zero = vec![0.0; free[0].0.len()];
    let (first, second) = (
        largest_move(&free[0].0, &zero),
        largest_move(&free[1].0, &free[0].0),
    );
    assert!(second > 1.2 * first, "{first:e} {second:e}");
    // A limit between the two: the second arc fails, its half (0.75 of the first) is below
    // the smallest arc allowed, and the run stops after its first increment.
    let limit = 0.5 * (first + second) / built.size;
    let (_, stopped, solution) = run(limit, 1.0);
    assert_eq!(stopped.len(), 1);
    let (u, states) = &stopped[0];
    assert_eq!(&solution.u, u);
    let bits = |s: &[asperity::material::PointState]| -> Vec<u64> {
        s.iter()
            .flat_map(|p| p.stress.iter().chain(p.strain.iter()).map(|x| x.to_bits()))
            .collect()
    };
    assert_eq!(bits(solution.point_states()), bits(states));
}
