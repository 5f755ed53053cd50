//! `asperity fit`: synthetic curves from known parameters are fitted back.
//!
//! - exact data: the parameters are recovered to 1e-6 relative;
//! - 1 % Gaussian noise, 100 seeds: each true value lies in the reported 95 % interval in at
//!   least 90 fits (binomial(100, 0.95) falls below 90 with probability 2.8 %; the seeds are
//!   fixed, so the test is deterministic);
//! - a fit through a full specimen model recovers the parameters that generated its data;
//! - a set-up that cannot separate two parameters is reported as not identifiable;
//! - parameters pushed to their range's bounds (the law's or the fit file's) end there, and
//!   the finite differences never leave the range;
//! - starting values three times off reach the minimum through the other starts;
//! - data that bound a parameter from one side only give that verdict whatever the start;
//! - bad input names the file and the key, and leaves no result file.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use asperity::Error;
use asperity::contact::rough;
use asperity::fit::experiment::{normal, tangential};
use asperity::fit::{Fit, FitResult, Outcome, Verdict};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// The generating parameters (rough joint, in the order of `rough::LAW.parameters`).
const TRUE: [(&str, f64); 10] = [
    ("c_n", 2e-3),
    ("m", 0.5),
    ("unloading_c_n", f64::NAN),
    ("unloading_m", f64::NAN),
    ("R", 2e-3),
    ("S", 0.5),
    ("mu_m", 0.3),
    ("beta", 0.6),
    ("n", 50.0),
    ("starting_pressure", 0.1),
];

fn true_values() -> Vec<f64> {
    TRUE.iter().map(|(_, v)| *v).collect()
}

fn closures() -> Vec<f64> {
    (1..=30).map(|i| 3e-4 * i as f64).collect()
}

fn displacements() -> Vec<f64> {
    (1..=30).map(|i| 1e-4 * (i as f64).powi(2)).collect()
}

/// A cycle: out to 0.09 mm, back to −0.09 mm and out again (reversed slip, hardening on).
fn cycle() -> Vec<f64> {
    let out = displacements();
    let back = out
        .iter()
        .rev()
        .skip(1)
        .chain(&[0.0])
        .copied()
        .chain(out.iter().map(|u| -u));
    let again = out
        .iter()
        .rev()
        .skip(1)
        .map(|u| -u)
        .chain([0.0])
        .chain(out.iter().copied());
    out.iter().copied().chain(back).chain(again).collect()
}

/// Writes a CSV with a units comment.
fn write_csv(path: &Path, units: &str, names: [&str; 2], x: &[f64], y: &[f64]) {
    let mut s = format!("# units: {units}\n{},{}\n", names[0], names[1]);
    for (a, b) in x.iter().zip(y) {
        writeln!(s, "{a:e},{b:e}").unwrap();
    }
    std::fs::write(path, s).unwrap();
}

/// Writes the normal test and tangential tests at `pressures` into `dir` with responses
/// multiplied by (1 + noise·ε), ε ~ N(0, 1) from `rng`; returns their [[test]] sections.
fn write_curves(
    dir: &Path,
    pressures: &[f64],
    noise: f64,
    rng: &mut ChaCha8Rng,
    errors: &str,
) -> String {
    let law = rough::LAW.build(&true_values()).unwrap();
    let mut noisy = |y: Vec<f64>| -> Vec<f64> {
        y.into_iter()
            .map(|v| {
                let e: f64 = StandardNormal.sample(rng);
                v * (1.0 + noise * e)
            })
            .collect()
    };
    let c = closures();
    write_csv(
        &dir.join("normal.csv"),
        "closure = mm, pressure = MPa",
        ["closure", "pressure"],
        &c,
        &noisy(normal(law.as_ref(), &c)),
    );
    let mut tests = format!("[[test]]\nkind = \"normal\"\ndata = \"normal.csv\"\n{errors}\n");
    for (k, p) in pressures.iter().enumerate() {
        // The last pressure level is cycled, the others loaded monotonically.
        let u = if k + 1 == pressures.len() && k > 0 {
            cycle()
        } else {
            displacements()
        };
        let name = format!("shear_{p}.csv");
        let y = noisy(tangential(law.as_ref(), *p, &u));
        write_csv(
            &dir.join(&name),
            "displacement = mm, shear = MPa",
            ["displacement", "shear"],
            &u,
            &y,
        );
        write!(
            tests,
            "[[test]]\nkind = \"tangential\"\ndata = \"{name}\"\npressure = {p:?}\n{errors}\n"
        )
        .unwrap();
    }
    tests
}

