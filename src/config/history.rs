//! `[[history]]`: quantities written to `history.csv` at every converged step (and the
//! unloaded state, step 0), with the keys of a `[[quantity]]` of a study — the same kinds
//! (reaction of a support, displacement of a physical point, contact pressure, stick zone,
//! relative displacement, stiffness of a pair), evaluated by the same code — but without its
//! convergence checks (`reference`, `min_order`), which mean nothing for a history.

use super::{Case, QuantitySpec};
use crate::{Error, Result};

/// Checks every `[[history]]` request of `case`: its keys as for a `[[quantity]]`, no
/// convergence-check keys, and a name used once.
pub fn check(case: &Case) -> Result<()> {
    let error = |message: String| Error::Case {
        path: case.path.clone(),
        message,
    };
    let mut names = std::collections::BTreeSet::new();
    for (i, q) in case.history.iter().enumerate() {
        q.check(case)
            .map_err(|m| error(format!("history[{i}]: {m}")))?;
        if let Some(key) = convergence_key(q) {
            return Err(error(format!(
                "history[{i}] '{}': `{key}` is a convergence check of a [[quantity]]; a \
                 [[history]] entry only records the value",
                q.name
            )));
        }
        if !names.insert(&q.name) {
            return Err(error(format!("[[history]] '{}' is defined twice", q.name)));
        }
    }
    Ok(())
}

/// A key of a study quantity that a history entry does not take.
fn convergence_key(q: &QuantitySpec) -> Option<&'static str> {
    if q.reference.is_some() {
        Some("reference")
    } else if q.min_order.is_some() {
        Some("min_order")
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    const CASE: &str = r#"
[mesh]
file = "m.msh"
[analysis]
type = "plane_strain"
[[body]]
group = "plate"
material = { E = 1000.0, nu = 0.3 }
[[support]]
group = "base"
uy = 0.0
"#;

    fn check_text(history: &str) -> Result<()> {
        let case = Case::from_toml(&format!("{CASE}{history}"), Path::new("c.toml"))?;
        check(&case)
    }

    #[test]
    fn valid_requests_pass_and_bad_ones_are_named() {
        check_text("[[history]]\nname = \"r\"\nkind = \"reaction\"\nsupport = \"base\"\ncomponent = \"y\"\n")
            .unwrap();
        let twice = "[[history]]\nname = \"r\"\nkind = \"reaction\"\nsupport = \"base\"\ncomponent = \"y\"\n";
        let e = check_text(&format!("{twice}{twice}"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("'r' is defined twice"), "{e}");
        let e = check_text(&format!("{twice}reference = 1.0\n"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("history[0]") && e.contains("`reference`"), "{e}");
    }
}
