//! Load histories (`[[step]]`, `[[amplitude]]`): every load follows its amplitude exactly at
//! every frame, steps hold what they do not name, cyclic steps repeat their frames, and a
//! sub-increment stops on an amplitude's breakpoint so that a path-dependent material sees
//! the peak of the load.
//!
//! The references are closed forms of a plate in uniform plane stress: one quad8 [0,2]×[0,1]
//! held by rollers on its left (u_x = 0) and bottom (u_y = 0) edges, pulled by tractions on
//! its top and right edges. Its stress is uniform, which the quadratic element represents
//! exactly, so the corner (2, 1) moves by u_x = 2 (σ_xx − ν σ_yy)/E, u_y = (σ_yy − ν σ_xx)/E.

use crate::common;

use std::path::Path;

use asperity::config::Case;
use asperity::model::Model;
use asperity::run::{self, folder::OutputFolder};
use asperity::solver::state::StepResult;
use common::{CaseBuilder, PLATE_MSH, elastic, list, table, with_keys};
use toml::{Table, Value};

const E: f64 = 1000.0;
const NU: f64 = 0.3;
/// Tractions at amplitude 1 (MPa): top (σ_yy) and right (σ_xx) edges.
const PULL: f64 = 2.0;
const SIDE: f64 = -1.5;

/// The plate's case head: mesh, plane stress, a body of `material` on the rollers.
fn plate(material: Table) -> CaseBuilder {
    CaseBuilder::plane_stress(1.0)
        .mesh_file(Path::new("m.msh"))
        .body("plate", material)
        .support("left", &[("ux", 0.0)])
        .support("bottom", &[("uy", 0.0)])
}

/// The elastic plate with its two loads, `pull` (top) and `side` (right).
fn elastic_plate() -> CaseBuilder {
    let traction = |name: &str, group: &str, traction: [f64; 2]| {
        table(&[
            ("name", name.into()),
            ("group", group.into()),
            ("traction", list(&traction)),
        ])
    };
    // Every increment solved, none accepted at its extrapolated start (which is exact only to
    // the linear-increment criterion, ~1e-12 here): the corner is then the closed form to
    // round-off, a check of the multipliers' arithmetic.
    plate(elastic(E, NU))
        .push("load", traction("pull", "top", [0.0, PULL]))
        .push("load", traction("side", "right", [SIDE, 0.0]))
        .set("solver", "extrapolate", false)
}

/// A `[[step]]` of `keys` that sets the multipliers `targets` (`loads` or `supports`).
fn step(keys: &[(&str, Value)], targets: &str, multipliers: &[(&str, Value)]) -> Table {
    let mut step = table(keys);
    step.insert(targets.into(), table(multipliers).into());
    step
}

/// The inline amplitude through (time, value).
fn inline_amplitude(time: &[f64], value: &[f64]) -> Value {
    table(&[("time", list(time)), ("value", list(value))]).into()
}

/// What the run handed to `on_step` at each frame.
#[derive(Clone, Debug)]
struct Seen {
    step: usize,
    analysis_step: usize,
    cycle: usize,
    step_time: f64,
    cycle_end: bool,
    /// Displacement (u_x, u_y) of the corner (2, 1).
    corner: [f64; 2],
    /// σ_yy at the first integration point.
    stress_yy: f64,
    increments: usize,
    cutbacks: usize,
}

/// Runs `case` on [`PLATE_MSH`] and returns every frame and the output folder.
fn run(case: &CaseBuilder) -> (Vec<Seen>, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("m.msh"), PLATE_MSH).unwrap();
    let case = Case::from_file(&case.write(&dir.path().join("case.toml"))).unwrap();
    let out = dir.path().join("out");
    let folder = OutputFolder::scratch(&out).unwrap();
    let (mesh, _) = run::load_mesh(&case, &folder).unwrap();
    let mut seen = Vec::new();
    run::run_mesh(
        &case,
        mesh,
        run::MeshTime::default(),
        &folder,
        false,
        |model, step| {
            seen.push(observe(model, step));
            Ok(())
        },
    )
    .unwrap();
    (seen, dir)
}

fn observe(model: &Model, step: &StepResult) -> Seen {
    let node = model
        .mesh
        .nodes
        .iter()
        .position(|p| *p == [2.0, 1.0])
        .unwrap();
    let u = &step.solution.u;
    Seen {
        step: step.step,
        analysis_step: step.frame.analysis_step,
        cycle: step.frame.cycle,
        step_time: step.frame.step_time,
        cycle_end: step.frame.cycle_end,
        corner: [u[2 * node], u[2 * node + 1]],
        stress_yy: step.solution.point_states()[0].stress[1],
        increments: step.increments,
        cutbacks: step.cutbacks,
    }
}

/// The corner displacement of the plate under the loads' multipliers (closed form).
fn corner(pull: f64, side: f64) -> [f64; 2] {
    let (sxx, syy) = (SIDE * side, PULL * pull);
    [2.0 * (sxx - NU * syy) / E, (syy - NU * sxx) / E]
}

