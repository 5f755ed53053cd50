//! Elements: shape functions ([`shape`]), quadrature rules ([`quadrature`]), the analysis
//! type that decides thickness, hoop strain and volume measure ([`Analysis`]), the 2D
//! continuum element ([`continuum`]), the interface element ([`interface6`]) and what one
//! element evaluation reads and writes ([`ElementInput`], [`ElementOutput`]).
//!
//! All element matrices are fixed 24×24 (8 nodes × at most 3 degrees of freedom: u_x, u_y
//! and, in an axisymmetric analysis with twist, u_θ); an element uses the leading block of
//! its nodes × [`Analysis::dofs_per_node`] (16×16 for a quad8 without twist). Fixed sizes
//! let nalgebra keep them on the stack, so assembly allocates nothing per element.

pub mod continuum;
pub mod interface6;
pub mod kinematics;
pub mod quadrature;
pub mod set;
pub mod shape;
mod small;
pub mod thermal_load;

use nalgebra::{SMatrix, SVector};
use serde::Deserialize;

use crate::contact::ContactAlgorithm;

/// Largest number of nodes of one element (quad8).
pub const MAX_ELEMENT_NODES: usize = 8;

/// Largest number of dofs of one element: 8 nodes × 3 components.
pub const MAX_ELEMENT_DOFS: usize = MAX_ELEMENT_NODES * 3;

/// Element stiffness (tangent) matrix, dof order node by node, (u_x1, u_y1, u_x2, ...)
/// or with twist (u_r1, u_z1, u_θ1, u_r2, ...): element dof D·i + c of node i, component c.
pub type ElementMatrix = SMatrix<f64, MAX_ELEMENT_DOFS, MAX_ELEMENT_DOFS>;
/// Element force or displacement vector in the same dof order.
pub type ElementVector = SVector<f64, MAX_ELEMENT_DOFS>;

/// What one element evaluation reads: its nodal displacements, the integration-point states
/// of the last converged increment, and the choices of the global iteration.
#[derive(Clone, Copy, Debug)]
pub struct ElementInput<'a, S> {
    /// Nodal displacements in [`ElementVector`] dof order.
    pub u: &'a ElementVector,
    /// States committed at the last converged increment, one per integration point.
    pub committed: &'a [S],
    /// Which interface tangent the global iterations use (Buczkowski & Kleiber (1994),
    /// §2.4). A setting of the solver, not of the model, so it travels with the assembly;
    /// continuum cells ignore it.
    pub algorithm: ContactAlgorithm,
}

/// What one element evaluation writes: the updated integration-point states, the internal
/// force and, when asked for, the tangent. Force and tangent are added to, not overwritten.
#[derive(Debug)]
pub struct ElementOutput<'a, S> {
    /// Trial states of the current iteration, one per integration point.
    pub trial: &'a mut [S],
    /// Tangent, or `None` for residual-only evaluations (line search).
    pub k: Option<&'a mut ElementMatrix>,
    /// Internal force, or `None` where only the trial states are wanted (a converged
    /// state's point states, a tangent alone).
    pub f: Option<&'a mut ElementVector>,
}

/// The 2D idealisation of the 3D problem.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Analysis {
    /// σ_zz = 0; the out-of-plane strain follows from the material. `thickness` in mm.
    PlaneStress { thickness: f64 },
    /// ε_zz = 0. `thickness` in mm (forces are per this thickness; default 1).
    PlaneStrain {
        #[serde(default = "unit_thickness")]
        thickness: f64,
    },
    /// Axisymmetric about the y axis: x = r, y = z, hoop strain ε_θθ = u_r / r.
    /// Forces are totals over the full circle (2πr weighting).
    Axisymmetric,
    /// Axisymmetric with twist (Abaqus' CGAX): every node also has the circumferential
    /// displacement u_θ, the strains gain γ_rθ = ∂u_θ/∂r − u_θ/r and γ_zθ = ∂u_θ/∂z, and
    /// the stress state has all six components; the geometry and the loads stay
    /// independent of θ, so a torque about the axis can be carried.
    AxisymmetricTwist,
}

fn unit_thickness() -> f64 {
    1.0
}

impl Analysis {
    /// Factor that turns an in-plane area (or length) integral into a volume (or area)
    /// integral at radius `r`: the thickness, or 2πr in axisymmetry (Buczkowski & Kleiber
    /// (1994), Eq. 37).
    #[inline]
    pub fn measure(&self, r: f64) -> f64 {
        match *self {
            Analysis::PlaneStress { thickness } | Analysis::PlaneStrain { thickness } => thickness,
            Analysis::Axisymmetric | Analysis::AxisymmetricTwist => 2.0 * std::f64::consts::PI * r,
        }
    }

    /// Whether the out-of-plane stress vanishes (plane stress) rather than the out-of-plane
    /// strain being given by the kinematics (plane strain, axisymmetry).
    #[inline]
    pub fn is_plane_stress(&self) -> bool {
        matches!(self, Analysis::PlaneStress { .. })
    }

    /// Whether this is an axisymmetric analysis (with or without twist).
    #[inline]
    pub fn is_axisymmetric(&self) -> bool {
        matches!(self, Analysis::Axisymmetric | Analysis::AxisymmetricTwist)
    }

    /// Whether the nodes carry the circumferential displacement u_θ (axisymmetry with twist).
    #[inline]
    pub fn has_twist(&self) -> bool {
        matches!(self, Analysis::AxisymmetricTwist)
    }

    /// Displacement components per node, D: 2 (u_x, u_y), or 3 with twist (u_r, u_z, u_θ).
    /// Node n's global dof of component c is D·n + c.
    #[inline]
    pub fn dofs_per_node(&self) -> usize {
        if self.has_twist() { 3 } else { 2 }
    }

    /// Short name for logs and reports.
    pub fn name(&self) -> &'static str {
        match self {
            Analysis::PlaneStress { .. } => "plane stress",
            Analysis::PlaneStrain { .. } => "plane strain",
            Analysis::Axisymmetric => "axisymmetric",
            Analysis::AxisymmetricTwist => "axisymmetric with twist",
        }
    }
}
