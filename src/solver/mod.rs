//! Solvers: the sparse linear solver ([`linear`]), Newton-Raphson for one increment
//! ([`newton`]), the mechanical problem it solves ([`mechanics`]) and the load stepping that
//! drives it ([`stepping`]).

pub mod arclength;
pub mod condensed;
pub mod cycles;
pub mod energy;
pub mod linear;
pub mod mechanics;
pub mod newton;
pub mod stepping;
