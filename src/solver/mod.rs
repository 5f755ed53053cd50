//! Solvers: the sparse linear solver ([`linear`]), Newton-Raphson for one increment
//! ([`newton`]), the mechanical problem it solves ([`mechanics`]), the run's state
//! ([`state`]) and the drivers that advance it: load stepping ([`stepping`]) and arc-length
//! control ([`arclength`]), with the cycle hooks ([`cycles`]), the energy ledger
//! ([`energy`]), the failure diagnosis ([`diagnosis`]) and the run's floor ([`floor`]).

pub mod arclength;
pub mod condensed;
pub mod coupling;
pub mod cycles;
pub mod diagnosis;
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
