//! The arithmetic of a convergence study: successive differences, observed order,
//! Richardson extrapolation and the pass criteria (see the module docs of [`crate::study`]).

use super::ROUND_OFF;
use crate::config::QuantitySpec;

/// The pass criteria of a quantity.
#[derive(Clone, Copy, Debug)]
pub struct Criteria {
    pub reference: Option<f64>,
    pub tolerance: f64,
    pub min_order: Option<f64>,
    /// Relative size of differences that cannot be told from solver error: the larger of
    /// round-off ([`ROUND_OFF`]) and the Newton force tolerance the levels were solved to.
    pub noise: f64,
}

impl Criteria {
    /// The criteria of quantity `q` of levels solved to the relative force tolerance
    /// `force_tolerance`.
    pub fn new(q: &QuantitySpec, force_tolerance: f64) -> Self {
        Self {
            reference: q.reference,
            tolerance: q.tolerance,
            min_order: q.min_order,
            noise: ROUND_OFF.max(force_tolerance),
        }
    }
}

/// Convergence analysis of one quantity over the levels (coarse to fine).
#[derive(Clone, Debug)]
pub struct Convergence {
    pub values: Vec<f64>,
    /// Relative mesh sizes h_k.
    pub h: Vec<f64>,
    /// d_k = q_{k+1} − q_k.
    pub differences: Vec<f64>,
    /// Observed order from the three finest levels (None: round-off or not converged).
    pub order: Option<f64>,
    /// Order fitted to the error against the reference over all levels.
    pub reference_order: Option<f64>,
    /// Richardson-extrapolated value (None when not converged).
    pub extrapolated: Option<f64>,
    /// |q∞ − q_f|.
    pub error_estimate: Option<f64>,
    /// |d_f| / |q_f|.
    pub relative_change: f64,
    /// |q_f − ref| / |ref| (absolute error if ref = 0).
    pub reference_error: Option<f64>,
    /// False when the differences do not decrease.
    pub converged: bool,
    /// One reason per failed check (empty: the quantity passes).
    pub failures: Vec<String>,
    /// Remarks that do not fail the quantity.
    pub notes: Vec<String>,
}

impl Convergence {
    /// Whether the quantity passes its checks.
    pub fn passed(&self) -> bool {
        self.failures.is_empty()
    }
}

/// Analyses the values `q` at relative sizes `h` (coarse to fine, refined by `ratio` each
/// time; at least three levels) against `criteria`.
pub fn analyse(q: &[f64], h: &[f64], ratio: f64, criteria: &Criteria) -> Convergence {
    assert!(q.len() >= 3 && q.len() == h.len(), "three or more levels");
    let n = q.len();
    let d: Vec<f64> = q.windows(2).map(|w| w[1] - w[0]).collect();
    let scale = q.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let floor = criteria.noise * scale;
    let (qf, dc, df) = (q[n - 1], d[n - 3], d[n - 2]);
    let mut c = Convergence {
        values: q.to_vec(),
        h: h.to_vec(),
        differences: d.clone(),
        order: None,
        reference_order: None,
        extrapolated: None,
        error_estimate: None,
        relative_change: if qf != 0.0 { (df / qf).abs() } else { df.abs() },
        reference_error: None,
        converged: true,
        failures: Vec::new(),
        notes: Vec::new(),
    };
    if df.abs() <= floor {
        // Exact to round-off on the finest levels: nothing to extrapolate.
        c.extrapolated = Some(qf);
        c.error_estimate = Some(df.abs());
        c.notes.push(if dc.abs() <= floor {
            "no change beyond round-off: exact on these meshes".into()
        } else {
            "the finest difference is round-off: converged faster than measurable".into()
        });
    } else {
        let p = (dc.abs() / df.abs()).ln() / ratio.ln();
        c.order = p.is_finite().then_some(p);
        // Growing differences anywhere (above round-off) mean the sequence does not settle.
        let growth = d
            .windows(2)
            .position(|w| w[0].abs() > floor && w[1].abs() > w[0].abs());
        if !p.is_finite() || p <= 0.0 {
            c.converged = false;
            c.failures.push(format!(
                "not converged: the differences do not decrease (|d| = {:.3e} then {:.3e}, observed order {p:.2})",
                dc.abs(),
                df.abs()
            ));
        } else if let Some(k) = growth {
            c.converged = false;
            c.failures.push(format!(
                "not converged: the differences grow from levels {}-{} to {}-{} (|d| = {:.3e} then {:.3e})",
                k,
                k + 1,
                k + 1,
                k + 2,
                d[k].abs(),
                d[k + 1].abs()
            ));
        } else {
            let extrapolated = qf + df / (ratio.powf(p) - 1.0);
            c.extrapolated = Some(extrapolated);
            c.error_estimate = Some((extrapolated - qf).abs());
            if dc * df < 0.0 {
                c.notes.push(
                    "the differences alternate in sign: order and extrapolation are unreliable"
                        .into(),
                );
            }
        }
    }
    if c.relative_change > criteria.tolerance {
        c.failures.push(format!(
            "relative change between the two finest levels {:.2e} > tolerance {:.1e}",
            c.relative_change, criteria.tolerance
        ));
    }
    if let Some(reference) = criteria.reference {
        let error = |v: f64| {
            if reference != 0.0 {
                ((v - reference) / reference).abs()
            } else {
                (v - reference).abs()
            }
        };
        let e = error(qf);
        c.reference_error = Some(e);
        // Fit over the levels whose error is above round-off.
        let points: Vec<(f64, f64)> = q
            .iter()
            .zip(h)
            .filter(|(v, _)| (*v - reference).abs() > floor)
            .map(|(v, h)| (h.ln(), error(*v).ln()))
            .collect();
        let signed: Vec<f64> = q
            .iter()
            .map(|v| v - reference)
            .filter(|e| e.abs() > floor)
            .collect();
        if signed.windows(2).any(|w| w[0] * w[1] < 0.0) {
            c.notes.push(
                "the error against the reference changes sign along the levels (oscillation, or a reference that \
                 is not the limit of the model: a modelling error), so no order is fitted to it"
                    .into(),
            );
        } else if points.len() >= 2 {
            c.reference_order = Some(slope(&points));
        }
        if e > criteria.tolerance {
            c.failures.push(format!(
                "relative error of the finest level against the reference {reference} is {e:.2e} > tolerance {:.1e}",
                criteria.tolerance
            ));
        }
    }
    if let (Some(min), Some(p)) = (criteria.min_order, c.order)
        && c.converged
        && p < min
    {
        c.failures
            .push(format!("observed order {p:.2} < min_order {min}"));
    }
    c
}

/// Least-squares slope of y against x.
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let sxy: f64 = points.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = points.iter().map(|(x, _)| (x - mx).powi(2)).sum();
    sxy / sxx
}
