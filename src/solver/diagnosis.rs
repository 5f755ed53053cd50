//! Why a run failed, in the user's terms: where the out-of-balance force of the last attempt
//! sits, whether a contact pair's friction cannot carry its load or a body lacks support
//! ([`diagnose`]); whether a converged increment is implausible for small-strain theory
//! ([`implausible_increment`]); and whether a failed step is a plastic collapse
//! ([`step_failure`]).

use crate::Error;
use crate::contact::ContactStatus;
use crate::element::set::{ElementSet, INTERFACE_POINTS};
use crate::error::{NoConvergence, ResidualAt};
use crate::model::Model;
use crate::solver::state::{Solution, StiffnessHistory};

/// Completes `failure` with where it happened: the node with the largest out-of-balance
/// force of the last attempt (and its body), how many interface points changed their
/// contact status against the last converged state, and a physical reading where one is
/// recognisable (a contact pair slipping everywhere: its friction cannot carry the load).
pub fn diagnose(
    model: &Model,
    solution: &Solution,
    f_ext: &[f64],
    f_int: &[f64],
    mut failure: NoConvergence,
) -> NoConvergence {
    failure.largest_residual = largest_residual(model, f_ext, f_int);
    failure.status_changes = solution
        .interface_trial
        .iter()
        .zip(&solution.interface_committed)
        .filter(|(t, c)| t.status != c.status)
        .count();
    failure.hint = friction_exceeded(model, solution).or_else(|| unsupported_bodies(model));
    failure
}

/// The free node with the largest out-of-balance force |f_ext − f_int|, with its body.
fn largest_residual(model: &Model, f_ext: &[f64], f_int: &[f64]) -> Option<ResidualAt> {
    let mut best: Option<(usize, [f64; 2])> = None;
    let mut best_norm = 0.0;
    for (node, (e, i)) in f_ext.chunks_exact(2).zip(f_int.chunks_exact(2)).enumerate() {
        let mut r = [0.0; 2];
        for c in 0..2 {
            if model.dofs.equation(2 * node + c).is_some() {
                r[c] = e[c] - i[c];
            }
        }
        let size = r[0].hypot(r[1]);
        if size.is_finite() && size > best_norm {
            best_norm = size;
            best = Some((node, r));
        }
    }
    let (node, force) = best?;
    Some(ResidualAt {
        node: model
            .mesh
            .node_tags
            .get(node)
            .copied()
            .unwrap_or(node as u64),
        position: model.mesh.nodes[node],
        body: body_of_node(model, node),
        force,
    })
}

/// The name of a body that `node` belongs to.
fn body_of_node(model: &Model, node: usize) -> Option<String> {
    let cells = &model.continuum.cells;
    (0..cells.len())
        .find(|&e| model.continuum.nodes(e).contains(&(node as u32)))
        .map(|e| model.bodies[cells[e].body as usize].clone())
}

/// "Friction capacity exceeded" when, in the last attempt, every closed point of a contact
/// pair slips: the pair transmits at most μ·|p_N| everywhere and the tangential load asks
/// for more (Buczkowski & Kleiber (1994), Eq. 11: F = 0 at every point).
fn friction_exceeded(model: &Model, solution: &Solution) -> Option<String> {
    let pairs: Vec<&str> = model
        .interface
        .pairs
        .iter()
        .filter(|p| {
            let points = &solution.interface_trial
                [p.elements.start * INTERFACE_POINTS..p.elements.end * INTERFACE_POINTS];
            let closed = points.iter().filter(|s| s.status != ContactStatus::Open);
            let mut any = false;
            closed.clone().all(|s| {
                any = true;
                s.status == ContactStatus::Slip
            }) && any
        })
        .map(|p| p.name.as_str())
        .collect();
    (!pairs.is_empty()).then(|| {
        format!(
            "friction capacity exceeded: every closed point of contact '{}' slips, so friction \
             cannot carry the tangential load there (raise the friction or the normal load, or \
             support the sliding body)",
            pairs.join("', '")
        )
    })
}

