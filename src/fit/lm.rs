//! Levenberg–Marquardt for small dense least-squares problems (a handful of parameters, up
//! to some thousand residuals) on nalgebra, and the statistics at the optimum.
//!
//! The iteration is Marquardt's with the scaled damping D = diag(JᵀJ) and Nielsen's update of
//! the damping factor (H. B. Nielsen, "Damping parameter in Marquardt's method", IMM-REP-1999-05):
//! the step δ solves (JᵀJ + λD) δ = −Jᵀr; it is accepted when the gain ratio
//! ρ = (F(θ) − F(θ+δ)) / (½ δᵀ(λDδ − Jᵀr)) is positive, F = ½‖r‖², and then
//! λ ← λ · max(1/3, 1 − (2ρ − 1)³), else λ ← λν, ν ← 2ν. The Jacobian is by central
//! differences: residual functions here are material-point simulations or finite-element runs,
//! whose derivatives are not available in closed form.

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Settings of [`minimize`].
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Most iterations (accepted or rejected steps).
    pub max_iterations: usize,
    /// Stop when the step is below this relative to ‖θ‖ (plus this, absolute).
    pub step_tolerance: f64,
    /// Stop when ‖Jᵀr‖∞ is below this.
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
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// The step became smaller than the tolerance.
    SmallStep,
    /// The gradient vanished.
    SmallGradient,
    /// The residuals are zero to round-off.
    ZeroResidual,
    /// The iteration limit.
    MaxIterations,
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
    /// Finite-difference step of each component at θ.
    fn steps(&self, theta: &DVector<f64>) -> DVector<f64> {
        theta.map(|t| 1e-6 * t.abs().max(1e-3))
    }
}

/// The central-difference Jacobian dr/dθ at `theta` (2 evaluations per column).
pub fn jacobian<P: Problem>(
    problem: &P,
    theta: &DVector<f64>,
    rows: usize,
) -> Result<DMatrix<f64>, P::Error> {
    let h = problem.steps(theta);
    let mut points = Vec::with_capacity(2 * theta.len());
    for j in 0..theta.len() {
        for sign in [1.0, -1.0] {
            let mut t = theta.clone();
            t[j] += sign * h[j];
            points.push(t);
        }
    }
    let values = problem.residuals_many(&points)?;
    let mut jac = DMatrix::zeros(rows, theta.len());
    for j in 0..theta.len() {
        let column = (&values[2 * j] - &values[2 * j + 1]) / (2.0 * h[j]);
        jac.set_column(j, &column);
    }
    Ok(jac)
}

/// Minimises ½‖r(θ)‖² from `start`.
pub fn minimize<P: Problem>(
    problem: &P,
    start: DVector<f64>,
    settings: &Settings,
) -> Result<Minimum, P::Error> {
    let mut theta = start;
    let mut r = problem.residuals(&theta)?;
    let mut evaluations = 1;
    let cost = |r: &DVector<f64>| 0.5 * r.norm_squared();
    let mut f = cost(&r);
    let mut nu = 2.0;
    let mut lambda: Option<f64> = None;
    let mut fresh = true; // the Jacobian must be (re)computed at θ
    let (mut a, mut g) = (DMatrix::zeros(0, 0), DVector::zeros(0));
    for iteration in 0..settings.max_iterations {
        if fresh {
            let jac = jacobian(problem, &theta, r.len())?;
            evaluations += 2 * theta.len();
            a = jac.transpose() * &jac;
            g = jac.transpose() * &r;
            fresh = false;
        }
        let finish = |stop| Minimum {
            theta: theta.clone(),
            residuals: r.clone(),
            iterations: iteration,
            evaluations,
            stop,
        };
        if f <= f64::MIN_POSITIVE {
            return Ok(finish(Stop::ZeroResidual));
        }
        if g.amax() <= settings.gradient_tolerance * (1.0 + f) {
            return Ok(finish(Stop::SmallGradient));
        }
        // Marquardt's scaling, floored so a parameter the residuals ignore still gets damped.
        let dmax = a.diagonal().max();
        let d = a
            .diagonal()
            .map(|x| x.max(1e-12 * dmax).max(f64::MIN_POSITIVE));
        let l = *lambda.get_or_insert(1e-3);
        let mut damped = a.clone();
        for i in 0..d.len() {
            damped[(i, i)] += l * d[i];
        }
        let Some(chol) = damped.cholesky() else {
            lambda = Some(l * nu);
            nu *= 2.0;
            continue;
        };
        let delta = -chol.solve(&g);
        if delta.norm() <= settings.step_tolerance * (theta.norm() + settings.step_tolerance) {
            return Ok(finish(Stop::SmallStep));
        }
        let trial = &theta + &delta;
        let r_trial = problem.residuals(&trial)?;
        evaluations += 1;
        let f_trial = cost(&r_trial);
        let predicted = 0.5 * delta.dot(&(d.component_mul(&delta) * l - &g));
        let rho = (f - f_trial) / predicted;
        if rho > 0.0 && f_trial.is_finite() {
            theta = trial;
            r = r_trial;
            f = f_trial;
            lambda = Some(l * (1.0 / 3.0f64).max(1.0 - (2.0 * rho - 1.0).powi(3)));
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
        stop: Stop::MaxIterations,
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
