//! Thermal strain (`expansion`, `[[temperature]]`) against closed forms: a free body under a
//! uniform temperature change (plane stress, plane strain, axisymmetry), a clamped bar
//! (stress −E α ΔT and the energy ledger), step histories, and a hub heated on a shaft with
//! an interference (Lamé pressure of the interference left at temperature, contact lost
//! exactly when α ΔT a exceeds it; (1 + ν) α ΔT a with ε_z = 0).
use crate::common;

use asperity::mesh::Mesh;
use common::*;
use toml::Value;

const E: f64 = 200_000.0;
const NU: f64 = 0.3;
const ALPHA: f64 = 1.2e-5;
const DT: f64 = 150.0;

fn steel() -> toml::Table {
    with_keys(elastic(E, NU), &[("expansion", ALPHA)])
}

fn temperature(group: &str, change: f64) -> toml::Table {
    table(&[("group", group.into()), ("change", change.into())])
}

/// Largest |u − expected(x)| over the nodes and largest |σ| over the points (in-plane and
/// out-of-plane components separately).
fn check_free(case: CaseBuilder, mesh: Mesh, expected: impl Fn([f64; 2]) -> [f64; 2]) -> f64 {
    let (model, solution) = solve(mesh, &case.case());
    let mut worst: f64 = 0.0;
    for (n, x) in model.mesh.nodes.iter().enumerate() {
        let u = displacement(&solution, n);
        let e = expected(*x);
        worst = worst.max((u[0] - e[0]).abs()).max((u[1] - e[1]).abs());
    }
    let scale = ALPHA * DT * 10.0;
    assert!(worst < 1e-9 * scale, "displacement error {worst:e}");
    solution
        .point_states()
        .iter()
        .map(|s| {
            s.stress[0]
                .abs()
                .max(s.stress[1].abs())
                .max(s.stress[2].abs())
        })
        .fold(0.0, f64::max)
}

#[test]
fn a_free_body_expands_without_stress() {
    let e = ALPHA * DT;
    for triangles in [false, true] {
        let mesh = || rectangle(10.0, 4.0, 4, 3, 0.3, triangles);
        // Plane stress: u = α ΔT x, no stress at all.
        let case = CaseBuilder::plane_stress(1.0)
            .body("body", steel())
            .support("s0", &[("ux", 0.0)])
            .support("t0", &[("uy", 0.0)])
            .push("temperature", temperature("body", DT));
        let stress = check_free(case, mesh(), |x| [e * x[0], e * x[1]]);
        assert!(stress < 1e-9 * E * e, "plane stress: stress {stress:e}");
        // Plane strain: ε_z = 0 holds the body, σ_zz = −E α ΔT, the plane grows by
        // (1 + ν) α ΔT and carries no in-plane stress.
        let case = CaseBuilder::plane_strain()
            .body("body", steel())
            .support("s0", &[("ux", 0.0)])
            .support("t0", &[("uy", 0.0)])
            .push("temperature", temperature("body", DT));
        let ep = (1.0 + NU) * e;
        let stress = check_free(case.clone(), mesh(), |x| [ep * x[0], ep * x[1]]);
        assert!(
            stress < 1e-9 * E * e,
            "plane strain: in-plane stress {stress:e}"
        );
        let (_, solution) = solve(mesh(), &case.case());
        for s in solution
            .point_states()
            .iter()
            .filter(|s| s.stress[3] != 0.0)
        {
            assert!(
                (s.stress[3] + E * e).abs() < 1e-9 * E * e,
                "σ_zz = {}",
                s.stress[3]
            );
            assert!(s.strain[3].abs() < 1e-15, "total ε_zz = {}", s.strain[3]);
        }
    }
    // Axisymmetry, a cylinder on the axis: u_r = α ΔT r, u_z = α ΔT z.
    let case = CaseBuilder::axisymmetric()
        .body("body", steel())
        .support("t0", &[("uz", 0.0)])
        .push("temperature", temperature("body", DT));
    let stress = check_free(case, rectangle(10.0, 4.0, 4, 3, 0.2, false), |x| {
        [e * x[0], e * x[1]]
    });
    assert!(stress < 1e-9 * E * e, "axisymmetric: stress {stress:e}");
}

