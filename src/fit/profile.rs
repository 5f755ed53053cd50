//! Profiles of the objective: what the data say about one parameter whatever the others do,
//! independently of where the fit stopped.
//!
//! The profile of parameter j is χ²_j(v) = min over the others of χ² with z_j = v (each point a
//! Levenberg–Marquardt fit of the others, started from the point before). Its rise
//! Δ(v) = (χ²_j(v) − χ²_min)/s² is compared with the threshold q² of the confidence level (the
//! likelihood-ratio interval: q = 1.96 with stated errors, Δ ≤ 3.84; Student's t₀.₉₇₅ with an
//! estimated scale s², the F(1, n − p) quantile). Each side is walked from the optimum with
//! steps that grow by extrapolating √Δ (linear in v where the profile is quadratic) until Δ
//! reaches the threshold, then the crossing is refined by regula falsi on √Δ; a side on which
//! Δ stays below the threshold up to the parameter's bound, or up to [`REACH`] times its scale
//! where it has none, is open: the data do not bound the parameter on that side.

use nalgebra::DVector;

use super::lm::{self, Problem};

/// How far an unbounded side is searched: a factor 10⁶ beyond the fitted (or starting) value
/// for a log parameter, 10⁶ times its magnitude for a linear one.
pub const REACH: f64 = 1e6;

/// Most profile points on one side, searching and refining.
const MAX_POINTS: usize = 40;

/// The crossing is refined until Δ is within this fraction of the threshold.
const CROSSING_TOLERANCE: f64 = 0.01;

/// What the profile's rise is measured against.
#[derive(Clone, Copy, Debug)]
pub struct Target {
    /// χ² at the optimum.
    pub chi_square: f64,
    /// s²: 1 with stated errors, else the estimated scale.
    pub scale: f64,
    /// The rise Δ (in units of s²) that bounds the confidence region.
    pub threshold: f64,
}

/// One side of one parameter's profile to walk.
#[derive(Clone, Copy, Debug)]
pub struct Search {
    /// The parameter (index among the free ones).
    pub j: usize,
    /// Where the side ends in z: the parameter's bound, or the reach.
    pub end: f64,
    /// Whether `end` is the parameter's bound (else the reach).
    pub end_is_bound: bool,
    /// The first step in z (from the linearised interval where there is one), positive.
    pub first_step: f64,
}

/// What one side of a profile shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Side {
    /// Δ reaches the threshold at this z.
    Crossed(f64),
    /// Δ stays below the threshold up to z (`bound`: the parameter's bound; else the reach,
    /// or the last point the model could be solved at).
    Open { until: f64, bound: bool },
}

/// The walk of one side.
#[derive(Clone, Debug)]
pub struct Walk {
    pub side: Side,
    pub evaluations: usize,
    /// The lowest χ² met and the point (all free parameters) it was met at.
    pub lowest: (f64, DVector<f64>),
}

/// The problem with free parameter `j` held at `value`: the others are its unknowns.
struct Pinned<'p, P> {
    inner: &'p P,
    j: usize,
    value: f64,
}

impl<P: Problem> Pinned<'_, P> {
    fn full(&self, others: &DVector<f64>) -> DVector<f64> {
        let n = others.len() + 1;
        DVector::from_fn(n, |i, _| match i.cmp(&self.j) {
            std::cmp::Ordering::Less => others[i],
            std::cmp::Ordering::Equal => self.value,
            std::cmp::Ordering::Greater => others[i - 1],
        })
    }

    fn index(&self, i: usize) -> usize {
        if i < self.j { i } else { i + 1 }
    }
}

