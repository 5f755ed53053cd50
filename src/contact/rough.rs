//! The interface law of the paper (§2): a rough joint with power-law normal compliance,
//! pressure-dependent tangential stiffness and slip-hardening Coulomb friction, integrated by
//! an implicit return map with the consistent (unsymmetric) tangent.
//!
//! Notation: closure c = −u_N (positive when the faces overlap), contact pressure
//! p = |p_N| = −p_N ≥ 0, accumulated slip ū = Σ|Δu_T^p|.
//!
//! - **Normal** (Eqs. 1–2): c = c_N p^m, so p = (c/c_N)^(1/m) from the *total* law (an
//!   accumulated Δp = k_N Δc would drift), with tangent k_N = dp/dc = p^(1−m)/(c_N m).
//!   After a maximum closure c_max an optional unloading curve c − c_perm = c_Nu p^(m_u) is
//!   followed back down (and up again until c_max), with c_perm chosen so that it passes
//!   through (c_max, p_max): a permanent set of the asperities. By default unloading uses the
//!   loading coefficients (c_perm = 0), the paper gives no values (docs/theory.md).
//!   No stress in opening (c ≤ 0).
//! - **Tangential elasticity** (Eq. 3): k_T = p^S / R, incremental as in Box 1 (corrected):
//!   p_T^tr = p_T,n + k_T(p_{n+1}) (u_T − u_T,n), from the converged p_T,n.
//! - **Friction** (Eqs. 4–5): μ_F(ū) = μ_m [1 − (1 − β) exp(−n ū)],
//!   F = |p_T| + μ_F p_N ≤ 0; non-associated slip with Δu_N^p = 0 (Eqs. 8–10).
//! - **Return map** (Box 1 corrected, Eq. 16): if F^tr > 0, find Δλ > 0 with
//!   g(Δλ) = |p_T^tr| − k_T Δλ − μ_F(ū_n + Δλ) p = 0 (g is decreasing, g(0) = F^tr > 0 and
//!   g(F^tr/k_T) ≤ 0, so the root is bracketed); solved by Newton safeguarded by bisection to
//!   1e-14 relative; then p_T = sign(p_T^tr) μ_F(ū_n+Δλ) p and u_T^p += sign·Δλ.
//! - **Consistent tangent** (Eq. 21): with H = μ_F'(ū) p,
//!   ∂p_T/∂u_T = k_T H/(k_T + H) and ∂p_T/∂u_N from differentiating g (the (1,2) coupling of
//!   shear to normal approach, through μ_F p and through k_T(p)); ∂p_N/∂u_N = k_N.
//!
//! **Small pressures (gaps of the paper; docs/theory.md).** For m < 1, k_N = p^(1−m)/(c_N m) and
//! for S > 0, k_T = p^S/R vanish at p = 0: a body held only by contact would have no
//! stiffness in the first iteration. Hence
//! - a point *exactly touching* (closure 0, e.g. coincident faces at the start) gets the
//!   normal stiffness at `starting_pressure` p_start, so the first iteration has a regular
//!   matrix; every point with positive pressure uses the consistent tangent dp/dc, so Newton
//!   keeps its quadratic convergence (a floored tangent at low pressures stalled it);
//! - the tangential stiffness is k_T = (p² + p_start²)^(S/2) / R: a smooth floor of the
//!   shear stiffness (equal to p^S/R within 0.5 % for p > 10 p_start when S = 0.5), part of
//!   the law itself, so stress update and tangent agree.
//!
//! Stresses of the normal law always come from the exact total law.
//!
//! **With twist** (two tangential directions, see [`super`]): k_T(p) acts in both, the trial
//! shear is the vector p_τ^tr = p_τ,n + k_T(p) (u_τ − u_τ,n), F = |p_τ^tr| − μ_F(ū) p, and the
//! return is radial: g(Δλ) above with |p_τ^tr|, p_τ = μ_F(ū_n + Δλ) p n, n = p_τ^tr/|p_τ^tr|,
//! u_τ^p += Δλ n, ū += Δλ: the slip hardening is driven by the length of the slip path,
//! whatever its direction. The consistent tangent: ∂p_τ/∂u_τ = k_T H/(k_T + H) n nᵀ +
//! μ_F p k_T/|p_τ^tr| (I − n nᵀ) (the direction turns with the trial shear), and
//! ∂p_τ/∂u_N = (H ∂Δλ/∂u_N − μ_F k_N) n − μ_F p k_T' k_N/|p_τ^tr| (I − n nᵀ)(u_τ − u_τ,n),
//! the second term because k_T(p) scales the trial increment too. Without twist n = sign(p_T^tr)
//! and the (I − n nᵀ) terms vanish: the scalar law above, number for number.