const FREE: &str = r#"law = "rough_joint"
[parameters]
c_n = { initial = 1e-3, log = true }
m = { initial = 0.7, min = 0.05, max = 1.5 }
R = { initial = 1e-3, log = true }
S = { initial = 0.3, min = 0.0, max = 2.0 }
mu_m = { initial = 0.5, min = 0.0, max = 2.0 }
beta = { initial = 0.8, min = 0.01, max = 1.0 }
n = { initial = 20.0, log = true }
"#;

fn fit(dir: &Path, text: &str) -> Result<FitResult, Error> {
    let path = dir.join("fit.toml");
    std::fs::write(&path, text).unwrap();
    Fit::from_file(&path)?.run()
}

fn value(r: &FitResult, name: &str) -> f64 {
    r.get(name).unwrap().value
}

#[test]
fn exact_data_gives_the_parameters_to_1e_6() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let tests = write_curves(dir.path(), &[10.0, 30.0], 0.0, &mut rng, "");
    let r = fit(dir.path(), &format!("{FREE}\n{tests}")).unwrap();
    assert!(r.identifiable, "{r}");
    assert!(
        r.parameters
            .iter()
            .filter(|e| e.free)
            .all(|e| e.verdict == Some(Verdict::Identified))
    );
    for (name, truth) in TRUE
        .iter()
        .filter(|(n, v)| !v.is_nan() && *n != "starting_pressure")
    {
        let got = value(&r, name);
        assert!(
            (got - truth).abs() <= 1e-6 * truth.abs(),
            "{name}: {got} vs {truth}\n{r}"
        );
    }
    assert!(r.chi_square < 1e-20, "{r}");
}

/// Free parameters of the calibration test: normal compliance, tangential stiffness from two
/// pressures, friction with hardening.
#[test]
fn noisy_fits_have_calibrated_95_percent_intervals() {
    let names = ["c_n", "m", "R", "S", "mu_m", "beta", "n"];
    // Linearised and profile intervals.
    let (mut inside, mut inside_profile) = ([0usize; 7], [0usize; 7]);
    // The starting values are those of the other tests: one start suffices (the intervals
    // are what is checked here, and 100 fits × 12 starts would only cost time).
    let free = format!("starts = 1\n{FREE}");
    let dir = tempfile::tempdir().unwrap();
    for seed in 0..100 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let tests = write_curves(
            dir.path(),
            &[10.0, 30.0],
            0.01,
            &mut rng,
            "relative_error = 0.01",
        );
        let r = fit(dir.path(), &format!("{free}\n{tests}")).unwrap();
        assert!(r.identifiable && r.errors_stated, "seed {seed}: {r}");
        for (k, name) in names.iter().enumerate() {
            let e = r.get(name).unwrap();
            let truth = TRUE.iter().find(|(n, _)| n == name).unwrap().1;
            if e.lower_95.unwrap() <= truth && truth <= e.upper_95.unwrap() {
                inside[k] += 1;
            }
            if e.profile_lower_95.unwrap() <= truth && truth <= e.profile_upper_95.unwrap() {
                inside_profile[k] += 1;
            }
        }
    }
    eprintln!(
        "coverage of the 95 % intervals in 100 fits: linearised {:?}, profile {:?}",
        names.iter().zip(inside).collect::<Vec<_>>(),
        names.iter().zip(inside_profile).collect::<Vec<_>>()
    );
    for (k, name) in names.iter().enumerate() {
        for (kind, n) in [("linearised", inside[k]), ("profile", inside_profile[k])] {
            assert!(
                n >= 90,
                "{name}: the true value is inside the {kind} 95 % interval in {n} of 100 fits"
            );
        }
    }
}

