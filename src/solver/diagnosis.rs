//! Why a run failed, in the user's terms: where the out-of-balance force of the last attempt
//! sits, and which mechanism the contact states of that attempt show — a contact whose
//! friction cannot carry the load, or bodies that lost their support when a contact opened
//! ([`diagnose`], with the model's rigid-body check [`Model::free_bodies_with`]); whether a
//! converged increment is implausible for small-strain theory ([`implausible_increment`]);
//! and whether a failed step is a limit load — such a mechanism, or a plastic collapse — or
//! a failure of the solver ([`step_failure`]); and which input drove its values beyond the
//! range of double precision, when one did (`out_of_range`).

use crate::Error;
use crate::element::quadrature::MAX_CELL_POINTS;
use crate::element::set::{ElementSet, INTERFACE_POINTS};
use crate::error::{AttemptFailure, FreeBody, Implausible, Mechanism, NoConvergence, ResidualAt};
use crate::model::{Hold, Model};
use crate::solver::state::{Solution, StiffnessHistory};

/// The largest magnitude a force, a stress, a stiffness or a displacement may have for the
/// solver's norms, which square such values, to stay finite in double precision
/// (√(1.8e308) ≈ 1.3e154). Beyond it a residual becomes infinite or NaN and Newton's method
/// cannot converge, whatever the increment.
const FLOAT_RANGE: f64 = 1e150;

/// The first quantity of an interface point's state beyond [`FLOAT_RANGE`]: its symbol, value
/// and unit.
fn interface_out_of_range(
    s: &crate::contact::InterfaceState,
) -> Option<(&'static str, f64, &'static str)> {
    [
        ("u_N", s.relative[1], "mm"),
        ("p_N", s.stress[1], "MPa"),
        ("k_N", s.stiffness[1], "MPa/mm"),
        ("u_T", s.relative[0], "mm"),
        ("p_T", s.stress[0], "MPa"),
        ("k_T", s.stiffness[0], "MPa/mm"),
        ("u_θ", s.relative[2], "mm"),
        ("p_θ", s.stress[2], "MPa"),
    ]
    .into_iter()
    .find(|&(_, value, _)| beyond_range(value))
}

/// Whether `x` is NaN, infinite or beyond [`FLOAT_RANGE`].
fn beyond_range(x: f64) -> bool {
    x.is_nan() || x.abs() > FLOAT_RANGE
}

/// Completes `failure` with where it happened: the node with the largest out-of-balance
/// force of the last attempt (and its body), how many interface points changed their
/// contact status against the last converged state, and the mechanism its contact states
/// show, if any (`contact_mechanism`) — or, when the last attempt's values went beyond the
/// range of double precision, the input that drove them there (`out_of_range`), the
/// contact states being meaningless then.
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
    failure.out_of_range = out_of_range(model, solution, f_ext);
    if failure.out_of_range.is_none() {
        failure.mechanism = contact_mechanism(model, solution);
    }
    failure
}

