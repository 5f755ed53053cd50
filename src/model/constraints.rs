//! Supports: prescribed displacements on physical curves and points, and the automatic axis
//! support of axisymmetric models.

use super::boundary_group;
use crate::config::SupportSpec;
use crate::mesh::Mesh;
use crate::{Error, Result};

/// A named set of prescribed dofs whose reaction force is reported.
#[derive(Clone, Debug)]
pub struct Support {
    pub name: String,
    /// Global dofs (2·node + component) this support prescribes.
    pub dofs: Vec<usize>,
}

/// Name of the automatic support of axisymmetric models.
pub const AXIS_SUPPORT: &str = "axis";

pub(super) fn support_nodes(mesh: &Mesh, spec: &SupportSpec, in_body: &[bool]) -> Result<Vec<u32>> {
    let group = boundary_group(mesh, &spec.group, "support")?;
    let mut nodes: Vec<u32> = if group.dim == 1 {
        mesh.lines_in(group).flat_map(|l| l.nodes).collect()
    } else {
        mesh.points_in(group).collect()
    };
    nodes.sort_unstable();
    nodes.dedup();
    if nodes.is_empty() {
        return Err(Error::Model(format!(
            "support '{}': the group has no elements",
            spec.group
        )));
    }
    if let Some(&n) = nodes.iter().find(|&&n| !in_body[n as usize]) {
        return Err(Error::Model(format!(
            "support '{}': node {} at {:?} belongs to no body",
            spec.group, mesh.node_tags[n as usize], mesh.nodes[n as usize]
        )));
    }
    Ok(nodes)
}

/// In axisymmetry nodes on the axis (r = 0 within a relative tolerance) have u_r = 0; nodes
/// at negative r are an input error.
pub(super) fn axis_support(
    mesh: &Mesh,
    in_body: &[bool],
    scale: f64,
    prescribed: &mut [Option<(f64, usize, usize)>],
    index: usize,
) -> Result<Support> {
    let tol = 1e-9 * scale;
    let mut dofs = Vec::new();
    for (n, p) in mesh.nodes.iter().enumerate().filter(|&(n, _)| in_body[n]) {
        if p[0] < -tol {
            return Err(Error::Model(format!(
                "axisymmetric model: node {} lies at negative radius r = {} (the axis is x = r = 0)",
                mesh.node_tags[n], p[0]
            )));
        }
        if p[0] <= tol {
            let dof = 2 * n;
            if let Some((v, _, _)) = prescribed[dof] {
                if v != 0.0 {
                    return Err(Error::Model(format!(
                        "node {} on the axis has a prescribed radial displacement {v}; it must be 0",
                        mesh.node_tags[n]
                    )));
                }
            } else {
                prescribed[dof] = Some((0.0, 0, index));
                dofs.push(dof);
            }
        }
    }
    Ok(Support {
        name: AXIS_SUPPORT.into(),
        dofs,
    })
}
