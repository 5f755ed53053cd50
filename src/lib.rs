//! # asperity
//!
//! Finite-element analysis of 2D plane and axisymmetric contact between elastic or
//! elasto-plastic bodies whose joint has its own compliance and friction, after
//! R. Buczkowski & M. Kleiber, *Elasto-plastic constitutive interface model for an
//! axisymmetric contact problem* (1994), called "the paper" in these docs.
//!
//! ## Pipeline
//! Data flows one way: gmsh geometry → [`mesh::Mesh`] (MSH 4.1 reader) → [`model::Model`]
//! (bodies, materials, supports, loads, degrees of freedom) → [`solver`] (incremental
//! Newton-Raphson over load steps, sparse Cholesky from `faer`) → [`output`] (VTU/PVD, CSV).
//! [`run::run`] strings these together for a [`config::Case`] file; [`study`] runs a
//! case at several mesh sizes and checks the convergence of quantities of interest.
//! `ARCHITECTURE.md` says what each module owns.
//!
//! ## Conventions
//! - Units: mm, N, MPa (N/mm²) throughout.
//! - Coordinates: plane analyses use (x, y); axisymmetric ones use x = r, y = z with the
//!   axis at r = 0.
//! - Voigt order of stress and strain inside the solver: (xx, yy, xy, zz), i.e. in
//!   axisymmetry (rr, zz, rz, θθ); engineering shear strain γ_xy = 2ε_xy. Output tensors use
//!   ParaView's six-component order (xx, yy, zz, xy, yz, xz).
//! - Contact sign convention (paper): normal contact stress p_N < 0 in compression; relative
//!   displacement = body B minus body A.

pub mod assembly;
pub mod config;
pub mod contact;
pub mod element;
pub mod error;
pub mod fit;
pub mod init;
pub mod material;
pub mod memory;
pub mod mesh;
pub mod model;
pub mod output;
pub mod post;
pub mod python;
pub mod reference;
pub mod run;
pub mod solver;
pub mod stop;
pub mod study;
pub mod sweep;
pub mod thermal;

pub use error::{Error, Result};
