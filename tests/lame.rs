//! Lamé thick cylinder under internal pressure (docs/theory.md, "Closed-form solutions used for verification"): axisymmetric
//! slice with u_z = 0 on both ends (= plane strain) and a plane-strain quarter annulus,
//! against the closed form; plus a mesh-refinement study of the displacement error.
use crate::common;

use asperity::element::kinematics::point_kinematics;
use asperity::element::quadrature::cell_rule;
use asperity::mesh::Mesh;
use common::*;

const A: f64 = 10.0;
const B: f64 = 20.0;
const P: f64 = 100.0;
const E: f64 = 200_000.0;
const NU: f64 = 0.3;

/// Plane-strain Lamé radial displacement.
fn lame_u(r: f64) -> f64 {
    P * A * A / (E * (B * B - A * A)) * (1.0 + NU) * ((1.0 - 2.0 * NU) * r + B * B / r)
}

/// Lamé hoop stress.
fn lame_hoop(r: f64) -> f64 {
    P * A * A / (B * B - A * A) * (1.0 + B * B / (r * r))
}

fn axisymmetric_slice(n_wall: usize) -> Mesh {
    let h = (B - A) / n_wall as f64;
    structured(n_wall, 2, 0.0, false, move |s, t| {
        [A + s * (B - A), t * 2.0 * h]
    })
}

/// The wall of a thick cylinder under internal pressure: in axisymmetry a slice held
/// axially, in plane strain a quarter held on its symmetry planes.
fn cylinder(axisymmetric: bool) -> CaseBuilder {
    let case = if axisymmetric {
        CaseBuilder::axisymmetric()
            .body("body", elastic(E, NU))
            .support("t0", &[("uz", 0.0)])
            .support("t1", &[("uz", 0.0)])
    } else {
        CaseBuilder::plane_strain()
            .body("body", elastic(E, NU))
            .support("t0", &[("uy", 0.0)])
            .support("t1", &[("ux", 0.0)])
    };
    case.pressure("s0", P)
}

/// Largest relative error of the bore displacement and of the hoop stress at the
/// integration points of the cells.
fn errors(mesh: Mesh, axisymmetric: bool) -> (f64, f64) {
    let (model, solution) = solve(mesh, &cylinder(axisymmetric).case());
    let mut u_err: f64 = 0.0;
    for (n, p) in model.mesh.nodes.iter().enumerate() {
        let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
        if (r - A).abs() < 1e-9 {
            let u = displacement(&solution, n);
            let ur = (u[0] * p[0] + u[1] * p[1]) / r;
            u_err = u_err.max((ur - lame_u(A)).abs() / lame_u(A));
        }
    }
    let mut hoop_err: f64 = 0.0;
    for (e, c) in model.continuum.cells.iter().enumerate() {
        for (g, q) in cell_rule(c.kind).iter().enumerate() {
            let x = point_kinematics(&model.analysis, c.kind, &c.coords, q)
                .unwrap()
                .x;
            let s = solution.point_states()[e * 9 + g].stress;
            let hoop = if axisymmetric {
                s[3]
            } else {
                // σ_θθ = σ_xx sin²θ + σ_yy cos²θ − 2 σ_xy sinθ cosθ
                let r = (x[0] * x[0] + x[1] * x[1]).sqrt();
                let (sn, cs) = (x[1] / r, x[0] / r);
                s[0] * sn * sn + s[1] * cs * cs - 2.0 * s[2] * sn * cs
            };
            let r = if axisymmetric {
                x[0]
            } else {
                (x[0] * x[0] + x[1] * x[1]).sqrt()
            };
            hoop_err = hoop_err.max((hoop - lame_hoop(r)).abs() / lame_hoop(A));
        }
    }
    (u_err, hoop_err)
}

#[test]
fn axisymmetric_lame_with_four_elements_through_the_wall() {
    let (u, hoop) = errors(axisymmetric_slice(4), true);
    println!(
        "axisymmetric, 4 elements: bore displacement error {u:.2e}, hoop stress error {hoop:.2e}"
    );
    assert!(u < 1e-4, "bore displacement error {u}");
    // Stresses of quadratic elements converge one order slower than displacements (O(h²)
    // pointwise); 1 % at four elements through the wall is what that order allows.
    assert!(hoop < 1e-2, "hoop stress error {hoop}");
}

#[test]
fn plane_strain_lame_with_four_elements_through_the_wall() {
    let (u, hoop) = errors(quarter_annulus(A, B, 4, 8), false);
    println!(
        "plane strain, 4 × 8 elements: bore displacement error {u:.2e}, hoop stress error {hoop:.2e}"
    );
    assert!(u < 1e-4, "bore displacement error {u}");
    // Stresses of quadratic elements converge one order slower than displacements (O(h²)
    // pointwise); 1 % at four elements through the wall is what that order allows.
    assert!(hoop < 1e-2, "hoop stress error {hoop}");
}

#[test]
fn displacement_error_converges_at_the_quad8_rate() {
    let levels = [1usize, 2, 4, 8];
    let h: Vec<f64> = levels.iter().map(|&n| (B - A) / n as f64).collect();
    let err: Vec<f64> = levels
        .iter()
        .map(|&n| errors(axisymmetric_slice(n), true).0)
        .collect();
    let rate = fitted_rate(&h, &err);
    println!("axisymmetric bore displacement errors {err:?} at h = {h:?}: fitted rate {rate:.2}");
    let err_p: Vec<f64> = levels
        .iter()
        .map(|&n| errors(quarter_annulus(A, B, n, 2 * n), false).0)
        .collect();
    let rate_p = fitted_rate(&h, &err_p);
    println!("plane-strain bore displacement errors {err_p:?}: fitted rate {rate_p:.2}");
    for r in [rate, rate_p] {
        assert!(
            r > 2.7,
            "displacement error rate {r} below the quadratic-element rate 3"
        );
    }
    let hoop: Vec<f64> = levels
        .iter()
        .map(|&n| errors(axisymmetric_slice(n), true).1)
        .collect();
    let hoop_rate = fitted_rate(&h, &hoop);
    println!(
        "axisymmetric integration-point hoop stress errors {hoop:?}: fitted rate {hoop_rate:.2}"
    );
    // Pointwise stress error is O(h²); over these coarse levels the fit is still
    // pre-asymptotic (measured 1.5, last pair 1.7), so the bound is set below 2.
    assert!(
        hoop_rate > 1.4,
        "stress error rate {hoop_rate} well below 2"
    );
    assert!(hoop[3] < 2.5e-3, "finest hoop stress error {}", hoop[3]);
    assert!(
        err[3] < 1e-5 && err_p[3] < 1e-5,
        "finest errors {} {}",
        err[3],
        err_p[3]
    );
}
