//! Steady heat conduction against closed forms: radial conduction through a hollow cylinder
//! (T(r), the heat flow and its thermal stresses, Timoshenko & Goodier §150), the heat
//! balance with a source and a film, two concentric cylinders joined by a conductance h
//! (jump = flux / h), and a two-block stack whose joint follows h0 (p/1 MPa)^n.
use crate::common;

use asperity::mesh::Mesh;
use asperity::solver::conduction::ConductionSolver;
use common::*;
use std::f64::consts::PI;

const A: f64 = 10.0;
const B: f64 = 20.0;
const H: f64 = 2.0;
const K: f64 = 0.05;
const E: f64 = 200_000.0;
const NU: f64 = 0.3;
const ALPHA: f64 = 1.2e-5;
const TA: f64 = 100.0;

fn fixed(group: &str, t: f64) -> toml::Table {
    table(&[("group", group.into()), ("temperature", t.into())])
}

/// An axisymmetric slice a ≤ r ≤ b, 0 ≤ z ≤ H held axially (plane strain), conducting.
fn slice(n: usize) -> Mesh {
    structured(n, 2, 0.0, false, move |s, t| [A + s * (B - A), t * H])
}

fn conducting(material: toml::Table) -> toml::Table {
    table(&[
        ("group", "body".into()),
        ("material", material.into()),
        ("conductivity", K.into()),
    ])
}

#[test]
fn radial_conduction_through_a_hollow_cylinder_and_its_thermal_stresses() {
    let material = with_keys(elastic(E, NU), &[("expansion", ALPHA)]);
    let case = CaseBuilder::axisymmetric()
        .push("body", conducting(material))
        .support("t0", &[("uz", 0.0)])
        .support("t1", &[("uz", 0.0)])
        .push("thermal_support", fixed("s0", TA))
        .push("thermal_support", fixed("s1", 0.0));
    let (model, solution) = solve(slice(16), &case.case());
    let heat = solution.thermal.heat.as_ref().expect("conduction solved");
    let ln = (B / A).ln();
    // T(r) = T_a ln(b/r) / ln(b/a): quadratic elements, 16 through the wall.
    for (n, x) in model.mesh.nodes.iter().enumerate() {
        let exact = TA * (B / x[0]).ln() / ln;
        assert!(
            (heat.nodal[n] - exact).abs() < 2e-4 * TA,
            "T({}) = {}",
            x[0],
            heat.nodal[n]
        );
    }
    // Heat flow 2π k H (T_a − T_b) / ln(b/a) in at the bore, out at the outside.
    let q = 2.0 * PI * K * H * TA / ln;
    assert!(
        (heat.supports[0] - q).abs() < 1e-4 * q,
        "{:?} vs {q}",
        heat.supports
    );
    assert!((heat.supports[0] + heat.supports[1]).abs() < 1e-10 * q);
    // Long hollow cylinder, plane strain (Timoshenko & Goodier, §150, T_b = 0).
    let c = ALPHA * E * TA / (2.0 * (1.0 - NU) * ln);
    let k = A * A / (B * B - A * A);
    let radial = |r: f64| c * (-(B / r).ln() - k * (1.0 - B * B / (r * r)) * ln);
    let hoop = |r: f64| c * (1.0 - (B / r).ln() - k * (1.0 + B * B / (r * r)) * ln);
    let scale = hoop(A).abs();
    let mut worst: f64 = 0.0;
    for (e, cell) in model.continuum.cells.iter().enumerate() {
        for (g, p) in asperity::element::quadrature::cell_rule(cell.kind)
            .iter()
            .enumerate()
        {
            let x = asperity::element::kinematics::point_kinematics(
                &model.analysis,
                cell.kind,
                &cell.coords,
                p,
            )
            .unwrap()
            .x;
            let s = solution.point_states()[e * 9 + g].stress;
            worst = worst
                .max((s[0] - radial(x[0])).abs())
                .max((s[3] - hoop(x[0])).abs());
        }
    }
    println!(
        "thermal stress error {:.2e} of the bore's hoop stress",
        worst / scale
    );
    // Pointwise stresses converge as h² (measured: 7.0e-3 at 8 cells through the wall,
    // 2.0e-3 at 16).
    assert!(worst < 3e-3 * scale, "stress error {worst} of {scale}");
}