use super::laws::{Bound, Built, LawDescriptor, ParameterDefault, ParameterDescriptor, check};
use super::{
    CIRCUMFERENTIAL, ContactStatus, InterfaceLaw, InterfaceState, InterfaceTangent, MERIDIONAL,
    NORMAL, OPEN_TANGENT_FRACTION, diagonal_tangent, direction, length, slip_tangent, sticks,
    tangential,
};
use crate::error::ParameterError;

/// The paper's rough-joint law (units mm, MPa: c_N in mm/MPa^m, R in mm·MPa^(S−1)... such
/// that p^S / R is in MPa/mm, n in 1/mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughJoint {
    /// Normal compliance coefficient c_N and exponent m (Eq. 1).
    pub c_n: f64,
    pub m: f64,
    /// Unloading coefficients (c_N, m); `None`: the loading curve.
    pub unloading: Option<(f64, f64)>,
    /// Tangential stiffness parameters R, S (Eq. 3).
    pub r: f64,
    pub s: f64,
    /// Friction: μ_m, β, n (Eq. 4).
    pub mu_m: f64,
    pub beta: f64,
    pub n: f64,
    /// Pressure below which stiffnesses are evaluated at this value (MPa).
    pub starting_pressure: f64,
}

/// The law in the table of interface laws: `law = { type = "rough_joint", ... }`.
pub const LAW: LawDescriptor = LawDescriptor {
    name: "rough_joint",
    doc: "The rough-joint law of Buczkowski & Kleiber (1994), Eqs. 1–5: power-law normal\n\
          compliance u_N = c_N p^m, tangential stiffness k_T = p^S / R, slip-hardening friction\n\
          μ_F = μ_m [1 − (1 − β) exp(−n ū)].",
    parameters: &[
        ParameterDescriptor {
            key: "c_n",
            unit: "mm/MPa^m",
            default: ParameterDefault::Required,
            bound: Bound::Positive,
            doc: "c_N in mm/MPa^m (values given in µm/MPa^m: multiply them by 1e-3).",
        },
        ParameterDescriptor {
            key: "m",
            unit: "",
            default: ParameterDefault::Required,
            bound: Bound::Positive,
            doc: "Exponent m of the normal compliance u_N = c_N p^m.",
        },
        ParameterDescriptor {
            key: "unloading_c_n",
            unit: "mm/MPa^m",
            default: ParameterDefault::Optional,
            bound: Bound::Positive,
            doc: "Optional unloading curve (c_N, m); default: the loading curve.",
        },
        ParameterDescriptor {
            key: "unloading_m",
            unit: "",
            default: ParameterDefault::Optional,
            bound: Bound::Positive,
            doc: "Exponent m of the optional unloading curve (given with `unloading_c_n`).",
        },
        ParameterDescriptor {
            key: "R",
            unit: "",
            default: ParameterDefault::Optional,
            bound: Bound::Positive,
            doc: "R such that p^S / R is in MPa/mm (values given per µm: × 1e-3), and S. Required\n\
                  when `mu_m > 0`; unused (and optional) without friction.",
        },
        ParameterDescriptor {
            key: "S",
            unit: "",
            default: ParameterDefault::Optional,
            bound: Bound::NonNegative,
            doc: "Exponent S of the tangential stiffness k_T = p^S / R. Required when `mu_m > 0`;\n\
                  unused (and optional) without friction.",
        },
        ParameterDescriptor {
            key: "mu_m",
            unit: "",
            default: ParameterDefault::Required,
            bound: Bound::NonNegative,
            doc: "Macroscopic friction coefficient μ_m.",
        },
        ParameterDescriptor {
            key: "beta",
            unit: "",
            default: ParameterDefault::Value(1.0),
            bound: Bound::Fraction,
            doc: "Initial friction as a fraction of μ_m (default 1: no hardening).",
        },
        ParameterDescriptor {
            key: "n",
            unit: "1/mm",
            default: ParameterDefault::Value(0.0),
            bound: Bound::NonNegative,
            doc: "Slip-hardening rate n in 1/mm (default 0).",
        },
        ParameterDescriptor {
            key: "starting_pressure",
            unit: "MPa",
            default: ParameterDefault::Value(0.1),
            bound: Bound::Positive,
            doc: "Pressure (MPa) below which stiffnesses are evaluated at this value (default 0.1).",
        },
    ],
    build,
    unused: |x| {
        let tangential_given = !(x[4].is_nan() && x[5].is_nan());
        (x[6] == 0.0 && tangential_given)
            .then_some("R and S are not used when mu_m = 0 (no friction)")
    },
};