impl<P: Problem> Problem for Pinned<'_, P> {
    type Error = P::Error;
    fn residuals(&self, others: &DVector<f64>) -> Result<DVector<f64>, P::Error> {
        self.inner.residuals(&self.full(others))
    }
    fn residuals_many(&self, points: &[DVector<f64>]) -> Result<Vec<DVector<f64>>, P::Error> {
        let full: Vec<DVector<f64>> = points.iter().map(|t| self.full(t)).collect();
        self.inner.residuals_many(&full)
    }
    fn range(&self, i: usize) -> (f64, f64) {
        self.inner.range(self.index(i))
    }
    fn steps(&self, others: &DVector<f64>) -> DVector<f64> {
        let all = self.inner.steps(&self.full(others));
        DVector::from_fn(others.len(), |i, _| all[self.index(i)])
    }
    fn infeasible(&self, e: &P::Error) -> bool {
        self.inner.infeasible(e)
    }
}

/// The others of `z` (all but component `j`).
fn without(z: &DVector<f64>, j: usize) -> DVector<f64> {
    DVector::from_iterator(
        z.len() - 1,
        z.iter()
            .enumerate()
            .filter(|(i, _)| *i != j)
            .map(|(_, v)| *v),
    )
}

/// A profile point: Δ (None: the model cannot be solved there) and the others fitted there.
struct Point {
    delta: Option<f64>,
    others: DVector<f64>,
}