#[test]
fn r_and_s_from_one_pressure_are_not_identifiable() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let tests = write_curves(dir.path(), &[20.0], 0.0, &mut rng, "");
    let r = fit(dir.path(), &format!("{FREE}\n{tests}")).unwrap();
    assert!(!r.identifiable, "{r}");
    for name in ["R", "S"] {
        let e = r.get(name).unwrap();
        assert!(
            e.standard_error.is_none() && e.lower_95.is_none(),
            "{name}: {e:?}"
        );
    }
    for name in ["R", "S"] {
        assert_eq!(
            r.get(name).unwrap().verdict,
            Some(Verdict::NotIdentified),
            "{r}"
        );
    }
    // The others are still determined, and well.
    for name in ["c_n", "m", "mu_m"] {
        let e = r.get(name).unwrap();
        assert!(e.standard_error.is_some(), "{name}\n{r}");
        assert_eq!(e.verdict, Some(Verdict::Identified), "{name}\n{r}");
    }
    let warning = r
        .warnings
        .iter()
        .find(|w| w.starts_with("not identifiable"))
        .expect("a warning");
    assert!(warning.contains("R") && warning.contains("S"), "{warning}");
    // k_T = p^S / R at the test pressure is what the data fix: it must be right.
    let kt = |r_: f64, s: f64| (20.0f64.powi(2) + 0.01).powf(0.5 * s) / r_;
    let (fr, fs) = (value(&r, "R"), value(&r, "S"));
    assert!(
        (kt(fr, fs) / kt(2e-3, 0.5) - 1.0).abs() < 1e-6,
        "R {fr}, S {fs}"
    );
}

/// The worked example of the README: curves made by pipelines/fit/make_synthetic.py from the
/// law's closed forms (independently of asperity), with 1 % + 0.005 MPa noise.
#[test]
fn shipped_example_brackets_its_generating_parameters() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/fit/joint.toml");
    let r = Fit::from_file(&path).unwrap().run().unwrap();
    let truth = [
        ("c_n", 2e-3),
        ("m", 0.5),
        ("unloading_c_n", 4e-4),
        ("unloading_m", 0.8),
        ("R", 2e-3),
        ("S", 0.5),
        ("mu_m", 0.3),
        ("beta", 0.6),
        ("n", 50.0),
    ];
    for (name, t) in truth {
        let e = r.get(name).unwrap();
        for (lo, hi) in [
            (e.lower_95.unwrap(), e.upper_95.unwrap()),
            (e.profile_lower_95.unwrap(), e.profile_upper_95.unwrap()),
        ] {
            assert!(lo <= t && t <= hi, "{name}: {t} outside [{lo}, {hi}]\n{r}");
        }
    }
    let dof = r.degrees_of_freedom as f64;
    // χ² with the stated errors: mean dof, standard deviation √(2 dof).
    assert!((r.chi_square - dof).abs() < 4.0 * (2.0 * dof).sqrt(), "{r}");
}

