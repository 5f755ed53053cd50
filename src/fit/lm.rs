//! Levenberg–Marquardt for small dense least-squares problems (a handful of parameters, up
//! to some thousand residuals) on nalgebra, within bounds.
//!
//! The iteration is Marquardt's with the scaled damping D = diag(JᵀJ) and Nielsen's update of
//! the damping factor (H. B. Nielsen, "Damping parameter in Marquardt's method", IMM-REP-1999-05):
//! the step δ solves (JᵀJ + λD) δ = −Jᵀr; it is accepted when the gain ratio
//! ρ = (F(θ) − F(θ+δ)) / (−gᵀδ − ½ δᵀJᵀJδ) is positive, F = ½‖r‖², g = Jᵀr, and then
//! λ ← λ · max(1/3, 1 − (2ρ − 1)³), else λ ← λν, ν ← 2ν.
//!
//! **Bounds** (each component in a closed interval, [`Problem::range`]) are kept by an active
//! set and projection, the projected Levenberg–Marquardt method of Kanzow, Yamashita and
//! Fukushima (J. Comput. Appl. Math. 172, 2004): a component at a bound whose gradient points
//! out of the range is held for the step, the others solve the damped system, and the trial
//! point is projected onto the range (the gain ratio uses the projected step). The gradient
//! that decides convergence is the projected one.
//!
//! The Jacobian is by finite differences: residual functions here are material-point
//! simulations or finite-element runs, whose derivatives are not available in closed form.
//! Central differences where both neighbours lie in the range; at a bound, the second-order
//! one-sided formula into the range, (−3r(θ) + 4r(θ+h) − r(θ+2h))/2h, with the same number of
//! evaluations and the same order of accuracy.

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Settings of [`minimize`].
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Most iterations (accepted or rejected steps).
    pub max_iterations: usize,
    /// Stop when the step is below this relative to ‖θ‖ (plus this, absolute).
    pub step_tolerance: f64,
    /// Stop when the projected ‖Jᵀr‖∞ is below this times (1 + F).
    pub gradient_tolerance: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            max_iterations: 200,
            step_tolerance: 1e-12,
            gradient_tolerance: 1e-14,
        }
    }
}

/// Why [`minimize`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Stop {
    /// The step became smaller than the tolerance.
    SmallStep,
    /// The (projected) gradient vanished.
    SmallGradient,
    /// The residuals are zero to round-off.
    ZeroResidual,
    /// The iteration limit.
    MaxIterations,
    /// The residuals or their finite differences are not finite numbers (overflow).
    NotFinite,
}

/// The optimum [`minimize`] reached.
#[derive(Clone, Debug)]
pub struct Minimum {
    pub theta: DVector<f64>,
    pub residuals: DVector<f64>,
    pub iterations: usize,
    /// Residual evaluations, including those of the Jacobians.
    pub evaluations: usize,
    pub stop: Stop,
}

impl Minimum {
    /// χ² = ‖r‖² (infinite when the residuals are not finite).
    pub fn chi_square(&self) -> f64 {
        let c = self.residuals.norm_squared();
        if c.is_nan() { f64::INFINITY } else { c }
    }
}

/// A least-squares problem: residuals r(θ) (already divided by their standard deviations)
/// and Jacobians, in parallel where the residual is expensive.
pub trait Problem {
    type Error;
    /// r(θ).
    fn residuals(&self, theta: &DVector<f64>) -> Result<DVector<f64>, Self::Error>;
    /// r at each of `thetas` (the Jacobian's perturbed points); sequential by default.
    fn residuals_many(&self, thetas: &[DVector<f64>]) -> Result<Vec<DVector<f64>>, Self::Error> {
        thetas.iter().map(|t| self.residuals(t)).collect()
    }
    /// The closed range of component `i` (default: unbounded).
    fn range(&self, _i: usize) -> (f64, f64) {
        (f64::NEG_INFINITY, f64::INFINITY)
    }
    /// Finite-difference step of each component at θ.
    fn steps(&self, theta: &DVector<f64>) -> DVector<f64> {
        theta.map(|t| 1e-6 * t.abs().max(1e-3))
    }
    /// Whether error `e` at a trial point only means that the point cannot be evaluated (a
    /// model that does not converge there): the step is then rejected like one that raises
    /// the residuals. Other errors end the minimisation.
    fn infeasible(&self, _e: &Self::Error) -> bool {
        false
    }
}

