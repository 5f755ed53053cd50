//! The backstress output of kinematic hardening: the yield surface's centre α = Σ α_k
//! recovered to the nodes like the stress (least-squares extrapolation of each cell's
//! integration-point values, averaged over the cells of one body at a node), as the point
//! fields `backstress` (a symmetric tensor with the stress's component names) and
//! `backstress_von_mises` (√(3/2 α:α), the centre's distance from the origin in stress units).
//! A model without kinematic hardening has neither field.

use super::{BodyPoints, extrapolation};
use crate::material::Voigt;
use crate::material::cyclic::centre_norm;
use crate::model::Model;
use crate::output::{Field, tensor_component_names, vtk_tensor};
use crate::solver::state::InternalVariables;

/// The backstress fields of the bodies' grid at the committed internal variables (none
/// without internal variables).
pub fn fields(model: &Model, points: &BodyPoints, internal: &InternalVariables) -> Vec<Field> {
    if internal.layout.is_empty() {
        return Vec::new();
    }
    let nodal = nodal_backstress(model, points, internal);
    // Solver order → VTK order, tensor shear.
    let tensor = nodal.iter().flat_map(|a| vtk_tensor(a, 1.0)).collect();
    let names = tensor_component_names(model.analysis.is_axisymmetric());
    vec![
        Field::tensor("backstress", tensor, names),
        Field::scalar(
            "backstress_von_mises",
            nodal.iter().map(centre_norm).collect(),
        ),
    ]
}

/// The total backstress per output point (zero in bodies without kinematic hardening).
fn nodal_backstress(
    model: &Model,
    points: &BodyPoints,
    internal: &InternalVariables,
) -> Vec<Voigt> {
    let mut out = vec![Voigt::zeros(); points.points.len()];
    let mut count = vec![0u32; points.points.len()];
    let continuum = &model.continuum;
    for (e, c) in continuum.cells.iter().enumerate() {
        let material = continuum.materials[c.body as usize].as_ref();
        let stride = material.internal_variables();
        let range = internal.layout.range(e);
        let centres: Vec<Voigt> = if stride == 0 {
            Vec::new()
        } else {
            internal.committed[range]
                .chunks_exact(stride)
                .map(|point| material.backstress(point))
                .collect()
        };
        let ex = extrapolation(c.kind);
        for (i, &n) in c.nodes[..c.kind.node_count()].iter().enumerate() {
            let p = points.point(c.body, n);
            for (g, alpha) in centres.iter().enumerate() {
                out[p] += ex[(i, g)] * alpha;
            }
            count[p] += 1;
        }
    }
    for (v, &k) in out.iter_mut().zip(&count) {
        *v /= k as f64;
    }
    out
}