/// The specimen's reaction at each step, computed with c_n = 2e-3, m = 0.5, is fitted from
/// c_n = 1e-3, m = 0.7.
#[test]
fn full_model_fit_recovers_its_generating_parameters() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let case = root.join("examples/fit/specimen/specimen.toml");
    let data = dir.path().join("reaction.csv");
    std::fs::write(
        &data,
        "# units: step = 1, value = 1\nstep,value\n1,0\n2,0\n3,0\n4,0\n",
    )
    .unwrap();
    let head = format!(
        "law = \"rough_joint\"\n[parameters]\nc_n = {{ initial = 1e-3, log = true }}\nm = {{ initial = 0.7, min = 0.1, max = 1.5 }}\n\
         R = {{ value = 2e-3 }}\nS = {{ value = 0.5 }}\nmu_m = {{ value = 0.3 }}\n\
         [[test]]\nkind = \"model\"\ncase = {case:?}\ndata = \"reaction.csv\"\nquantity = \"reactions.block_top.y\"\n"
    );
    // The measured values: the model with the generating parameters (read off a fit whose
    // parameters are fixed at them is not possible, so simulate directly).
    std::fs::write(dir.path().join("fit.toml"), &head).unwrap();
    let f = Fit::from_file(&dir.path().join("fit.toml")).unwrap();
    let mut x = f.parameters.values.clone();
    x[0] = 2e-3;
    x[1] = 0.5;
    let y = f.simulate(&x).unwrap().remove(0);
    assert!(y.iter().all(|v| *v < -10.0), "{y:?}"); // compressive, non-trivial
    let mut csv = "# units: step = 1, value = 1\nstep,value\n".to_string();
    for (k, v) in y.iter().enumerate() {
        writeln!(csv, "{},{v:e}", k + 1).unwrap();
    }
    std::fs::write(&data, csv).unwrap();
    let r = fit(dir.path(), &head).unwrap();
    assert!(r.identifiable, "{r}");
    // The solver's force tolerance (1e-8 relative) bounds how well the data are reproduced.
    assert!((value(&r, "c_n") / 2e-3 - 1.0).abs() < 1e-5, "{r}");
    assert!((value(&r, "m") / 0.5 - 1.0).abs() < 1e-5, "{r}");
}

fn key_of(e: Error) -> (PathBuf, String) {
    match e {
        Error::InvalidParameter { path, key, .. } => (path, key),
        other => panic!("expected an invalid-parameter error, got {other}"),
    }
}

#[test]
fn bad_input_names_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let tests = write_curves(d, &[10.0, 30.0], 0.0, &mut rng, "");
    let normal_csv = d.join("normal.csv");
    let good = std::fs::read_to_string(&normal_csv).unwrap();
    let cases: [(&str, String, &str); 3] = [
        ("missing column", good.replace("pressure\n", "p\n").replace("pressure = MPa", "p = MPa"), "column 'pressure'"),
        ("NaN", good.replacen("e-4,", "e-4,NaN\n#", 1), "column 'pressure', line 3"),
        (
            "time going back",
            "# units: time = s, closure = mm, pressure = MPa\ntime,closure,pressure\n0,1e-3,1\n2,2e-3,2\n1,3e-3,3\n".into(),
            "column 'time', line 5",
        ),
    ];
    for (what, text, key) in cases {
        std::fs::write(&normal_csv, text).unwrap();
        let (path, k) = key_of(fit(d, &format!("{FREE}\n{tests}")).unwrap_err());
        assert_eq!(
            (path.as_path(), k.as_str()),
            (normal_csv.as_path(), key),
            "{what}"
        );
    }
    std::fs::write(&normal_csv, good).unwrap();

    // An unknown parameter, and bounds that do not contain the start.
    for (bad, key) in [
        (
            "S = { initial = 0.3, min = 0.5, max = 2.0 }",
            "parameters.S",
        ),
        ("Q = { value = 1.0 }\nS = { value = 0.5 }", "parameters.Q"),
    ] {
        let text = FREE.replace("S = { initial = 0.3, min = 0.0, max = 2.0 }", bad);
        let (_, k) = key_of(fit(d, &format!("{text}\n{tests}")).unwrap_err());
        assert_eq!(k, key);
    }

    // More starts than the documented limit, named by its key before any fit runs.
    let (_, k) = key_of(fit(d, &format!("starts = 1001\n{FREE}\n{tests}")).unwrap_err());
    assert_eq!(k, "starts");
    // A data file is read no further than the 64 MiB limit (here an endless one).
    #[cfg(unix)]
    {
        let endless = tests.replace(
            normal_csv.file_name().unwrap().to_str().unwrap(),
            "/dev/zero",
        );
        assert_ne!(endless, tests);
        match fit(d, &format!("{FREE}\n{endless}")).unwrap_err() {
            Error::Case { path, message } => {
                assert_eq!(path, Path::new("/dev/zero"));
                assert!(message.contains("larger than 64 MiB"), "{message}");
            }
            other => panic!("expected a file error, got {other}"),
        }
    }
}