/// A body whose every node a temperature support holds (one quad8 cell, held on its four
/// sides) has no unknown temperature: the run solves nothing, keeps the prescribed values
/// (a corner held by two supports takes the later one's) and the heat its supports let in
/// sums to zero.
#[test]
fn a_body_held_at_every_node_keeps_its_prescribed_temperatures() {
    let case = CaseBuilder::axisymmetric()
        .push("body", conducting(elastic(E, NU)))
        .support("t0", &[("uz", 0.0)])
        .support("s0", &[("ur", 0.0)])
        .push("thermal_support", fixed("s0", TA))
        .push("thermal_support", fixed("t0", 0.0))
        .push("thermal_support", fixed("t1", 0.0))
        .push("thermal_support", fixed("s1", 0.0));
    let cell = structured(1, 1, 0.0, false, |s, t| [A + s * (B - A), t * H]);
    let (model, solution) = solve(cell, &case.case());
    let heat = solution.thermal.heat.as_ref().expect("conduction solved");
    assert_eq!(model.mesh.nodes.len(), 8);
    for (n, x) in model.mesh.nodes.iter().enumerate() {
        let held = x[0] == A && x[1] > 0.0 && x[1] < H;
        let expected = if held { TA } else { 0.0 };
        assert_eq!(heat.nodal[n], expected, "T at {x:?}");
    }
    let sum: f64 = heat.supports.iter().sum();
    assert!(heat.supports[0] > 0.0, "{:?}", heat.supports);
    assert!(sum.abs() < 1e-12 * heat.supports[0], "{:?}", heat.supports);
}

#[test]
fn heat_in_equals_heat_out_with_a_source_and_a_film() {
    let film = table(&[
        ("group", "s1".into()),
        (
            "film",
            table(&[("h", 2e-3.into()), ("ambient", 20.0.into())]).into(),
        ),
    ]);
    let flux = table(&[("group", "t1".into()), ("flux", 5e-3.into())]);
    let source = table(&[("group", "body".into()), ("power", 1e-3.into())]);
    let case = CaseBuilder::plane_strain()
        .push("body", conducting(elastic(E, NU)))
        .support("s0", &[("ux", 0.0)])
        .support("t0", &[("uy", 0.0)])
        .push("thermal_support", fixed("s0", 0.0))
        .push("thermal_support", film)
        .push("thermal_support", flux)
        .push("heat_source", source);
    let (_, solution) = solve(rectangle(10.0, 4.0, 5, 3, 0.3, true), &case.case());
    let heat = solution.thermal.heat.as_ref().unwrap();
    let generated = 1e-3 * 10.0 * 4.0;
    assert!((heat.sources[0] - generated).abs() < 1e-12 * generated);
    assert!((heat.supports[2] - 5e-3 * 10.0).abs() < 1e-12);
    let balance: f64 = heat.supports.iter().sum::<f64>() + heat.sources[0];
    assert!(balance.abs() < 1e-10 * generated, "{heat:?}");
    // The fixed side takes heat out.
    assert!(heat.supports[0] < 0.0, "{:?}", heat.supports);
}

/// Renames a structured mesh's groups: the surface becomes `name`, a curve "s0" "<name>_s0".
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

fn body(name: &str) -> toml::Table {
    table(&[
        ("group", name.into()),
        ("material", elastic(E, NU).into()),
        ("conductivity", K.into()),
    ])
}

/// Radius of the joint of [`concentric`].
const M: f64 = 15.0;
/// Conductance of the joint of [`concentric`].
const H_JOINT: f64 = 4e-3;