#[test]
fn a_clamped_bar_is_compressed_by_e_alpha_dt_and_its_energy_balances() {
    // Plane stress bar held at both ends (u_x = 0) and on its axis: σ_xx = −E α ΔT; the
    // supports do no work, the stored energy ½ E (α ΔT)² V is the thermal strain's work.
    let case = CaseBuilder::plane_stress(2.0)
        .body("body", steel())
        .support("s0", &[("ux", 0.0)])
        .support("s1", &[("ux", 0.0)])
        .support("t0", &[("uy", 0.0)])
        .push("temperature", temperature("body", DT))
        .steps(3);
    let (_, solution) = solve(rectangle(10.0, 4.0, 5, 2, 0.2, false), &case.case());
    let sigma = -E * ALPHA * DT;
    for s in solution
        .point_states()
        .iter()
        .filter(|s| s.stress[0] != 0.0)
    {
        assert!(
            (s.stress[0] - sigma).abs() < 1e-9 * sigma.abs(),
            "{}",
            s.stress[0]
        );
        assert!(s.stress[1].abs() < 1e-9 * sigma.abs());
    }
    let energy = solution.energy.total;
    let stored = 0.5 * sigma * sigma / E * 10.0 * 4.0 * 2.0;
    assert!((energy.elastic_energy - stored).abs() < 1e-9 * stored);
    // Trapezoidal over three equal increments of a linear response: exact.
    assert!(
        (energy.thermal_work + stored).abs() < 1e-9 * stored,
        "{energy:?}"
    );
    assert!(energy.imbalance().abs() < 1e-9 * stored, "{energy:?}");
}

#[test]
fn a_temperature_follows_its_step_history() {
    // Heat to ΔT, then cool to ΔT/4 along an amplitude: the free body follows.
    let amplitude = table(&[
        ("name", "cool".into()),
        ("time", list(&[0.0, 0.5, 1.0])),
        ("value", list(&[1.0, 0.6, 0.25])),
    ]);
    let thermal = |v: Value| table(&[("thermal", table(&[("heat", v)]).into())]);
    let mut heat = thermal(1.0.into());
    heat.insert("increments".into(), 2.into());
    let mut cool = thermal("cool".into());
    cool.insert("increments".into(), 3.into());
    let mut t = temperature("body", DT);
    t.insert("name".into(), "heat".into());
    let case = CaseBuilder::plane_stress(1.0)
        .body("body", steel())
        .support("s0", &[("ux", 0.0)])
        .support("t0", &[("uy", 0.0)])
        .push("temperature", t)
        .push("amplitude", amplitude)
        .push("step", heat)
        .push("step", cool);
    let e = ALPHA * DT * 0.25;
    let stress = check_free(case, rectangle(10.0, 4.0, 3, 2, 0.0, false), |x| {
        [e * x[0], e * x[1]]
    });
    assert!(stress < 1e-9 * E * e);
}

