//! The bound on a linear bulk's strain increment (`asperity::solver::strain_bound`), which
//! spares a converged increment whose force is K·u its element loop, is never below the
//! largest strain increment its point states give — on every analysis (plane strain, plane
//! stress, axisymmetry with and without twist), formulation (full, B-bar) and cell kind
//! (quad8, tri6) — is not needlessly loose on a smooth field, and sees no strain in a
//! translation that strains nothing.

use crate::common;

use asperity::config::SolverSpec;
use asperity::mesh::msh::read_msh;
use asperity::model::Model;
use asperity::run::newton_settings;
use asperity::solver::newton::Newton;
use asperity::solver::state::Solution;
use asperity::solver::strain_bound::StrainBound;
use common::{CaseBuilder, elastic, fixture, model};

/// The meshes, their bodies and the curves that hold them: two quad8 blocks [0,2]×[0,1] and
/// [0,2]×[1,2], and two tri6 bodies on a base.
const MESHES: [(&str, [&str; 2], &[&str]); 2] = [
    ("contact_pair.msh", ["lower", "upper"], &["base", "lid"]),
    ("tri6.msh", ["left", "right"], &["base"]),
];

/// A case of an analysis, with nothing in it yet.
type Analysis = fn() -> CaseBuilder;

/// Every analysis, formulation and mesh, each with the case's name; ν = 0.45 (plane
/// stress's out-of-plane strain grows with ν).
fn models() -> Vec<(String, Model)> {
    let analyses: [(&str, Analysis); 4] = [
        ("plane strain", CaseBuilder::plane_strain),
        ("plane stress", || CaseBuilder::plane_stress(1.0)),
        ("axisymmetric", CaseBuilder::axisymmetric),
        ("twist", || {
            CaseBuilder::axisymmetric().set("analysis", "twist", true)
        }),
    ];
    let mut out = Vec::new();
    for (analysis, builder) in analyses {
        for formulation in ["full", "bbar"] {
            if analysis == "plane stress" && formulation == "bbar" {
                continue;
            }
            for (mesh, bodies, held) in MESHES {
                let mut case = builder().mesh_file(&fixture(mesh));
                for body in bodies {
                    case = case.body_with(body, elastic(1000.0, 0.45), formulation);
                }
                let components: &[(&str, f64)] = if analysis == "twist" {
                    &[("ux", 0.0), ("uy", 0.0), ("utheta", 0.0)]
                } else {
                    &[("ux", 0.0), ("uy", 0.0)]
                };
                for group in held {
                    case = case.support(group, components);
                }
                let case = case.case();
                let built = model(read_msh(&fixture(mesh)).unwrap(), &case).unwrap();
                out.push((format!("{analysis}, {formulation}, {mesh}"), built));
            }
        }
    }
    out
}

/// A small pseudo-random generator (the same numbers on every machine).
struct Numbers(u64);

