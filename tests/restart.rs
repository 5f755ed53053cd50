//! The restart record (`restart.bin`) and `asperity run --resume`: the record gives back every
//! bit it was given, and a record that does not belong to the case is refused with a clear
//! error instead of continuing a different model. (Resuming killed runs is `tests/crash.rs`.)

use crate::common;

use std::path::Path;
use std::process::Command;

use asperity::contact::{ContactStatus, InterfaceState, PointHistory};
use asperity::material::{PointState, Voigt};
use asperity::output::append::FileMark;
use asperity::output::restart::{ContinuumStates::Stored, OutputState, read_record};
use asperity::output::writer::RecordWriter;
use asperity::solver::energy::{Energy, EnergyLedger};
use asperity::solver::newton::ForceAverage;
use asperity::solver::state::{LoopState, RunStatistics, Solution, StiffnessHistory};
use common::{
    CaseBuilder, fixture, held_block, incompressible_plastic_blocks, list,
    plastic_blocks_pressed_and_sheared, table, two_blocks,
};
use toml::Table;

/// Values that no formatting round trip would keep: thirds, subnormals, negative zero.
fn awkward(i: usize) -> f64 {
    match i % 4 {
        0 => (i as f64 + 1.0) / 3.0,
        1 => -0.0,
        2 => f64::MIN_POSITIVE / 3.0,
        _ => -1e300 / (i as f64 + 7.0),
    }
}

fn solution() -> Solution {
    let point = |k: usize| PointState {
        strain: Voigt::from_fn(|i, _| awkward(k + i)),
        stress: Voigt::from_fn(|i, _| awkward(k + i + 4)),
        plastic_strain: Voigt::from_fn(|i, _| awkward(k + i + 8)),
        equivalent_plastic_strain: awkward(k + 12),
        yielding: k.is_multiple_of(2),
    };
    let interface = |k: usize| InterfaceState {
        relative: [awkward(k), awkward(k + 1), awkward(k + 27)],
        stress: [awkward(k + 2), awkward(k + 3), awkward(k + 28)],
        plastic_slip: [awkward(k + 4), awkward(k + 29)],
        accumulated_slip: awkward(k + 5),
        max_closure: awkward(k + 6),
        friction: awkward(k + 7),
        stiffness: [awkward(k + 8), awkward(k + 9)],
        status: [
            ContactStatus::Open,
            ContactStatus::Stick,
            ContactStatus::Slip,
        ][k % 3],
        unsymmetric: !k.is_multiple_of(2),
        history: PointHistory {
            dissipation: awkward(k + 10),
            wear: [awkward(k + 11), awkward(k + 12)],
            gap_wear: awkward(k + 24),
            cycle_start_dissipation: awkward(k + 13),
            cycle_start_wear: [awkward(k + 14), awkward(k + 15)],
            cycle_slip: [awkward(k + 25), awkward(k + 30)],
            cycle_slip_ends: [
                [awkward(k + 16), awkward(k + 17)],
                [awkward(k + 31), awkward(k + 32)],
            ],
            cycle_max_shear: awkward(k + 18),
            cycle_elastic_closure: awkward(k + 26),
            last_cycle_dissipation: awkward(k + 19),
            last_cycle_slip_amplitude: awkward(k + 20),
            last_cycle_max_shear: awkward(k + 21),
            last_cycle_wear: [awkward(k + 22), awkward(k + 23)],
        },
    };
    let committed: Vec<PointState> = (0..7).map(point).collect();
    let interface_committed: Vec<InterfaceState> = (0..5).map(interface).collect();
    Solution {
        u: (0..10).map(awkward).collect(),
        trial: vec![PointState::default(); 7],
        states_follow_displacements: false,
        interface_trial: vec![InterfaceState::default(); 5],
        internal: Default::default(),
        committed,
        interface_committed,
        energy: EnergyLedger {
            total: Energy {
                external_work: awkward(30),
                elastic_energy: awkward(31),
                interface_energy: awkward(32),
                plastic_dissipation: awkward(33),
                friction_dissipation: awkward(34),
                wear_work: awkward(35),
                numerical_dissipation: awkward(36),
                thermal_work: awkward(37),
            },
            previous_force: (40..50).map(awkward).collect(),
            weights: Default::default(),
        },
        // Output of the last cycle end only: not part of the record.
        jump_use: vec![0.25],
        // Recomputed from the model when a run continues: not part of the record.
        thermal: Default::default(),
    }
}