/// With `[steps]`, a `[[temperature]]` follows its own `factors` (one per step) as a load
/// does, or the global load factor without them; with `[[step]]` its `factors` are refused,
/// naming the key, as are factors of the wrong length.
#[test]
fn a_temperature_follows_its_own_steps_factors() {
    let global = [0.5, 1.0, 0.25];
    let own = [1.0, -0.5, 0.5];
    let free = |t: toml::Table| {
        CaseBuilder::plane_stress(1.0)
            .body("body", steel())
            .support("s0", &[("ux", 0.0)])
            .support("t0", &[("uy", 0.0)])
            .push("temperature", t)
    };
    for (factors, expected) in [(Some(own), own), (None, global)] {
        let mut t = temperature("body", DT);
        if let Some(f) = factors {
            t.insert("factors".into(), list(&f));
        }
        let case = free(t).step_factors(&global).case();
        let model = model(rectangle(10.0, 4.0, 3, 2, 0.0, false), &case).unwrap();
        let corner = model
            .mesh
            .nodes
            .iter()
            .position(|x| x[0] == 10.0 && x[1] == 4.0)
            .unwrap();
        let mut seen = Vec::new();
        asperity::solver::stepping::run_steps(&model, &settings(&case), |step| {
            seen.push(displacement(step.solution, corner));
            Ok(0.0)
        })
        .unwrap();
        assert_eq!(seen.len(), 3);
        for (u, f) in seen.iter().zip(expected) {
            // u = α ΔT f x at the corner (10, 4).
            let e = ALPHA * DT * f;
            assert!(
                (u[0] - 10.0 * e).abs() < 1e-9 * ALPHA * DT * 10.0,
                "{u:?} vs {f}"
            );
            assert!(
                (u[1] - 4.0 * e).abs() < 1e-9 * ALPHA * DT * 10.0,
                "{u:?} vs {f}"
            );
        }
    }
    let refused = |case: CaseBuilder| match case.try_case() {
        Err(e @ asperity::Error::InvalidParameter { .. }) => e.to_string(),
        other => panic!("expected an invalid parameter, got {other:?}"),
    };
    let mut t = temperature("body", DT);
    t.insert("factors".into(), list(&[1.0, 0.5]));
    let m = refused(free(t.clone()).step_factors(&global));
    assert!(
        m.contains("temperature[0].factors") && m.contains("one finite value per step (3)"),
        "{m}"
    );
    let step = table(&[("thermal", table(&[("body", 1.0.into())]).into())]);
    let m = refused(free(t).push("step", step));
    assert!(
        m.contains("temperature[0].factors") && m.contains("[[step]]"),
        "{m}"
    );
}

/// Renames a structured mesh's groups: the surface "body" becomes `name`, a curve "s0"
/// becomes "<name>_s0".
fn named(mut mesh: Mesh, name: &str) -> Mesh {
    for g in &mut mesh.groups {
        g.name = if g.dim == 2 {
            name.into()
        } else {
            format!("{name}_{}", g.name)
        };
    }
    mesh
}

const C: f64 = 10.0;
const A: f64 = 20.0;
const B: f64 = 40.0;
const DELTA: f64 = 0.02;

/// A hollow shaft (c ≤ r ≤ a) and a hub (a ≤ r ≤ b), quarters with coincident nodes at r = a,
/// the interference δ between them; the hub at ΔT.
fn shrink_fit(plane_stress: bool, dt: f64) -> (Mesh, CaseBuilder) {
    let mesh = merge(
        named(quarter_annulus(C, A, 6, 8), "shaft"),
        named(quarter_annulus(A, B, 8, 8), "hub"),
        false,
    );
    let case = if plane_stress {
        CaseBuilder::plane_stress(1.0)
    } else {
        CaseBuilder::plane_strain()
    };
    // A stiff frictionless joint: its compliance p/k_N is 1e-6 of δ.
    let law = linear_coulomb(1e9, 1e3, 0.0);
    let case = case
        .body("shaft", elastic(E, NU))
        .body("hub", steel())
        .support("shaft_t0", &[("uy", 0.0)])
        .support("shaft_t1", &[("ux", 0.0)])
        .support("hub_t0", &[("uy", 0.0)])
        .support("hub_t1", &[("ux", 0.0)])
        .contact(
            &[
                ("side_a", "shaft_s1".into()),
                ("side_b", "hub_s0".into()),
                ("interference", DELTA.into()),
            ],
            law,
        )
        .push("temperature", temperature("hub", dt));
    (mesh, case)
}

/// Mean contact pressure |p_N| over the closed points of the solution.
fn contact_pressure(solution: &asperity::solver::state::Solution) -> f64 {
    let p: Vec<f64> = solution
        .interface_committed
        .iter()
        .map(|s| -s.stress[1])
        .collect();
    p.iter().sum::<f64>() / p.len() as f64
}