/// The law at the values of [`LAW`]'s parameters: the unloading curve is given whole or not
/// at all, and k_T = p^S / R (Eq. 3) only matters with friction, so R and S are required when
/// mu_m > 0.
fn build(x: &[f64]) -> Built {
    let given = |v: f64| (!v.is_nan()).then_some(v);
    let (unloading_c_n, unloading_m, r, s, mu_m) =
        (given(x[2]), given(x[3]), given(x[4]), given(x[5]), x[6]);
    let half = match (unloading_c_n, unloading_m) {
        (Some(v), None) => Some(("unloading_c_n", v)),
        (None, Some(v)) => Some(("unloading_m", v)),
        _ => None,
    };
    if let Some((key, v)) = half {
        let reason = "give both unloading_c_n and unloading_m, or neither";
        return Err(ParameterError::new(key, v, reason));
    }
    if mu_m != 0.0 {
        for (key, value) in [("R", r), ("S", s)] {
            if value.is_none() {
                let reason =
                    format!("the rough-joint law needs R and S (k_T = p^S / R) when mu_m = {mu_m}");
                return Err(ParameterError::new(key, f64::NAN, reason));
            }
        }
    }
    Ok(Box::new(RoughJoint::new(RoughJoint {
        c_n: x[0],
        m: x[1],
        unloading: unloading_c_n.zip(unloading_m),
        // Only absent when mu_m = 0, where the tangential traction is bounded by μ_F |p| = 0
        // and k_T never shows in a result; R = 1, S = 0 is a valid placeholder (k_T = 1 MPa/mm).
        r: r.unwrap_or(1.0),
        s: s.unwrap_or(0.0),
        mu_m,
        beta: x[7],
        n: x[8],
        starting_pressure: x[9],
    })?))
}

impl RoughJoint {
    /// Checks the parameters against the bounds of [`LAW`] and names the first wrong one.
    pub fn new(law: RoughJoint) -> Result<Self, ParameterError> {
        let (unloading_c_n, unloading_m) = law.unloading.unwrap_or((f64::NAN, f64::NAN));
        let values = [
            law.c_n,
            law.m,
            unloading_c_n,
            unloading_m,
            law.r,
            law.s,
            law.mu_m,
            law.beta,
            law.n,
            law.starting_pressure,
        ];
        check(LAW.parameters, &values)?;
        Ok(law)
    }

    /// Friction coefficient μ_F(ū) and its slope (Eq. 4, Eq. 14).
    pub fn friction(&self, slip: f64) -> (f64, f64) {
        let e = (-self.n * slip).exp();
        (
            self.mu_m * (1.0 - (1.0 - self.beta) * e),
            self.mu_m * (1.0 - self.beta) * self.n * e,
        )
    }

    /// Tangential stiffness k_T = (p² + p_start²)^(S/2) / R and its derivative in p: Eq. (3),
    /// k_T = p^S / R, with a smooth floor at small pressures (a kinked floor max(p, p_start)
    /// made Newton cycle when many points sat at the kink).
    pub fn tangential_stiffness(&self, p: f64) -> (f64, f64) {
        let q = p * p + self.starting_pressure * self.starting_pressure;
        let k = q.powf(0.5 * self.s) / self.r;
        (k, self.s * p * k / q)
    }

    /// Pressure and tangent k_N = dp/dc for closure `c`, with the largest closure so far
    /// `c_max` (Eqs. 1–2; unloading curve below c_max).
    pub fn normal(&self, c: f64, c_max: f64) -> (f64, f64) {
        if c < 0.0 {
            return (0.0, 0.0);
        }
        if c == 0.0 {
            // Exactly touching: no stress, the starting stiffness.
            return (0.0, self.starting_stiffness());
        }
        let (coefficient, exponent, offset) = match self.unloading {
            Some((cu, mu)) if c < c_max => {
                let p_max = (c_max / self.c_n).powf(1.0 / self.m);
                (cu, mu, c_max - cu * p_max.powf(mu))
            }
            _ => (self.c_n, self.m, 0.0),
        };
        let x = c - offset;
        if x <= 0.0 {
            return (0.0, 0.0);
        }
        let p = (x / coefficient).powf(1.0 / exponent);
        // The consistent tangent dp/dc = p^(1−m)/(c_N m) (Eq. 2) for every loaded point;
        // the starting stiffness is only for points exactly touching (see `normal` above).
        (p, p.powf(1.0 - exponent) / (coefficient * exponent))
    }

    /// Normal tangent at the starting pressure: what a point just touching gets.
    pub fn starting_stiffness(&self) -> f64 {
        self.starting_pressure.powf(1.0 - self.m) / (self.c_n * self.m)
    }

