//! The process's stop request: the CLI sets it on the first Ctrl-C, SIGTERM or SIGHUP
//! ([`request_stop`]); a run's drivers stop after their current increment when it is set,
//! and a wait for a child program (gmsh) stops the child. Importing nothing of the crate, it
//! sits below every module that reads it.

use std::sync::atomic::{AtomicBool, Ordering};

/// Whether the process was asked to stop ([`request_stop`]).
static STOP_REQUESTED: AtomicBool = AtomicBool::new(false);

/// Asks the run in progress to stop after its current increment, its converged steps' files
/// complete. Returns whether a stop had been asked for already (the CLI then exits at once).
pub fn request_stop() -> bool {
    STOP_REQUESTED.swap(true, Ordering::SeqCst)
}

/// Whether a stop was asked for ([`request_stop`]).
pub fn stop_requested() -> bool {
    STOP_REQUESTED.load(Ordering::SeqCst)
}