#[test]
fn a_heated_hub_loosens_its_fit_as_lame_says() {
    // Plane stress (free axial expansion): the bore grows by α ΔT a, the interference
    // left is δ − α ΔT a, and Lamé gives p = E δ_T / (a [(b² + a²)/(b² − a²) +
    // (a² + c²)/(a² − c²)]) for equal moduli.
    let lame = |interference: f64| {
        let k = (B * B + A * A) / (B * B - A * A) + (A * A + C * C) / (A * A - C * C);
        E * interference / (A * k)
    };
    let open_at = DELTA / (ALPHA * A);
    for fraction in [0.0, 0.5, 0.9] {
        let dt = fraction * open_at;
        let (mesh, case) = shrink_fit(true, dt);
        let (_, solution) = solve(mesh, &case.case());
        let expected = lame(DELTA - ALPHA * dt * A);
        let p = contact_pressure(&solution);
        // Mesh (quadratic, 8 cells through each wall) and joint compliance: 1e-3.
        assert!(
            (p - expected).abs() < 1e-3 * lame(DELTA),
            "ΔT = {dt}: p = {p}, Lamé {expected}"
        );
    }
    // Just past α ΔT a = δ the fit is lost: every point open, no pressure.
    let (mesh, case) = shrink_fit(true, 1.01 * open_at);
    let (_, solution) = solve(mesh, &case.case());
    assert!(
        solution
            .interface_committed
            .iter()
            .all(|s| s.status == asperity::contact::ContactStatus::Open && s.stress[1] == 0.0)
    );
    // With ε_z = 0 the bore grows by (1 + ν) α ΔT a: the fit is lost at δ / ((1 + ν) α a).
    let open_strain = open_at / (1.0 + NU);
    for (fraction, open) in [(0.98, false), (1.02, true)] {
        let (mesh, case) = shrink_fit(false, fraction * open_strain);
        let (_, solution) = solve(mesh, &case.case());
        let p = contact_pressure(&solution);
        assert_eq!(
            p == 0.0,
            open,
            "plane strain at {fraction} of the opening: p = {p}"
        );
    }
}

/// A linear bulk under a temperature field on the condensed path takes its force as
/// K u − G ΔT: no element loop for forces in any increment, one for the states of each
/// converged increment (its energy terms), the stiffness assembled once. Its answer is that
/// of the Krylov path, which evaluates the elements at every iteration: the hub heated in
/// four increments, in plane stress and in plane strain.
#[test]
fn a_linear_bulk_under_a_temperature_field_needs_no_element_loop_for_its_forces() {
    let dt = 0.6 * DELTA / (ALPHA * A);
    for plane_stress in [true, false] {
        let run = |linear_solver: &str| {
            let (mesh, case) = shrink_fit(plane_stress, dt);
            let case = case
                .step_factors(&[0.25, 0.5, 0.75, 1.0])
                .set("solver", "linear_solver", linear_solver)
                .case();
            let model = common::model(mesh, &case).expect("model builds");
            let (solution, stats) =
                asperity::solver::stepping::run_steps(&model, &settings(&case), |_| Ok(0.0))
                    .expect("solves");
            (solution, stats)
        };
        let (condensed, stats) = run("condensed");
        let work = &stats.work.solver;
        assert_eq!(stats.increments, 4);
        assert_eq!(work.force_assemblies.calls, 0, "{work:?}");
        assert_eq!(work.tangent_assemblies.calls, 1, "{work:?}");
        assert_eq!(work.state_evaluations.calls, 4, "{work:?}");
        let (krylov, _) = run("krylov");
        let scale = krylov.u.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let difference =
            (condensed.u.iter().zip(&krylov.u)).fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        // Both converge to the Newton tolerance (1e-8 of the displacements by default).
        assert!(
            difference < 1e-7 * scale,
            "plane stress {plane_stress}: {difference:e} of {scale:e}"
        );
        let pressure = contact_pressure(&condensed);
        assert!(pressure > 0.0);
        let relative = (pressure - contact_pressure(&krylov)).abs() / pressure;
        assert!(
            relative < 1e-7,
            "plane stress {plane_stress}: pressure {relative:e}"
        );
        // The stresses of the committed states are those of the elements at u and ΔT.
        let stress = |s: &asperity::solver::state::Solution| {
            s.committed
                .iter()
                .map(|p| p.stress.amax())
                .fold(0.0, f64::max)
        };
        let relative = (stress(&condensed) - stress(&krylov)).abs() / stress(&krylov);
        assert!(
            relative < 1e-7,
            "plane stress {plane_stress}: stresses {relative:e}"
        );
    }
}
