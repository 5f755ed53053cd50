//! The crate's error type. Every error names the file or entity it concerns and what is wrong,
//! so that a user can fix the input without reading the source.

use std::path::PathBuf;

/// Errors of asperity. Messages are complete sentences meant for the user.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A mesh file could not be read or is not usable (wrong version, element order, ...).
    #[error("{}: {message}", path.display())]
    Mesh { path: PathBuf, message: String },
    /// A case file could not be read or is inconsistent.
    #[error("{}: {message}", path.display())]
    Case { path: PathBuf, message: String },
    /// The mesh and case do not fit together (missing group, bad element, ...).
    #[error("model: {0}")]
    Model(String),
    /// An external program (gmsh) failed.
    #[error("{0}")]
    External(String),
    /// The linear solver failed (e.g. the stiffness matrix is singular: a body without supports).
    #[error("linear solver: {0}")]
    Linear(String),
    /// Newton-Raphson did not converge.
    #[error("{0}")]
    NoConvergence(String),
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
