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

/// The two-sided 97.5 % quantile of Student's t with `dof` degrees of freedom (the 1.96 of
/// the normal distribution as dof → ∞), by bisection on the distribution function.
pub fn t_quantile_975(dof: f64) -> f64 {
    let cdf = |t: f64| 1.0 - 0.5 * incomplete_beta(0.5 * dof, 0.5, dof / (dof + t * t));
    let (mut lo, mut hi) = (0.0, 1e3);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if cdf(mid) < 0.975 { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// The regularised incomplete beta function I_x(a, b), by the continued fraction of
/// Numerical Recipes (3rd ed., §6.4) with the modified Lentz method.
fn incomplete_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    if x < (a + 1.0) / (a + b + 2.0) {
        ln_front.exp() * beta_fraction(a, b, x) / a
    } else {
        1.0 - ln_front.exp() * beta_fraction(b, a, 1.0 - x) / b
    }
}

fn beta_fraction(a: f64, b: f64, x: f64) -> f64 {
    let tiny = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < tiny {
        d = tiny;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..300 {
        let m = m as f64;
        let m2 = 2.0 * m;
        for aa in [
            m * (b - m) * x / ((qam + m2) * (a + m2)),
            -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
        ] {
            d = 1.0 + aa * d;
            if d.abs() < tiny {
                d = tiny;
            }
            c = 1.0 + aa / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            h *= d * c;
        }
        if (d * c - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, n = 9; relative error below 1e-15).
fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x)Γ(1−x) = π / sin(πx).
        return (std::f64::consts::PI / (std::f64::consts::PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let t = x + 7.5;
    let sum = G[1..]
        .iter()
        .enumerate()
        .fold(G[0], |s, (i, g)| s + g / (x + i as f64 + 1.0));
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + sum.ln()
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
    fn t_quantiles_match_tables() {
        // Tables of Student's t, 97.5 % (e.g. Abramowitz & Stegun, Table 26.10).
        for (dof, t) in [
            (1.0, 12.706_204_736),
            (2.0, 4.302_652_730),
            (5.0, 2.570_581_836),
            (10.0, 2.228_138_852),
            (30.0, 2.042_272_456),
            (1e7, 1.959_963_985),
        ] {
            assert!((t_quantile_975(dof) - t).abs() < 1e-6 * t, "dof {dof}");
        }
    }
}