/// Two concentric cylinders a ≤ r ≤ m ≤ r ≤ b pressed together by an interference, joined
/// by the conductance h (pair "fit"), the bore at T_a (support "bore"), the outside at 0.
fn concentric() -> (Mesh, CaseBuilder) {
    let mesh = merge(
        named(
            structured(6, 2, 0.0, false, move |s, t| [A + s * (M - A), t * H]),
            "inner",
        ),
        named(
            structured(6, 2, 0.0, false, move |s, t| [M + s * (B - M), t * H]),
            "outer",
        ),
        false,
    );
    let mut bore = fixed("inner_s0", TA);
    bore.insert("name".into(), "bore".into());
    let case = CaseBuilder::axisymmetric()
        .push("body", body("inner"))
        .push("body", body("outer"))
        .support("inner_t0", &[("uz", 0.0)])
        .support("outer_t0", &[("uz", 0.0)])
        .contact(
            &[
                ("name", "fit".into()),
                ("side_a", "inner_s1".into()),
                ("side_b", "outer_s0".into()),
                ("interference", 0.01.into()),
                ("conductance", H_JOINT.into()),
            ],
            linear_coulomb(1e7, 1e3, 0.0),
        )
        .push("thermal_support", bore)
        .push("thermal_support", fixed("outer_s1", 0.0));
    (mesh, case)
}

/// The heat flow of [`concentric`] in series, Q = 2π H T_a / (ln(m/a)/k + ln(b/m)/k + 1/(h m)).
fn concentric_heat_flow() -> f64 {
    TA / (((M / A).ln() / K + (B / M).ln() / K + 1.0 / (H_JOINT * M)) / (2.0 * PI * H))
}

#[test]
fn a_joint_conductance_makes_the_temperature_jump_flux_over_h() {
    let (m, h) = (M, H_JOINT);
    let (mesh, case) = concentric();
    let (model, solution) = solve(mesh, &case.case());
    let heat = solution.thermal.heat.as_ref().unwrap();
    let q = concentric_heat_flow();
    assert!(
        (heat.joints[0] - q).abs() < 1e-4 * q,
        "{} vs {q}",
        heat.joints[0]
    );
    assert!((heat.supports[0] - q).abs() < 1e-4 * q);
    // The jump at r = m is the flux over h.
    let flux = q / (2.0 * PI * m * H);
    let side = |r: f64, body: &str| {
        let cells = model.continuum.cells.iter();
        let b = model.bodies.iter().position(|n| n == body).unwrap() as u32;
        let nodes: Vec<u32> = cells
            .filter(|c| c.body == b)
            .flat_map(|c| c.nodes[..8].to_vec())
            .filter(|&n| (model.mesh.nodes[n as usize][0] - r).abs() < 1e-9)
            .collect();
        heat.nodal[nodes[0] as usize]
    };
    let jump = side(m, "inner") - side(m, "outer");
    assert!(
        (jump - flux / h).abs() < 1e-4 * flux / h,
        "jump {jump} vs {}",
        flux / h
    );
}

/// `summary.json` lists every step's heat flows (W, totals over 2π) by the entries' names:
/// the thermal supports', the sources' and the conducting pairs', the same numbers as the
/// `heat_flow_*` columns of `history.csv`, and the series flow of the closed form.
/// Runs `case` on `mesh` into a temporary folder; the folder and its `summary.json`.
fn run_to_summary(case: &CaseBuilder, mesh: Mesh) -> (tempfile::TempDir, serde_json::Value) {
    let dir = tempfile::tempdir().unwrap();
    let folder = asperity::run::folder::OutputFolder::scratch(dir.path()).unwrap();
    asperity::run::run_mesh(
        &case.case(),
        mesh,
        Default::default(),
        &folder,
        false,
        |_, _| Ok(()),
    )
    .unwrap();
    let text = std::fs::read_to_string(dir.path().join("summary.json")).unwrap();
    (dir, serde_json::from_str(&text).unwrap())
}