/// How a Jacobian column is differenced.
#[derive(Clone, Copy)]
enum Difference {
    /// r(θ+h), r(θ−h).
    Central,
    /// r(θ+h), r(θ+2h) with r(θ).
    Forward,
    /// r(θ−h), r(θ−2h) with r(θ).
    Backward,
}

/// The finite-difference Jacobian dr/dθ at `theta`, where the residuals are `r0` (two
/// evaluations per column, none outside the range: see the module documentation).
pub fn jacobian<P: Problem>(
    problem: &P,
    theta: &DVector<f64>,
    r0: &DVector<f64>,
) -> Result<DMatrix<f64>, P::Error> {
    let h = problem.steps(theta);
    let mut columns = Vec::with_capacity(theta.len());
    let mut points = Vec::with_capacity(2 * theta.len());
    for j in 0..theta.len() {
        let (lo, hi) = problem.range(j);
        // A step of at most a quarter of the range: one side then has room for 2h.
        let h = h[j].min(0.25 * (hi - lo));
        let at = |k: f64| {
            let mut t = theta.clone();
            t[j] += k * h;
            t
        };
        let (kind, a, b) = if theta[j] - h >= lo && theta[j] + h <= hi {
            (Difference::Central, at(1.0), at(-1.0))
        } else if theta[j] + 2.0 * h <= hi {
            (Difference::Forward, at(1.0), at(2.0))
        } else {
            (Difference::Backward, at(-1.0), at(-2.0))
        };
        columns.push((kind, h));
        points.push(a);
        points.push(b);
    }
    let values = problem.residuals_many(&points)?;
    let mut jac = DMatrix::zeros(r0.len(), theta.len());
    for (j, (kind, h)) in columns.into_iter().enumerate() {
        let (a, b) = (&values[2 * j], &values[2 * j + 1]);
        let column = match kind {
            Difference::Central => (a - b) / (2.0 * h),
            Difference::Forward => (a * 4.0 - b - r0 * 3.0) / (2.0 * h),
            Difference::Backward => (r0 * 3.0 - a * 4.0 + b) / (2.0 * h),
        };
        jac.set_column(j, &column);
    }
    Ok(jac)
}

