//! Patch tests: on distorted meshes of quad8 and tri6 a constant-strain field must be
//! reproduced exactly (to round-off), in plane stress, plane strain and axisymmetry, with the
//! full and (plane strain, axisymmetry) the B-bar formulation.
use crate::common;

use asperity::config::AnalysisSpec;
use asperity::material::elastic::LinearElastic;
use asperity::material::{OutOfPlane, Voigt, voigt};
use asperity::mesh::Mesh;
use asperity::solver::stepping::run_steps;
use common::*;

const E: f64 = 70_000.0;
const NU: f64 = 0.33;
/// Round-off bound: the solutions are O(1e-3) and the stiffness entries O(1e5); 1e-10
/// relative leaves room for the condition number of these small meshes.
const TOL: f64 = 1e-10;

/// Constant in-plane stress applied as boundary tractions on the rectangle [0, 2] × [0, 1];
/// u_y = 0 along y = 0 and u_x = 0 at the origin remove rigid-body motion, so the exact field
/// is u_x = ε_xx x + γ_xy y, u_y = ε_yy y.
fn traction_patch(analysis: CaseBuilder, triangles: bool, formulation: &str) {
    let (sxx, syy, sxy) = (100.0, -40.0, 25.0);
    let case = analysis
        .body_with("body", elastic(E, NU), formulation)
        .support("origin", &[("ux", 0.0)])
        .support("t0", &[("uy", 0.0)])
        .traction("s0", [-sxx, -sxy])
        .traction("s1", [sxx, sxy])
        .traction("t0", [-sxy, -syy])
        .traction("t1", [sxy, syy])
        .case();
    let out_of_plane = if matches!(case.analysis, AnalysisSpec::PlaneStress { .. }) {
        OutOfPlane::StressFree
    } else {
        OutOfPlane::StrainGiven
    };
    let d = LinearElastic::new(E, NU).unwrap().stiffness(out_of_plane);
    // Strain from stress through the in-plane block of the elasticity matrix (ε_zz = 0 in
    // plane strain, eliminated in plane stress).
    let d3 = d.fixed_view::<3, 3>(0, 0).into_owned();
    let strain = d3.try_inverse().unwrap() * nalgebra::Vector3::new(sxx, syy, sxy);
    let mesh = rectangle(2.0, 1.0, 4, 3, 0.35, triangles);
    let (model, solution) = solve(mesh, &case);
    let scale = strain.amax() * 2.0;
    for (n, p) in model.mesh.nodes.iter().enumerate() {
        let exact = [strain[0] * p[0] + strain[2] * p[1], strain[1] * p[1]];
        let u = displacement(&solution, n);
        for c in 0..2 {
            assert!(
                (u[c] - exact[c]).abs() < TOL * scale,
                "node {n} at {p:?}: u = {u:?}, exact {exact:?}"
            );
        }
    }
    for s in solution
        .point_states()
        .iter()
        .filter(|s| s.stress != Voigt::zeros())
    {
        for (c, expected) in [sxx, syy, sxy].into_iter().enumerate() {
            assert!(
                (s.stress[c] - expected).abs() < TOL * sxx,
                "stress {:?}",
                s.stress
            );
        }
    }
}

#[test]
fn plane_stress_patch_quad8() {
    traction_patch(CaseBuilder::plane_stress(2.5), false, "full");
}

#[test]
fn plane_stress_patch_tri6() {
    traction_patch(CaseBuilder::plane_stress(2.5), true, "full");
}

#[test]
fn plane_strain_patch_quad8() {
    for formulation in ["full", "bbar"] {
        traction_patch(CaseBuilder::plane_strain(), false, formulation);
    }
}

#[test]
fn plane_strain_patch_tri6() {
    for formulation in ["full", "bbar"] {
        traction_patch(CaseBuilder::plane_strain(), true, formulation);
    }
}

#[test]
fn bbar_is_rejected_in_plane_stress() {
    let case = CaseBuilder::plane_stress(1.0)
        .body_with("body", elastic(E, NU), "bbar")
        .case();
    let e = model(rectangle(2.0, 1.0, 2, 2, 0.0, false), &case).unwrap_err();
    // The reason says why: plane stress has no volumetric constraint for B-bar to relax.
    assert!(
        matches!(&e, asperity::Error::InvalidParameter { key, reason, .. }
            if key == "body[0].formulation" && reason.contains("plane stress")),
        "{e}"
    );
}

/// Axisymmetric patch test u_r = c r, u_z = d z, prescribed on the whole boundary of a
/// distorted mesh; the interior must follow exactly, with ε_rr = ε_θθ = c, ε_zz = d.
fn axisymmetric_patch(mesh: Mesh, formulation: &str) {
    let (c, d) = (1.2e-3, -0.7e-3);
    let fixed = [("ur", 0.0), ("uz", 0.0)];
    let case = CaseBuilder::axisymmetric()
        .body_with("body", elastic(E, NU), formulation)
        .support("s0", &fixed)
        .support("s1", &fixed)
        .support("t0", &fixed)
        .support("t1", &fixed)
        .case();
    let mut model = model(mesh, &case).unwrap();
    // Replace the placeholder values by the exact field on every prescribed dof.
    let nodes = model.mesh.nodes.clone();
    for (dof, value, _) in &mut model.prescribed {
        let p = nodes[*dof / 2];
        *value = if *dof % 2 == 0 { c * p[0] } else { d * p[1] };
    }
    let (solution, _) = run_steps(&model, &settings(&case), |_| Ok(0.0)).unwrap();
    let interior = (0..nodes.len()).filter(|&n| model.dofs.equation(2 * n).is_some());
    assert!(
        interior.clone().count() > 5,
        "the patch must have free nodes"
    );
    for n in interior {
        let u = displacement(&solution, n);
        let p = nodes[n];
        assert!(
            (u[0] - c * p[0]).abs() < TOL * 1e-3 && (u[1] - d * p[1]).abs() < TOL * 1e-3,
            "node {n} {p:?}: {u:?}"
        );
    }
    let expected = LinearElastic::new(E, NU)
        .unwrap()
        .stiffness(OutOfPlane::StrainGiven)
        * voigt(c, d, 0.0, c);
    for s in solution
        .point_states()
        .iter()
        .filter(|s| s.stress != Voigt::zeros())
    {
        assert!(
            (s.stress - expected).amax() < TOL * expected.amax(),
            "{:?} vs {expected:?}",
            s.stress
        );
    }
}

#[test]
fn axisymmetric_patch_quad8_off_axis() {
    for formulation in ["full", "bbar"] {
        axisymmetric_patch(
            common::structured(4, 4, 0.35, false, |s, t| [1.0 + 2.0 * s, 2.0 * t]),
            formulation,
        );
    }
}

#[test]
fn axisymmetric_patch_quad8_on_axis() {
    for formulation in ["full", "bbar"] {
        axisymmetric_patch(rectangle(2.0, 2.0, 4, 4, 0.35, false), formulation);
    }
}

#[test]
fn axisymmetric_patch_tri6_on_axis() {
    for formulation in ["full", "bbar"] {
        axisymmetric_patch(rectangle(2.0, 2.0, 4, 4, 0.35, true), formulation);
    }
}