/// Piecewise-linear interpolation through (time, value): the amplitude's closed form.
fn amplitude(time: &[f64], value: &[f64], t: f64) -> f64 {
    let i = time.iter().position(|&x| x >= t).unwrap().max(1);
    value[i - 1] + (t - time[i - 1]) / (time[i] - time[i - 1]) * (value[i] - value[i - 1])
}

fn assert_corner(seen: &Seen, pull: f64, side: f64) {
    for (c, (got, expected)) in seen.corner.iter().zip(corner(pull, side)).enumerate() {
        // A linear elastic solve of one element: round-off only.
        assert!(
            (got - expected).abs() <= 1e-12 * expected.abs().max(1e-3),
            "frame {}: u[{c}] = {got:e}, expected {expected:e}",
            seen.step,
        );
    }
}

/// The columns of `history.csv` as (header, values).
fn history(dir: &Path) -> Vec<(String, Vec<f64>)> {
    let text = std::fs::read_to_string(dir.join("out/history.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    header
        .into_iter()
        .enumerate()
        .map(|(i, h)| (h, rows.iter().map(|r| r[i]).collect()))
        .collect()
}

fn column<'h>(history: &'h [(String, Vec<f64>)], name: &str) -> &'h [f64] {
    &history.iter().find(|(h, _)| h == name).unwrap().1
}

const WAVE_TIME: [f64; 4] = [0.0, 0.3, 0.55, 1.0];
const WAVE_VALUE: [f64; 4] = [1.0, -1.5, 0.2, -0.5];

#[test]
fn loads_follow_their_amplitudes_exactly_through_reversal_and_sign_change() {
    let wave = table(&[
        ("name", "wave".into()),
        ("time", list(&WAVE_TIME)),
        ("value", list(&WAVE_VALUE)),
    ]);
    let case = elastic_plate()
        .push("amplitude", wave)
        .push(
            "step",
            step(
                &[("name", "load".into()), ("increments", 4.into())],
                "loads",
                &[("pull", 1.0.into()), ("side", 0.5.into())],
            ),
        )
        .push(
            "step",
            step(
                &[("name", "reverse".into()), ("increments", 7.into())],
                "loads",
                &[("pull", "wave".into())],
            ),
        );
    let (seen, dir) = run(&case);
    assert_eq!(seen.len(), 4 + 7);
    for s in &seen {
        let (pull, side) = if s.analysis_step == 1 {
            assert!((s.step_time - s.step as f64 / 4.0).abs() < 1e-15);
            (s.step_time, 0.5 * s.step_time)
        } else {
            (amplitude(&WAVE_TIME, &WAVE_VALUE, s.step_time), 0.5)
        };
        assert_corner(s, pull, side);
    }
    // The reversal to −1.5 and the sign change are in the frames.
    let last = &seen[10];
    assert_eq!(
        (last.analysis_step, last.step_time, last.cycle_end),
        (2, 1.0, true)
    );
    assert!(seen.iter().any(|s| s.corner[1] < 0.0));
    // The increments that contain a breakpoint (0.3 in 2/7..3/7, 0.55 in 3/7..4/7) end a
    // sub-increment there.
    let increments: Vec<usize> = seen[4..].iter().map(|s| s.increments).collect();
    assert_eq!(increments, [1, 1, 2, 2, 1, 1, 1]);
    let h = history(dir.path());
    let pull = column(&h, "factor_load_pull");
    let time = column(&h, "load_factor");
    let step_time = column(&h, "step_time");
    for (j, s) in seen.iter().enumerate() {
        let expected = if s.analysis_step == 1 {
            s.step_time
        } else {
            amplitude(&WAVE_TIME, &WAVE_VALUE, s.step_time)
        };
        assert!((pull[j + 1] - expected).abs() < 1e-14, "row {}", j + 1);
        // The load factor of [[step]] cases is the total analysis time.
        let analysis_time = (s.analysis_step - 1) as f64 + s.step_time;
        assert!((time[j + 1] - analysis_time).abs() < 1e-14);
        assert_eq!(step_time[j + 1], s.step_time);
    }
    assert_eq!(
        column(&h, "analysis_step")[1..],
        [1., 1., 1., 1., 2., 2., 2., 2., 2., 2., 2.]
    );
}

#[test]
fn a_step_holds_the_loads_it_does_not_name_while_another_ramps() {
    let ramp = |increments: i64, load: &str, to: f64| {
        step(
            &[("increments", increments.into())],
            "loads",
            &[(load, to.into())],
        )
    };
    let case = elastic_plate()
        .push("step", ramp(2, "pull", 1.0))
        .push("step", ramp(3, "side", -2.0))
        .push("step", ramp(2, "pull", 0.0));
    let (seen, dir) = run(&case);
    assert_eq!(seen.len(), 7);
    for s in &seen {
        let t = s.step_time;
        let (pull, side) = match s.analysis_step {
            1 => (t, 0.0),
            2 => (1.0, -2.0 * t),
            _ => (1.0 - t, -2.0),
        };
        assert_corner(s, pull, side);
    }
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap(),
    )
    .unwrap();
    let steps = &summary["analysis_steps"];
    assert_eq!(steps[1]["name"], "step-2");
    assert_eq!(steps[1]["first_frame"], 3);
    assert_eq!(steps[1]["frames"], 3);
}

