//! The case-file parser with its validation. Half of the inputs are raw text; the other half
//! are typed case values (made by `arbitrary`, serialized to TOML) so that the fuzzer spends
//! its time in the range checks rather than in TOML syntax errors. A case that passes the
//! checks must also give a model spec without panicking, and every value it accepted must
//! be finite.

#![no_main]

use std::collections::BTreeMap;
use std::path::Path;

use arbitrary::{Arbitrary, Unstructured};
use asperity::config::Case;
use asperity::model::ModelSpec;
use libfuzzer_sys::fuzz_target;
use serde::Serialize;

/// A number that is often one a case file would hold (or a classic bad one), and otherwise
/// any f64.
#[derive(Clone, Copy, Debug, Serialize)]
#[serde(transparent)]
struct Num(f64);

impl<'a> Arbitrary<'a> for Num {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        const TYPICAL: [f64; 16] = [
            0.0,
            1.0,
            -1.0,
            0.3,
            0.5,
            0.499,
            1e-8,
            1e-3,
            2.0,
            210000.0,
            1e12,
            1e300,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            -0.0,
        ];
        Ok(Num(match u.int_in_range(0..=3u8)? {
            0 => f64::arbitrary(u)?,
            1 => f64::from(i16::arbitrary(u)?) / 64.0,
            _ => TYPICAL[usize::from(u.int_in_range(0..=15u8)?)],
        }))
    }
}

/// A group or contact name: mostly ones a mesh would hold, sometimes arbitrary text
/// (file-name checks).
#[derive(Debug, Serialize)]
#[serde(transparent)]
struct Name(String);

impl<'a> Arbitrary<'a> for Name {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        const NAMES: [&str; 8] = [
            "plate", "lower", "upper", "cut", "top", "bottom", "../x", "",
        ];
        Ok(Name(if bool::arbitrary(u)? {
            String::arbitrary(u)?
        } else {
            NAMES[usize::from(u.int_in_range(0..=7u8)?)].to_string()
        }))
    }
}

#[derive(Arbitrary, Debug, Serialize)]
struct FuzzCase {
    mesh: Mesh,
    analysis: Analysis,
    body: Vec<Body>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    support: Vec<Support>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    load: Vec<Load>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    contact: Vec<Contact>,
    #[serde(skip_serializing_if = "Option::is_none")]
    steps: Option<Steps>,
    #[serde(skip_serializing_if = "Option::is_none")]
    solver: Option<Solver>,
}

#[derive(Arbitrary, Debug, Serialize)]
struct Mesh {
    #[serde(skip_serializing_if = "Option::is_none")]
    file: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    geo: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    size: Option<Num>,
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    parameters: BTreeMap<String, Num>,
}

#[derive(Arbitrary, Debug, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
enum Analysis {
    PlaneStress {
        thickness: Num,
    },
    PlaneStrain {
        #[serde(skip_serializing_if = "Option::is_none")]
        thickness: Option<Num>,
    },
    Axisymmetric {
        #[serde(skip_serializing_if = "Option::is_none")]
        thickness: Option<Num>,
    },
}

#[derive(Arbitrary, Debug, Serialize)]
struct Body {
    group: Name,
    material: Material,
}

#[derive(Arbitrary, Debug, Serialize)]
struct Material {
    #[serde(rename = "E")]
    e: Num,
    nu: Num,
    #[serde(skip_serializing_if = "Option::is_none")]
    yield_stress: Option<Num>,
    #[serde(skip_serializing_if = "Option::is_none")]
    hardening: Option<Num>,
}

#[derive(Arbitrary, Debug, Serialize)]
struct Support {
    group: Name,
    #[serde(skip_serializing_if = "Option::is_none")]
    ux: Option<Num>,
    #[serde(skip_serializing_if = "Option::is_none")]
    uy: Option<Num>,
    #[serde(skip_serializing_if = "Option::is_none")]
    factors: Option<Vec<Num>>,
}

#[derive(Arbitrary, Debug, Serialize)]
struct Load {
    group: Name,
    #[serde(skip_serializing_if = "Option::is_none")]
    pressure: Option<Num>,
    /// Any length, so that a missing or third component is tried.
    #[serde(skip_serializing_if = "Option::is_none")]
    traction: Option<Vec<Num>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    force: Option<Vec<Num>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    factors: Option<Vec<Num>>,
}

#[derive(Arbitrary, Debug, Serialize)]
struct Contact {
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<Name>,
    #[serde(skip_serializing_if = "Option::is_none")]
    side_a: Option<Name>,
    #[serde(skip_serializing_if = "Option::is_none")]
    side_b: Option<Name>,
    #[serde(skip_serializing_if = "Option::is_none")]
    curve: Option<Name>,
    #[serde(skip_serializing_if = "Option::is_none")]
    body_a: Option<Name>,
    #[serde(skip_serializing_if = "Option::is_none")]
    body_b: Option<Name>,
    #[serde(skip_serializing_if = "Option::is_none")]
    interference: Option<Num>,
    law: Law,
}

#[derive(Arbitrary, Debug, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
enum Law {
    LinearCoulomb {
        normal_stiffness: Num,
        tangential_stiffness: Num,
        #[serde(skip_serializing_if = "Option::is_none")]
        friction: Option<Num>,
    },
    RoughJoint {
        c_n: Num,
        m: Num,
        #[serde(rename = "R", skip_serializing_if = "Option::is_none")]
        r: Option<Num>,
        #[serde(rename = "S", skip_serializing_if = "Option::is_none")]
        s: Option<Num>,
        mu_m: Num,
        #[serde(skip_serializing_if = "Option::is_none")]
        beta: Option<Num>,
        #[serde(skip_serializing_if = "Option::is_none")]
        n: Option<Num>,
        #[serde(skip_serializing_if = "Option::is_none")]
        starting_pressure: Option<Num>,
    },
}

#[derive(Arbitrary, Debug, Serialize)]
struct Steps {
    #[serde(skip_serializing_if = "Option::is_none")]
    count: Option<i64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    factors: Option<Vec<Num>>,
}

#[derive(Arbitrary, Debug, Serialize)]
struct Solver {
    #[serde(skip_serializing_if = "Option::is_none")]
    max_iterations: Option<i64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    force_tolerance: Option<Num>,
    #[serde(skip_serializing_if = "Option::is_none")]
    displacement_tolerance: Option<Num>,
    #[serde(skip_serializing_if = "Option::is_none")]
    max_cutbacks: Option<i64>,
}

fn check(text: &str) {
    let Ok(case) = Case::from_toml(text, Path::new("fuzz/case.toml")) else {
        return;
    };
    // What validation accepted must be usable: a spec or a clean error, never a panic.
    let _ = ModelSpec::new(&case);
}

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    if mode % 4 == 0 {
        check(&String::from_utf8_lossy(rest));
        return;
    }
    let mut u = Unstructured::new(rest);
    let Ok(case) = FuzzCase::arbitrary(&mut u) else {
        return;
    };
    // NaN, inf and other numbers TOML can write; a serialization error means nothing to test.
    if let Ok(text) = toml::to_string(&case) {
        check(&text);
    }
});