#[test]
fn summary_json_lists_the_heat_flows_by_name() {
    let (mesh, case) = concentric();
    let (dir, summary) = run_to_summary(&case, mesh);
    let heat = &summary["steps"].as_array().unwrap().last().unwrap()["heat"];
    let history = std::fs::read_to_string(dir.path().join("history.csv")).unwrap();
    let header: Vec<&str> = history.lines().next().unwrap().split(',').collect();
    let last: Vec<f64> = history
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    let column = |name: &str| last[header.iter().position(|h| *h == name).expect(name)];
    let q = concentric_heat_flow();
    for (group, name, column_name, expected) in [
        ("supports", "bore", "heat_flow_bore", q),
        ("supports", "outer_s1", "heat_flow_outer_s1", -q),
        ("contacts", "fit", "heat_flow_fit", q),
    ] {
        let value = heat[group][name]
            .as_f64()
            .unwrap_or_else(|| panic!("{group}.{name}: {heat}"));
        assert_eq!(value, column(column_name), "{group}.{name}");
        assert!(
            (value - expected).abs() < 1e-4 * q,
            "{group}.{name}: {value} vs {expected}"
        );
    }
    assert_eq!(heat["sources"], serde_json::json!({}));
    // A run without conduction has no `heat` record.
    let plain = CaseBuilder::plane_strain()
        .body("body", elastic(E, NU))
        .support("s0", &[("ux", 0.0)])
        .support("t0", &[("uy", 0.0)])
        .traction("s1", [1.0, 0.0]);
    let (_dir, summary) = run_to_summary(&plain, rectangle(4.0, 2.0, 2, 1, 0.0, false));
    assert!(summary["steps"][0].get("heat").is_none(), "{summary}");
}

/// A block pressed by `p` on a base of the same size, the bottom at 0 and the top at T_a,
/// the joint conducting with h0 (p/1 MPa)^n: (jump, flux through the joint, exchanges).
fn stack(p: f64, h0: f64, n: f64) -> (f64, f64, usize) {
    let (w, t) = (4.0, 2.0);
    let mesh = stack_mesh(w, t);
    let (_, solution) = solve(mesh, &stack_case(p, h0, n).case());
    let heat = solution.thermal.heat.as_ref().unwrap();
    // One-dimensional: q = T_a / (2t/k + 1/h) per area, the jump q / h.
    let flux = -heat.joints[0] / w;
    (TA - flux * 2.0 * t / K, flux, solution.thermal.exchanges)
}

/// The case of [`stack`].
fn stack_case(p: f64, h0: f64, n: f64) -> CaseBuilder {
    let conductance = table(&[("h0", h0.into()), ("exponent", n.into())]);
    held_stack(conductance.into(), (1e6, 1e3))
        .pressure("block_t1", p)
        .push("thermal_support", fixed("base_t0", 0.0))
        .push("thermal_support", fixed("block_t1", TA))
}

/// `summary.json` of a coupled run: the conduction's time is a phase of its own, and its
/// floor counts one conduction factorisation (the part that changes with neither the time
/// nor the contact, factored once per run) and one conduction solve per increment, of
/// solves made at the run's start, at every increment's start and at every exchange.
#[test]
fn a_coupled_runs_floor_has_one_conduction_factorisation_and_its_solves() {
    let case = stack_case(20.0, 1e-3, 0.8).step_factors(&[0.5, 1.0]);
    let (_dir, summary) = run_to_summary(&case, stack_mesh(4.0, 2.0));
    crate::floor::check_floor(&summary);
    let count = |key| crate::floor::count(&summary, key);
    let increments = count("increments");
    assert_eq!(increments, 2, "{summary}");
    assert_eq!(count("conduction_factorisations"), 1, "{summary}");
    // The run's start, and per increment its start and at least one exchange.
    assert!(count("conduction_solves") > 2 * increments, "{summary}");
    let work = &summary["floor"]["work_seconds"];
    let seconds = crate::floor::seconds;
    assert_eq!(
        seconds(&summary["seconds"]["conduction"]),
        seconds(&work["conduction_factorisations"]) + seconds(&work["conduction_solves"]),
        "{summary}"
    );
    assert!(seconds(&summary["floor"]["parts"]["conduction"]) > 0.0);
}

/// A block (w × t) on a base of the same size, their faces joined at y = t.
fn stack_mesh(w: f64, t: f64) -> Mesh {
    merge(
        named(rectangle(w, t, 4, 2, 0.0, false), "base"),
        named(
            structured(4, 2, 0.0, false, move |s, r| [s * w, t + r * t]),
            "block",
        ),
        false,
    )
}

