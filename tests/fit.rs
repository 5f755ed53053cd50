//! `asperity fit`: synthetic curves from known parameters are fitted back.
//!
//! - exact data: the parameters are recovered to 1e-6 relative;
//! - 1 % Gaussian noise, 100 seeds: each true value lies in the reported 95 % interval in at
//!   least 90 fits (binomial(100, 0.95) falls below 90 with probability 2.8 %; the seeds are
//!   fixed, so the test is deterministic);
//! - a fit through a full specimen model recovers the parameters that generated its data;
//! - a set-up that cannot separate two parameters is reported as not identifiable;
//! - bad input names the file and the key.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use asperity::Error;
use asperity::contact::rough;
use asperity::fit::experiment::{normal, tangential};
use asperity::fit::{Fit, FitResult};
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
    let mut inside = [0usize; 7];
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
        let r = fit(dir.path(), &format!("{FREE}\n{tests}")).unwrap();
        assert!(r.identifiable && r.errors_stated, "seed {seed}: {r}");
        for (k, name) in names.iter().enumerate() {
            let e = r.get(name).unwrap();
            let truth = TRUE.iter().find(|(n, _)| n == name).unwrap().1;
            if e.lower_95.unwrap() <= truth && truth <= e.upper_95.unwrap() {
                inside[k] += 1;
            }
        }
    }
    eprintln!(
        "coverage of the 95 % intervals in 100 fits: {:?}",
        names.iter().zip(inside).collect::<Vec<_>>()
    );
    for (name, n) in names.iter().zip(inside) {
        assert!(
            n >= 90,
            "{name}: the true value is inside the 95 % interval in {n} of 100 fits"
        );
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
    // The others are still determined, and well.
    for name in ["c_n", "m", "mu_m"] {
        assert!(r.get(name).unwrap().standard_error.is_some(), "{name}\n{r}");
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
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("pipelines/fit/joint.toml");
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
        let (lo, hi) = (e.lower_95.unwrap(), e.upper_95.unwrap());
        assert!(lo <= t && t <= hi, "{name}: {t} outside [{lo}, {hi}]\n{r}");
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
    let case = root.join("pipelines/fit/specimen/specimen.toml");
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

    // A friction coefficient without bounds that the data drive negative (a shear offset of
    // −0.05 MPa in full slip): the error names the parameter and says to bound it.
    let u: Vec<f64> = (1..=10).map(|i| 0.1 * i as f64).collect();
    write_csv(
        &d.join("slip.csv"),
        "displacement = mm, shear = MPa",
        ["displacement", "shear"],
        &u,
        &[-0.05; 10],
    );
    let text = "law = \"linear_coulomb\"\n[parameters]\nnormal_stiffness = { value = 1e4 }\ntangential_stiffness = { value = 1e4 }\n\
                friction = { initial = 0.3 }\n[[test]]\nkind = \"tangential\"\ndata = \"slip.csv\"\npressure = 10.0\n";
    let e = fit(d, text).unwrap_err();
    let message = e.to_string();
    let (path, key) = key_of(e);
    assert_eq!(
        (path, key.as_str()),
        (d.join("fit.toml"), "parameters.friction")
    );
    assert!(message.contains("give it bounds"), "{message}");

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
}
