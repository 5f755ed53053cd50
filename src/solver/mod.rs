//! Solvers: the sparse linear solver ([`linear`]), Newton-Raphson for one increment
//! ([`newton`]), the mechanical problem it solves ([`mechanics`]), the run's state
//! ([`state`]) and the drivers that advance it: load stepping ([`stepping`]) and arc-length
//! control ([`arclength`]), with the cycle hooks ([`cycles`]), the energy ledger
//! ([`energy`]), the failure diagnosis ([`diagnosis`]) and the run's floor ([`floor`]).

pub mod arclength;
pub mod condensed;
pub mod conduction;
pub mod coupling;
pub mod cycles;
pub mod diagnosis;
pub mod elastic_cells;
pub mod energy;
pub mod floor;
pub mod interface_lu;
pub mod linear;
pub mod mechanics;
pub mod newton;
pub mod shakedown;
pub mod state;
pub mod stepping;
pub mod strain_bound;
pub mod tree_cholesky;

use faer::sparse::FaerError;

use crate::{Error, Result};

/// Refuses storage of `bytes` (the solver's for a model of `unknowns` unknowns; `what` says
/// for what) when it exceeds the memory this process may still take ([`crate::memory`]),
/// before it is allocated: a clear error instead of a failed allocation or the kernel's
/// out-of-memory kill part way through the run. Nothing is refused where no limit can be
/// read.
pub(crate) fn ensure_memory(
    what: impl FnOnce() -> String,
    unknowns: usize,
    bytes: u64,
) -> Result<()> {
    let room = crate::memory::headroom();
    tracing::debug!(bytes, ?room, "memory check");
    match room {
        Some(room) if bytes > room.bytes => Err(Error::InsufficientMemory {
            what: what(),
            unknowns,
            needed: bytes,
            available: room.bytes,
            limit: room.limit,
        }),
        _ => Ok(()),
    }
}

/// faer's error `e` of the step `what` (for a model of `unknowns` unknowns): a failed
/// allocation as [`Error::allocation_failed`], anything else as a linear-solver error.
pub(crate) fn faer_error(e: FaerError, what: &str, unknowns: usize) -> Error {
    match e {
        FaerError::OutOfMemory => Error::allocation_failed(what, unknowns),
        other => Error::Linear(format!("{what} failed: {other:?}")),
    }
}