/// The input that drove the last attempt's values beyond [`FLOAT_RANGE`], named by its
/// case-file key, checked from the most direct: the applied loads (`[[load]]` values times
/// `[analysis] thickness`), a support's prescribed values, a contact law's stresses and
/// stiffnesses (its parameters and `interference`), a body's stresses (its material).
fn out_of_range(model: &Model, solution: &Solution, f_ext: &[f64]) -> Option<String> {
    let d = model.analysis.dofs_per_node();
    let tag = |node: usize| {
        model
            .mesh
            .node_tags
            .get(node)
            .copied()
            .unwrap_or(node as u64)
    };
    if let Some((dof, f)) = f_ext.iter().enumerate().find(|(_, f)| beyond_range(**f)) {
        return Some(format!(
            "the applied loads reach {f:.3e} N at node {}: check the [[load]] values, \
             [analysis] thickness and the steps' factors",
            tag(dof / d)
        ));
    }
    // The values the supports prescribe in the last attempt: their values times the
    // multipliers (amplitudes, step factors) at its time.
    let prescribed = |s: &crate::model::Support| {
        s.dofs
            .iter()
            .map(|&dof| solution.u[dof])
            .find(|&v| beyond_range(v))
    };
    if let Some((support, value)) = model
        .supports
        .iter()
        .find_map(|s| prescribed(s).map(|v| (s, v)))
    {
        return Some(format!(
            "[[support]] '{}' prescribes {value:.3e}: check its values and the multipliers \
             (amplitudes, steps' factors) applied to it",
            support.name
        ));
    }
    for pair in &model.interface.pairs {
        let points = &solution.interface_trial
            [pair.elements.start * INTERFACE_POINTS..pair.elements.end * INTERFACE_POINTS];
        if let Some((name, value, unit)) = points.iter().find_map(interface_out_of_range) {
            // Parameters as given, a huge one in exponent form.
            return Some(crate::error::shorten_numbers(&format!(
                "contact '{}' ({}; interference {} mm) reaches {name} = {value:.3e} {unit}: \
                 check its law's parameters and interference (units: \
                 docs/guide/contact-laws.md)",
                pair.name,
                pair.describe(),
                pair.interference,
            )));
        }
    }
    let cells = &model.continuum.cells;
    let stressed = (0..cells.len()).find(|&e| {
        solution.trial[e * MAX_CELL_POINTS..(e + 1) * MAX_CELL_POINTS]
            .iter()
            .any(|p| p.stress.iter().any(|&x| beyond_range(x)))
    });
    if let Some(e) = stressed {
        let body = &model.bodies[cells[e].body as usize];
        return Some(format!(
            "body '{body}' reaches stresses beyond that range: check its material ({})",
            crate::error::shorten_numbers(
                &model.continuum.materials[cells[e].body as usize].describe()
            )
        ));
    }
    None
}