/// Every frame of a run (the bits of the displacements, interface stresses, temperatures
/// and energy ledger) and the state to resume from after each.
#[derive(Default)]
struct Frames {
    frames: Vec<Vec<u64>>,
    resumes: Vec<asperity::solver::state::Resume>,
}

impl asperity::solver::state::Observer for Frames {
    fn step(
        &mut self,
        step: &asperity::solver::state::StepResult,
        progress: &asperity::solver::state::Progress,
    ) -> asperity::Result<f64> {
        let s = step.solution;
        let heat = s.thermal.heat.as_ref().expect("conduction solved");
        let e = &s.energy.total;
        let values =
            s.u.iter()
                .chain(s.interface_committed.iter().flat_map(|p| &p.stress));
        let values = values
            .chain(&heat.nodal)
            .chain(&heat.supports)
            .chain(&heat.joints);
        let energy = [
            e.external_work,
            e.elastic_energy,
            e.thermal_work,
            e.friction_dissipation,
        ];
        self.frames
            .push(values.chain(&energy).map(|v| v.to_bits()).collect());
        self.resumes.push(progress.to_resume());
        Ok(0.0)
    }
}

/// The predictor extrapolates a coupled increment from the last one as a whole: its record
/// of the last increment is the change over all of that increment's exchanges, not over its
/// last exchange alone (which would extrapolate nothing).
#[test]
fn a_coupled_increment_is_recorded_whole_for_the_predictor() {
    use asperity::solver::stepping::run_steps_from;
    let case = stack_case(20.0, 1e-3, 0.8).step_factors(&[0.5, 1.0]).case();
    let model = model(stack_mesh(4.0, 2.0), &case).unwrap();
    let mut frames = Frames::default();
    run_steps_from(&model, &settings(&case), None, &mut frames).unwrap();
    let (first, second) = (&frames.resumes[0], &frames.resumes[1]);
    assert!(second.solution.thermal.exchanges > 1, "the case exchanges");
    let last = second.last_increment.as_ref().expect("the predictor is on");
    assert!(last.ready);
    let (u0, u1) = (&first.solution.u, &second.solution.u);
    for (d, du) in last.du.iter().enumerate() {
        assert_eq!(*du, u1[d] - u0[d], "dof {d}");
    }
    assert!(last.du.iter().any(|du| du.abs() > 0.0));
}

