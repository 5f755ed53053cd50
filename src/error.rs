//! The crate's error type. Every error names the file or entity it concerns and what is wrong,
//! so that a user can fix the input without reading the source; the variants carry those
//! facts as data, so that callers (and tests) can act on them without parsing messages.

use std::fmt;
use std::path::PathBuf;

/// Errors of asperity. Messages are complete sentences meant for the user.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A mesh file could not be read or is not usable (wrong version, element order, ...).
    #[error("{}: {message}", path.display())]
    Mesh { path: PathBuf, message: String },
    /// A case file could not be read or is inconsistent (TOML syntax, unknown keys, missing
    /// sections). Invalid values of known keys are [`Error::InvalidParameter`].
    #[error("{}: {message}", path.display())]
    Case { path: PathBuf, message: String },
    /// A case-file value is out of its range: `key` is its path in the case
    /// (`contact[2].law.friction`, `body[0].material.nu`, `steps.count`).
    #[error("{}: {key} = {value}: {reason}", path.display())]
    InvalidParameter {
        path: PathBuf,
        key: String,
        value: String,
        reason: String,
    },
    /// The mesh and case do not fit together (missing group, bad element, ...).
    #[error("model: {0}")]
    Model(String),
    /// An external program (gmsh) failed.
    #[error("{0}")]
    External(String),
    /// The linear solver failed (e.g. the stiffness matrix is singular: a body without supports).
    #[error("linear solver: {0}")]
    Linear(String),
    /// A load step did not converge, even after cutting it back.
    #[error("{0}")]
    NoConvergence(Box<NoConvergence>),
    /// One level of a convergence study failed.
    #[error("{}: level {level} (size {size}) failed: {source}", case.display())]
    StudyLevel {
        case: PathBuf,
        level: usize,
        size: f64,
        #[source]
        source: Box<Error>,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// Result with [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// Shorthand for an [`Error::Mesh`].
    pub fn mesh(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Mesh {
            path: path.into(),
            message: message.into(),
        }
    }

    /// Shorthand for an [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// A load step that could not be made to converge: where it stopped and every attempt.
#[derive(Clone, Debug)]
pub struct NoConvergence {
    /// 1-based step number.
    pub step: usize,
    /// Load factor at the end of the step.
    pub load_factor: f64,
    /// Pseudo-time of the last converged state (step j ends at time j).
    pub converged_time: f64,
    /// Global load factor of the last converged state.
    pub converged_load_factor: f64,
    /// Cut-backs made in this step.
    pub cutbacks: usize,
    /// Every attempt of the step, in order.
    pub attempts: Vec<Attempt>,
}

/// One attempted (sub-)increment of a step that failed.
#[derive(Clone, Debug)]
pub struct Attempt {
    /// Pseudo-time the increment tried to reach.
    pub time: f64,
    /// Global load factor at that time.
    pub load_factor: f64,
    /// Newton iterations made.
    pub iterations: usize,
    /// Relative residual before each solve and after the last one.
    pub residuals: Vec<f64>,
    /// Why it stopped when it was not for the iteration limit (e.g. a singular tangent).
    pub reason: Option<String>,
}

impl fmt::Display for NoConvergence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "step {} (load factor {}) did not converge after {} cut-backs; the last converged state is at time \
             {:.6} (load factor {:.6}). Attempts:",
            self.step,
            self.load_factor,
            self.cutbacks,
            self.converged_time,
            self.converged_load_factor
        )?;
        for a in &self.attempts {
            write!(
                f,
                "\n  at time {:.6} (load factor {:.6}): ",
                a.time, a.load_factor
            )?;
            match &a.reason {
                Some(reason) => write!(f, "{reason}")?,
                None => {
                    let residuals: Vec<String> =
                        a.residuals.iter().map(|r| format!("{r:.2e}")).collect();
                    write!(f, "relative residuals {}", residuals.join(", "))?;
                }
            }
        }
        Ok(())
    }
}
