//! The energy balance of a run (`solver::energy`; docs/theory.md, "Energy balance") against
//! independent references: Clapeyron's theorem and closed-form strain energies of elastic
//! bodies, the plastic work of uniaxial stress with linear hardening, and the dissipation
//! per cycle of an elastic–perfectly-sliding Coulomb interface, 4 μ p A (δ − μ p / k_T).

use crate::common;

use asperity::config::Case;
use asperity::model::Model;
use asperity::solver::energy::Energy;
use asperity::solver::stepping::run_steps;
use common::{
    CaseBuilder, add_curve_group, elastic, graded, linear_coulomb, merge, model, rectangle,
    settings, sliding_rough_joint, tensor, uniform,
};

/// The energy totals after every step of `case` on `mesh`.
fn energies(model: &Model, case: &Case) -> Vec<Energy> {
    let mut totals = Vec::new();
    run_steps(model, &settings(case), |step| {
        totals.push(step.solution.energy.total);
        Ok(0.0)
    })
    .expect("solves");
    totals
}

/// Newton run to round-off: what is left of the imbalance is then the arithmetic's. The
/// increments start from the converged state (no predictor): the relative tolerances are
/// measured against the first residual, the increment's whole out-of-balance force; from an
/// extrapolated start that residual is itself near round-off and 1e-11 of it is not reached.
fn tight(case: CaseBuilder) -> CaseBuilder {
    case.set("solver", "force_tolerance", 1e-11)
        .set("solver", "displacement_tolerance", 1e-11)
        .set("solver", "extrapolate", false)
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

const E: f64 = 200_000.0;
const NU: f64 = 0.3;

/// A plane-stress bar L × H of thickness t pulled by a ramped traction σ: uniform uniaxial
/// stress, which quad8 reproduces exactly. The trapezoidal work of a linear response is
/// exact, so at every step the external work equals ½ F u (Clapeyron) and the stored energy
/// σ² V / 2E, both to round-off; nothing is dissipated.
#[test]
fn elastic_bar_stores_the_work_of_its_load() {
    let (l, h, t, sigma) = (4.0, 1.0, 2.5, 120.0);
    let mesh = rectangle(l, h, 4, 2, 0.2, false);
    let case = tight(
        CaseBuilder::plane_stress(t)
            .body("body", elastic(E, NU))
            .support("s0", &[("ux", 0.0)])
            .support("origin", &[("uy", 0.0)])
            .traction("s1", [sigma, 0.0])
            .step_factors(&[0.25, 0.5, 0.75, 1.0]),
    )
    .case();
    let model = model(mesh, &case).unwrap();
    let totals = energies(&model, &case);
    let volume = l * h * t;
    for (k, e) in totals.iter().enumerate() {
        let s = sigma * (k + 1) as f64 / 4.0;
        let clapeyron = 0.5 * (s * h * t) * (s * l / E);
        let stored = s * s * volume / (2.0 * E);
        assert!(relative(e.external_work, clapeyron) < 1e-10, "{e:?}");
        assert!(relative(e.elastic_energy, stored) < 1e-10, "{e:?}");
        assert!(e.imbalance().abs() < 1e-10 * e.external_work, "{e:?}");
        assert_eq!(e.dissipation() + e.numerical_dissipation, 0.0);
    }
}

/// The arc-length loop records its increments too: the bar of
/// [`elastic_bar_stores_the_work_of_its_load`] followed by arc length to beyond its
/// reference load ends with the Clapeyron work ½ F u of the load factor it reached.
#[test]
fn arc_length_increments_are_recorded() {
    let (l, h, t, sigma) = (4.0, 1.0, 2.5, 120.0);
    let case = CaseBuilder::plane_stress(t)
        .body("body", elastic(E, NU))
        .support("s0", &[("ux", 0.0)])
        .support("origin", &[("uy", 0.0)])
        .traction("s1", [sigma, 0.0])
        .set("steps", "control", "arc_length")
        .set("steps", "initial_increment", 0.3)
        .set("steps", "max_load_factor", 1.0)
        .case();
    let model = model(rectangle(l, h, 4, 2, 0.2, false), &case).unwrap();
    let mut last = (0.0, Energy::default());
    run_steps(&model, &settings(&case), |step| {
        last = (step.load_factor, step.solution.energy.total);
        Ok(0.0)
    })
    .unwrap();
    let (lambda, e) = last;
    assert!(lambda >= 1.0, "{lambda}");
    let s = lambda * sigma;
    let clapeyron = 0.5 * (s * h * t) * (s * l / E);
    assert!(
        relative(e.external_work, clapeyron) < 1e-7,
        "{e:?} vs {clapeyron}"
    );
    assert!(e.imbalance().abs() < 1e-7 * e.external_work, "{e:?}");
}

/// An axisymmetric thick cylinder a ≤ r ≤ b (plane-strain ends) under internal pressure p:
/// the external work p·2πaH·u(a)/2 with Lamé's bore displacement, and the stored energy
/// equal to it (the mesh's discretisation error, ~1e-5 here, bounds the first; the second
/// is the balance itself and holds to round-off).
#[test]
fn thick_cylinder_stores_the_work_of_its_pressure() {
    let (a, b, h, p) = (10.0, 20.0, 2.0, 100.0);
    let mut mesh = tensor(&graded(a, b - a, 16, 1.05), &uniform(0.0, h, 1), "wall");
    add_curve_group(&mut mesh, "bore", |x| (x[0] - a).abs() < 1e-12);
    add_curve_group(&mut mesh, "ends", |x| x[1] == 0.0 || x[1] == h);
    let case = tight(
        CaseBuilder::axisymmetric()
            .body("wall", elastic(E, NU))
            .support("ends", &[("uz", 0.0)])
            .pressure("bore", p)
            .steps(3),
    )
    .case();
    let model = model(mesh, &case).unwrap();
    let e = *energies(&model, &case).last().unwrap();
    let u_a = p * a * a * (1.0 + NU) * ((1.0 - 2.0 * NU) * a + b * b / a) / (E * (b * b - a * a));
    let work = 0.5 * p * 2.0 * std::f64::consts::PI * a * h * u_a;
    assert!(relative(e.external_work, work) < 1e-4, "{e:?} vs {work}");
    assert!(relative(e.elastic_energy, e.external_work) < 1e-10, "{e:?}");
    assert!(e.imbalance().abs() < 1e-10 * e.external_work, "{e:?}");
}

/// Uniaxial stress with linear hardening H, loaded to σ_max past yield and unloaded to zero:
/// the plastic work is ∫ σ dεᵖ = (σ_max² − σ_Y²)/2H per volume, exactly the trapezoidal rule
/// on the linear σ(εᵖ) when a step ends at yield. Backward Euler's σ_{n+1}:Δεᵖ exceeds it by
/// ½ H Δεᵖ² per step, which the numerical dissipation takes back: the physical plastic
/// dissipation converges to the closed form at first order in the increment.
#[test]
fn plastic_work_of_a_uniaxial_load_cycle() {
    let (sy, hardening, s_max, t) = (250.0, 20_000.0, 375.0, 2.0);
    let (l, h) = (2.0, 1.0);
    let run = |steps: usize| {
        let mesh = rectangle(l, h, 2, 2, 0.0, false);
        let mut material = elastic(E, NU);
        material.insert("yield_stress".into(), sy.into());
        material.insert("hardening".into(), hardening.into());
        // To yield in one step, on to σ_max in `steps`, back to zero in two.
        let at_yield = sy / s_max;
        let mut factors = vec![at_yield];
        factors.extend((1..=steps).map(|i| at_yield + (1.0 - at_yield) * i as f64 / steps as f64));
        factors.extend([0.5, 0.0]);
        let case = tight(
            CaseBuilder::plane_stress(t)
                .body("body", material)
                .support("s0", &[("ux", 0.0)])
                .support("origin", &[("uy", 0.0)])
                .traction("s1", [s_max, 0.0])
                .step_factors(&factors),
        )
        .case();
        let model = model(mesh, &case).unwrap();
        *energies(&model, &case).last().unwrap()
    };
    let volume = l * h * t;
    let exact = (s_max * s_max - sy * sy) / (2.0 * hardening) * volume;
    let coarse = run(4);
    let fine = run(8);
    for e in [coarse, fine] {
        // Unloaded and homogeneous: nothing stays stored.
        assert!(e.elastic_energy.abs() < 1e-12 * exact, "{e:?}");
        let plastic_work = e.plastic_dissipation + e.numerical_dissipation;
        assert!(relative(plastic_work, exact) < 1e-9, "{e:?} vs {exact}");
        assert!(relative(e.external_work, plastic_work) < 1e-9, "{e:?}");
        assert!(e.imbalance().abs() < 1e-9 * e.external_work, "{e:?}");
    }
    // The overshoot is Σ ½ H Δεᵖ² = ½ H (εᵖ)² / n: halves with the increment.
    let overshoot = |e: Energy| e.plastic_dissipation - exact;
    let eps_p = (s_max - sy) / hardening;
    let expected = 0.5 * hardening * eps_p * eps_p / 4.0 * volume;
    assert!(relative(overshoot(coarse), expected) < 1e-6, "{coarse:?}");
    assert!(relative(overshoot(coarse) / overshoot(fine), 2.0) < 1e-6);
}

/// The near-rigid joint: base [0, 4] × [0, 1] held on the ground and block [1, 3] × [1, 2]
/// (E = 1e9, so that the interface takes all the compliance), a linear Coulomb joint between
/// them, the block's top pressed down by `closure` and its left side moved by `delta` times
/// `drive`, one step per entry.
fn near_rigid_joint(law: [f64; 3], closure: f64, delta: f64, drive: &[f64]) -> (Model, Case) {
    let stiff = 1e9;
    let mut base = tensor(&uniform(0.0, 4.0, 4), &uniform(0.0, 1.0, 1), "base");
    add_curve_group(&mut base, "ground", |x| x[1] == 0.0);
    add_curve_group(&mut base, "base_top", |x| {
        x[1] == 1.0 && (1.0..=3.0).contains(&x[0])
    });
    let mut block = tensor(&uniform(1.0, 3.0, 2), &uniform(1.0, 2.0, 1), "block");
    add_curve_group(&mut block, "block_bottom", |x| x[1] == 1.0);
    add_curve_group(&mut block, "block_top", |x| x[1] == 2.0);
    add_curve_group(&mut block, "block_left", |x| x[0] == 1.0);
    let n = drive.len();
    let case = tight(
        CaseBuilder::plane_strain()
            .body("base", elastic(stiff, NU))
            .body("block", elastic(stiff, NU))
            .support("ground", &[("ux", 0.0), ("uy", 0.0)])
            .support_history("block_top", &[("uy", -closure)], &vec![1.0; n])
            .support_history("block_left", &[("ux", delta)], drive)
            .contact(
                &[
                    ("side_a", "base_top".into()),
                    ("side_b", "block_bottom".into()),
                ],
                linear_coulomb(law[0], law[1], law[2]),
            )
            .steps(n as i64),
    )
    .case();
    (model(merge(base, block, false), &case).unwrap(), case)
}

/// The near-rigid block pressed by a prescribed closure g on the base through a linear
/// Coulomb joint (k_N, k_T, μ) at uniform pressure p = k_N g, then moved sideways
/// cyclically between ±δ: each full cycle dissipates 4 μ p A (δ − μ p / k_T) (the area of
/// the elastic–perfectly-sliding loop), the cycle's external work equals it plus the change
/// of the stored energy (zero over a periodic cycle), and the balance holds to 1e-6 of the
/// cycle's work.
#[test]
fn coulomb_joint_dissipates_its_hysteresis_loop_per_cycle() {
    let (k_n, k_t, mu, g, delta) = (1e4, 1e3, 0.3, 1e-3, 1e-2);
    // Quarter cycles of 4 increments: press, then 0 → δ, then 3 cycles δ → −δ → δ.
    let mut drive = vec![0.0];
    drive.extend((1..=4).map(|i| i as f64 / 4.0));
    for _ in 0..3 {
        drive.extend((1..=8).map(|i| 1.0 - i as f64 / 4.0));
        drive.extend((1..=8).map(|i| -1.0 + i as f64 / 4.0));
    }
    let (model, case) = near_rigid_joint([k_n, k_t, mu], g, delta, &drive);
    let totals = energies(&model, &case);
    let (p, area) = (k_n * g, 2.0);
    let loop_area = 4.0 * mu * p * area * (delta - mu * p / k_t);
    // Cycle ends: the steps at +δ after the first quarter.
    let ends: Vec<usize> = (0..4).map(|c| 4 + 16 * c).collect();
    for w in ends.windows(2) {
        let cycle = totals[w[1]] - totals[w[0]];
        // Body compliance (h/E against 1/k) perturbs the closed form at ~1e-5.
        assert!(
            relative(cycle.friction_dissipation, loop_area) < 1e-4,
            "{cycle:?} vs {loop_area}"
        );
        assert!(
            cycle.imbalance().abs() < 1e-6 * cycle.external_work,
            "{cycle:?}"
        );
        let stored_change = cycle.stored();
        let friction = cycle.external_work - stored_change - cycle.numerical_dissipation;
        assert!(
            relative(cycle.friction_dissipation, friction) < 1e-6,
            "{cycle:?}"
        );
    }
}

/// A press fit (axisymmetric shaft in a hub with interference, rough-joint interface) pulled
/// axially at the default convergence criteria: the balance holds to the residual the
/// criteria accept. Each increment's imbalance is the work of its out-of-balance forces,
/// |r|·|Δu| with |r|∞ ≤ R_n q̃, R_n = 5e-4 of the average force (docs/theory.md 7.7): with
/// every free dof at that bound the imbalance could approach R_n times the work of the
/// average force, ~5e-4 of the energies; converged residuals are orders of magnitude below
/// it (~1e-9 measured), so 1e-3 of the largest energy is a safe bound that any missing or
/// double-counted term (a fraction of the energies) breaks.
#[test]
fn press_fit_balances_at_the_default_criteria() {
    let (a, b, l, delta) = (10.0, 20.0, 10.0, 0.01);
    let zs = uniform(0.0, l, 6);
    let mut shaft = tensor(&uniform(0.0, a, 4), &zs, "shaft");
    add_curve_group(&mut shaft, "shaft_top", |x| x[1] == l);
    add_curve_group(&mut shaft, "shaft_outer", |x| (x[0] - a).abs() < 1e-12);
    let mut hub = tensor(&uniform(a, b, 4), &zs, "hub");
    add_curve_group(&mut hub, "hub_bottom", |x| x[1] == 0.0);
    add_curve_group(&mut hub, "hub_bore", |x| (x[0] - a).abs() < 1e-12);
    let case = CaseBuilder::axisymmetric()
        .body("shaft", elastic(E, NU))
        .body("hub", elastic(E, NU))
        .support("hub_bottom", &[("uz", 0.0)])
        .traction("shaft_top", [0.0, 20.0])
        .contact(
            &[
                ("side_a", "shaft_outer".into()),
                ("side_b", "hub_bore".into()),
                ("interference", delta.into()),
            ],
            sliding_rough_joint(),
        )
        .step_factors(&[0.0, 0.5, 1.0, 0.5, 0.0])
        .case();
    let model = model(merge(shaft, hub, false), &case).unwrap();
    let totals = energies(&model, &case);
    let last = *totals.last().unwrap();
    let scale = totals
        .iter()
        .map(|e| e.external_work.abs().max(e.elastic_energy))
        .fold(0.0, f64::max);
    for e in &totals {
        println!("{e:?} imbalance {:.3e}", e.imbalance());
        assert!(e.imbalance().abs() < 1e-3 * scale, "{e:?}");
    }
    assert!(
        last.friction_dissipation > 0.0,
        "the pull slides the joint: {last:?}"
    );
}

/// Through the pipeline: `summary.json`'s `energy` (total, one entry per analysis step and
/// per cycle) and the energy columns of `history.csv` carry the ledger's numbers: the bar of
/// [`elastic_bar_stores_the_work_of_its_load`], whose increment k adds
/// ½ (F_{k−1} + F_k)(u_k − u_{k−1}).
#[test]
fn summary_and_history_report_the_balance() {
    let (l, h, t, sigma) = (4.0, 1.0, 2.5, 120.0);
    let case = CaseBuilder::plane_stress(t)
        .body("body", elastic(E, NU))
        .support("s0", &[("ux", 0.0)])
        .support("origin", &[("uy", 0.0)])
        .traction("s1", [sigma, 0.0])
        .step_factors(&[0.5, 1.0, 0.25])
        .case();
    let dir = tempfile::tempdir().unwrap();
    let mesh = rectangle(l, h, 4, 2, 0.0, false);
    asperity::run::run_mesh(
        &case,
        mesh,
        Default::default(),
        &asperity::run::folder::OutputFolder::scratch(dir.path()).unwrap(),
        false,
        |_, _| Ok(()),
    )
    .unwrap();
    let text = std::fs::read_to_string(dir.path().join("summary.json")).unwrap();
    let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
    let energy = &summary["energy"];
    let clapeyron = |s: f64| 0.5 * (s * h * t) * (s * l / E);
    // Loads 0.5σ → σ → 0.25σ: the work of each step is the trapezoid of its end forces.
    let force_times_u = |a: f64, b: f64| 0.5 * (a + b) * sigma * h * t * (b - a) * sigma * l / E;
    // A `[steps]` schedule is one analysis step ("step-1") and one cycle; the work of each
    // of its increments is in history.csv.
    let steps = energy["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 1);
    assert_eq!(steps[0]["name"], "step-1");
    assert_eq!(energy["cycles"].as_array().unwrap().len(), 1);
    assert_eq!(
        energy["cycles"][0]["external_work"],
        steps[0]["external_work"]
    );
    let per_increment = [
        force_times_u(0.0, 0.5),
        force_times_u(0.5, 1.0),
        force_times_u(1.0, 0.25),
    ];
    let total = &energy["total"];
    let work = total["external_work"].as_f64().unwrap();
    assert!(relative(work, clapeyron(0.25 * sigma)) < 1e-9, "{total}");
    let history = std::fs::read_to_string(dir.path().join("history.csv")).unwrap();
    let header: Vec<&str> = history.lines().next().unwrap().split(',').collect();
    let last: Vec<f64> = history
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    let column = |name: &str| last[header.iter().position(|h| *h == name).unwrap()];
    assert_eq!(
        header[header.len() - 4..],
        [
            "external_work",
            "stored_energy",
            "dissipation",
            "energy_imbalance"
        ]
    );
    assert_eq!(column("external_work"), work);
    let works: Vec<f64> = history
        .lines()
        .skip(2)
        .map(|line| {
            let row: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
            row[header.iter().position(|h| *h == "external_work").unwrap()]
        })
        .collect();
    let mut done = 0.0;
    for (k, (w, increment)) in works.iter().zip(per_increment).enumerate() {
        done += increment;
        assert!(
            relative(*w, done) < 1e-9,
            "increment {}: {w} vs {done}",
            k + 1
        );
    }
    assert_eq!(
        column("stored_energy"),
        total["elastic_energy"].as_f64().unwrap()
    );
    assert_eq!(column("dissipation"), 0.0);
    assert_eq!(
        column("energy_imbalance"),
        total["imbalance"].as_f64().unwrap()
    );
}

/// A resumed run rebuilds `summary.json`'s energy from its restart record: resuming a
/// finished run (the record of its last increment) reports the same energy entries. The
/// shrink fit of `examples/shrink_fit/shrink_fit.toml`: its interference stores energy in the bodies
/// without external work, which the interface energy balances.
#[test]
fn resume_keeps_the_energy_report() {
    use asperity::run::folder::OutputMode;
    use asperity::run::{RunOptions, run_with};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/shrink_fit/shrink_fit.toml");
    let case = Case::from_file(&path).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let energy = |mode| {
        let options = RunOptions {
            progress: false,
            mode,
            command_line: Vec::new(),
        };
        run_with(&case, dir.path(), &options, |_| Ok(())).unwrap();
        let text = std::fs::read_to_string(dir.path().join("summary.json")).unwrap();
        let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
        summary["energy"].clone()
    };
    let first = energy(OutputMode::Fresh);
    let total = &first["total"];
    let stored = total["elastic_energy"].as_f64().unwrap();
    assert_eq!(first["steps"].as_array().unwrap().len(), 1);
    assert_eq!(total["external_work"], 0.0);
    assert!(stored > 0.0, "{first}");
    assert!(
        total["imbalance"].as_f64().unwrap().abs() < 1e-6 * stored,
        "{first}"
    );
    assert_eq!(energy(OutputMode::Resume), first);
}

/// Pressed alone, the joint stores ½ p²/k_N per unit area (the interface term of a linear
/// law); a wear jump of depth Δh at a point then moves −p_N Δh dA from the interface energy
/// to the wear work (dA = 2/3 at the middle Newton–Cotes point of an element of length 1:
/// weight 4/3 times det j = 1/2), leaving the balance as it was.
#[test]
fn interface_energy_and_wear_jumps() {
    let (k_n, g) = (1e4, 1e-3);
    let (model, case) = near_rigid_joint([k_n, 1e3, 0.3], g, 0.0, &[0.0]);
    let (mut solution, _) = run_steps(&model, &settings(&case), |_| Ok(0.0)).unwrap();
    let p = k_n * g;
    let before = solution.energy.total;
    // The bodies take 2 p h/E = 2e-8 mm of the 1e-3 mm closure: p is 2e-5 low, its energy
    // 4e-5.
    assert!(
        relative(before.interface_energy, 0.5 * p * p / k_n * 2.0) < 1e-4,
        "{before:?}"
    );
    let state = solution.interface_committed[1];
    let depth = 1e-4;
    solution.energy.record_wear_jump(&model, 1, &state, depth);
    let after = solution.energy.total;
    let moved = p * depth * 2.0 / 3.0;
    assert!(
        relative(after.wear_work - before.wear_work, moved) < 1e-4,
        "{after:?}"
    );
    assert!(relative(before.interface_energy - after.interface_energy, moved) < 1e-4);
    assert!((after.imbalance() - before.imbalance()).abs() < 1e-15);
}
