//! The quick form of `make cyclic_press_fit` (issue 27): the two shipped cases without their
//! VTU output (a few seconds). Kinematic hardening keeps reverse-yielding the hub's bore in every cycle
//! (plastic shakedown; its net change per cycle decays through the tenth of the flow the
//! verdict allows for it by the last cycle, so fewer cycles would read "ratcheting"), isotropic hardening shakes down elastically,
//! the elastic shaft in both; every body has a verdict.

use std::path::Path;
use std::process::Command;

fn verdicts(case: &str) -> (Vec<(String, String)>, String) {
    let dir = tempfile::tempdir().unwrap();
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("pipelines/cyclic_press_fit");
    let text = std::fs::read_to_string(source.join(format!("{case}.toml")))
        .unwrap()
        .replace("vtu = true", "vtu = false")
        .replace(
            "../../geo/",
            &format!("{}/geo/", env!("CARGO_MANIFEST_DIR")),
        );
    let path = dir.path().join("case.toml");
    std::fs::write(&path, text).unwrap();
    let out = dir.path().join("out");
    let run = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args([
            "run".as_ref(),
            path.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ])
        .output()
        .unwrap();
    assert!(run.status.success(), "{run:?}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let list = summary["shakedown"].as_array().unwrap();
    let verdicts = list
        .iter()
        .map(|v| {
            assert_eq!(v["step"], "cycling");
            (
                v["body"].as_str().unwrap().to_string(),
                v["shakedown"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    (
        verdicts,
        std::fs::read_to_string(out.join("cycles.csv")).unwrap(),
    )
}

#[test]
fn kinematic_hub_alternates_isotropic_hub_shakes_down() {
    let pair = |hub: &str| {
        vec![
            ("shaft".to_string(), "elastic shakedown".to_string()),
            ("hub".to_string(), hub.to_string()),
        ]
    };
    let (kinematic, cycles) = verdicts("kinematic");
    assert_eq!(kinematic, pair("plastic shakedown"));
    assert!(
        cycles
            .lines()
            .next()
            .unwrap()
            .contains("hub_ratchet_strain")
    );
    let (isotropic, _) = verdicts("isotropic");
    assert_eq!(isotropic, pair("elastic shakedown"));
}