/// Minimises ½‖r(θ)‖² from `start` (projected onto the range) within the problem's range.
/// A start whose residuals are not finite ends at once with [`Stop::NotFinite`].
pub fn minimize<P: Problem>(
    problem: &P,
    start: DVector<f64>,
    settings: &Settings,
) -> Result<Minimum, P::Error> {
    let n = start.len();
    let (lo, hi): (Vec<f64>, Vec<f64>) = (0..n).map(|i| problem.range(i)).unzip();
    let project = |t: DVector<f64>| DVector::from_fn(n, |i, _| t[i].clamp(lo[i], hi[i]));
    let mut theta = project(start);
    let mut r = problem.residuals(&theta)?;
    let mut evaluations = 1;
    let cost = |r: &DVector<f64>| 0.5 * r.norm_squared();
    let mut f = cost(&r);
    let mut nu = 2.0;
    let mut lambda: Option<f64> = None;
    let mut fresh = true; // the Jacobian must be (re)computed at θ
    let (mut a, mut g) = (DMatrix::zeros(0, 0), DVector::zeros(0));
    for iteration in 0..settings.max_iterations {
        let finish = |theta: &DVector<f64>, r: &DVector<f64>, evaluations, stop| Minimum {
            theta: theta.clone(),
            residuals: r.clone(),
            iterations: iteration,
            evaluations,
            stop,
        };
        if !f.is_finite() {
            return Ok(finish(&theta, &r, evaluations, Stop::NotFinite));
        }
        if fresh {
            let jac = jacobian(problem, &theta, &r)?;
            evaluations += 2 * n;
            if !jac.iter().all(|x| x.is_finite()) {
                return Ok(finish(&theta, &r, evaluations, Stop::NotFinite));
            }
            a = jac.transpose() * &jac;
            g = jac.transpose() * &r;
            fresh = false;
        }
        if f <= f64::MIN_POSITIVE {
            return Ok(finish(&theta, &r, evaluations, Stop::ZeroResidual));
        }
        // Held: at a bound, with the descent direction −g pointing out of the range.
        let held: Vec<bool> = (0..n)
            .map(|i| (theta[i] <= lo[i] && g[i] > 0.0) || (theta[i] >= hi[i] && g[i] < 0.0))
            .collect();
        let projected = DVector::from_fn(n, |i, _| if held[i] { 0.0 } else { g[i] });
        if projected.amax() <= settings.gradient_tolerance * (1.0 + f) {
            return Ok(finish(&theta, &r, evaluations, Stop::SmallGradient));
        }
        // Marquardt's scaling, floored so a parameter the residuals ignore still gets damped.
        let dmax = a.diagonal().max();
        let d = a
            .diagonal()
            .map(|x| x.max(1e-12 * dmax).max(f64::MIN_POSITIVE));
        let l = *lambda.get_or_insert(1e-3);
        let mut damped = a.clone();
        for i in 0..n {
            damped[(i, i)] += l * d[i];
            if held[i] {
                // δ_i = 0: the row and column drop out of the system.
                damped.row_mut(i).fill(0.0);
                damped.column_mut(i).fill(0.0);
                damped[(i, i)] = 1.0;
            }
        }
        let Some(chol) = damped.cholesky() else {
            lambda = Some(l * nu);
            nu *= 2.0;
            continue;
        };
        let trial = project(&theta - chol.solve(&projected));
        let step = &trial - &theta;
        if step.norm() <= settings.step_tolerance * (theta.norm() + settings.step_tolerance) {
            return Ok(finish(&theta, &r, evaluations, Stop::SmallStep));
        }
        // The decrease the Gauss–Newton model predicts for the projected step.
        let predicted = -g.dot(&step) - 0.5 * step.dot(&(&a * &step));
        let r_trial = match problem.residuals(&trial) {
            Ok(r) => Some(r),
            Err(e) if problem.infeasible(&e) => None,
            Err(e) => return Err(e),
        };
        evaluations += 1;
        let accepted = r_trial.filter(|r_trial| {
            let f_trial = cost(r_trial);
            let rho = (f - f_trial) / predicted;
            let ok = predicted > 0.0 && rho > 0.0 && f_trial.is_finite();
            if ok {
                lambda = Some(l * (1.0 / 3.0f64).max(1.0 - (2.0 * rho - 1.0).powi(3)));
            }
            ok
        });
        if let Some(r_trial) = accepted {
            theta = trial;
            f = cost(&r_trial);
            r = r_trial;
            nu = 2.0;
            fresh = true;
        } else {
            lambda = Some(l * nu);
            nu *= 2.0;
        }
    }
    Ok(Minimum {
        theta,
        residuals: r,
        iterations: settings.max_iterations,
        evaluations,
        stop: if f.is_finite() {
            Stop::MaxIterations
        } else {
            Stop::NotFinite
        },
    })
}