/// Shear −0.05 MPa measured in full slip at 10 MPa: the data drive the friction coefficient
/// below zero, out of the law's range (μ ≥ 0). With or without `log = true` and without
/// bounds in the fit file, the fit ends at the law's bound (μ = 0, or a value indistinguishable
/// from it) instead of aborting: the finite differences there step into the range. The data
/// bound μ from above only.
#[test]
fn a_parameter_driven_out_of_the_laws_range_ends_at_its_bound() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let u: Vec<f64> = (1..=10).map(|i| 0.1 * i as f64).collect();
    write_csv(
        &d.join("slip.csv"),
        "displacement = mm, shear = MPa",
        ["displacement", "shear"],
        &u,
        &[-0.05; 10],
    );
    for friction in ["{ initial = 0.3 }", "{ initial = 0.3, log = true }"] {
        let text = format!(
            "law = \"linear_coulomb\"\n[parameters]\nnormal_stiffness = {{ value = 1e4 }}\ntangential_stiffness = {{ value = 1e4 }}\n\
             friction = {friction}\n[[test]]\nkind = \"tangential\"\ndata = \"slip.csv\"\npressure = 10.0\nerror = 0.01\n"
        );
        let r = fit(d, &text).unwrap_or_else(|e| panic!("{friction}: {e}"));
        let e = r.get("friction").unwrap();
        assert!(e.value < 1e-6, "{friction}: {r}");
        assert_eq!(e.verdict, Some(Verdict::BoundedAbove), "{friction}: {r}");
        // The upper limit: Δχ² = 10 ((10 μ + 0.05)² − 0.05²) / 0.01² = 3.84 at μ = 6.07e-5.
        let limit = ((3.84e-4f64 / 10.0 + 0.05 * 0.05).sqrt() - 0.05) / 10.0;
        let upper = e.profile_upper_95.unwrap();
        assert!(
            (upper / limit - 1.0).abs() < 0.02,
            "{friction}: {upper} vs {limit}"
        );
        assert!(e.lower_95.is_none() && e.standard_error.is_none());
        assert!(!r.identifiable);
    }
}

/// Tangential curves generated with β = 1 (no slip hardening) and with β = 1e-12 (friction
/// starting from nothing), fitted with β free in `min = 0`, `max = 1`: β reaches the ends of
/// the law's range (0, 1] without a step or a finite difference leaving it.
#[test]
fn beta_reaches_the_ends_of_its_range() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (beta, at_upper) in [(1.0, true), (1e-12, false)] {
        let mut x = true_values();
        x[7] = beta;
        let law = rough::LAW.build(&x).unwrap();
        let u = cycle();
        let y = tangential(law.as_ref(), 20.0, &u);
        write_csv(
            &d.join("shear.csv"),
            "displacement = mm, shear = MPa",
            ["displacement", "shear"],
            &u,
            &y,
        );
        let text = "law = \"rough_joint\"\n[parameters]\nc_n = { value = 2e-3 }\nm = { value = 0.5 }\nR = { value = 2e-3 }\n\
                    S = { value = 0.5 }\nmu_m = { initial = 0.5, min = 0.0, max = 2.0 }\nbeta = { initial = 0.5, min = 0.0, max = 1.0 }\n\
                    n = { value = 50.0 }\n[[test]]\nkind = \"tangential\"\ndata = \"shear.csv\"\npressure = 20.0\nerror = 1e-3\n";
        let r = fit(d, text).unwrap_or_else(|e| panic!("β = {beta}: {e}"));
        let e = r.get("beta").unwrap();
        assert!((e.value - beta).abs() < 1e-6, "β = {beta}: {r}");
        assert!((value(&r, "mu_m") - 0.3).abs() < 1e-6, "β = {beta}: {r}");
        let expected = if at_upper {
            Verdict::BoundedBelow
        } else {
            Verdict::BoundedAbove
        };
        assert_eq!(e.verdict, Some(expected), "β = {beta}: {r}");
    }
}