fn state() -> LoopState {
    LoopState {
        step: 3,
        time: 2.0 + 1.0 / 3.0,
        size: 1.0 / 6.0,
        cutbacks: 4,
        increments: 2,
        iterations: 17,
        force_floor: 1e-7 / 3.0,
        stiffness: StiffnessHistory {
            first: Some(1.0 / 7.0),
            last: None,
        },
        force_average: ForceAverage {
            sum: 1.0 / 3.0,
            count: 5,
        },
        arc: None,
    }
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn a_record_gives_back_every_bit() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("restart.bin");
    let original = solution();
    let stats = RunStatistics {
        steps: 2,
        increments: 9,
        iterations: 40,
        cutbacks: 4,
        last_residual: 1e-13 / 3.0,
        ..RunStatistics::default()
    };
    let output = OutputState {
        files: vec![(
            "history.csv".into(),
            FileMark {
                length: u64::MAX - 1,
                crc: 0xdead_beef,
            },
        )],
    };
    let mut writer = RecordWriter::default();
    let progress = asperity::solver::state::Progress {
        state: state(),
        stats: &stats,
        solution: &original,
        last_increment: None,
    };
    writer
        .write(&path, "case text", &progress, &output, Stored)
        .unwrap();
    writer.finish().unwrap();
    let template = Solution {
        u: vec![0.0; 10],
        committed: vec![PointState::default(); 7],
        trial: vec![PointState::default(); 7],
        states_follow_displacements: false,
        interface_committed: vec![InterfaceState::default(); 5],
        interface_trial: vec![InterfaceState::default(); 5],
        internal: Default::default(),
        energy: EnergyLedger::default(),
        jump_use: vec![0.0],
        thermal: Default::default(),
    };
    let record = read_record(&path, "case text", &template, Stored).unwrap();
    let resume = &record.resume;
    assert_eq!(resume.state, state());
    assert_eq!(resume.state.time.to_bits(), state().time.to_bits());
    assert_eq!(resume.stats.iterations, 40);
    assert_eq!(
        resume.stats.last_residual.to_bits(),
        stats.last_residual.to_bits()
    );
    assert_eq!(bits(&resume.solution.u), bits(&original.u));
    for (a, b) in resume
        .solution
        .point_states()
        .iter()
        .zip(original.point_states())
    {
        for (x, y) in [
            (a.strain, b.strain),
            (a.stress, b.stress),
            (a.plastic_strain, b.plastic_strain),
        ] {
            assert_eq!(bits(x.as_slice()), bits(y.as_slice()));
        }
        assert_eq!(
            a.equivalent_plastic_strain.to_bits(),
            b.equivalent_plastic_strain.to_bits()
        );
        assert_eq!(a.yielding, b.yielding);
    }
    for (a, b) in resume
        .solution
        .interface_committed
        .iter()
        .zip(&original.interface_committed)
    {
        let flat = |s: &InterfaceState| {
            bits(&[
                s.relative[0],
                s.relative[1],
                s.relative[2],
                s.stress[0],
                s.stress[1],
                s.stress[2],
                s.plastic_slip[0],
                s.plastic_slip[1],
                s.accumulated_slip,
                s.max_closure,
                s.friction,
                s.stiffness[0],
                s.stiffness[1],
            ])
        };
        assert_eq!(flat(a), flat(b));
        assert_eq!((a.status, a.unsymmetric), (b.status, b.unsymmetric));
        assert_eq!(a.history, b.history);
    }
    assert_eq!(resume.solution.energy, original.energy);
    // Trial states start from the committed ones.
    assert_eq!(
        resume.solution.interface_trial,
        resume.solution.interface_committed
    );
    assert_eq!(record.output, output);

    // Another case, another model size, and a damaged file are refused with the reason.
    let refusal = |err: asperity::Error| match err {
        asperity::Error::Restart { path: p, reason } if p == path => reason,
        other => panic!("expected a refused record, got {other:?}"),
    };
    let reason = refusal(read_record(&path, "other case", &template, Stored).unwrap_err());
    assert!(reason.contains("case file changed"), "{reason}");
    let mut small = template.clone();
    small.u.pop();
    let reason = refusal(read_record(&path, "case text", &small, Stored).unwrap_err());
    assert!(
        reason.contains("damaged") && reason.contains("displacements"),
        "{reason}"
    );
    let bytes = std::fs::read(&path).unwrap();
    for cut in [0, 10, bytes.len() / 2, bytes.len() - 1] {
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let err = read_record(&path, "case text", &template, Stored).unwrap_err();
        assert!(
            matches!(err, asperity::Error::Restart { .. }),
            "cut at {cut}: {err}"
        );
    }
}

