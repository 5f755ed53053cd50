//! The linearised statistics at the optimum: standard errors, correlations and the directions
//! the data do not determine (see the module documentation of [`super`]).

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use super::params::Parameters;

/// Ratio of the smallest to the largest eigenvalue of the unit-diagonal information matrix
/// below which parameters are not separately identifiable. Central differences give
/// derivatives to about 1e-10 relative; exactly dependent columns then show ratios near
/// 1e-16…1e-12, while a merely poor design stays above 1e-8.
pub const SINGULAR: f64 = 1e-9;

/// |correlation| above which a pair of parameters is reported as poorly separable.
pub const CORRELATION_WARNING: f64 = 0.99;

/// Standard errors, correlations and the non-identifiable directions of a Jacobian.
pub struct Statistics {
    pub standard_errors: Vec<Option<f64>>,
    pub correlation: Vec<Vec<Option<f64>>>,
    /// Eigenvectors (of the unit-diagonal information matrix) with a vanishing eigenvalue.
    pub null_space: Vec<DVector<f64>>,
}

impl Statistics {
    /// Messages about poorly and non-identifiable parameters.
    pub fn warnings(&self, parameters: &Parameters) -> Vec<String> {
        let names: Vec<&str> = parameters.free.iter().map(|f| f.name).collect();
        let mut out = Vec::new();
        // A direction of one parameter alone (a parameter the data do not change with, here)
        // is left to its profile, which tells whether the data bound it on one side.
        for v in self
            .null_space
            .iter()
            .filter(|v| v.iter().filter(|c| c.abs() > 0.1).count() > 1)
        {
            let involved: Vec<String> = v
                .iter()
                .enumerate()
                .filter(|(_, c)| c.abs() > 0.1)
                .map(|(k, c)| format!("{c:+.3} {}", names[k]))
                .collect();
            out.push(format!(
                "not identifiable: the data do not change along the direction {} (each parameter scaled by its \
                 sensitivity): fix one of {} or add a test that separates them (e.g. another pressure level)",
                involved.join(" "),
                v.iter()
                    .enumerate()
                    .filter(|(_, c)| c.abs() > 0.1)
                    .map(|(k, _)| names[k])
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        for i in 0..names.len() {
            for j in 0..i {
                if let Some(c) = self.correlation[i][j].filter(|c| c.abs() > CORRELATION_WARNING) {
                    out.push(format!(
                        "{} and {} are strongly correlated ({c:+.4}): the data hardly separate them",
                        names[j], names[i]
                    ));
                }
            }
        }
        out
    }
}

/// The statistics of Jacobian `jac` = ∂r/∂x at `x` with scale s² = `scale`.
pub fn statistics(jac: &DMatrix<f64>, scale: f64, x: &[f64]) -> Statistics {
    let p = x.len();
    let info = jac.transpose() * jac;
    // Relative scaling: unit diagonal (a zero column is itself non-identifiable).
    let d: Vec<f64> = (0..p).map(|i| info[(i, i)].sqrt()).collect();
    let mut unit = DMatrix::zeros(p, p);
    for i in 0..p {
        for j in 0..p {
            let dd = d[i] * d[j];
            unit[(i, j)] = if dd > 0.0 { info[(i, j)] / dd } else { 0.0 };
        }
    }
    let eig = SymmetricEigen::new(unit.clone());
    let largest = eig.eigenvalues.max().max(f64::MIN_POSITIVE);
    let mut null_space = Vec::new();
    let mut unidentified = vec![false; p];
    for (k, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda < SINGULAR * largest {
            let v = eig.eigenvectors.column(k).into_owned();
            for (i, c) in v.iter().enumerate() {
                unidentified[i] |= c.abs() > 0.1;
            }
            null_space.push(v);
        }
    }
    // C = s² D⁻¹ U⁻¹ D⁻¹ on the identifiable subspace (pseudo-inverse of U).
    let mut u_inv = DMatrix::zeros(p, p);
    for (k, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda >= SINGULAR * largest {
            let v = eig.eigenvectors.column(k);
            u_inv += v * v.transpose() / lambda;
        }
    }
    let standard_errors: Vec<Option<f64>> = (0..p)
        .map(|i| (!unidentified[i] && d[i] > 0.0).then(|| (scale * u_inv[(i, i)]).sqrt() / d[i]))
        .collect();
    let correlation = (0..p)
        .map(|i| {
            (0..p)
                .map(|j| {
                    let ok = !unidentified[i] && !unidentified[j];
                    ok.then(|| u_inv[(i, j)] / (u_inv[(i, i)] * u_inv[(j, j)]).sqrt())
                })
                .collect()
        })
        .collect();
    Statistics {
        standard_errors,
        correlation,
        null_space,
    }
}

impl Statistics {
    /// Whether each parameter is part of a direction the data do not change along that
    /// involves two or more parameters (R and S of k_T = p^S/R from a single pressure): such
    /// parameters are not identified separately, whatever a profile of one of them shows (its
    /// rise then only comes from the bounds of the others).
    pub fn unseparated(&self, p: usize) -> Vec<bool> {
        let mut out = vec![false; p];
        for v in &self.null_space {
            let involved: Vec<usize> = (0..p).filter(|&i| v[i].abs() > 0.1).collect();
            if involved.len() > 1 {
                for i in involved {
                    out[i] = true;
                }
            }
        }
        out
    }
}