/// Starting values three times off (the normal curve's exponents and coefficients, and k_T,
/// friction and hardening): from them alone the fit stops in a local minimum; the other starts
/// reach the minimum of the fit from the good starting values, which is reported, with a
/// warning that the fit file's start did not.
#[test]
fn other_starts_find_the_minimum_from_starting_values_three_times_off() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/fit");
    let good = Fit::from_file(&root.join("joint.toml"))
        .unwrap()
        .run()
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    for f in ["normal.csv", "shear_10MPa.csv", "shear_30MPa.csv"] {
        std::fs::copy(root.join(f), dir.path().join(f)).unwrap();
    }
    let text = std::fs::read_to_string(root.join("joint.toml")).unwrap();
    let tests = &text[text.find("[[test]]").unwrap()..];
    let off = "law = \"rough_joint\"\n[parameters]\nc_n = { initial = 6.67e-4, log = true }\nm = { initial = 1.4, min = 0.05, max = 1.5 }\n\
               unloading_c_n = { initial = 1.33e-4, log = true }\nunloading_m = { initial = 0.267, min = 0.05, max = 1.5 }\n\
               R = { initial = 1e-3, log = true }\nS = { initial = 1.0, min = 0.0, max = 2.0 }\nmu_m = { initial = 0.6, min = 0.0, max = 2.0 }\n\
               beta = { initial = 0.3, min = 0.01, max = 1.0 }\nn = { initial = 100.0, log = true }\nstarting_pressure = { value = 0.1 }\n";
    let alone = fit(dir.path(), &format!("starts = 1\n{off}\n{tests}")).unwrap();
    assert!(
        alone.chi_square > 10.0 * good.chi_square,
        "one start: {alone}"
    );
    let r = fit(dir.path(), &format!("{off}\n{tests}")).unwrap();
    assert!(
        (r.chi_square / good.chi_square - 1.0).abs() < 1e-8,
        "{r}\nagainst\n{good}"
    );
    assert_eq!(r.starts.runs[0].outcome, Outcome::Higher);
    assert!(r.starts.same_minimum >= 1 && r.starts.count == 12);
    assert!(
        r.warnings
            .iter()
            .any(|w| w.starts_with("from the fit file's starting values")),
        "{:?}",
        r.warnings
    );
    for e in r.parameters.iter().filter(|e| e.free) {
        let g = good.get(e.name).unwrap();
        assert!((e.value / g.value - 1.0).abs() < 1e-5, "{}: {r}", e.name);
    }
}