/// The two-sided 97.5 % quantile of Student's t with `dof` ≥ 1 degrees of freedom (the 1.96
/// of the normal distribution as dof → ∞): where statrs's survival function falls to 2.5 %,
/// by bisection. (statrs's `inverse_cdf` starts from an approximation that loses digits as
/// dof grows: 3e-7 relative at dof = 3·10⁴; the survival function keeps 1e-11 there.)
pub fn t_quantile_975(dof: f64) -> f64 {
    let t = StudentsT::new(0.0, 1.0, dof)
        .expect("a fit has more measured points than free parameters (checked when read)");
    let (mut lo, mut hi) = (0.0, 1e3);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if t.sf(mid) > 0.025 {
            lo = mid
        } else {
            hi = mid
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock as least squares: r = (10(y − x²), 1 − x), minimum (1, 1).
    struct Rosenbrock;
    impl Problem for Rosenbrock {
        type Error = ();
        fn residuals(&self, t: &DVector<f64>) -> Result<DVector<f64>, ()> {
            Ok(DVector::from_vec(vec![
                10.0 * (t[1] - t[0] * t[0]),
                1.0 - t[0],
            ]))
        }
    }

    #[test]
    fn finds_the_rosenbrock_minimum() {
        let m = minimize(
            &Rosenbrock,
            DVector::from_vec(vec![-1.2, 1.0]),
            &Settings::default(),
        )
        .unwrap();
        assert!((m.theta[0] - 1.0).abs() < 1e-10 && (m.theta[1] - 1.0).abs() < 1e-10);
    }

    /// A linear problem: one step of Gauss–Newton solves it; LM must land on the normal
    /// equations' solution.
    #[test]
    fn linear_least_squares_matches_the_normal_equations() {
        struct Line;
        impl Problem for Line {
            type Error = ();
            fn residuals(&self, t: &DVector<f64>) -> Result<DVector<f64>, ()> {
                let y = [1.0, 2.9, 5.2, 7.1];
                Ok(DVector::from_iterator(
                    4,
                    (0..4).map(|i| t[0] + t[1] * i as f64 - y[i]),
                ))
            }
        }
        let m = minimize(
            &Line,
            DVector::from_vec(vec![0.0, 0.0]),
            &Settings::default(),
        )
        .unwrap();
        // Normal equations by hand: x̄ = 1.5, ȳ = 4.05, slope = Σ(x−x̄)(y−ȳ)/Σ(x−x̄)² = 10.3/5.
        let slope = 10.3 / 5.0;
        assert!((m.theta[1] - slope).abs() < 1e-9);
        assert!((m.theta[0] - (4.05 - 1.5 * slope)).abs() < 1e-9);
    }

    /// A minimum outside the range: the bounded optimum lies on the bound (x = 2 for
    /// (x − 3)² with x ≤ 2), is reached without a residual ever evaluated outside the range,
    /// and the Jacobian there is the one-sided one (exact for this quadratic).
    #[test]
    fn bounds_hold_the_iterates_and_the_differences() {
        struct Capped(std::cell::Cell<bool>);
        impl Problem for Capped {
            type Error = ();
            fn residuals(&self, t: &DVector<f64>) -> Result<DVector<f64>, ()> {
                if t[0] > 2.0 || t[1] < 0.0 {
                    self.0.set(true);
                }
                Ok(DVector::from_vec(vec![t[0] - 3.0, t[1] - 1.0, t[0] * t[1]]))
            }
            fn range(&self, i: usize) -> (f64, f64) {
                [(f64::NEG_INFINITY, 2.0), (0.0, f64::INFINITY)][i]
            }
        }
        let p = Capped(std::cell::Cell::new(false));
        let m = minimize(&p, DVector::from_vec(vec![0.5, 3.0]), &Settings::default()).unwrap();
        // With x = 2 held: minimise (y − 1)² + 4y² → y = 1/5.
        assert!(
            (m.theta[0] - 2.0).abs() < 1e-12 && (m.theta[1] - 0.2).abs() < 1e-9,
            "{m:?}"
        );
        assert!(!p.0.get(), "a residual was evaluated outside the range");
        let at = DVector::from_vec(vec![2.0, 0.0]);
        let jac = jacobian(&p, &at, &p.residuals(&at).unwrap()).unwrap();
        let exact = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 1.0, 0.0, 2.0]);
        // Exact but for round-off: residuals of order 1 differenced over h = 1e-9 (y = 0).
        assert!((jac - exact).amax() < 1e-6);
        assert!(!p.0.get());
    }

    #[test]
    fn t_quantiles_match_closed_forms_tables_and_the_normal_limit() {
        let p: f64 = 0.975;
        // Closed forms: ν = 1 (Cauchy) tan(π(p − ½)); ν = 2: (2p − 1) √(2 / (4p(1 − p))).
        let cauchy = (std::f64::consts::PI * (p - 0.5)).tan();
        let two = (2.0 * p - 1.0) * (2.0 / (4.0 * p * (1.0 - p))).sqrt();
        // Tables of Student's t, 97.5 % (Abramowitz & Stegun, Table 26.10; here to 16 digits,
        // as R's `qt(0.975, ν)` gives them).
        for (dof, t) in [
            (1.0, cauchy),
            (2.0, two),
            (5.0, 2.570_581_835_636_314),
            (10.0, 2.228_138_851_986_274),
            (30.0, 2.042_272_456_301_238),
        ] {
            let q = t_quantile_975(dof);
            assert!((q - t).abs() < 1e-12 * t, "dof {dof}: {q} against {t}");
        }
        // Large ν: the normal quantile z plus the first term of Fisher's expansion,
        // (z³ + z) / 4ν; the next one, O(ν⁻²), is below 1e-14 here.
        let (z, dof): (f64, f64) = (1.959_963_984_540_054, 1e7);
        let t = z + (z.powi(3) + z) / (4.0 * dof);
        let q = t_quantile_975(dof);
        assert!((q - t).abs() < 1e-8 * t, "{q} against {t}");
    }
}
