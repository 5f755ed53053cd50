//! The starting guess of a load increment: the last converged increment's displacements,
//! extrapolated when the prescribed changes are proportional to that increment's.

use crate::assembly::DofMap;

/// The last converged increment, from which the next one is predicted: when the loads and
/// prescribed displacements of an increment change in proportion to those of the last
/// converged one (Δg = s Δg_last, s > 0, as in every proportional load schedule), its free
/// displacements start from u + s Δu_last rather than from u (Abaqus' default extrapolation).
/// With friction this starts the points that slipped in the last increment slipping, instead
/// of all points sticking in the first iteration (a converged state is in stick), which spares
/// the stick–slip switching of the first iterations.
#[derive(Debug)]
pub(super) struct Predictor {
    /// Whether `last.u`, `last.f_ext` are the state the current increment started from.
    pub(super) anchored: bool,
    pub(super) last: LastIncrement,
}

/// The last converged increment as the predictor keeps it: where it ended and what changed
/// over it. A restart record holds it (when the predictor is on), so that a resumed run
/// extrapolates its first increment as the uninterrupted run would.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LastIncrement {
    /// Whether `du` and `df` are the changes of a converged increment that started where
    /// the one before it ended (else only `u` and `f_ext` are set).
    pub ready: bool,
    /// Displacements and external forces (all dofs) at its end.
    pub u: Vec<f64>,
    pub f_ext: Vec<f64>,
    /// Their changes over it.
    pub du: Vec<f64>,
    pub df: Vec<f64>,
}

/// Relative tolerance of the proportionality of two load changes (they come from the same
/// load factors, so they agree to round-off when proportional).
pub(super) const PROPORTIONAL: f64 = 1e-9;

impl Predictor {
    /// A record of the unloaded state u = 0 with `n` dofs.
    pub(super) fn new(n: usize) -> Self {
        Self {
            anchored: true,
            last: LastIncrement {
                ready: false,
                u: vec![0.0; n],
                f_ext: vec![0.0; n],
                du: vec![0.0; n],
                df: vec![0.0; n],
            },
        }
    }

    /// The last converged increment (the unloaded state before the first).
    pub(super) fn last(&self) -> &LastIncrement {
        &self.last
    }

    /// Continues from `last`, the converged increment of an interrupted run (of this size).
    pub(super) fn restore(&mut self, last: LastIncrement) {
        self.last = last;
        self.anchored = true;
    }

    /// Starts an increment from `u` (prescribed dofs already at their new values) with the
    /// external forces `f_ext`: adds s Δu_last to the free dofs if the increment is
    /// proportional to the last converged one. Returns s (0: no prediction).
    pub(super) fn predict(&mut self, dofs: &DofMap, u: &mut [f64], f_ext: &[f64]) -> f64 {
        let free = |d: usize| dofs.equation(d).is_some();
        let last = &self.last;
        self.anchored = (0..u.len()).all(|d| !free(d) || u[d] == last.u[d]);
        if !(last.ready && self.anchored) {
            return 0.0;
        }
        let prescribed = (0..u.len()).filter(|&d| !free(d));
        let s_u = proportion(prescribed.map(|d| (u[d] - last.u[d], last.du[d])));
        let s_f = proportion((0..u.len()).map(|d| (f_ext[d] - last.f_ext[d], last.df[d])));
        let s = match (s_u, s_f) {
            (Some(Some(a)), Some(Some(b))) if (a - b).abs() <= PROPORTIONAL * a.abs() => a,
            (Some(Some(a)), None) | (None, Some(Some(a))) => a,
            _ => return 0.0,
        };
        if s <= 0.0 {
            // A reversal: the last increment's slip says nothing about the next one's.
            return 0.0;
        }
        for (d, x) in u.iter_mut().enumerate() {
            if free(d) {
                *x += s * last.du[d];
            }
        }
        s
    }

    /// Records the converged increment that ended in `u` under `f_ext`.
    pub(super) fn record(&mut self, u: &[f64], f_ext: &[f64]) {
        let last = &mut self.last;
        if self.anchored {
            for (((du, df), (x, f)), (x0, f0)) in last
                .du
                .iter_mut()
                .zip(last.df.iter_mut())
                .zip(u.iter().zip(f_ext))
                .zip(last.u.iter().zip(&last.f_ext))
            {
                *du = x - x0;
                *df = f - f0;
            }
        }
        last.ready = self.anchored;
        self.anchored = true;
        last.u.copy_from_slice(u);
        last.f_ext.copy_from_slice(f_ext);
    }
}

/// The factor s with new = s · old for pairs (new, old): None if both are zero throughout (no
/// change of this kind), Some(None) if they are not proportional, Some(Some(s)) otherwise.
fn proportion(pairs: impl Iterator<Item = (f64, f64)> + Clone) -> Option<Option<f64>> {
    let (dot, old2, new2) = pairs.clone().fold((0.0, 0.0, 0.0), |(d, o, n), (a, b)| {
        (d + a * b, o + b * b, n + a * a)
    });
    if old2 == 0.0 && new2 == 0.0 {
        return None;
    }
    if old2 == 0.0 {
        return Some(None);
    }
    let s = dot / old2;
    let misfit = pairs.fold(0.0, |m, (a, b)| m + (a - s * b) * (a - s * b));
    Some((misfit <= PROPORTIONAL * PROPORTIONAL * new2).then_some(s))
}
