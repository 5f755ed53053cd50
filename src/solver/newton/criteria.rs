//! The engineering convergence criteria of a Newton iteration (see [`super`]'s module docs and
//! `docs/convergence_criteria.md`): the criteria's parameters, the force flux of an iteration
//! and its time average over the run.

/// Engineering convergence criteria (see the module docs): the field parameters of CalculiX's
/// *CONTROLS, PARAMETERS=FIELD. The defaults are CalculiX's, except R_n = 5e-4 and C_n = 1e-3
/// (CalculiX and Abaqus: 5e-3, 1e-2), which keep path-dependent frictional answers within
/// 1e-4 of a tight run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Criteria {
    /// R_n: the largest residual force relative to the time-averaged force q̃.
    pub residual: f64,
    /// R_p: the same, used after `late_iteration` iterations (a slowly converging increment).
    pub late_residual: f64,
    /// I_P: the iteration after which R_p replaces R_n.
    pub late_iteration: usize,
    /// C_n: the largest correction relative to the largest displacement change of the
    /// increment.
    pub correction: f64,
    /// ε: zero flux when the current flux q̄ ≤ ε q̃; then the residual must be ≤ ε q̃.
    pub zero_flux: f64,
    /// C_ε: the correction criterion under zero flux.
    pub zero_flux_correction: f64,
    /// R_l: a residual this small relative to q̃ is accepted without the correction check.
    pub linear_residual: f64,
    /// q_u: a user-given average force (N) that replaces q̃.
    pub average_force: Option<f64>,
    /// Whether the relative-norm tolerances of [`super::NewtonSettings`] are required as well.
    pub relative_norms: bool,
}

impl Default for Criteria {
    /// The `[solver]` defaults.
    fn default() -> Self {
        Self {
            residual: 5e-4,
            late_residual: 2e-2,
            late_iteration: 9,
            correction: 1e-3,
            zero_flux: 1e-5,
            zero_flux_correction: 1e-3,
            linear_residual: 1e-8,
            average_force: None,
            relative_norms: false,
        }
    }
}

/// The force flux of one evaluation, Σf² and Σ|f| over the bodies' nodal forces: the
/// force-weighted mean magnitude Σf²/Σ|f| is the typical nodal force, whatever the number of
/// unloaded nodes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Flux {
    pub(super) squares: f64,
    pub(super) magnitudes: f64,
}

impl Flux {
    pub(super) fn of(forces: &[f64]) -> Self {
        forces.iter().fold(Self::default(), |f, &x| Self {
            squares: f.squares + x * x,
            magnitudes: f.magnitudes + x.abs(),
        })
    }

    /// The typical nodal force q̄ (0 when no force acts).
    pub(super) fn typical(self) -> f64 {
        if self.magnitudes > 0.0 {
            self.squares / self.magnitudes
        } else {
            0.0
        }
    }
}

/// The converged increments' part of the time-averaged force q̃: the sum of their fluxes and
/// their number. Carried across increments by [`super::Newton`], and by a restart record across a
/// resumed run ([`super::Newton::force_average`], [`super::Newton::restore_force_average`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ForceAverage {
    pub sum: f64,
    pub count: usize,
}

/// The time average q̃ of the flux: over the run's converged increments with non-zero flux
/// (their converged q̄) and the present iteration's q̄. In the first increment, which has no
/// history, zero flux is judged against the mean of q̄ over its iterations so far (CalculiX's
/// iteration average), which then is q̃: that gives a scale to a first increment that ends
/// stress-free (a body pulled off a contact). Otherwise that mean is not used: the large
/// flux of iterations far from equilibrium would loosen the residual test (measured: a
/// frictional punch's first increment accepted at 7e-4 relative residual).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct FluxHistory {
    pub(super) past: ForceAverage,
    /// Σ q̄ and the number of iterations of the present increment.
    pub(super) present: f64,
    pub(super) iterations: usize,
}

impl FluxHistory {
    /// Starts an increment.
    pub(super) fn start(&mut self) {
        self.present = 0.0;
        self.iterations = 0;
    }

    /// q̃ for an iteration of flux `current`, and whether the flux is zero (q̄ ≤ ε × the
    /// average of the earlier increments, or of the present one's iterations in the first):
    /// a zero flux does not enter the average.
    pub(super) fn with(&mut self, current: f64, zero_flux: f64) -> (f64, bool) {
        self.present += current;
        self.iterations += 1;
        let present = self.present / self.iterations as f64;
        let ForceAverage { sum, count } = self.past;
        if count == 0 {
            return if current <= zero_flux * present {
                (present, true)
            } else {
                (current, false)
            };
        }
        let past = sum / count as f64;
        if current <= zero_flux * past {
            (past, true)
        } else {
            ((sum + current) / (count + 1) as f64, false)
        }
    }

    /// Records the flux `current` of a converged increment that had `zero` flux or not.
    pub(super) fn record(&mut self, current: f64, zero: bool) {
        if current > 0.0 && !zero {
            self.past.sum += current;
            self.past.count += 1;
        }
    }
}

/// The state of one iteration that the criteria judge.
#[derive(Clone, Copy, Debug)]
pub(super) struct Measures {
    /// ‖r‖∞ over the free dofs.
    pub(super) residual_max: f64,
    /// q̃.
    pub(super) average: f64,
    /// Whether zero-flux conditions hold.
    pub(super) zero_flux: bool,
    /// ‖α δu‖∞ of the last correction (∞ before the first) and ‖u − u_start‖∞.
    pub(super) correction_max: f64,
    pub(super) increment_max: f64,
}

impl Criteria {
    /// Whether the iteration `iteration` (0: before the first solve) with `m` has converged.
    pub(super) fn converged(&self, iteration: usize, m: &Measures) -> bool {
        let q = m.average;
        if m.residual_max <= self.linear_residual * q {
            return true;
        }
        if iteration == 0 {
            return false;
        }
        let (residual, correction) = if m.zero_flux {
            (self.zero_flux, self.zero_flux_correction)
        } else if iteration > self.late_iteration {
            (self.late_residual, self.correction)
        } else {
            (self.residual, self.correction)
        };
        m.residual_max <= residual * q && m.correction_max <= correction * m.increment_max
    }

    /// The ratio r_max / q̃ that the log records (∞ if q̃ = 0 with a residual).
    pub(super) fn ratio(m: &Measures) -> f64 {
        if m.residual_max == 0.0 {
            0.0
        } else {
            m.residual_max / m.average
        }
    }
}