/// Linear stick measured at 10 MPa up to a shear of 3 MPa and never slipping: the friction
/// coefficient is bounded below (μ ≥ 0.3 less what the errors allow) and not above. A fit
/// started below 0.3 climbs to the stick–slip kink and stops there (where the slope is
/// one-sided), one started above stays where it is (where the slope is zero): either way the
/// verdict is "bounded below" with the same limit, and the linearised interval is not given.
#[test]
fn friction_from_stick_only_data_is_bounded_below_whatever_the_start() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let law = asperity::contact::linear::LAW
        .build(&[1e4, 1e3, 0.5])
        .unwrap();
    let u: Vec<f64> = (1..=30).map(|i| 1e-4 * i as f64).collect();
    let y = tangential(law.as_ref(), 10.0, &u);
    assert!((y[29] - 3.0).abs() < 1e-9, "{y:?}");
    write_csv(
        &d.join("stick.csv"),
        "displacement = mm, shear = MPa",
        ["displacement", "shear"],
        &u,
        &y,
    );
    let mut limits = Vec::new();
    for start in [0.1, 0.25, 0.3, 0.31, 0.5, 1.5] {
        let text = format!(
            "law = \"linear_coulomb\"\n[parameters]\nnormal_stiffness = {{ value = 1e4 }}\n\
             tangential_stiffness = {{ initial = 500.0, log = true }}\nfriction = {{ initial = {start:?}, min = 0.0, max = 2.0 }}\n\
             [[test]]\nkind = \"tangential\"\ndata = \"stick.csv\"\npressure = 10.0\nerror = 0.01\n"
        );
        let r = fit(d, &text).unwrap();
        let e = r.get("friction").unwrap();
        assert!(e.value >= 0.3 - 1e-6, "start {start}: {r}");
        assert_eq!(e.verdict, Some(Verdict::BoundedBelow), "start {start}: {r}");
        assert!(
            e.profile_upper_95.is_none() && e.standard_error.is_none() && e.upper_95.is_none(),
            "start {start}: {e:?}"
        );
        let kt = r.get("tangential_stiffness").unwrap();
        assert_eq!(kt.verdict, Some(Verdict::Identified), "start {start}: {r}");
        assert!(!r.identifiable);
        limits.push(e.profile_lower_95.unwrap());
    }
    // With μ < 0.3 the last points slip at 10 μ MPa instead of 3 MPa; with σ = 0.01 MPa the
    // last point alone raises χ² by 3.84 at 10 μ = 3 − 0.0196: the limit lies just below 0.3.
    for l in &limits {
        assert!((0.297..0.2999).contains(l), "{limits:?}");
        assert!((l - limits[0]).abs() < 1e-4 * limits[0], "{limits:?}");
    }
}

#[test]
fn bad_data_and_settings_name_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let tests = write_curves(d, &[10.0, 30.0], 0.0, &mut rng, "");
    let normal_csv = d.join("normal.csv");
    let good = std::fs::read_to_string(&normal_csv).unwrap();
    let lines: Vec<&str> = good.lines().collect();
    // A duplicate column: which one is meant is ambiguous.
    let duplicate = format!(
        "{}\nclosure,pressure,pressure\n{}\n",
        lines[0],
        lines[2..]
            .iter()
            .map(|l| format!("{l},0"))
            .collect::<Vec<_>>()
            .join("\n")
    );
    // A closure in metres that overflows when converted to mm; a pressure whose square
    // overflows χ².
    let overflow = good
        .replace("closure = mm", "closure = m")
        .replacen("\n3e-4,", "\n1e306,", 1);
    let huge = good.replacen("e-4,", "e-4,1e200\n#", 1);
    for (what, text, key) in [
        ("duplicate", duplicate, "column 'pressure'"),
        ("overflow", overflow, "column 'closure', line 3"),
        ("huge", huge, "column 'pressure', line 3"),
    ] {
        std::fs::write(&normal_csv, text).unwrap();
        let (path, k) = key_of(fit(d, &format!("{FREE}\n{tests}")).unwrap_err());
        assert_eq!(
            (path.as_path(), k.as_str()),
            (normal_csv.as_path(), key),
            "{what}"
        );
    }
    // A UTF-8 byte-order mark (spreadsheet exports) is skipped.
    std::fs::write(&normal_csv, format!("\u{FEFF}{good}")).unwrap();
    fit(d, &format!("{FREE}\n{tests}")).unwrap();
    std::fs::write(&normal_csv, &good).unwrap();
    for key in ["max_iterations", "starts"] {
        let (path, k) = key_of(fit(d, &format!("{key} = 0\n{FREE}\n{tests}")).unwrap_err());
        assert_eq!((path, k.as_str()), (d.join("fit.toml"), key));
    }
}