/// A thermal run continued from its restart record after any frame (as `--resume` reads
/// it) repeats the uninterrupted run bit for bit: displacements, contact stresses,
/// temperatures, heat flows and energy. The case couples both ways: a pressed block with a
/// heat source and thermal strain, held at its sides, on a base through a pressure-dependent
/// conductance, with the source's own `[steps]` factors.
#[test]
fn a_coupled_thermal_run_resumed_from_any_frame_is_bit_identical() {
    use asperity::solver::stepping::run_steps_from;
    let material = || with_keys(elastic(E, NU), &[("expansion", ALPHA)]);
    let part = |name: &str| {
        table(&[
            ("group", name.into()),
            ("material", material().into()),
            ("conductivity", K.into()),
        ])
    };
    let conductance = table(&[("h0", 1e-3.into()), ("exponent", 0.7.into())]);
    let source = table(&[
        ("group", "block".into()),
        ("power", 5e-2.into()),
        ("factors", list(&[0.0, 0.5, 1.0, 1.0, 0.25])),
    ]);
    let builder = CaseBuilder::plane_strain()
        .push("body", part("base"))
        .push("body", part("block"))
        .support("base_t0", &[("uy", 0.0)])
        .support("base_s0", &[("ux", 0.0)])
        .support("block_s0", &[("ux", 0.0)])
        .support("block_s1", &[("ux", 0.0)])
        .pressure("block_t1", 5.0)
        .contact(
            &[
                ("side_a", "base_t1".into()),
                ("side_b", "block_t0".into()),
                ("conductance", conductance.into()),
            ],
            linear_coulomb(1e5, 1e5, 0.2),
        )
        .push("heat_source", source)
        .push("thermal_support", fixed("base_t0", 0.0))
        .step_factors(&[1.0, 1.0, 1.0, 2.0, 2.0]);
    let (case, text) = (builder.case(), builder.text());
    let model = model(stack_mesh(4.0, 2.0), &case).unwrap();
    assert!(model.is_thermally_coupled());
    let mut reference = Frames::default();
    run_steps_from(&model, &settings(&case), None, &mut reference).unwrap();
    assert_eq!(reference.frames.len(), 5);
    let exchanges = reference.resumes[2].solution.thermal.exchanges;
    assert!(
        exchanges > 1,
        "the case must exchange to test the coupling: {exchanges}"
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("restart.bin");
    for (k, resume) in reference.resumes.iter().enumerate() {
        let record = through_record(&path, &text, resume, &model);
        let mut resumed = Frames::default();
        run_steps_from(&model, &settings(&case), Some(record.resume), &mut resumed).unwrap();
        assert!(
            resumed.frames == reference.frames[k + 1..],
            "resumed after frame {} differs",
            k + 1
        );
    }
}

/// The conduction of `model` at time 1 with the joints in the contact `states`.
fn solve_heat(
    model: &asperity::model::Model,
    states: &[asperity::contact::InterfaceState],
) -> asperity::Result<asperity::thermal::HeatSolution> {
    let mut solver = ConductionSolver::new(model)?.expect("a conducting model");
    solver.solve(model, 1.0, states)
}

/// The two blocks of [`stack_mesh`] held mechanically (the base's bottom, both left
/// sides), their frictionless pair with normal and tangential stiffness `stiffness`
/// conducting with `conductance`.
fn held_stack(conductance: toml::Value, stiffness: (f64, f64)) -> CaseBuilder {
    CaseBuilder::plane_strain()
        .push("body", body("base"))
        .push("body", body("block"))
        .support("base_t0", &[("uy", 0.0)])
        .support("base_s0", &[("ux", 0.0)])
        .support("block_s0", &[("ux", 0.0)])
        .contact(
            &[
                ("side_a", "base_t1".into()),
                ("side_b", "block_t0".into()),
                ("conductance", conductance),
            ],
            linear_coulomb(stiffness.0, stiffness.1, 0.0),
        )
}

/// The condensed conduction solve (the constant part factored once, the joints in a dense
/// block) gives the temperatures and heat flows of a dense solve of the whole system
/// K_ff T_f = f_f − K_fp T_p assembled from the same parts: a stack whose open joint conducts
/// through its gap conductance, with a source in the block and a temperature support on the
/// block's side, which holds one of the joint's nodes (the joint's entries in prescribed rows
/// and columns).
#[test]
fn the_condensed_conduction_solve_equals_a_dense_solve_of_the_whole_system() {
    let conductance = table(&[
        ("h0", 1e-3.into()),
        ("exponent", 0.0.into()),
        ("gap", 4e-4.into()),
    ]);
    let source = table(&[("group", "block".into()), ("power", 2e-3.into())]);
    let case = held_stack(conductance.into(), (1e5, 1e5))
        .push("heat_source", source)
        .push("thermal_support", fixed("base_t0", 10.0))
        .push("thermal_support", fixed("block_s0", TA))
        .step_factors(&[1.0])
        .case();
    let model = model(stack_mesh(4.0, 2.0), &case).unwrap();
    let open =
        vec![asperity::contact::InterfaceState::default(); model.interface.elements.len() * 3];
    let solved = solve_heat(&model, &open).unwrap();

    let c = model.thermal.conduction.as_ref().unwrap();
    let n = c.size();
    let mut k = nalgebra::DMatrix::<f64>::zeros(n, n);
    c.constant_entries(&model.continuum, |i, j, v| k[(i as usize, j as usize)] += v);
    c.joint_entries(&model.interface, &open, |i, j, v| {
        k[(i as usize, j as usize)] += v
    });
    let multiplier = |a: usize| model.schedule.value(a, 1.0);
    let load = c.load(&multiplier);
    let mut t = vec![0.0; n];
    c.set_prescribed(&multiplier, &mut t);
    let held = c.prescribed();
    let free: Vec<usize> = (0..n).filter(|&i| !held[i]).collect();
    assert!(free.len() < n, "some temperatures are prescribed");
    let k_ff = nalgebra::DMatrix::from_fn(free.len(), free.len(), |a, b| k[(free[a], free[b])]);
    let rhs = nalgebra::DVector::from_fn(free.len(), |a, _| {
        load.f[free[a]]
            - (0..n)
                .filter(|&j| held[j])
                .map(|j| k[(free[a], j)] * t[j])
                .sum::<f64>()
    });
    let t_f = k_ff.lu().solve(&rhs).expect("regular");
    for (a, &i) in free.iter().enumerate() {
        t[i] = t_f[a];
    }
    let reaction: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|j| k[(i, j)] * t[j]).sum::<f64>() - load.f[i])
        .collect();
    let dense = c.heat_solution(&model.interface, &open, &multiplier, &t, &reaction, load);

    let close = |a: &[f64], b: &[f64], what: &str| {
        let scale = b.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() <= 1e-11 * scale, "{what}: {x} vs {y}");
        }
    };
    close(&solved.nodal, &dense.nodal, "temperatures");
    close(&solved.supports, &dense.supports, "support heat");
    close(&solved.joints, &dense.joints, "joint heat");
    close(&solved.sources, &dense.sources, "source heat");
    assert!(dense.joints[0].abs() > 0.0, "heat crosses the open joint");
}

