//! Rigid-body freedom found when the model is built, before anything is solved
//! (`Error::RigidBodyMotion`): which body can move, how, and nothing for a model that is
//! held. The references are the rigid motions of the supports as written: a support at one
//! point does not stop rotation about it, a support along a line holding only the
//! direction of that line does not stop rotation either, a frictionless contact does not
//! stop sliding along it, and in axisymmetry only the axial translation is a rigid motion.
use crate::common;

use asperity::Error;
use asperity::error::FreeBody;
use asperity::mesh::Mesh;
use common::{
    CaseBuilder, add_point_group, block_on_base, block_on_base_mesh, elastic, linear_coulomb,
    model, rectangle,
};

/// A plate [0, 2] × [0, 1] (curves s0 = left, s1 = right, t0 = bottom, t1 = top; point
/// "origin"), with the point "mid_bottom" at (1, 0).
fn plate() -> Mesh {
    let mut mesh = rectangle(2.0, 1.0, 4, 2, 0.0, false);
    add_point_group(&mut mesh, "mid_bottom", [1.0, 0.0]);
    mesh
}

/// The free bodies of `case` on `mesh` (empty when the model builds).
fn free_bodies(mesh: Mesh, case: CaseBuilder) -> Vec<FreeBody> {
    match model(mesh, &case.case()) {
        Ok(_) => Vec::new(),
        Err(Error::RigidBodyMotion { bodies }) => bodies,
        Err(e) => panic!("expected a rigid-body error or a model, got: {e}"),
    }
}

fn plate_case(supports: &[(&str, &[(&str, f64)])]) -> CaseBuilder {
    let mut case = CaseBuilder::plane_strain().body("body", elastic(1000.0, 0.3));
    for (group, components) in supports {
        case = case.support(group, components);
    }
    case.steps(1)
}

fn close(a: [f64; 2], b: [f64; 2]) -> bool {
    (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9
}

#[test]
fn supports_that_hold_every_rigid_motion_pass() {
    for supports in [
        // Rollers: x on the left edge, y on the bottom.
        &[("s0", &[("ux", 0.0)][..]), ("t0", &[("uy", 0.0)][..])][..],
        // A clamped edge.
        &[("t0", &[("ux", 0.0), ("uy", 0.0)][..])][..],
        // y along the bottom (which stops rotation) and x at one point.
        &[("t0", &[("uy", 0.0)][..]), ("origin", &[("ux", 0.0)][..])][..],
        // Two points held in both directions.
        &[
            ("origin", &[("ux", 0.0), ("uy", 0.0)][..]),
            ("mid_bottom", &[("uy", 0.0)][..]),
        ][..],
    ] {
        assert_eq!(
            free_bodies(plate(), plate_case(supports)),
            [],
            "{supports:?}"
        );
    }
}

#[test]
fn a_missing_direction_is_named_with_the_support_to_add() {
    let free = free_bodies(plate(), plate_case(&[("t0", &[("uy", 0.0)])]));
    assert_eq!(free.len(), 1);
    let body = &free[0];
    assert_eq!(body.body, "body");
    assert_eq!(body.translations, [[1.0, 0.0]]);
    assert!(!body.rotates);
    let text = Error::RigidBodyMotion {
        bodies: free.clone(),
    }
    .to_string();
    assert!(
        text.contains("body 'body' is free to move in x") && text.contains("hold ux"),
        "{text}"
    );
    // Nothing at all: both translations and the rotation.
    let free = free_bodies(plate(), plate_case(&[]));
    assert_eq!(free[0].translations, [[1.0, 0.0], [0.0, 1.0]]);
    assert!(free[0].rotates);
}

#[test]
fn one_held_point_or_a_line_held_along_itself_leaves_the_rotation_free() {
    // A pin at the origin: rotation about it.
    let free = free_bodies(
        plate(),
        plate_case(&[("origin", &[("ux", 0.0), ("uy", 0.0)])]),
    );
    assert_eq!(free.len(), 1);
    assert!(free[0].rotates && free[0].translations.is_empty());
    let centre = free[0].centre.expect("the one centre of rotation");
    assert!(close(centre, [0.0, 0.0]), "{centre:?}");
    // x held along the bottom (the line's own direction) and y at (1, 0): the bottom's x
    // displacement is the same for a rotation about (1, 0) as for none.
    let free = free_bodies(
        plate(),
        plate_case(&[("t0", &[("ux", 0.0)]), ("mid_bottom", &[("uy", 0.0)])]),
    );
    assert_eq!(free.len(), 1);
    let centre = free[0].centre.expect("the one centre of rotation");
    assert!(close(centre, [1.0, 0.0]), "{centre:?}");
    let text = Error::RigidBodyMotion { bodies: free }.to_string();
    assert!(
        text.contains("free to rotate about (1.000000, 0.000000)")
            && text.contains("does not stop rotation"),
        "{text}"
    );
}

/// The block [0.5, 2.5] × [1, 1.75] on the base [0, 3] × [0, 1], the base held on the ground;
/// the block held by the contact only, plus `block_supports`.
fn block_on_base_with(law: toml::Table, block_supports: &[(&str, f64)]) -> Vec<FreeBody> {
    let mut mesh = block_on_base_mesh(3.0, [0.5, 2.5], 1.75, [6, 4], 2);
    add_point_group(&mut mesh, "block_corner", [0.5, 1.75]);
    let mut case = block_on_base(1000.0, 0.3, &[("name", "joint".into())], law).steps(1);
    if !block_supports.is_empty() {
        case = case.support("block_corner", block_supports);
    }
    free_bodies(mesh, case)
}

#[test]
fn a_frictionless_contact_leaves_sliding_free_and_friction_holds() {
    assert_eq!(block_on_base_with(linear_coulomb(1e4, 1e4, 0.3), &[]), []);
    let free = block_on_base_with(linear_coulomb(1e4, 1e4, 0.0), &[]);
    assert_eq!(free.len(), 1, "{free:?}");
    assert_eq!(free[0].body, "block");
    assert_eq!(free[0].translations, [[1.0, 0.0]]);
    assert!(!free[0].rotates, "the contact holds the block's rotation");
    // Holding the block's corner in x stops the sliding.
    assert_eq!(
        block_on_base_with(linear_coulomb(1e4, 1e4, 0.0), &[("ux", 0.0)]),
        []
    );
}

#[test]
fn axisymmetric_bodies_need_only_an_axial_support() {
    let case = |supports: &[(&str, &[(&str, f64)])]| {
        let mut case = CaseBuilder::axisymmetric().body("body", elastic(1000.0, 0.3));
        for (group, components) in supports {
            case = case.support(group, components);
        }
        case.steps(1)
    };
    // A ring 1 ≤ r ≤ 2: held axially on its bottom, nothing radially.
    let ring = || structured_ring();
    assert_eq!(free_bodies(ring(), case(&[("t0", &[("uy", 0.0)])])), []);
    let free = free_bodies(ring(), case(&[("s0", &[("ux", 0.0)])]));
    assert_eq!(free.len(), 1);
    assert_eq!(free[0].translations, [[0.0, 1.0]]);
    assert!(!free[0].rotates);
}

/// The ring 1 ≤ r ≤ 2, 0 ≤ z ≤ 1 (curves s0 = bore, s1 = outside, t0 = bottom, t1 = top).
fn structured_ring() -> Mesh {
    common::structured(2, 2, 0.0, false, |s, t| [1.0 + s, t])
}
