//! Volumetric locking (issue 17): the B-bar formulation of quad8 and tri6 in plane strain and
//! axisymmetry against closed forms that fully integrated quadratic elements get wrong.
//!
//! - Nearly incompressible elasticity (ν = 0.4999): Lamé's thick cylinder.
//! - Perfectly plastic thick cylinder (a = 10, b = 20, σ_Y = 100): the elastic–plastic
//!   boundary c(p) against Hill's solution and the limit pressure p_L = (2/√3) σ_Y ln(b/a).
//! - Prandtl's flat punch: collapse pressure (2 + π) k, k = σ_Y/√3.
use crate::common;

use asperity::mesh::Mesh;
use asperity::model::Model;
use asperity::solver::stepping::run_steps;
use common::*;
use toml::Table;

const A: f64 = 10.0;
const B: f64 = 20.0;
const E: f64 = 210_000.0;
const SY: f64 = 100.0;

/// The perfectly plastic material (E, ν, σ_Y).
fn plastic(nu: f64) -> Table {
    with_keys(elastic(E, nu), &[("yield_stress", SY)])
}

/// Limit pressure of the perfectly plastic cylinder (plane strain, von Mises).
fn p_limit() -> f64 {
    2.0 / 3f64.sqrt() * SY * (B / A).ln()
}

/// The two idealisations of the long cylinder (ε_z = 0).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Cylinder {
    /// Axisymmetric slice of height (b − a)/n with u_z = 0 on both ends.
    Axisymmetric,
    /// Plane-strain quarter annulus with symmetry supports.
    PlaneStrain,
}

impl Cylinder {
    fn mesh(self, n: usize, triangles: bool) -> Mesh {
        match self {
            Cylinder::Axisymmetric => {
                let h = (B - A) / n as f64;
                structured(n, 1, 0.0, triangles, move |s, t| [A + s * (B - A), t * h])
            }
            Cylinder::PlaneStrain => structured(n, 2 * n, 0.0, triangles, move |s, t| {
                let (r, th) = (A + s * (B - A), t * std::f64::consts::FRAC_PI_2);
                [r * th.cos(), r * th.sin()]
            }),
        }
    }

    /// The cylinder of `material` and `formulation`, its bore pressed by `pressure`; the
    /// steps are the caller's.
    fn case(self, material: Table, formulation: &str, pressure: f64) -> CaseBuilder {
        let (case, supports) = match self {
            Cylinder::Axisymmetric => (CaseBuilder::axisymmetric(), [("t0", "uz"), ("t1", "uz")]),
            Cylinder::PlaneStrain => (CaseBuilder::plane_strain(), [("t0", "uy"), ("t1", "ux")]),
        };
        let case = case.body_with("body", material, formulation);
        let case = supports.iter().fold(case, |case, (group, component)| {
            case.support(group, &[(component, 0.0)])
        });
        case.pressure("s0", pressure)
            .set("solver", "max_cutbacks", 6)
    }

    /// Mean radial displacement of the bore nodes.
    fn bore_displacement(self, model: &Model, u: &[f64]) -> f64 {
        let mut sum = (0.0, 0);
        for (n, p) in model.mesh.nodes.iter().enumerate() {
            let r = p[0].hypot(p[1]);
            if (r - A).abs() < 1e-9 {
                sum.0 += (u[2 * n] * p[0] + u[2 * n + 1] * p[1]) / r;
                sum.1 += 1;
            }
        }
        sum.0 / sum.1 as f64
    }
}

fn kind_name(triangles: bool) -> &'static str {
    if triangles { "tri6" } else { "quad8" }
}

/// Lamé bore displacement of the long cylinder (ε_z = 0) under internal pressure p.
fn lame_bore_displacement(p: f64, nu: f64) -> f64 {
    p * A * A * (1.0 + nu) * ((1.0 - 2.0 * nu) * A + B * B / A) / (E * (B * B - A * A))
}

