//! Why a step failed, in the user's terms: the mechanism (friction capacity, plastic
//! collapse, a lost support), the `[[step]]` by name and the multiplier of its load reached.
//! Each case has a limit known in closed form, which the reported multiplier must respect.
use crate::common;

use asperity::Error;
use asperity::error::{LoadPoint, Mechanism};
use common::{
    CaseBuilder, block_on_base, block_on_base_mesh, elastic, linear_coulomb, list, model,
    rectangle, settings, sliding_rough_joint, table, with_keys,
};
use toml::{Table, Value};

/// A `[[step]]` called `name` of `increments` increments setting the multipliers of `loads`.
fn step(name: &str, increments: i64, loads: &[(&str, Value)]) -> Table {
    table(&[
        ("name", name.into()),
        ("increments", increments.into()),
        ("loads", table(loads).into()),
    ])
}

/// A named load on the curve `group`: a `pressure` or a `traction`.
fn load(name: &str, group: &str, kind: &str, value: Value) -> Table {
    table(&[
        ("name", name.into()),
        ("group", group.into()),
        (kind, value),
    ])
}

/// Runs `case` on `mesh` and returns the error it stops with.
fn failure(mesh: asperity::mesh::Mesh, case: &CaseBuilder) -> Error {
    let case = case.case();
    let model = model(mesh, &case).expect("the model builds");
    match asperity::solver::stepping::run_steps(&model, &settings(&case), |_| Ok(0.0)) {
        Ok(_) => panic!("the run was expected to fail"),
        Err(e) => e,
    }
}

/// The multiplier of history.csv column `column` at `point`.
fn multiplier(point: &LoadPoint, column: &str) -> f64 {
    point
        .multipliers
        .iter()
        .find(|(c, _)| c == column)
        .unwrap_or_else(|| panic!("no {column} in {point:?}"))
        .1
}

/// The sliding block [0.5, 2.5] × [1, 1.75] on the base [0, 3] × [0, 1] (held on the
/// ground), joined by the pair "joint" with `law`, and its top loaded by `loads` through
/// `steps`.
fn block(law: Table, loads: &[Table], steps: &[Table]) -> (asperity::mesh::Mesh, CaseBuilder) {
    let mesh = block_on_base_mesh(3.0, [0.5, 2.5], 1.75, [6, 4], 2);
    let mut case = block_on_base(1000.0, 0.3, &[("name", "joint".into())], law);
    for l in loads {
        case = case.push("load", l.clone());
    }
    for s in steps {
        case = case.push("step", s.clone());
    }
    (mesh, case)
}

/// An elastic block pressed by 10 MPa on a slip-hardening rough joint (μ from β μ_m = 0.09 to
/// μ_m = 0.3) and then sheared by a traction rising to 4.5 MPa: the joint carries at most
/// μ_m · 10 = 3 MPa, 2/3 of the shear step. The failure is the joint's friction capacity,
/// not a plastic collapse (the bodies are elastic), a limit load (exit code 5), reported in
/// step 'shear' at a shear multiplier below 2/3.
#[test]
fn exhausted_slip_hardening_friction_is_friction_capacity() {
    let (mesh, case) = block(
        sliding_rough_joint(),
        &[
            load("press", "block_top", "pressure", 10.0.into()),
            load("shear", "block_top", "traction", list(&[4.5, 0.0])),
        ],
        &[
            step("press", 2, &[("press", 1.0.into())]),
            step("shear", 10, &[("shear", 1.0.into())]),
        ],
    );
    let error = failure(mesh, &case);
    let text = error.to_string();
    let Error::Collapse {
        mechanism, details, ..
    } = &error
    else {
        panic!("expected a limit load, got: {text}");
    };
    let Mechanism::FrictionCapacity { pairs, bodies } = mechanism else {
        panic!("expected friction capacity, got: {text}");
    };
    assert_eq!(pairs, &["joint"]);
    assert_eq!(bodies.len(), 1, "{text}");
    assert_eq!(bodies[0].body, "block");
    assert_eq!(bodies[0].translations, [[1.0, 0.0]], "{text}");
    assert_eq!(error.exit_code(), 5);
    assert_eq!(details.reached.step, Some(("shear".to_string(), 1)));
    let reached = multiplier(&details.reached, "factor_load_shear");
    // Beyond the initial friction β μ_m p (0.2 of the step) and within the capacity.
    assert!(
        reached > 0.2 && reached <= 2.0 / 3.0 + 1e-9,
        "{reached}: {text}"
    );
    assert_eq!(details.reached.step_time, reached, "a ramp from 0 to 1");
    assert!(
        text.starts_with("friction capacity exceeded")
            && text.contains("step 'shear' (step[1])")
            && text.contains("factor_load_shear = ")
            && !text.contains("plastic"),
        "{text}"
    );
}

