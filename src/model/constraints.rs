//! Supports: prescribed displacements on physical curves and points, and the automatic axis
//! support of axisymmetric models.

use super::{Prescribed, Schedule, boundary_group};
use crate::element::Analysis;
use crate::error::{GroupProblem, MeshEntity};
use crate::mesh::Mesh;
use crate::{Error, Result};

/// A named set of prescribed dofs whose reaction force is reported.
#[derive(Clone, Debug)]
pub struct Support {
    /// The user's name (`name`, else the group).
    pub name: String,
    /// The physical group it holds.
    pub group: String,
    /// Global dofs (2·node + component) this support prescribes.
    pub dofs: Vec<usize>,
    /// (u_x, u_y) at factor 1 (`None`: the component is free).
    pub values: [Option<f64>; 2],
    /// The amplitude in the model's schedule the values follow.
    pub amplitude: usize,
}

impl Support {
    /// Whether it prescribes a non-zero displacement (drives the model).
    pub fn is_driven(&self) -> bool {
        self.values.iter().flatten().any(|&v| v != 0.0)
    }
}

/// Name of the automatic support of axisymmetric models.
pub const AXIS_SUPPORT: &str = "axis";

/// The supports of a model and the dofs they prescribe.
pub(super) struct Constraints {
    /// In case-file order, then the axis support in axisymmetry.
    pub(super) supports: Vec<Support>,
    /// (dof, value at factor 1, amplitude), by dof.
    pub(super) prescribed: Vec<(usize, f64, usize)>,
}

/// Prescribes the supports' components (adding their own histories to `schedule`, in
/// order), then, in axisymmetry, u_r = 0 on the axis. Two supports may prescribe the same
/// component only with the same history.
pub(super) fn prescribe(
    mesh: &Mesh,
    analysis: Analysis,
    specs: &[Prescribed],
    in_body: &[bool],
    scale: f64,
    schedule: &mut Schedule,
) -> Result<Constraints> {
    // Per dof: (value, amplitude, index of the support that set it).
    let mut prescribed: Vec<Option<(f64, usize, usize)>> = vec![None; 2 * mesh.nodes.len()];
    let mut supports = Vec::new();
    for (i, spec) in specs.iter().enumerate() {
        let amplitude = schedule.add(&spec.factors);
        let nodes = support_nodes(mesh, spec, in_body)?;
        let mut dofs = Vec::new();
        for n in nodes {
            for (c, value) in spec.values.into_iter().enumerate() {
                let Some(value) = value else { continue };
                let dof = 2 * n as usize + c;
                match prescribed[dof] {
                    Some((v, k, j))
                        if (v != 0.0 || value != 0.0)
                            && (k != amplitude
                                || (v - value).abs() > 1e-12 * v.abs().max(value.abs())) =>
                    {
                        return Err(Error::ConflictingSupports {
                            first: specs[j].group.clone(),
                            second: spec.group.clone(),
                            component: c,
                            values: [v, value],
                            node: mesh.node_tags[n as usize],
                            position: mesh.nodes[n as usize],
                        });
                    }
                    Some(_) => {}
                    None => {
                        prescribed[dof] = Some((value, amplitude, i));
                        dofs.push(dof);
                    }
                }
            }
        }
        supports.push(Support {
            name: spec.name.clone(),
            group: spec.group.clone(),
            dofs,
            values: spec.values,
            amplitude,
        });
    }
    if analysis.is_axisymmetric() {
        supports.push(axis_support(
            mesh,
            in_body,
            scale,
            &mut prescribed,
            supports.len(),
        )?);
    }
    let prescribed = prescribed
        .iter()
        .enumerate()
        .filter_map(|(d, p)| p.map(|(v, k, _)| (d, v, k)))
        .collect();
    Ok(Constraints {
        supports,
        prescribed,
    })
}

/// The nodes of a support's group, each once, all in a body.
fn support_nodes(mesh: &Mesh, spec: &Prescribed, in_body: &[bool]) -> Result<Vec<u32>> {
    let group = boundary_group(mesh, &spec.group, "support")?;
    let mut nodes: Vec<u32> = if group.dim == 1 {
        mesh.lines_in(group).flat_map(|l| l.nodes).collect()
    } else {
        mesh.points_in(group).collect()
    };
    nodes.sort_unstable();
    nodes.dedup();
    if nodes.is_empty() {
        let kind = group.kind();
        let problem = GroupProblem::Empty;
        return Err(mesh.group_error("support", &spec.group, kind, problem));
    }
    if let Some(&n) = nodes.iter().find(|&&n| !in_body[n as usize]) {
        return Err(Error::NotOnBody {
            role: "support",
            group: spec.group.clone(),
            entity: MeshEntity::Node(mesh.node_tags[n as usize]),
            position: mesh.nodes[n as usize],
        });
    }
    Ok(nodes)
}

/// In axisymmetry nodes on the axis (r = 0 within a relative tolerance) have u_r = 0; nodes
/// at negative r are an input error.
fn axis_support(
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
            return Err(Error::NegativeRadius {
                node: mesh.node_tags[n],
                radius: p[0],
            });
        }
        if p[0] <= tol {
            let dof = 2 * n;
            if let Some((v, _, _)) = prescribed[dof] {
                if v != 0.0 {
                    return Err(Error::AxisDisplacement {
                        node: mesh.node_tags[n],
                        value: v,
                    });
                }
            } else {
                prescribed[dof] = Some((0.0, 0, index));
                dofs.push(dof);
            }
        }
    }
    Ok(Support {
        name: AXIS_SUPPORT.into(),
        group: AXIS_SUPPORT.into(),
        dofs,
        values: [Some(0.0), None],
        amplitude: 0,
    })
}