/// "A body without support" when a group of bodies joined by shared nodes or interface
/// elements has no prescribed dof in x or in y: nothing stops its rigid translation.
fn unsupported_bodies(model: &Model) -> Option<String> {
    let nodes = model.mesh.nodes.len();
    let mut parent: Vec<usize> = (0..nodes).collect();
    fn root(parent: &mut [usize], mut n: usize) -> usize {
        while parent[n] != n {
            parent[n] = parent[parent[n]];
            n = parent[n];
        }
        n
    }
    let mut join = |nodes: &[u32]| {
        let first = root(&mut parent, nodes[0] as usize);
        for &n in &nodes[1..] {
            let r = root(&mut parent, n as usize);
            parent[r] = first;
        }
    };
    for e in 0..model.continuum.cells.len() {
        join(model.continuum.nodes(e));
    }
    for e in 0..model.interface.elements.len() {
        join(model.interface.nodes(e));
    }
    let mut held = vec![[false; 2]; nodes];
    for &(dof, _, _) in &model.prescribed {
        let r = root(&mut parent, dof / 2);
        held[r][dof % 2] = true;
    }
    let mut free: Vec<(String, &str)> = Vec::new();
    for cell in &model.continuum.cells {
        let r = root(&mut parent, cell.nodes[0] as usize);
        let body = &model.bodies[cell.body as usize];
        let missing = match held[r] {
            [false, false] => "x and y",
            [false, true] => "x",
            [true, false] => "y",
            [true, true] => continue,
        };
        if !free.iter().any(|(b, _)| b == body) {
            free.push((body.clone(), missing));
        }
    }
    (!free.is_empty()).then(|| {
        let list: Vec<String> = free
            .iter()
            .map(|(b, m)| format!("'{b}' (free to move in {m})"))
            .collect();
        format!(
            "a body without support: {} — no support holds it, directly or through another \
             body or a contact interface, against rigid-body motion",
            list.join(", ")
        )
    })
}

/// Why a converged increment from `converged_u` to `solution` is implausible for
/// small-strain theory, if it is: a nodal displacement increment larger than
/// `[solver] max_displacement_increment` × the model size, or an equivalent strain increment
/// √(⅔ Δε:Δε) larger than `[solver] max_strain_increment` at an integration point. Such an
/// "equilibrium" is a locked mesh or a mechanism, not an answer.
pub fn implausible_increment(
    model: &Model,
    solution: &Solution,
    converged_u: &[f64],
) -> Option<String> {
    let control = &model.control;
    let limit = control.max_displacement_increment * model.size;
    let (node, du) = solution
        .u
        .chunks_exact(2)
        .zip(converged_u.chunks_exact(2))
        .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
        .enumerate()
        .fold(
            (0, 0.0),
            |best, (n, d)| if d > best.1 { (n, d) } else { best },
        );
    if !du.is_finite() || du > limit {
        return Some(format!(
            "implausible increment: node {} moves by {du:.3e} mm in one increment, more than \
             {} of the model size {:.3e} mm ([solver] max_displacement_increment); small-strain \
             theory does not hold there (a collapse mechanism, or a locked mesh)",
            model
                .mesh
                .node_tags
                .get(node)
                .copied()
                .unwrap_or(node as u64),
            control.max_displacement_increment,
            model.size
        ));
    }
    let de = solution
        .trial
        .iter()
        .zip(&solution.committed)
        .map(|(t, c)| equivalent_strain(&(t.strain - c.strain)))
        .fold(0.0, f64::max);
    if !de.is_finite() || de > control.max_strain_increment {
        return Some(format!(
            "implausible increment: an equivalent strain increment of {de:.3e}, more than {} \
             ([solver] max_strain_increment); small-strain theory does not hold there (a \
             collapse mechanism, or a locked mesh)",
            control.max_strain_increment
        ));
    }
    None
}

/// √(⅔ ε:ε) of a strain in Voigt order (xx, yy, γ_xy, zz), γ the engineering shear strain.
fn equivalent_strain(e: &crate::material::Voigt) -> f64 {
    let tensor = e[0] * e[0] + e[1] * e[1] + e[3] * e[3] + 0.5 * e[2] * e[2];
    (2.0 / 3.0 * tensor).sqrt()
}

/// The error of a step that could not be completed: [`Error::Collapse`] when the load was
/// rising and the structure's stiffness collapsed — the secant stiffness of the last
/// converged increment fell below `[solver] collapse_stiffness_ratio` of the first one, or
/// (with a plastic body) an attempt met a tangent that is not positive definite or an
/// implausible increment — and [`Error::NoConvergence`] otherwise.
pub fn step_failure(model: &Model, failure: NoConvergence, stiffness: &StiffnessHistory) -> Error {
    let converged = failure.converged_load_factor;
    let failed = failure
        .attempts
        .last()
        .map_or(failure.load_factor, |a| a.load_factor);
    let rising = failed.abs() > converged.abs();
    let ratio = stiffness.ratio();
    let reasons = |pattern: &str| {
        failure
            .attempts
            .iter()
            .any(|a| a.reason.as_deref().is_some_and(|r| r.contains(pattern)))
    };
    let indicator = if let Some(r) = ratio.filter(|&r| r < model.control.collapse_stiffness_ratio) {
        Some(format!(
            "the secant stiffness fell to {r:.2e} of the first increment's"
        ))
    } else if model.control.plastic && reasons("not positive definite") {
        Some("the tangent of the plastic model lost positive definiteness".to_string())
    } else if model.control.plastic && reasons("implausible increment") {
        Some("the plastic model only converged to implausibly large increments".to_string())
    } else {
        None
    };
    match indicator {
        Some(indicator) if rising => Error::Collapse {
            step: failure.step,
            converged_load_factor: converged,
            failed_load_factor: failed,
            indicator,
            details: Box::new(failure),
        },
        _ => Error::NoConvergence(Box::new(failure)),
    }
}