/// The command line: a data error exits with the data code 3 and writes nothing; a fit's
/// warnings go to standard error, its results to standard output.
#[test]
fn command_line_exit_codes_and_streams() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let tests = write_curves(d, &[20.0], 0.0, &mut rng, "");
    std::fs::write(d.join("fit.toml"), format!("{FREE}\n{tests}")).unwrap();
    let run = |out: &Path| {
        Command::new(env!("CARGO_BIN_EXE_asperity"))
            .args(["fit", "fit.toml", "--no-plot", "--out"])
            .arg(out)
            .current_dir(d)
            .output()
            .unwrap()
    };
    // R and S from one pressure: exit 1, with the warning on standard error only.
    let out = run(&d.join("one"));
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{stderr}");
    assert!(stderr.contains("not identifiable"), "{stderr}");
    assert!(!stdout.to_lowercase().contains("warning"), "{stdout}");
    assert!(stdout.contains("law = {"), "{stdout}");
    assert!(d.join("one/fit.json").is_file());
    // Data that overflow: exit 3, no folder, no fit.json or law.toml.
    let csv = d.join("normal.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    std::fs::write(
        &csv,
        text.replace("closure = mm", "closure = m")
            .replacen("\n3e-4,", "\n1e306,", 1),
    )
    .unwrap();
    let out = run(&d.join("bad"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("normal.csv") && stderr.contains("line 3"),
        "{stderr}"
    );
    assert!(!d.join("bad").exists());
}

/// A fit's folder: a file of a fit's name (`curves.csv`, `fit.json`, ...) that no fit wrote
/// is refused before the fit runs and before it writes, and left as it was; a folder whose
/// `fit.json` is a fit's is an earlier fit's, whose files a new fit replaces.
#[test]
fn a_fit_never_overwrites_files_no_fit_wrote() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    asperity::fit::check_folder(&out.join("new")).unwrap();
    asperity::fit::check_folder(out).unwrap();
    for name in ["curves.csv", "fit.json"] {
        std::fs::write(out.join(name), "mine").unwrap();
        match asperity::fit::check_folder(out) {
            Err(Error::OutputForeign { file, .. }) => assert_eq!(file, out.join(name)),
            other => panic!("{name}: expected a refusal, got {other:?}"),
        }
        std::fs::remove_file(out.join(name)).unwrap();
    }
    std::fs::write(out.join("curves.csv"), "an earlier fit's").unwrap();
    std::fs::write(
        out.join("fit.json"),
        r#"{"fit_file": "joint.toml", "chi_square": 1.0}"#,
    )
    .unwrap();
    asperity::fit::check_folder(out).unwrap();
}

/// The plots a fit makes (`fit.png`, `residuals.png`, by `pipelines/fit/plot_fit.py`) replace
/// a symbolic link of their name in the folder of an earlier fit, never write through it.
#[cfg(unix)]
#[test]
fn a_fits_plots_never_write_through_a_link() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let tests = write_curves(d, &[10.0, 30.0], 0.0, &mut rng, "");
    std::fs::write(d.join("fit.toml"), format!("{FREE}\n{tests}")).unwrap();
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let run = || {
        Command::new(env!("CARGO_BIN_EXE_asperity"))
            .args(["fit", "fit.toml", "--out", "out"])
            .env("ASPERITY_PIPELINES", repo.join("pipelines"))
            .current_dir(d)
            .output()
            .unwrap()
    };
    let first = run();
    assert!(d.join("out/fit.json").is_file(), "{first:?}");
    let outside = d.join("precious.txt");
    std::fs::write(&outside, "keep").unwrap();
    let _ = std::fs::remove_file(d.join("out/fit.png"));
    std::os::unix::fs::symlink(&outside, d.join("out/fit.png")).unwrap();
    let second = run();
    assert!(d.join("out/fit.json").is_file(), "{second:?}");
    assert_eq!(std::fs::read_to_string(&outside).unwrap(), "keep");
    // With the repository's Python environment (`make test` makes it) the plot was made.
    if repo.join(".venv/bin/python").is_file() {
        let png = d.join("out/fit.png").symlink_metadata().unwrap();
        assert!(png.is_file(), "{second:?}");
    }
}