/// The free node with the largest out-of-balance force |f_ext − f_int|, with its body.
fn largest_residual(model: &Model, f_ext: &[f64], f_int: &[f64]) -> Option<ResidualAt> {
    let d = model.analysis.dofs_per_node();
    let mut best: Option<(usize, [f64; 3])> = None;
    let mut best_norm = 0.0;
    for (node, (e, i)) in f_ext.chunks_exact(d).zip(f_int.chunks_exact(d)).enumerate() {
        let mut r = [0.0; 3];
        for c in 0..d {
            if model.dofs.equation(d * node + c).is_some() {
                r[c] = e[c] - i[c];
            }
        }
        let size = r[0].hypot(r[1]).hypot(r[2]);
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

/// The mechanism the contact states of the last attempt show, from the rigid-body check
/// with the contacts holding as they do in that attempt:
/// - *loss of support* when bodies are free even with every closed point holding as
///   defined (the contacts that held them opened);
/// - *friction capacity exceeded* when bodies are free once slipping points hold only normal
///   to the contact: friction transmits at most μ|p_N| there (Buczkowski & Kleiber (1994),
///   Eq. 11: F = 0 at every point), and nothing else holds them along it.
fn contact_mechanism(model: &Model, solution: &Solution) -> Option<Mechanism> {
    let states = &solution.interface_trial;
    let lost = model.free_bodies_with(|e| model.hold_in(states, e, true));
    if !lost.is_empty() {
        let open_pairs = touching(model, &lost, |e| {
            model.hold_in(states, e, true) == Hold::None
        });
        return Some(Mechanism::LostSupport {
            open_pairs,
            bodies: lost,
        });
    }
    let sliding = model.free_bodies_with(|e| model.hold_in(states, e, false));
    if sliding.is_empty() {
        return None;
    }
    let pairs = touching(model, &sliding, |e| {
        model.hold_in(states, e, true) == Hold::Full
            && model.hold_in(states, e, false) != Hold::Full
    });
    Some(Mechanism::FrictionCapacity {
        pairs,
        bodies: sliding,
    })
}

/// The contact pairs with an interface element `which` selects that touches one of `bodies`.
fn touching(model: &Model, bodies: &[FreeBody], which: impl Fn(usize) -> bool) -> Vec<String> {
    let node_bodies = model.node_bodies();
    let free: Vec<usize> = bodies
        .iter()
        .filter_map(|b| model.bodies.iter().position(|name| *name == b.body))
        .collect();
    let touches = |e: usize| {
        let nodes = &model.interface.elements[e].nodes;
        nodes
            .iter()
            .any(|&n| node_bodies[n as usize].iter().any(|b| free.contains(b)))
    };
    model
        .interface
        .pairs
        .iter()
        .filter(|pair| pair.elements.clone().any(|e| which(e) && touches(e)))
        .map(|pair| pair.name.clone())
        .collect()
}

/// Why a converged increment from `converged_u` to `solution` is implausible for
/// small-strain theory, if it is: a nodal displacement increment larger than
/// `[solver] max_displacement_increment` × the model size, or an equivalent strain increment
/// √(⅔ Δε:Δε) larger than `[solver] max_strain_increment` at an integration point (the
/// increment's `strain_increment`, from its pass over the point states,
/// [`crate::solver::state::Solution::scan_increment`]). Such an "equilibrium" is a locked
/// mesh or a mechanism, not an answer.
pub fn implausible_increment(
    model: &Model,
    solution: &Solution,
    converged_u: &[f64],
    strain_increment: f64,
) -> Option<Implausible> {
    let control = &model.control;
    let limit = control.max_displacement_increment * model.size;
    // A node's whole displacement increment (u_θ's too, with twist).
    let d = model.analysis.dofs_per_node();
    let (node, du) = solution
        .u
        .chunks_exact(d)
        .zip(converged_u.chunks_exact(d))
        .map(|(a, b)| {
            let plane = (a[0] - b[0]).hypot(a[1] - b[1]);
            a.iter()
                .zip(b)
                .skip(2)
                .fold(plane, |m, (a, b)| m.hypot(a - b))
        })
        .enumerate()
        .fold(
            (0, 0.0),
            |best, (n, d)| if d > best.1 { (n, d) } else { best },
        );
    if !du.is_finite() || du > limit {
        return Some(Implausible::Displacement {
            node: model
                .mesh
                .node_tags
                .get(node)
                .copied()
                .unwrap_or(node as u64),
            increment: du,
            fraction: control.max_displacement_increment,
            size: model.size,
        });
    }
    let de = strain_increment;
    (!de.is_finite() || de > control.max_strain_increment).then_some(Implausible::Strain {
        increment: de,
        limit: control.max_strain_increment,
    })
}

/// The error of a step that could not be completed: [`Error::Collapse`] when its load
/// exceeds what the model can carry — the contact states of the last attempt show a
/// mechanism (friction capacity exhausted, a lost support: `contact_mechanism`), or, with
/// a plastic body and a rising load, the structure's stiffness collapsed (the secant
/// stiffness of the last converged increment fell below `[solver]
/// collapse_stiffness_ratio` of the first one, or an attempt met a tangent that could not be
/// factored or an implausible increment) — and [`Error::NoConvergence`] otherwise (an
/// elastic model whose stiffness fell without such a mechanism says so in its note).
pub fn step_failure(
    model: &Model,
    mut failure: NoConvergence,
    stiffness: &StiffnessHistory,
) -> Error {
    if failure.out_of_range.is_some() {
        return Error::NoConvergence(Box::new(failure));
    }
    let converged = failure.converged_load_factor;
    let failed = failure
        .attempts
        .last()
        .map_or(failure.load_factor, |a| a.load_factor);
    let rising = failed.abs() > converged.abs();
    let fell = stiffness
        .ratio()
        .filter(|&r| r < model.control.collapse_stiffness_ratio)
        .map(|r| format!("the secant stiffness fell to {r:.2e} of the first increment's"));
    let met = |wanted: fn(&AttemptFailure) -> bool| {
        failure
            .attempts
            .iter()
            .any(|a| a.failure.as_ref().is_some_and(wanted))
    };
    let plastic_indicator = fell.clone().or_else(|| {
        if met(|f| matches!(f, AttemptFailure::Tangent(_))) {
            Some("the tangent of the plastic model could not be factored".to_string())
        } else if met(|f| matches!(f, AttemptFailure::Implausible(_))) {
            Some("the plastic model only converged to implausibly large increments".to_string())
        } else {
            None
        }
    });
    let mechanism = failure.mechanism.clone().or_else(|| {
        plastic_indicator
            .filter(|_| model.control.plastic && rising)
            .map(|indicator| Mechanism::PlasticCollapse { indicator })
    });
    match mechanism {
        Some(mechanism) => Error::Collapse {
            mechanism,
            converged_load_factor: converged,
            failed_load_factor: failed,
            details: Box::new(failure),
        },
        None => {
            failure.note = fell.map(|f| {
                if model.control.plastic {
                    f
                } else {
                    format!("{f}, but the bodies are elastic: no plastic collapse")
                }
            });
            Error::NoConvergence(Box::new(failure))
        }
    }
}