#[test]
fn nearly_incompressible_lame_cylinder_within_one_percent() {
    let nu = 0.4999;
    let exact = lame_bore_displacement(100.0, nu);
    for cylinder in [Cylinder::Axisymmetric, Cylinder::PlaneStrain] {
        for triangles in [false, true] {
            let mut errors = Vec::new();
            for formulation in ["full", "bbar"] {
                let case = cylinder
                    .case(elastic(E, nu), formulation, 100.0)
                    .step_factors(&[1.0])
                    .case();
                let (model, solution) = solve(cylinder.mesh(4, triangles), &case);
                let u = cylinder.bore_displacement(&model, &solution.u);
                errors.push((u - exact) / exact);
            }
            println!(
                "{cylinder:?} {}, 4 elements through the wall, nu = {nu}: bore displacement error full {:+.2} %, \
                 bbar {:+.4} %",
                kind_name(triangles),
                100.0 * errors[0],
                100.0 * errors[1]
            );
            assert!(errors[1].abs() < 0.01, "bbar error {}", errors[1]);
            // The test can tell: fully integrated quad8 locks (measured −9 %).
            if !triangles {
                assert!(errors[0] < -0.05, "full integration error {}", errors[0]);
            }
        }
    }
}

/// Hill's elastic–plastic boundary radius c for internal pressure p < p_L (plane strain,
/// σ_z = (σ_r + σ_θ)/2, i.e. Tresca, or von Mises with k = σ_Y/√3 and incompressible
/// elasticity): p = k [1 − c²/b² + 2 ln(c/a)], solved for c by bisection.
fn hill_boundary(p: f64) -> f64 {
    let k = SY / 3f64.sqrt();
    let pressure = |c: f64| k * (1.0 - c * c / (B * B) + 2.0 * (c / A).ln());
    if p <= pressure(A) {
        return A;
    }
    let (mut lo, mut hi) = (A, B);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if pressure(mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// One converged step of a pressure-loaded plastic cylinder.
#[derive(Clone, Copy, Debug)]
struct CylinderStep {
    /// p / p_L.
    load: f64,
    /// Elastic–plastic boundary radius from the integration points (see [`boundary_radius`]).
    c: f64,
    /// Bore displacement.
    u: f64,
}

/// The elastic–plastic boundary from the integration points: the innermost point that has
/// not yielded, at radius r_e with von Mises stress q_e < σ_Y, is moved inwards to where
/// the elastic solution reaches yield, c = r_e √(q_e/σ_Y) (Lamé: q ∝ 1/r² for ν = ½;
/// within 1 % for ν = 0.3 over the fraction of a cell this moves), but not past the
/// outermost yielded point (if the two overlap in radius, their mean).
fn boundary_radius(model: &Model, states: &[asperity::material::PointState]) -> f64 {
    use asperity::element::kinematics::point_kinematics;
    use asperity::element::quadrature::{MAX_CELL_POINTS, cell_rule};
    let (mut plastic, mut elastic) = (A, (B, SY));
    for (e, c) in model.continuum.cells.iter().enumerate() {
        for (g, q) in cell_rule(c.kind).iter().enumerate() {
            let x = point_kinematics(&model.analysis, c.kind, &c.coords, q)
                .unwrap()
                .x;
            let r = x[0].hypot(x[1]);
            let s = &states[e * MAX_CELL_POINTS + g];
            if s.equivalent_plastic_strain > 0.0 {
                plastic = plastic.max(r);
            } else if r < elastic.0 {
                elastic = (r, asperity::material::von_mises(&s.stress));
            }
        }
    }
    if plastic <= elastic.0 {
        (elastic.0 * (elastic.1 / SY).sqrt()).clamp(plastic, elastic.0)
    } else {
        // A ragged front (triangles): yielded and elastic points overlap in radius.
        0.5 * (plastic + elastic.0)
    }
}

/// Loads a perfectly plastic cylinder by internal pressure through `factors` (× p_L) and
/// returns the converged steps, stopping at the first step that cannot be made to converge.
fn plastic_cylinder(
    cylinder: Cylinder,
    n: usize,
    triangles: bool,
    nu: f64,
    formulation: &str,
    factors: &[f64],
) -> Vec<CylinderStep> {
    let case = cylinder
        .case(plastic(nu), formulation, p_limit())
        .step_factors(factors)
        .case();
    let model = model(cylinder.mesh(n, triangles), &case).unwrap();
    let mut steps = Vec::new();
    let _ = run_steps(&model, &settings(&case), |step| {
        steps.push(CylinderStep {
            load: step.load_factor,
            c: boundary_radius(&model, step.solution.point_states()),
            u: cylinder.bore_displacement(&model, &step.solution.u),
        });
        Ok(0.0)
    });
    steps
}

#[test]
fn plastic_cylinder_elastic_plastic_boundary_follows_hill() {
    // Hill's solution assumes σ_z = (σ_r + σ_θ)/2, exact for von Mises with incompressible
    // elasticity. With ν = 0.49 the remaining terms are O(1 − 2ν)² in the elastic zone's
    // yield condition (4·10⁻⁴ relative) and O(1 − 2ν) in the plastic zone's σ_z, so the
    // front is held to 0.5 % of the wall (measured ≤ 0.12 % at 16 cells through the wall).
    // With ν = 0.3, σ_z = ν(σ_r + σ_θ) in the elastic zone raises the von Mises stress by up to
    // 2.6 % near c = b, and the converged FE front lies 1.5 % of the wall outside Hill's at
    // 0.95 p_L (measured with 32 cells): that is the model difference, not discretisation
    // error, and the 2 % bound covers it with 0.3 % to spare.
    let loads = [0.6, 0.7, 0.8, 0.9, 0.95];
    for (nu, tolerance) in [(0.49, 0.005), (0.3, 0.02)] {
        for cylinder in [Cylinder::Axisymmetric, Cylinder::PlaneStrain] {
            for triangles in [false, true] {
                let steps = plastic_cylinder(cylinder, 16, triangles, nu, "bbar", &loads);
                assert_eq!(steps.len(), loads.len(), "every load step converges");
                let mut worst: f64 = 0.0;
                for s in &steps {
                    let hill = hill_boundary(s.load * p_limit());
                    worst = worst.max((s.c - hill).abs() / (B - A));
                    println!(
                        "nu = {nu}, {cylinder:?} {}: p = {:.2} p_L: c = {:.3} mm, Hill {hill:.3} mm",
                        kind_name(triangles),
                        s.load,
                        s.c
                    );
                }
                println!("  worst |c − c_Hill| = {:.2} % of the wall", 100.0 * worst);
                assert!(worst < tolerance, "front {worst} of the wall from Hill's");
            }
        }
    }
}

/// Pressure steps up to and past p_L, fine near p_L (relative resolution 10⁻⁵).
const PAST_THE_LIMIT: [f64; 22] = [
    0.5, 0.8, 0.9, 0.95, 0.98, 0.99, 0.995, 0.998, 0.999, 1.0, 1.00001, 1.00002, 1.00005, 1.0001,
    1.0002, 1.0005, 1.001, 1.002, 1.005, 1.01, 1.02, 1.05,
];

#[test]
fn plastic_cylinder_carries_the_limit_pressure_and_no_more() {
    // Load-stepped until Newton fails (after the cut-backs): the largest pressure carried.
    // A displacement element with the exact isochoric mechanism would give an upper bound;
    // B-bar only enforces incompressibility on average, so the bound is not guaranteed, but
    // the measured limit approaches p_L from above (1.00001–1.00002 p_L on 4 cells, 1.000001
    // on 16). Held to: at least 0.999 p_L, below 1.02 p_L (the bound), and not
    // growing as the mesh is refined.
    let p_l = p_limit();
    for cylinder in [Cylinder::Axisymmetric, Cylinder::PlaneStrain] {
        for triangles in [false, true] {
            let meshes: &[usize] = match cylinder {
                Cylinder::Axisymmetric => &[4, 8, 16],
                Cylinder::PlaneStrain => &[4, 8],
            };
            let mut previous = f64::INFINITY;
            for &n in meshes {
                let steps = plastic_cylinder(cylinder, n, triangles, 0.3, "bbar", &PAST_THE_LIMIT);
                let last = steps.last().expect("the elastic steps converge");
                println!(
                    "{cylinder:?} {} n = {n}: largest pressure carried {:.5} p_L = {:.3} MPa (p_L = {p_l:.3} MPa), \
                     bore displacement there {:.3e} mm",
                    kind_name(triangles),
                    last.load,
                    last.load * p_l,
                    last.u
                );
                assert!(
                    last.load >= 0.999 && last.load < 1.02,
                    "largest pressure {} p_L",
                    last.load
                );
                assert!(last.load <= previous, "limit grows under refinement");
                previous = last.load;
            }
        }
    }
    // Fully integrated elements lock: they "carry" 1.05 p_L (printed, not asserted: a
    // collapse check in the solver may reject these absurd states).
    for (n, triangles) in [(4, false), (16, false), (16, true)] {
        let steps = plastic_cylinder(
            Cylinder::Axisymmetric,
            n,
            triangles,
            0.3,
            "full",
            &PAST_THE_LIMIT,
        );
        let last = steps.last().unwrap();
        println!(
            "full integration, axisymmetric {} n = {n}: carried {:.4} p_L with a bore displacement of {:.3e} mm",
            kind_name(triangles),
            last.load,
            last.u
        );
    }
}

/// Meshes `geo/prandtl.geo` with gmsh (size factor `size`).
fn prandtl_mesh(size: f64) -> Mesh {
    let dir = tempfile::tempdir().unwrap();
    let geo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("geo/prandtl.geo");
    let out = dir.path().join("prandtl.msh");
    asperity::mesh::gmsh::mesh_geo(&geo, size, &[], &out).expect("gmsh meshes geo/prandtl.geo");
    asperity::mesh::msh::read_msh(&out).unwrap()
}

/// Mean punch pressure −F_y / a against the punch displacement.
fn prandtl_curve(size: f64, formulation: &str, steps: usize, depth: f64) -> Vec<(f64, f64)> {
    let a = 10.0;
    let factors: Vec<f64> = (1..=steps)
        .map(|i| (i as f64 / steps as f64).powf(1.5))
        .collect();
    // The punch: an elastic block 1000 times stiffer than the half-space, on a frictionless
    // contact (penalty k_N = 1000 E / a: an overlap of 1.4·10⁻⁵ mm at collapse), driven at
    // its top. Driving the face nodes directly is the same smooth rigid punch, but the
    // solver's first iteration then concentrates each displacement increment in the first
    // layer of cells, and Newton needs many cut-backs.
    let face = [
        ("curve", "face".into()),
        ("body_a", "half_space".into()),
        ("body_b", "punch".into()),
    ];
    let case = CaseBuilder::plane_strain()
        .body_with("half_space", plastic(0.3), formulation)
        .body("punch", elastic(1000.0 * E, 0.3))
        .support("top", &[("uy", -depth)])
        .support("punch_axis", &[("ux", 0.0)])
        .support("symmetry", &[("ux", 0.0)])
        .support("far", &[("ux", 0.0)])
        .support("base", &[("ux", 0.0), ("uy", 0.0)])
        .contact(&face, linear_coulomb(1000.0 * E / a, 1.0, 0.0))
        .step_factors(&factors)
        .case();
    let model = model(prandtl_mesh(size), &case).unwrap();
    let top = model.supports.iter().position(|s| s.name == "top").unwrap();
    let mut curve = Vec::new();
    run_steps(&model, &settings(&case), |step| {
        let r = asperity::post::reactions(&model, step.internal_force, step.external_force);
        curve.push((step.load_factor * depth, -r[top][1] / a));
        Ok(0.0)
    })
    .expect("the punch problem converges");
    curve
}

#[test]
fn prandtl_punch_collapses_at_two_plus_pi_k() {
    let q = (2.0 + std::f64::consts::PI) * SY / 3f64.sqrt();
    // 0.02 a of indentation: 40 times the displacement at first yield, far on the plateau.
    let curve = prandtl_curve(2.0, "bbar", 20, 0.2);
    for (d, p) in &curve {
        println!(
            "punch displacement {d:.4} mm: mean pressure {p:.2} MPa = {:.4} (2 + pi) k",
            p / q
        );
    }
    let p_max = curve.iter().map(|c| c.1).fold(0.0, f64::max);
    println!("collapse: {p_max:.2} MPa = {:.4} (2 + pi) k", p_max / q);
    // FE collapse loads on good meshes lie a few per cent above (2 + π) k (this coarse mesh:
    // +1.0 %; +0.55 % and +0.25 % at size factors 1 and 0.5); the issue asks for 5 %.
    assert!(
        (p_max / q - 1.0).abs() < 0.05,
        "collapse pressure {p_max} vs {q}"
    );
    // On the plateau: the last quarter of the drive adds less than 0.5 %.
    let quarter = curve[curve.len() * 3 / 4].1;
    assert!((p_max - quarter) / quarter < 0.005, "{quarter} → {p_max}");
}

/// Runs the perfectly plastic cylinder under p = `overload` · p_L through `factors` and
/// returns how the run ended.
fn overloaded_cylinder(
    cylinder: Cylinder,
    n: usize,
    formulation: &str,
    overload: f64,
    factors: &[f64],
) -> asperity::Result<usize> {
    let case = cylinder
        .case(plastic(0.3), formulation, overload * p_limit())
        .step_factors(factors)
        .case();
    let model = model(cylinder.mesh(n, false), &case).unwrap();
    let mut steps = 0;
    run_steps(&model, &settings(&case), |_| {
        steps += 1;
        Ok(0.0)
    })
    .map(|_| steps)
}

#[test]
fn overloaded_cylinder_is_reported_as_plastic_collapse() {
    // p = 1.05 p_L: no equilibrium exists above λ = 1/1.05. B-bar: the run stops with
    // Error::Collapse at a load factor within 2 % of p_L/p.
    let overload = 1.05;
    let factors = [0.5, 0.8, 0.9, 0.95, 1.0];
    for cylinder in [Cylinder::Axisymmetric, Cylinder::PlaneStrain] {
        for n in [4, 8] {
            let outcome = overloaded_cylinder(cylinder, n, "bbar", overload, &factors);
            match &outcome {
                Err(asperity::Error::Collapse {
                    converged_load_factor,
                    failed_load_factor,
                    ..
                }) => {
                    let carried = converged_load_factor * overload;
                    println!(
                        "{cylinder:?} n = {n}: collapse at λ_c = {converged_load_factor:.6} \
                         ({carried:.6} p_L), λ_f = {failed_load_factor:.6}: {}",
                        outcome.as_ref().unwrap_err()
                    );
                    assert!((carried - 1.0).abs() < 0.02, "collapse at {carried} p_L");
                }
                other => panic!("{cylinder:?} n = {n}: expected a collapse, got {other:?}"),
            }
        }
    }
}

#[test]
fn overloaded_locking_cylinder_is_a_failure_not_a_success() {
    // The fully integrated (locking) element "converged" to metres of displacement here
    // before issue 17; the plausibility bounds of [solver] now reject those increments.
    for cylinder in [Cylinder::Axisymmetric, Cylinder::PlaneStrain] {
        let outcome = overloaded_cylinder(cylinder, 4, "full", 1.05, &[0.5, 0.8, 0.9, 0.95, 1.0]);
        match outcome {
            Err(e) => println!("{cylinder:?} full: {e}"),
            Ok(steps) => panic!("{cylinder:?} full integration: {steps} steps 'converged'"),
        }
    }
}

#[test]
fn arc_length_control_follows_the_cylinder_to_its_limit_pressure() {
    // [steps] control = "arc_length" with the reference pressure p_L: the largest load factor
    // reached is the limit pressure in units of p_L, and the run ends normally (at the
    // plateau the arc cannot be continued and shrinks below min_arc_length).
    for cylinder in [Cylinder::Axisymmetric, Cylinder::PlaneStrain] {
        let case = cylinder
            .case(plastic(0.3), "bbar", p_limit())
            .set("steps", "control", "arc_length")
            .set("steps", "initial_increment", 0.2)
            .set("steps", "max_load_factor", 1.5)
            .set("steps", "max_increments", 200)
            .case();
        let model = model(cylinder.mesh(4, false), &case).unwrap();
        let mut path = Vec::new();
        run_steps(&model, &settings(&case), |step| {
            path.push((
                step.load_factor,
                cylinder.bore_displacement(&model, &step.solution.u),
            ));
            Ok(0.0)
        })
        .expect("arc-length control ends normally");
        let lambda_max = path.iter().map(|p| p.0).fold(0.0, f64::max);
        println!(
            "{cylinder:?}: {} increments, λ_max = {lambda_max:.6} p_L, last (λ, u_a) = {:?}",
            path.len(),
            path.last().unwrap()
        );
        assert!((lambda_max - 1.0).abs() < 0.02, "λ_max = {lambda_max} p_L");
    }
}