impl Numbers {
    /// The next number in [−1, 1).
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// A displacement increment over all dofs: a translation, a smooth quadratic field and, if
/// `noise`, a different random value at every node.
fn increment(model: &Model, numbers: &mut Numbers, noise: bool) -> Vec<f64> {
    let d = model.analysis.dofs_per_node();
    let mut du = vec![0.0; model.dofs.dof_count()];
    let coefficients: Vec<[f64; 6]> = (0..d)
        .map(|_| std::array::from_fn(|_| numbers.next()))
        .collect();
    for (node, &[x, y]) in model.mesh.nodes.iter().enumerate() {
        for (c, k) in coefficients.iter().enumerate() {
            let smooth =
                10.0 * k[0] + k[1] * x + k[2] * y + k[3] * x * x + k[4] * x * y + k[5] * y * y;
            let rough = if noise { numbers.next() } else { 0.0 };
            du[d * node + c] = 1e-4 * (smooth + rough);
        }
    }
    du
}

/// The largest equivalent strain increment of the point states from zero displacements to
/// `du`.
fn exact(model: &Model, du: &[f64]) -> f64 {
    let settings = newton_settings(&SolverSpec::default());
    let mut newton = Newton::new(settings, &model.dofs, &model.pattern).unwrap();
    let mut solution = Solution::new(model);
    let (_, mut problem) = solution.split(model);
    let start = vec![0.0; du.len()];
    newton.strain_increment(&mut problem, &start, du)
}

#[test]
fn the_bound_is_never_below_the_point_states_largest_strain_increment() {
    let mut numbers = Numbers(29);
    for (name, model) in models() {
        let bound = StrainBound::new(&model);
        let zero = vec![0.0; model.dofs.dof_count()];
        for trial in 0..12 {
            let du = increment(&model, &mut numbers, trial % 2 == 1);
            let (exact, bound) = (exact(&model, &du), bound.of(&model, &du, &zero));
            assert!(exact > 0.0, "{name}: trial {trial} strains nothing");
            assert!(
                bound >= exact,
                "{name}, trial {trial}: bound {bound:e} < {exact:e}"
            );
            // Loose by the norms it uses, not by orders of magnitude: a filter that lets
            // through every ordinary increment.
            assert!(
                bound <= 40.0 * exact,
                "{name}, trial {trial}: bound {bound:e} against {exact:e}"
            );
        }
        // Increments from a displaced state count only the change.
        let (u_old, du) = (
            increment(&model, &mut numbers, true),
            increment(&model, &mut numbers, false),
        );
        let u: Vec<f64> = u_old.iter().zip(&du).map(|(a, b)| a + b).collect();
        assert!(
            bound.of(&model, &u, &u_old) >= exact(&model, &du),
            "{name}: from a displaced state"
        );
    }
}

#[test]
fn a_translation_that_strains_nothing_has_a_zero_bound() {
    for (name, model) in models() {
        let bound = StrainBound::new(&model);
        let d = model.analysis.dofs_per_node();
        let zero = vec![0.0; model.dofs.dof_count()];
        // Along y (the axis of symmetry), and along x too in a plane analysis; in
        // axisymmetry a radial translation is a hoop strain u_r / r, which the bound sees.
        let components: &[usize] = if model.analysis.is_axisymmetric() {
            &[1]
        } else {
            &[0, 1]
        };
        for &c in components {
            let mut du = zero.clone();
            du.iter_mut().skip(c).step_by(d).for_each(|v| *v = 0.5);
            let b = bound.of(&model, &du, &zero);
            assert!(b < 1e-12, "{name}: translation {c} bounded by {b:e}");
        }
        if model.analysis.is_axisymmetric() {
            let mut du = zero.clone();
            du.iter_mut().step_by(d).for_each(|v| *v = 1e-3);
            let (b, e) = (bound.of(&model, &du, &zero), exact(&model, &du));
            assert!(
                b >= e && e > 0.0,
                "{name}: radial translation {b:e} < {e:e}"
            );
        }
    }
}

#[test]
fn a_displacement_that_is_not_a_number_has_no_bound() {
    let (_, model) = models().swap_remove(0);
    let mut du = vec![0.0; model.dofs.dof_count()];
    du[7] = f64::NAN;
    let zero = vec![0.0; model.dofs.dof_count()];
    assert!(StrainBound::new(&model).of(&model, &du, &zero).is_nan());
}

/// Two elastic blocks on a frictional joint pressed together by moving the upper one's lid
/// down, in two steps, with `max_strain_increment` below the strain of a whole step:
/// increments are cut back until they pass. Elastic states follow the displacements and are
/// kept once, so their increments are judged by the bound, and exactly — from the states at
/// the increment's start and end, made cell by cell — where the bound exceeds the limit: on
/// the condensed path (contact, the bulk's force K·u) and with the Krylov solver (every
/// iteration evaluates the elements). The reference keeps committed and trial states and
/// compares them point by point: the same blocks, the lower one of a J2 material that never
/// yields (yield stress 1e12 MPa). All three must cut back alike.
#[test]
fn a_linear_bulk_judges_its_increments_as_its_point_states_do() {
    let run = |solver: &str, yield_stress: Option<f64>| {
        let material = match yield_stress {
            Some(s) => common::with_keys(common::elastic(1000.0, 0.3), &[("yield_stress", s)]),
            None => common::elastic(1000.0, 0.3),
        };
        let case = common::two_blocks_on(material, 0.3)
            .support("lid", &[("ux", 0.0), ("uy", -0.01)])
            .steps(2)
            .set("solver", "max_strain_increment", 1.5e-3)
            .set("solver", "linear_solver", solver)
            .case();
        let mesh = read_msh(&fixture("contact_pair.msh")).unwrap();
        let built = model(mesh, &case).unwrap();
        assert_eq!(built.states_follow_displacements(), yield_stress.is_none());
        let settings = newton_settings(&case.solver);
        asperity::solver::stepping::run_steps(&built, &settings, |_| Ok(0.0))
            .unwrap()
            .1
    };
    let (condensed, krylov) = (run("condensed", None), run("krylov", None));
    let stored = run("krylov", Some(1e12));
    assert!(stored.cutbacks > 0, "the limit cuts back: {stored:?}");
    for stats in [&condensed, &krylov] {
        assert_eq!(
            (stats.cutbacks, stats.increments),
            (stored.cutbacks, stored.increments)
        );
    }
    let work = condensed.work.solver;
    // The increments whose bound exceeded the limit were judged from their point states at
    // their start and end (two loops each, storing nothing); each step's frame made the
    // converged state's.
    assert!(
        work.state_evaluations.calls >= 2 * condensed.cutbacks,
        "{work:?}"
    );
    assert_eq!(work.state_evaluations.calls % 2, 0, "{work:?}");
    assert!(work.frame_states.calls <= 2, "{work:?}");
}

/// Elastic states follow the displacements: a solution keeps them once (no committed
/// array), a plastic body's twice.
#[test]
fn states_that_follow_the_displacements_are_kept_once() {
    for (name, built) in models() {
        let solution = Solution::new(&built);
        assert!(solution.states_follow_displacements, "{name}");
        assert!(solution.committed.is_empty(), "{name}");
        assert_eq!(
            solution.point_states().len(),
            built.continuum.cells.len() * 9,
            "{name}"
        );
    }
    let plastic = common::with_keys(common::elastic(1000.0, 0.3), &[("yield_stress", 50.0)]);
    let case = common::two_blocks_on(plastic, 0.3).case();
    let built = model(read_msh(&fixture("contact_pair.msh")).unwrap(), &case).unwrap();
    let solution = Solution::new(&built);
    assert!(!solution.states_follow_displacements);
    assert_eq!(solution.committed.len(), solution.trial.len());
}
