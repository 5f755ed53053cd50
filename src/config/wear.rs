//! `wear` of a `[[contact]]`: the wear law of the pair's surfaces, its coefficients and the
//! limits of the run (wear-through depth, stability of cycle jumping), and their checks.

use schemars::JsonSchema;
use serde::Deserialize;

use super::Case;
use crate::Result;

/// What `jump_limit` is, for `asperity schema` and the error of a value out of range (the
/// closure is the one `crate::solver::cycles` bounds a jump with).
pub const JUMP_LIMIT_DOC: &str = "Stability limit of cycle jumping: the depth a jump adds at a \
    place of the surface may be at most this multiple of its elastic closure \
    |p_N| (1/k_N + l/(pi E*)), the interface (normal stiffness k_N) and the bodies' surfaces \
    under the shortest pressure wave the mesh resolves (wavelength l, the interface element's \
    length; 1/E* = (1 - nu_A^2)/E_A + (1 - nu_B^2)/E_B) in series; 0 < jump_limit <= 1 \
    (default 0.5: accurate and monotone; 1 wears the whole closure away in one jump). See \
    docs/guide/fretting-and-wear.md, \"Cycle jumping and its stability limit\".";

/// Largest `jump_limit`: a jump adding more than a point's elastic closure overshoots the
/// unloaded state of the shortest pressure wave (the pressure then alternates from node to
/// node, and beyond 2 the alternation grows from jump to jump).
pub const MAX_JUMP_LIMIT: f64 = 1.0;

/// How the surfaces of a contact pair wear (`wear = { model = "archard", coefficient = 1e-8 }`).
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WearSpec {
    /// `"archard"`: dh = k |p_N| |du_slip|; `"energy"`: dh = alpha |p_T du_slip|.
    pub model: WearLawKind,
    /// Coefficient (1/MPa = mm²/N) of each worn surface.
    pub coefficient: Option<f64>,
    /// Coefficient of the surface of body A (instead of `coefficient`, with
    /// `coefficient_b`).
    pub coefficient_a: Option<f64>,
    /// Coefficient of the surface of body B (with `coefficient_a`; a missing one: that
    /// surface does not wear).
    pub coefficient_b: Option<f64>,
    /// Which surfaces wear with `coefficient`: `"a"`, `"b"` or `"both"` (default).
    pub surface: Option<WearSurface>,
    /// Total depth h_A + h_B (mm) at which the interface counts as worn through: the run
    /// stops there, keeping the converged results.
    pub max_depth: Option<f64>,
    /// [`JUMP_LIMIT_DOC`].
    #[schemars(description = JUMP_LIMIT_DOC, range(max = MAX_JUMP_LIMIT))]
    pub jump_limit: Option<f64>,
}

/// The local wear law of [`WearSpec`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum WearLawKind {
    Archard,
    Energy,
}

/// The worn surfaces of [`WearSpec`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum WearSurface {
    A,
    B,
    Both,
}

impl WearSpec {
    /// Coefficients of the surfaces of body A and of body B (0: the surface does not wear).
    pub fn coefficients(&self) -> [f64; 2] {
        match self.coefficient {
            Some(k) => match self.surface.unwrap_or(WearSurface::Both) {
                WearSurface::A => [k, 0.0],
                WearSurface::B => [0.0, k],
                WearSurface::Both => [k, k],
            },
            None => [
                self.coefficient_a.unwrap_or(0.0),
                self.coefficient_b.unwrap_or(0.0),
            ],
        }
    }

    /// The first problem of this spec as (key, value, reason), the key relative to `wear`.
    fn problem(&self) -> Option<(&'static str, String, String)> {
        let given = |x: Option<f64>| x.map_or_else(|| "(missing)".to_string(), |v| v.to_string());
        let per_surface = self.coefficient_a.is_some() || self.coefficient_b.is_some();
        if self.coefficient.is_some() && per_surface {
            return Some((
                "coefficient",
                given(self.coefficient),
                "give either `coefficient` (with `surface`) or `coefficient_a`/`coefficient_b`, \
                 not both"
                    .into(),
            ));
        }
        if self.coefficient.is_none() && !per_surface {
            return Some((
                "coefficient",
                given(None),
                "a wear model needs `coefficient` (or `coefficient_a`/`coefficient_b`), in 1/MPa"
                    .into(),
            ));
        }
        if per_surface && let Some(surface) = self.surface {
            return Some((
                "surface",
                format!("{surface:?}").to_lowercase(),
                "with `coefficient_a`/`coefficient_b` the worn surfaces are those given a \
                 coefficient; `surface` goes with `coefficient`"
                    .into(),
            ));
        }
        let coefficients = [
            ("coefficient", self.coefficient),
            ("coefficient_a", self.coefficient_a),
            ("coefficient_b", self.coefficient_b),
        ];
        for (key, value) in coefficients {
            if let Some(k) = value.filter(|k| !(k.is_finite() && *k >= 0.0)) {
                return Some((
                    key,
                    k.to_string(),
                    "a wear coefficient must be zero or positive and finite (1/MPa)".into(),
                ));
            }
        }
        if self.coefficients() == [0.0, 0.0] {
            let (key, value) = coefficients
                .into_iter()
                .find(|(_, v)| v.is_some())
                .unwrap_or(("coefficient", Some(0.0)));
            return Some((
                key,
                given(value),
                "no surface wears with zero coefficients; remove `wear` from a pair that does \
                 not wear"
                    .into(),
            ));
        }
        if let Some(d) = self.max_depth.filter(|d| !(d.is_finite() && *d > 0.0)) {
            return Some((
                "max_depth",
                d.to_string(),
                "the wear-through depth must be positive and finite (mm)".into(),
            ));
        }
        if let Some(l) = self
            .jump_limit
            .filter(|l| !(*l > 0.0 && *l <= MAX_JUMP_LIMIT))
        {
            return Some((
                "jump_limit",
                l.to_string(),
                format!("must be in (0, {MAX_JUMP_LIMIT}]. {JUMP_LIMIT_DOC}"),
            ));
        }
        None
    }
}

impl Case {
    /// Every `[[contact]] wear`: coefficients given once, non-negative and not all zero,
    /// positive limits.
    pub(super) fn check_wear(&self) -> Result<()> {
        for (i, c) in self.contacts.iter().enumerate() {
            if let Some((key, value, reason)) = c.wear.as_ref().and_then(WearSpec::problem) {
                return Err(self.invalid(
                    format!("contact[{i}].wear.{key}"),
                    value,
                    format!("{reason} (contact '{}')", c.name()),
                ));
            }
        }
        Ok(())
    }
}
