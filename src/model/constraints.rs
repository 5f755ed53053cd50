//! Supports: prescribed displacements on physical curves and points (with twist also the
//! circumferential displacement u_θ, or a rigid rotation u_θ = φ r), and the automatic axis
//! support of axisymmetric models.

use super::{Circumferential, Prescribed, Schedule, boundary_group};
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
    /// Global dofs (D·node + component, D the analysis' dofs per node) this support
    /// prescribes.
    pub dofs: Vec<usize>,
    /// (u_x, u_y) at factor 1 (`None`: the component is free).
    pub values: [Option<f64>; 2],
    /// u_θ or the rotation φ at factor 1, with twist (`None`: u_θ is free).
    pub circumferential: Option<Circumferential>,
    /// The amplitude in the model's schedule the values follow.
    pub amplitude: usize,
}

impl Support {
    /// Whether it prescribes a non-zero displacement (drives the model).
    pub fn is_driven(&self) -> bool {
        let theta = self.circumferential.map(Circumferential::value);
        self.values
            .iter()
            .chain([&theta])
            .flatten()
            .any(|&v| v != 0.0)
    }

    /// The value given for component `c` (0: x, 1: y, 2: u_θ or φ), if it is prescribed.
    pub fn value(&self, c: usize) -> Option<f64> {
        match c {
            0 | 1 => self.values[c],
            _ => self.circumferential.map(Circumferential::value),
        }
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
/// order), then, in axisymmetry, u_r = 0 on the axis (and u_θ = 0 with twist). Two supports
/// may prescribe the same component only with the same history.
pub(super) fn prescribe(
    mesh: &Mesh,
    analysis: Analysis,
    specs: &[Prescribed],
    in_body: &[bool],
    scale: f64,
    schedule: &mut Schedule,
) -> Result<Constraints> {
    let d = analysis.dofs_per_node();
    debug_assert!(
        analysis.has_twist() || specs.iter().all(|s| s.circumferential.is_none()),
        "u_θ is prescribed only with twist (checked when the case is read)"
    );
    let axis = 1e-9 * scale;
    // Per dof: (value, amplitude, index of the support that set it).
    let mut prescribed: Vec<Option<(f64, usize, usize)>> = vec![None; d * mesh.nodes.len()];
    let mut supports = Vec::new();
    for (i, spec) in specs.iter().enumerate() {
        let amplitude = schedule.add(&spec.factors);
        let nodes = support_nodes(mesh, spec, in_body)?;
        let mut dofs = Vec::new();
        for n in nodes {
            // A node on the axis turns with no circumferential displacement.
            let r = mesh.nodes[n as usize][0];
            let r = if r.abs() <= axis { 0.0 } else { r };
            let theta = spec.circumferential.map(|t| t.at(r));
            for (c, value) in spec.values.into_iter().chain([theta]).enumerate() {
                let Some(value) = value else { continue };
                let dof = d * n as usize + c;
                match prescribed[dof] {
                    Some((v, k, j))
                        if (v != 0.0 || value != 0.0)
                            && (k != amplitude
                                || (v - value).abs() > 1e-12 * v.abs().max(value.abs())) =>
                    {
                        return Err(Error::ConflictingSupports {
                            first: specs[j].name.clone(),
                            second: spec.name.clone(),
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
            circumferential: spec.circumferential,
            amplitude,
        });
    }
    if analysis.is_axisymmetric() {
        supports.push(axis_support(
            mesh,
            analysis,
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

/// In axisymmetry nodes on the axis (r = 0 within a relative tolerance) have u_r = 0, and
/// with twist u_θ = 0 (a circumferential displacement on the axis would tear the material
/// there: γ_rθ = ∂u_θ/∂r − u_θ/r); nodes at negative r are an input error.
fn axis_support(
    mesh: &Mesh,
    analysis: Analysis,
    in_body: &[bool],
    scale: f64,
    prescribed: &mut [Option<(f64, usize, usize)>],
    index: usize,
) -> Result<Support> {
    let tol = 1e-9 * scale;
    let (d, twist) = (analysis.dofs_per_node(), analysis.has_twist());
    let held: &[usize] = if twist { &[0, 2] } else { &[0] };
    let mut dofs = Vec::new();
    for (n, p) in mesh.nodes.iter().enumerate().filter(|&(n, _)| in_body[n]) {
        if p[0] < -tol {
            return Err(Error::NegativeRadius {
                node: mesh.node_tags[n],
                radius: p[0],
            });
        }
        if p[0] > tol {
            continue;
        }
        for &c in held {
            let dof = d * n + c;
            if let Some((v, _, _)) = prescribed[dof] {
                if v != 0.0 {
                    return Err(Error::AxisDisplacement {
                        node: mesh.node_tags[n],
                        component: c,
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
        circumferential: twist.then_some(Circumferential::Displacement(0.0)),
        amplitude: 0,
    })
}
