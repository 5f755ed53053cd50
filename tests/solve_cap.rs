//! `[solver] max_solves` counts every increment solve: the sub-increments that amplitude
//! breakpoints add (counted before solving, from the amplitudes) and the attempts that
//! cut-backs retry (counted as the run goes).
use crate::common;

use asperity::Error;
use common::{
    CaseBuilder, block_on_base, block_on_base_mesh, elastic, list, model, rectangle, settings,
    sliding_rough_joint, table,
};
use toml::Value;

/// The elastic plate [0, 2] × [0, 1] on rollers, pulled on its right edge through one step
/// 'wave' of 2 increments whose amplitude has a breakpoint every 0.05 of the step: 21 knots,
/// of which 18 lie inside an increment (u = 0.1 k, k = 1 … 19 without u = 1), so the step
/// takes 2 + 18 = 20 solves.
fn wave(max_solves: i64) -> CaseBuilder {
    let time: Vec<f64> = (0..=20).map(|k| k as f64 / 20.0).collect();
    let value: Vec<f64> = time.iter().map(|t| (t * 7.0).sin()).collect();
    let amplitude = table(&[("time", list(&time)), ("value", list(&value))]);
    CaseBuilder::plane_strain()
        .body("body", elastic(1000.0, 0.3))
        .support("s0", &[("ux", 0.0)])
        .support("t0", &[("uy", 0.0)])
        .push(
            "load",
            table(&[
                ("name", "pull".into()),
                ("group", "s1".into()),
                ("traction", list(&[1.0, 0.0])),
            ]),
        )
        .push(
            "step",
            table(&[
                ("name", "wave".into()),
                ("increments", 2.into()),
                ("loads", table(&[("pull", Value::from(amplitude))]).into()),
            ]),
        )
        .set("solver", "max_solves", max_solves)
}

#[test]
fn amplitude_breakpoints_count_before_solving() {
    let mesh = || rectangle(2.0, 1.0, 2, 1, 0.0, false);
    // At the limit: the run makes exactly the 20 planned solves.
    let case = wave(20).case();
    let built = model(mesh(), &case).expect("20 solves are allowed");
    let (_, stats) = asperity::solver::stepping::run_steps(&built, &settings(&case), |_| Ok(0.0))
        .expect("the elastic plate solves");
    assert_eq!(stats.increments + stats.cutbacks, 20);
    // One below: refused when the model is built, naming the step and the key.
    let error = model(mesh(), &wave(19).case()).expect_err("19 solves are too few");
    let text = error.to_string();
    let Error::TooManySolves {
        at,
        count,
        limit,
        planned,
    } = &error
    else {
        panic!("expected the solve limit, got: {text}");
    };
    assert_eq!((*count, *limit, *planned), (20, 19, true));
    assert_eq!(at.step, Some(("wave".to_string(), 0)));
    assert_eq!(error.exit_code(), 3);
    assert!(
        text.contains("step 'wave' (step[0])") && text.contains("raise solver.max_solves"),
        "{text}"
    );
}

/// The sliding block whose rough joint runs out of friction at 2/3 of step 'shear' (see
/// tests/diagnosis.rs) plans 2 + 10 = 12 solves; its cut-backs at the capacity would make
/// more. With `max_solves = 14` the run stops in step 'shear' when the 14th solve is
/// spent (exit code 1: it did not get to an answer), not after its cut-backs.
#[test]
fn cut_back_retries_count_as_the_run_goes() {
    let load = |name: &str, kind: &str, value: Value| {
        table(&[
            ("name", name.into()),
            ("group", "block_top".into()),
            (kind, value),
        ])
    };
    let step = |name: &str, increments: i64, target: &str| {
        table(&[
            ("name", name.into()),
            ("increments", increments.into()),
            ("loads", table(&[(target, 1.0.into())]).into()),
        ])
    };
    let case = block_on_base(
        1000.0,
        0.3,
        &[("name", "joint".into())],
        sliding_rough_joint(),
    )
    .push("load", load("press", "pressure", 10.0.into()))
    .push("load", load("shear", "traction", list(&[4.5, 0.0])))
    .push("step", step("press", 2, "press"))
    .push("step", step("shear", 10, "shear"))
    .set("solver", "max_solves", 14)
    .case();
    let mesh = block_on_base_mesh(3.0, [0.5, 2.5], 1.75, [6, 4], 2);
    let built = model(mesh, &case).expect("12 planned solves are within 14");
    let error = asperity::solver::stepping::run_steps(&built, &settings(&case), |_| Ok(0.0))
        .expect_err("the joint cannot carry the shear");
    let text = error.to_string();
    let Error::TooManySolves {
        at,
        count,
        limit,
        planned,
    } = &error
    else {
        panic!("expected the solve limit, got: {text}");
    };
    assert_eq!((*count, *limit, *planned), (14, 14, false));
    assert_eq!(at.step, Some(("shear".to_string(), 1)));
    assert_eq!(error.exit_code(), 1);
    assert!(
        text.contains("step 'shear' (step[1])") && text.contains("raise solver.max_solves"),
        "{text}"
    );
}