fn asperity(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn write_case(path: &Path, steps: i64) {
    held_block().steps(steps).write(path);
}

/// `--resume` of a finished run changes no result; of a changed case it is refused (exit 3)
/// and leaves the results alone; without a record it starts from the beginning.
#[test]
fn resume_continues_only_the_same_case() {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("case.toml");
    let case_s = case.to_str().unwrap();
    let out = dir.path().join("out");
    let out_s = out.to_str().unwrap();
    write_case(&case, 2);
    assert_eq!(asperity(&["run", case_s, "--out", out_s]).0, Some(0));
    let history = std::fs::read(out.join("history.csv")).unwrap();
    let vtu = std::fs::read(out.join("bodies_0002.vtu")).unwrap();

    let (code, text) = asperity(&["run", case_s, "--out", out_s, "--resume"]);
    assert_eq!(code, Some(0), "{text}");
    assert_eq!(std::fs::read(out.join("history.csv")).unwrap(), history);
    assert_eq!(std::fs::read(out.join("bodies_0002.vtu")).unwrap(), vtu);

    write_case(&case, 3);
    let (code, text) = asperity(&["run", case_s, "--out", out_s, "--resume"]);
    assert_eq!(code, Some(3), "{text}");
    assert!(
        text.contains("cannot resume") && text.contains("case file changed"),
        "{text}"
    );
    assert_eq!(std::fs::read(out.join("history.csv")).unwrap(), history);

    let fresh = dir.path().join("fresh");
    let (code, text) = asperity(&["run", case_s, "--out", fresh.to_str().unwrap(), "--resume"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(fresh.join("bodies_0003.vtu").is_file());
}

/// A frictional pair pressed in one step, then sheared back and forth in a cyclic step whose
/// five cycles are simulated as three (2 + 2 + 1 by cycle jumping).
fn multi_step() -> CaseBuilder {
    fretting(5, 2)
}

/// A frictional pair with Archard wear pressed in one step (2 frames), then sheared back and
/// forth in a cyclic step of `cycles` cycles, 4 frames each, simulated in jumps of `per_jump`.
fn fretting(cycles: i64, per_jump: i64) -> CaseBuilder {
    let step = |name: &str, keys: &[(&str, i64)], supports: Table| {
        let mut step = table(&[("name", name.into()), ("supports", supports.into())]);
        for (k, v) in keys {
            step.insert(k.to_string(), (*v).into());
        }
        step
    };
    let lid = |name: &str, component: &str, value: f64| {
        table(&[
            ("name", name.into()),
            ("group", "lid".into()),
            (component, value.into()),
        ])
    };
    let shear = table(&[
        ("time", list(&[0.0, 0.25, 0.75, 1.0])),
        ("value", list(&[0.0, 1.0, -1.0, 0.0])),
    ]);
    two_blocks(0.2)
        .set_last(
            "contact",
            "wear",
            table(&[("model", "archard".into()), ("coefficient", 1e-5.into())]),
        )
        .push("support", lid("press", "uy", -0.01))
        .push("support", lid("shear", "ux", 0.03))
        .push(
            "step",
            step(
                "press",
                &[("increments", 2)],
                table(&[("press", 1.0.into())]),
            ),
        )
        .push(
            "step",
            step(
                "fret",
                &[
                    ("cycles", cycles),
                    ("cycles_per_jump", per_jump),
                    ("increments", 4),
                ],
                table(&[("shear", shear.into())]),
            ),
        )
}

/// Every frame of a run (step number and the bits of the displacements and interface
/// stresses), and the state to resume from after each.
#[derive(Default)]
struct Frames {
    /// Step, bits of the state, and the energy ledger (its `Debug` text: every f64 in its
    /// shortest round-trip form, so equal texts are equal bits).
    frames: Vec<(usize, Vec<u64>, String)>,
    resumes: Vec<asperity::solver::state::Resume>,
    slipping: bool,
}

impl asperity::solver::state::Observer for Frames {
    fn step(
        &mut self,
        step: &asperity::solver::state::StepResult,
        progress: &asperity::solver::state::Progress,
    ) -> asperity::Result<f64> {
        let s = step.solution;
        let mut values = bits(&s.u);
        // The bodies' states too: a record may leave them out for the resumed run to
        // evaluate again (elastic bodies).
        for p in s.point_states() {
            values.extend(bits(p.stress.as_slice()));
            values.extend(bits(p.strain.as_slice()));
        }
        for p in &s.interface_committed {
            values.extend(bits(&p.stress));
            self.slipping |= p.status == ContactStatus::Slip;
        }
        self.frames
            .push((step.step, values, format!("{:?}", s.energy)));
        self.resumes.push(progress.to_resume());
        Ok(0.0)
    }
}

#[test]
fn a_multi_step_cyclic_run_resumed_from_any_frame_is_bit_identical() {
    let frames = resumed_from_any_frame_is_bit_identical(multi_step());
    assert_eq!(frames.frames.len(), 2 + 3 * 4);
    assert!(frames.slipping, "the case must slip to test anything");
}

/// The same off the condensed path: the elastic bodies' states, left out of the records,
/// are evaluated again by an element loop of their own.
#[test]
fn a_krylov_run_resumed_from_any_frame_is_bit_identical() {
    let frames = resumed_from_any_frame_is_bit_identical(multi_step().set(
        "solver",
        "linear_solver",
        "krylov",
    ));
    assert!(frames.slipping, "the case must slip to test anything");
}

/// A plastic body on the condensed path: the bulk factor kept within an increment while
/// the tangent changes by less than `[solver]`'s reuse threshold — the resumed run's first
/// increment, which factors where the uninterrupted one compared, keeps it alike (it did
/// not: the first factorisation left the increment's "same matrix only" rule on for the
/// next iteration) — and the elastic cells left out of the iterations
/// (`solver::elastic_cells`), judged from each solve's own first evaluation.
#[test]
fn a_plastic_run_resumed_from_any_frame_is_bit_identical() {
    let frames =
        resumed_from_any_frame_is_bit_identical(plastic_blocks_pressed_and_sheared("condensed"));
    assert_eq!(frames.frames.len(), 4);
}

/// The same with a chord step that fails to contract (a nearly incompressible lower block,
/// in the fourth increment): the factor's reuse, stopped for the rest of that increment, is
/// allowed again in the fifth, as in a run resumed there.
#[test]
fn a_run_whose_chord_steps_stall_resumed_from_any_frame_is_bit_identical() {
    let builder =
        incompressible_plastic_blocks("condensed").step_factors(&[0.25, 0.5, 0.75, 1.0, 1.05]);
    let frames = resumed_from_any_frame_is_bit_identical(builder);
    assert_eq!(frames.frames.len(), 5);
}

/// Runs `builder`'s case on the two-block mesh, then resumes it from the record of every
/// frame and compares the frames that follow, bit for bit; returns the frames.
fn resumed_from_any_frame_is_bit_identical(builder: CaseBuilder) -> Frames {
    use asperity::model::{Model, ModelSpec};
    use asperity::solver::stepping::run_steps_from;
    let text = builder.text();
    let case = asperity::config::Case::from_toml(&text, Path::new("case.toml")).unwrap();
    let settings = asperity::run::newton_settings(&case.solver);
    let model = Model::build(
        asperity::mesh::msh::read_msh(&fixture("contact_pair.msh")).unwrap(),
        ModelSpec::new(&case).unwrap(),
    )
    .unwrap();
    let mut reference = Frames::default();
    run_steps_from(&model, &settings, None, &mut reference).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("restart.bin");
    for (k, resume) in reference.resumes.iter().enumerate() {
        let record = common::through_record(&path, &text, resume, &model);
        let mut resumed = Frames::default();
        run_steps_from(&model, &settings, Some(record.resume), &mut resumed).unwrap();
        assert!(
            resumed.frames == reference.frames[k + 1..],
            "resumed after frame {} differs",
            k + 1
        );
    }
    reference
}

/// Arc-length control continues from its restart record bit for bit: the arc, its bounds,
/// the load factor and the last increment's direction travel in the record
/// ([`asperity::solver::state::ArcState`]), so a run resumed after any increment repeats the
/// uninterrupted one (here through the limit point, with arcs cut back on the plateau).
#[test]
fn an_arc_length_run_resumed_from_any_increment_is_bit_identical() {
    use asperity::solver::stepping::run_steps_from;
    let (mesh, builder) = common::plastic_cylinder_under_arc_length();
    let (case, text) = (builder.case(), builder.text());
    let model = common::model(mesh, &case).unwrap();
    let settings = common::settings(&case);
    let mut reference = Frames::default();
    let (_, stats) = run_steps_from(&model, &settings, None, &mut reference).unwrap();
    let increments = reference.frames.len();
    assert!(
        increments > 10 && stats.cutbacks > 0,
        "the path must adapt and cut back its arc: {increments} increments, {} cut-backs",
        stats.cutbacks
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("restart.bin");
    for (k, resume) in reference.resumes.iter().enumerate() {
        let arc = resume
            .state
            .arc
            .as_ref()
            .expect("the record holds the arc state");
        assert_eq!(arc.previous_increment.len(), model.dofs.free_count());
        let record = common::through_record(&path, &text, resume, &model);
        assert_eq!(record.resume.state, resume.state);
        let mut resumed = Frames::default();
        run_steps_from(&model, &settings, Some(record.resume), &mut resumed).unwrap();
        assert!(
            resumed.frames == reference.frames[k + 1..],
            "resumed after increment {} differs",
            k + 1
        );
    }
}

/// Runs `case` into `out` (with `extra` arguments); returns the exit code and stderr.
fn run_case(case: &Path, out: &Path, extra: &[&str]) -> (Option<i32>, String) {
    let mut args = vec![
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    asperity(&args)
}

/// The restart record keeps what continues the tables that grow with the frames (their
/// lengths and checksums), not their rows: a run of four times the cycles has a record of the
/// same size. (Each frame adds at least a history row of ~30 numbers, a hysteresis row and
/// two point-loop rows, ~400 bytes; the counters in the record may take a byte more each.)
#[test]
fn the_restart_record_does_not_grow_with_the_frames() {
    let dir = tempfile::tempdir().unwrap();
    let mut sizes = Vec::new();
    for cycles in [3, 12] {
        let case = fretting(cycles, 1)
            .set_last(
                "contact",
                "hysteresis_points",
                vec![list(&[0.5, 1.0]), list(&[1.5, 1.0])],
            )
            .write(&dir.path().join(format!("case_{cycles}.toml")));
        let out = dir.path().join(format!("out_{cycles}"));
        let (code, text) = run_case(&case, &out, &[]);
        assert_eq!(code, Some(0), "{text}");
        let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
        assert_eq!(history.lines().count(), 1 + 1 + 2 + 4 * cycles as usize);
        sizes.push(std::fs::metadata(out.join("restart.bin")).unwrap().len());
    }
    assert!(sizes[1] <= sizes[0] + 64, "record sizes {sizes:?}");
}

/// `--resume` continues each growing table where the record left it: rows after the record
/// (here the partial line of a run killed while appending) are cut off, and a table that
/// changed before that point is refused, naming it, with the folder left as it was.
#[test]
fn resume_cuts_tables_back_to_the_record_and_refuses_changed_ones() {
    let dir = tempfile::tempdir().unwrap();
    let case = fretting(3, 1).write(&dir.path().join("case.toml"));
    let out = dir.path().join("out");
    let (code, text) = run_case(&case, &out, &[]);
    assert_eq!(code, Some(0), "{text}");
    let tables = [
        "history.csv",
        "hysteresis_joint.csv",
        "cycles.csv",
        "wear_joint.csv",
    ];
    let read = |name: &str| std::fs::read(out.join(name)).unwrap();
    let finished: Vec<Vec<u8>> = tables.iter().map(|t| read(t)).collect();
    for table in tables {
        let mut bytes = read(table);
        bytes.extend_from_slice(b"17,0.2");
        std::fs::write(out.join(table), bytes).unwrap();
    }
    let (code, text) = run_case(&case, &out, &["--resume"]);
    assert_eq!(code, Some(0), "{text}");
    for (table, bytes) in tables.iter().zip(&finished) {
        assert!(read(table) == *bytes, "{table} after --resume");
    }

    // A digit changed in the middle of the hysteresis table.
    let mut changed = finished[1].clone();
    let middle = changed.len() / 2;
    let digit = middle
        + changed[middle..]
            .iter()
            .position(u8::is_ascii_digit)
            .unwrap();
    changed[digit] = if changed[digit] == b'1' { b'2' } else { b'1' };
    std::fs::write(out.join(tables[1]), &changed).unwrap();
    let (code, text) = run_case(&case, &out, &["--resume"]);
    assert_eq!(code, Some(3), "{text}");
    assert!(
        text.contains("cannot resume") && text.contains("hysteresis_joint.csv"),
        "{text}"
    );
    assert!(read(tables[1]) == changed);
    assert!(read(tables[0]) == finished[0]);
}