/// A block held only across a joint that is open (before it is pressed) keeps the reference
/// temperature while no heat enters it, and is refused once its source heats it.
#[test]
fn a_block_cut_off_by_an_open_joint_keeps_the_reference_or_is_refused() {
    let stack = |source_factor: f64| {
        let source = table(&[
            ("group", "block".into()),
            ("power", 1e-2.into()),
            ("factors", list(&[source_factor])),
        ]);
        let case = held_stack(1e-3.into(), (1e5, 1e5))
            .push("heat_source", source)
            .push("thermal_support", fixed("base_t0", 10.0))
            .step_factors(&[1.0])
            .case();
        model(stack_mesh(4.0, 2.0), &case).unwrap()
    };
    let model = stack(0.0);
    let open =
        vec![asperity::contact::InterfaceState::default(); model.interface.elements.len() * 3];
    assert_eq!(open[0].status, asperity::contact::ContactStatus::Open);
    let heat = solve_heat(&model, &open).unwrap();
    let block = model.bodies.iter().position(|b| b == "block").unwrap() as u32;
    for c in model.continuum.cells.iter().filter(|c| c.body == block) {
        for &n in &c.nodes[..c.kind.node_count()] {
            assert!(
                heat.nodal[n as usize].abs() < 1e-12,
                "{}",
                heat.nodal[n as usize]
            );
        }
    }
    assert!(
        (heat.nodal[0] - 10.0).abs() < 1e-12,
        "the base stays at its support's value"
    );
    match solve_heat(&stack(1.0), &open) {
        Err(asperity::Error::Conduction(m)) => {
            assert!(m.contains("body 'block'") && m.contains("gap"), "{m}")
        }
        other => panic!("expected a conduction error, got {other:?}"),
    }
}

#[test]
fn a_pressed_stack_follows_the_rough_joints_conductance() {
    let (h0, n) = (1e-3, 0.8);
    for p in [2.0_f64, 20.0, 200.0] {
        let h = h0 * p.powf(n);
        let expected_flux = TA / (2.0 * 2.0 / K + 1.0 / h);
        let (jump, flux, exchanges) = stack(p, h0, n);
        assert!(
            (flux - expected_flux).abs() < 1e-6 * expected_flux,
            "p = {p}: flux {flux} vs {expected_flux}"
        );
        assert!(
            (jump - flux / h).abs() < 1e-5 * jump,
            "p = {p}: jump {jump}"
        );
        // The pressure does not depend on the temperature here: the second exchange
        // confirms the first.
        assert!((1..=3).contains(&exchanges), "{exchanges} exchanges");
    }
}