#[test]
fn the_frames_of_a_cyclic_elastic_step_repeat_every_cycle() {
    let case = elastic_plate()
        .push(
            "step",
            step(
                &[("name", "preload".into())],
                "loads",
                &[("pull", 1.0.into())],
            ),
        )
        .push(
            "step",
            step(
                &[
                    ("name", "cycling".into()),
                    ("cycles", 4.into()),
                    ("increments", 5.into()),
                ],
                "loads",
                &[(
                    "side",
                    inline_amplitude(&[0.0, 0.2, 0.7, 1.0], &[0.0, 1.0, -1.0, 0.0]),
                )],
            ),
        );
    let (seen, dir) = run(&case);
    assert_eq!(seen.len(), 1 + 4 * 5);
    let cycling = &seen[1..];
    for (k, s) in cycling.iter().enumerate() {
        assert_eq!((s.analysis_step, s.cycle), (2, k / 5 + 1));
        assert_eq!(s.cycle_end, k % 5 == 4);
        let side = amplitude(&[0.0, 0.2, 0.7, 1.0], &[0.0, 1.0, -1.0, 0.0], s.step_time);
        assert_corner(s, 1.0, side);
        let first = &cycling[k % 5];
        for (a, b) in s.corner.iter().zip(first.corner) {
            assert!(
                (a - b).abs() <= 1e-12 * b.abs().max(1e-3),
                "cycle {} differs from cycle 1",
                s.cycle
            );
        }
    }
    let h = history(dir.path());
    assert_eq!(
        column(&h, "cycle")[2..],
        [
            1., 1., 1., 1., 1., 2., 2., 2., 2., 2., 3., 3., 3., 3., 3., 4., 4., 4., 4., 4.
        ]
    );
    assert_eq!(column(&h, "cycles")[21], 4.0);
    // Field output at cycle ends: every frame of the first and last cycle, the end of the
    // others (frames 11 and 16); history.csv has all of them.
    let out = dir.path().join("out");
    let vtu: Vec<usize> = (1..=21)
        .filter(|j| out.join(format!("frame_{j:04}.vtm")).is_file())
        .collect();
    assert_eq!(vtu, [1, 2, 3, 4, 5, 6, 11, 16, 17, 18, 19, 20, 21]);
}

#[test]
fn a_cut_back_increment_stops_on_the_breakpoint_and_the_plastic_bar_keeps_the_peak() {
    // A bar yielding in tension, then unloaded, all in one increment: the amplitude peaks at
    // step time 0.5. With E = 1000, σ_Y = 1, H = 100 and a peak strain of 0.004 (four times
    // the yield strain) the first sub-increment is implausible ([solver]
    // max_strain_increment) and is cut back; the sub-increments meet the peak exactly.
    let (sy, h, peak) = (1.0, 100.0, 0.004);
    let material = with_keys(elastic(E, NU), &[("yield_stress", sy), ("hardening", h)]);
    let grip = table(&[
        ("name", "grip".into()),
        ("group", "top".into()),
        ("uy", peak.into()),
    ]);
    let case = plate(material)
        .push("support", grip)
        .push(
            "step",
            step(
                &[],
                "supports",
                &[("grip", inline_amplitude(&[0.0, 0.5, 1.0], &[0.0, 1.0, 0.4]))],
            ),
        )
        .set("solver", "max_strain_increment", 0.003)
        .set("solver", "residual_tolerance", 1e-8)
        .set("solver", "correction_tolerance", 1e-8)
        .set("solver", "linear_residual_tolerance", 1e-10);
    let (seen, _dir) = run(&case);
    assert_eq!(seen.len(), 1);
    assert!(seen[0].cutbacks >= 1, "{seen:?}");
    // Uniaxial stress, linear hardening: σ = E (σ_Y + H ε)/(E + H) at the peak, ε_p = ε − σ/E,
    // then elastic unloading σ = E (ε_end − ε_p).
    let sigma_peak = E * (sy + h * peak) / (E + h);
    let plastic = peak - sigma_peak / E;
    let expected = E * (0.4 * peak - plastic);
    let got = seen[0].stress_yy;
    assert!(
        (got - expected).abs() < 1e-6 * sigma_peak,
        "σ_yy = {got}, expected {expected}"
    );
    // Loading straight to the end value (skipping the peak) would have ended in tension at
    // E (σ_Y + H ε_end)/(E + H) ≈ 1.05 MPa; with the peak the bar ends in compression.
    assert!(expected < -1.0 && got < -1.0);
}