/// Walks one side of the profile of `search.j` from the optimum `best`.
pub fn walk<P: Problem>(
    problem: &P,
    best: &DVector<f64>,
    target: &Target,
    search: &Search,
    settings: &lm::Settings,
) -> Result<Walk, P::Error> {
    let j = search.j;
    let origin = best[j];
    let direction = (search.end - origin).signum();
    let room = (search.end - origin).abs();
    let mut evaluations = 0;
    let mut lowest = (target.chi_square, best.clone());
    // Δ at origin + direction·h, fitting the others from `warm`.
    let mut at = |h: f64, warm: &DVector<f64>| -> Result<Point, P::Error> {
        let value = if h >= room {
            search.end
        } else {
            origin + direction * h
        };
        let pinned = Pinned {
            inner: problem,
            j,
            value,
        };
        let fitted = if warm.is_empty() {
            evaluations += 1;
            problem.residuals(&pinned.full(warm)).map(|r| {
                let chi = r.norm_squared();
                (if chi.is_nan() { f64::INFINITY } else { chi }, warm.clone())
            })
        } else {
            lm::minimize(&pinned, warm.clone(), settings).map(|m| {
                evaluations += m.evaluations;
                (m.chi_square(), m.theta)
            })
        };
        match fitted {
            Ok((chi, others)) => {
                if chi < lowest.0 {
                    lowest = (chi, pinned.full(&others));
                }
                let delta = (chi - target.chi_square) / target.scale;
                Ok(Point {
                    delta: Some(if delta.is_nan() { f64::INFINITY } else { delta }),
                    others,
                })
            }
            Err(e) if problem.infeasible(&e) => Ok(Point {
                delta: None,
                others: warm.clone(),
            }),
            Err(e) => Err(e),
        }
    };
    let z_of = |h: f64| {
        if h >= room {
            search.end
        } else {
            origin + direction * h
        }
    };
    let root = |delta: f64| delta.max(0.0).sqrt();
    let goal = target.threshold.sqrt();
    // The last point below the threshold: its h, √Δ and the others there.
    let (mut h_in, mut rho_in, mut warm) = (0.0, 0.0, without(best, j));
    let mut h = search.first_step.min(room);
    let mut points = 0;
    let side = loop {
        if room <= 0.0 || points >= MAX_POINTS {
            break Side::Open {
                until: z_of(h_in),
                bound: room <= 0.0 && search.end_is_bound,
            };
        }
        points += 1;
        let point = at(h, &warm)?;
        let Some(delta) = point.delta else {
            break Side::Open {
                until: z_of(h_in),
                bound: false,
            };
        };
        if delta >= target.threshold {
            // Regula falsi on √Δ between h_in (below) and h (above), warm from below.
            let (mut a, mut rho_a, mut b, mut rho_b) = (h_in, rho_in, h, root(delta));
            while points < MAX_POINTS && (b - a) > 1e-3 * b {
                let w = if rho_b.is_finite() {
                    ((goal - rho_a) / (rho_b - rho_a)).clamp(0.05, 0.95)
                } else {
                    0.5
                };
                let m = a + w * (b - a);
                points += 1;
                let point = at(m, &warm)?;
                let Some(delta) = point.delta else { break };
                if (delta - target.threshold).abs() <= CROSSING_TOLERANCE * target.threshold {
                    (a, rho_a, b, rho_b) = (m, goal, m, goal);
                    break;
                }
                if delta < target.threshold {
                    (a, rho_a, warm) = (m, root(delta), point.others);
                } else {
                    (b, rho_b) = (m, root(delta));
                }
            }
            let w = if rho_b.is_finite() && rho_b > rho_a {
                ((goal - rho_a) / (rho_b - rho_a)).clamp(0.0, 1.0)
            } else {
                0.5
            };
            break Side::Crossed(z_of(a + w * (b - a)));
        }
        if h >= room {
            break Side::Open {
                until: search.end,
                bound: search.end_is_bound,
            };
        }
        // Next: where √Δ, extrapolated linearly through the optimum, reaches the goal (a
        // little beyond, to bracket it), but at least 1.2 and at most 4 times as far.
        let predicted = if delta > 0.0 {
            1.05 * h * goal / root(delta)
        } else {
            f64::INFINITY
        };
        (h_in, rho_in, warm) = (h, root(delta), point.others);
        h = predicted.clamp(1.2 * h, 4.0 * h);
    };
    Ok(Walk {
        side,
        evaluations,
        lowest,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// r = (x − 1, y − 2, x + y − 3) / σ: a quadratic χ² whose profile of x is
    /// χ²_x(v) = (v − 1)²/σ² · 3/2 (y = (5 − v)/2 at its best), so Δ = 3.84 at
    /// v = 1 ± σ √(3.84 · 2/3) exactly; x ≤ 1.5 bounds the upper side.
    struct Plane {
        sigma: f64,
    }
    impl Problem for Plane {
        type Error = ();
        fn residuals(&self, t: &DVector<f64>) -> Result<DVector<f64>, ()> {
            let r = [t[0] - 1.0, t[1] - 2.0, t[0] + t[1] - 3.0];
            Ok(DVector::from_iterator(3, r.iter().map(|v| v / self.sigma)))
        }
        fn range(&self, i: usize) -> (f64, f64) {
            [(f64::NEG_INFINITY, 1.5), (f64::NEG_INFINITY, f64::INFINITY)][i]
        }
    }

    #[test]
    fn profile_crossings_are_the_likelihood_ratio_limits() {
        let best = DVector::from_vec(vec![1.0, 2.0]);
        let target = Target {
            chi_square: 0.0,
            scale: 1.0,
            threshold: 3.84,
        };
        let settings = lm::Settings::default();
        let half = |sigma: f64| sigma * (3.84f64 * 2.0 / 3.0).sqrt();
        for (sigma, first_step) in [(0.01, 0.001), (0.01, 0.5), (0.1, 0.02)] {
            let p = Plane { sigma };
            let search = |end: f64, end_is_bound| Search {
                j: 0,
                end,
                end_is_bound,
                first_step,
            };
            let lower = walk(&p, &best, &target, &search(-1e6, false), &settings).unwrap();
            let Side::Crossed(z) = lower.side else {
                panic!("{lower:?}")
            };
            assert!((1.0 - z - half(sigma)).abs() < 0.01 * half(sigma), "{z}");
            let upper = walk(&p, &best, &target, &search(1.5, true), &settings).unwrap();
            let Side::Crossed(z) = upper.side else {
                panic!("{upper:?}")
            };
            assert!((z - 1.0 - half(sigma)).abs() < 0.01 * half(sigma), "{z}");
        }
        // σ = 1: the half-width 1.6 exceeds the room to the bound 1.5: open there.
        let p = Plane { sigma: 1.0 };
        let search = Search {
            j: 0,
            end: 1.5,
            end_is_bound: true,
            first_step: 0.1,
        };
        let upper = walk(&p, &best, &target, &search, &settings).unwrap();
        assert_eq!(
            upper.side,
            Side::Open {
                until: 1.5,
                bound: true
            }
        );
    }
}