    /// The local return: Δλ > 0 solving g(Δλ) = |p^tr| − k_T Δλ − μ_F(ū_n + Δλ) p = 0.
    fn slip_increment(&self, trial: f64, kt: f64, p: f64, slip_n: f64) -> f64 {
        let g = |dl: f64| {
            let (mu, dmu) = self.friction(slip_n + dl);
            (trial - kt * dl - mu * p, -kt - dmu * p)
        };
        let (mut lo, mut hi) = (0.0, trial / kt);
        let mut dl = hi;
        for _ in 0..100 {
            let (value, slope) = g(dl);
            if value.abs() <= 1e-14 * trial {
                break;
            }
            if value > 0.0 {
                lo = dl
            } else {
                hi = dl
            }
            let newton = dl - value / slope;
            dl = if newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            if hi - lo <= 1e-16 * hi.max(f64::MIN_POSITIVE) {
                break;
            }
        }
        dl
    }
}

impl InterfaceLaw for RoughJoint {
    fn update(
        &self,
        relative: [f64; 3],
        committed: &InterfaceState,
    ) -> (InterfaceState, InterfaceTangent) {
        let closure = -relative[NORMAL];
        let loading_max = committed.max_closure.max(closure);
        let (p, kn) = self.normal(closure, committed.max_closure);
        let mut s = InterfaceState {
            relative,
            plastic_slip: committed.plastic_slip,
            accumulated_slip: committed.accumulated_slip,
            max_closure: loading_max,
            ..InterfaceState::default()
        };
        let (kt, dkt) = self.tangential_stiffness(p);
        let (mu_n, _) = self.friction(committed.accumulated_slip);
        s.friction = mu_n;
        s.stiffness = [kt, kn];
        if closure < 0.0 || (closure > 0.0 && p == 0.0) {
            // Open (or unloaded below the permanent set): no stress.
            s.status = ContactStatus::Open;
            let k0 = self.starting_stiffness();
            return (s, diagonal_tangent([kt, k0]) * OPEN_TANGENT_FRACTION);
        }
        let (u, u_n) = (tangential(relative), tangential(committed.relative));
        let du = [u[0] - u_n[0], u[1] - u_n[1]];
        let shear_n = tangential(committed.stress);
        let trial = [shear_n[0] + kt * du[0], shear_n[1] + kt * du[1]];
        let norm = length(trial);
        let f = norm - mu_n * p;
        if sticks(f, mu_n * p, committed) {
            s.stress = [trial[0], -p, trial[1]];
            s.status = ContactStatus::Stick;
            // ∂p_τ/∂u_N through k_T(p): dk_T/du_N = k_T'(p) · dp/du_N = −k_T' k_N.
            let mut k = diagonal_tangent([kt, kn]);
            k[(MERIDIONAL, NORMAL)] = -dkt * kn * du[0];
            k[(CIRCUMFERENTIAL, NORMAL)] = -dkt * kn * du[1];
            return (s, k);
        }
        let n = direction(trial, norm);
        // On the cone (see `sticks`) the slip increment is zero.
        let dl = if f > 0.0 {
            self.slip_increment(norm, kt, p, committed.accumulated_slip)
        } else {
            0.0
        };
        let (mu, dmu) = self.friction(committed.accumulated_slip + dl);
        s.stress = [n[0] * mu * p, -p, n[1] * mu * p];
        let up = committed.plastic_slip;
        s.plastic_slip = [up[0] + n[0] * dl, up[1] + n[1] * dl];
        s.accumulated_slip = committed.accumulated_slip + dl;
        s.friction = mu;
        s.status = ContactStatus::Slip;
        let h = dmu * p;
        // Consistent tangent from g(Δλ; u_τ, u_N) = 0 (Eq. 21 completed; docs/theory.md, "The
        // consistent tangent"), along n; across n the direction of the trial shear turns.
        let along_du = n[0] * du[0] + n[1] * du[1];
        let dg_dun = -kn * dkt * (along_du - dl) + mu * kn;
        let along = kt * h / (kt + h);
        let turn = if norm > 0.0 { mu * p / norm } else { 0.0 };
        let radial = h * dg_dun / (kt + h) - mu * kn;
        // (I − n nᵀ) du: the part of the increment across the slip direction.
        let across_du = [
            (1.0 - n[0] * n[0]) * du[0] - n[0] * n[1] * du[1],
            (1.0 - n[1] * n[1]) * du[1] - n[0] * n[1] * du[0],
        ];
        let coupling = [
            radial * n[0] - turn * dkt * kn * across_du[0],
            radial * n[1] - turn * dkt * kn * across_du[1],
        ];
        (s, slip_tangent(n, along, turn * kt, coupling, kn))
    }

    fn carries_shear(&self) -> bool {
        self.mu_m > 0.0
    }

    fn describe(&self) -> String {
        format!(
            "rough joint (paper §2): c_N = {} mm/MPa^m, m = {}, R = {}, S = {}, mu_m = {}, beta = {}, n = {} 1/mm",
            self.c_n, self.m, self.r, self.s, self.mu_m, self.beta, self.n
        )
    }
}