/// A perfectly plastic plate in plane strain pulled by σ = 1.3 σ_y in step 'pull' after a
/// 'preload' step: it yields first at σ/σ_y = 1/√(1 − ν + ν²) = 1.125 and cannot carry more
/// than the plane-strain limit 2/√3 = 1.1547 (σ_zz → σ_xx/2). The run stops in step 'pull'
/// with a plastic collapse whose multiplier lies between the two.
#[test]
fn an_overloaded_plastic_plate_is_a_plastic_collapse_in_its_step() {
    let sigma_y = 100.0;
    let material = with_keys(elastic(1000.0, 0.3), &[("yield_stress", sigma_y)]);
    let case = CaseBuilder::plane_strain()
        .body("body", material)
        .support("s0", &[("ux", 0.0)])
        .support("t0", &[("uy", 0.0)])
        .push(
            "load",
            load("pull", "s1", "traction", list(&[sigma_y, 0.0])),
        )
        .push("step", step("preload", 2, &[("pull", 0.5.into())]))
        .push("step", step("pull", 8, &[("pull", 1.3.into())]));
    let error = failure(rectangle(2.0, 1.0, 2, 1, 0.0, false), &case);
    let text = error.to_string();
    let Error::Collapse {
        mechanism: Mechanism::PlasticCollapse { .. },
        details,
        ..
    } = &error
    else {
        panic!("expected a plastic collapse, got: {text}");
    };
    assert_eq!(error.exit_code(), 5);
    assert_eq!(details.reached.step, Some(("pull".to_string(), 1)));
    let reached = multiplier(&details.reached, "factor_load_pull");
    let first_yield = 1.0 / (1.0f64 - 0.3 + 0.09).sqrt();
    let limit = 2.0 / 3.0f64.sqrt();
    assert!(
        reached >= first_yield && reached <= limit,
        "{reached} outside [{first_yield}, {limit}]: {text}"
    );
    assert!(
        text.starts_with("plastic collapse") && text.contains("step 'pull' (step[1])"),
        "{text}"
    );
}

/// A block pressed on a frictional joint by 1 MPa, then pulled off: the pressure ramps to
/// −1 MPa in step 'lift' and the joint, which carries no tension, opens at half the step.
/// Nothing else holds the block: a lost support in step 'lift', at a multiplier of the
/// load at most 0 (the contact carries compression only).
#[test]
fn a_block_pulled_off_its_contact_has_lost_its_support() {
    let (mesh, case) = block(
        linear_coulomb(1e4, 1e4, 0.3),
        &[load("press", "block_top", "pressure", 1.0.into())],
        &[
            step("press", 2, &[("press", 1.0.into())]),
            step("lift", 4, &[("press", (-1.0).into())]),
        ],
    );
    let error = failure(mesh, &case);
    let text = error.to_string();
    let Error::Collapse {
        mechanism: Mechanism::LostSupport { open_pairs, bodies },
        details,
        ..
    } = &error
    else {
        panic!("expected a lost support, got: {text}");
    };
    assert_eq!(open_pairs, &["joint"]);
    assert_eq!(bodies.len(), 1);
    assert_eq!(bodies[0].body, "block");
    assert!(bodies[0].translations.contains(&[0.0, 1.0]), "{text}");
    assert_eq!(details.reached.step, Some(("lift".to_string(), 1)));
    let reached = multiplier(&details.reached, "factor_load_press");
    assert!((-1e-9..=1.0).contains(&reached), "{reached}: {text}");
    assert!(
        text.starts_with("loss of support: contact 'joint' opened")
            && text.contains("step 'lift' (step[1])"),
        "{text}"
    );
}

/// Inputs far outside any physical range drive forces, stresses or stiffnesses beyond what
/// the residual norms can square in double precision (NaN or infinite residuals). The run
/// cannot converge at any increment; the failure names the input that did it — the loads,
/// a support's prescribed value, a contact law's parameters — by its case-file key, and is
/// not taken for a mechanism (the contact states of such an attempt mean nothing).
#[test]
fn values_beyond_double_precision_name_the_input_that_drove_them() {
    let press = |pressure: f64| {
        (
            vec![load("press", "block_top", "pressure", pressure.into())],
            vec![step("press", 2, &[("press", 1.0.into())])],
        )
    };
    let rough_m = with_keys(sliding_rough_joint(), &[("m", 1e300)]);
    let cases = [
        (
            "huge pressure",
            linear_coulomb(1e4, 1e4, 0.3),
            1e300,
            None,
            "the applied loads reach",
        ),
        (
            "huge k_N",
            linear_coulomb(1e300, 1e4, 0.3),
            1.0,
            None,
            "contact 'joint' (linear Coulomb, k_N = 1e300",
        ),
        (
            "huge rough-law m",
            rough_m,
            1.0,
            None,
            "contact 'joint' (rough joint",
        ),
        (
            "huge prescribed ux",
            linear_coulomb(1e4, 1e4, 0.3),
            1.0,
            Some(1e300),
            "[[support]] 'block_top' prescribes ",
        ),
    ];
    for (label, law, pressure, push, expected) in cases {
        let (loads, mut steps) = press(pressure);
        if push.is_some() {
            let supports = table(&[("block_top", 1.0.into())]);
            steps[0].insert("supports".into(), supports.into());
        }
        let (mesh, mut case) = block(law, &loads, &steps);
        if let Some(ux) = push {
            case = case.support("block_top", &[("ux", ux)]);
        }
        let error = failure(mesh, &case);
        let text = error.to_string();
        let Error::NoConvergence(details) = &error else {
            panic!("{label}: expected a failure to converge, got: {text}");
        };
        let cause = details.out_of_range.as_deref().unwrap_or_default();
        assert!(cause.contains(expected), "{label}: {text}");
        assert!(details.mechanism.is_none(), "{label}: {text}");
        assert!(
            text.contains("Likely cause: values beyond the range of double precision"),
            "{label}: {text}"
        );
    }
}