#[test]
fn bad_thermal_input_is_refused_with_a_clear_message() {
    let base = || {
        CaseBuilder::plane_strain()
            .push("body", conducting(elastic(E, NU)))
            .support("s0", &[("ux", 0.0)])
            .support("t0", &[("uy", 0.0)])
    };
    let message = |case: CaseBuilder, mut mesh: Mesh| {
        add_point_group(&mut mesh, "corner", [0.0, 0.0]);
        let case = case.case();
        let run = model(mesh, &case).and_then(|m| {
            asperity::solver::stepping::run_steps(&m, &settings(&case), |_| Ok(0.0)).map(|_| ())
        });
        run.expect_err("bad thermal input").to_string()
    };
    let mesh = || rectangle(4.0, 2.0, 2, 1, 0.0, false);
    // A thermal support on a point, and on a name that is no curve.
    let m = message(base().push("thermal_support", fixed("corner", 1.0)), mesh());
    assert!(m.contains("corner") && m.contains("curve"), "{m}");
    let m = message(
        base().push("thermal_support", fixed("nowhere", 1.0)),
        mesh(),
    );
    assert!(m.contains("nowhere"), "{m}");
}

/// A conducting body whose temperature nothing fixes is refused when the model is built
/// (before any solve, so no cut-backs), naming the body: one with only a flux, and one held
/// only through a contact pair without `conductance`; the same pair with a conductance
/// holds it.
#[test]
fn a_body_whose_temperature_nothing_fixes_is_refused_before_the_run() {
    let unfixed = |mesh: Mesh, case: CaseBuilder| match model(mesh, &case.case()) {
        Err(asperity::Error::UnfixedTemperature { body, .. }) => body,
        Err(e) => panic!("expected UnfixedTemperature, got {e}"),
        Ok(_) => panic!("expected UnfixedTemperature, the model built"),
    };
    let flux = table(&[("group", "s1".into()), ("flux", 1e-3.into())]);
    let case = CaseBuilder::plane_strain()
        .push("body", conducting(elastic(E, NU)))
        .support("s0", &[("ux", 0.0)])
        .support("t0", &[("uy", 0.0)])
        .push("thermal_support", flux);
    assert_eq!(
        unfixed(rectangle(4.0, 2.0, 2, 1, 0.0, false), case.clone()),
        "body"
    );
    let error = model(rectangle(4.0, 2.0, 2, 1, 0.0, false), &case.case()).unwrap_err();
    assert_eq!(error.exit_code(), 3, "{error}");
    let message = error.to_string();
    assert!(
        message.contains("[[thermal_support]]") && message.contains("conductance"),
        "{message}"
    );
    // The outer cylinder of the concentric pair is held only across the joint.
    let (mesh, case) = concentric();
    let mut through_joint = case.case();
    through_joint.thermal_supports.pop();
    assert!(model(mesh.clone(), &through_joint).is_ok());
    let mut cut_off = through_joint.clone();
    cut_off.contacts[0].conductance = None;
    match model(mesh, &cut_off) {
        Err(asperity::Error::UnfixedTemperature { body, .. }) => assert_eq!(body, "outer"),
        other => panic!(
            "expected UnfixedTemperature for 'outer', got {:?}",
            other.err()
        ),
    }
}

/// Conducting bodies that do not expand, pressed together through a conducting joint: the
/// bulk's force is K u (no thermal load), and the energy ledger balances — its pass reads
/// the bodies' point states, made for it although no element was evaluated in the increment.
#[test]
fn conducting_bodies_without_expansion_balance_their_energy() {
    let case = stack_case(20.0, 1e-3, 0.8).step_factors(&[0.5, 1.0]);
    let (_, solution) = solve(stack_mesh(4.0, 2.0), &case.case());
    let e = &solution.energy.total;
    assert!(e.external_work > 0.0, "{e:?}");
    assert!(e.imbalance().abs() < 1e-9 * e.external_work, "{e:?}");
}
