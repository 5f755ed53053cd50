//! The zero-thickness 6-node quadratic interface element (Buczkowski & Kleiber (1994), §3).
//!
//! Nodes [a0, a1, a_mid, b0, b1, b_mid] (gmsh line order: end, end, middle): three on the face
//! of body A and the three paired nodes of body B. Geometry and local frame come from side B
//! (Eqs. 22–25): t = ∂x^B/∂ξ / |∂x^B/∂ξ| and n = (−t_y, t_x), with the B nodes ordered so n
//! points into body B. The relative displacement u = (u_T, u_N) = B·u_e with B = T·M
//! (Eqs. 26–31); here u_N also includes the initial normal gap g₀ (from the geometry of
//! non-coincident faces) minus the interference δ, so that closure is −u_N.
//!
//! With twist (axisymmetry with u_θ, [`Analysis::AxisymmetricTwist`]) every node has three
//! dofs (element dof 3i + c) and the relative displacement gains its third component, the
//! circumferential slide u_θ = Σ N_i (u_θ,B,i − u_θ,A,i): e_θ is normal to the meridian
//! plane, hence to both t and n, so it needs no rotation. The interface vectors are then
//! (u_T, u_N, u_θ) and (p_T, p_N, p_θ) (see [`crate::contact`]); without twist the element
//! computes exactly the 2-component operator of the paper.
//!
//! Stiffness and internal force are K = ∫ Bᵀ E B dA, F = ∫ Bᵀ p dA (Eqs. 35–36) with
//! dA = w · det j · (2πr or thickness) (Eqs. 37–38). The default rule is 3-point
//! Newton-Cotes (Lobatto, Eqs. 39–40): its points are the nodes, so the element matrices are
//! lumped (node pairs uncoupled), which avoids the stress oscillations of full Gauss
//! integration (§3.3.1). 3-point Gauss is available for comparison.

use nalgebra::{SMatrix, SVector};
use serde::Deserialize;

use super::quadrature::{GAUSS3, LOBATTO3};
use super::shape::line3;
use super::{Analysis, ElementInput, ElementOutput, ElementVector};
use crate::contact::wear::WearModel;
use crate::contact::{InterfaceLaw, InterfaceState};

/// Integration rule of an interface element.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InterfaceRule {
    /// 3-point Newton-Cotes (Lobatto) at the nodes: lumped (Buczkowski & Kleiber (1994),
    /// Eqs. 39–40).
    #[default]
    NewtonCotes,
    /// 3-point Gauss: consistent (full) integration.
    Gauss,
}

impl InterfaceRule {
    /// (ξ, weight) of the rule's points.
    pub fn points(self) -> &'static [(f64, f64); 3] {
        match self {
            InterfaceRule::NewtonCotes => &LOBATTO3,
            InterfaceRule::Gauss => &GAUSS3,
        }
    }
}

/// Geometry of one integration point of an interface element.
#[derive(Clone, Copy, Debug)]
pub struct InterfacePoint {
    /// Shape function values in line order (end, end, middle).
    pub n: [f64; 3],
    /// Unit tangent t and normal n (Eqs. 24–25).
    pub tangent: [f64; 2],
    pub normal: [f64; 2],
    /// Area weight w · det j · (2πr or thickness), Eqs. (37)–(39).
    pub da: f64,
    /// Position on side B.
    pub x: [f64; 2],
}

/// Geometry of the point ξ with weight `w` on side B with node coordinates `b` (line order).
pub fn interface_point(analysis: &Analysis, b: &[[f64; 2]; 3], xi: f64, w: f64) -> InterfacePoint {
    let (n, dn) = line3(xi);
    let (mut x, mut dx) = ([0.0; 2], [0.0; 2]);
    for i in 0..3 {
        for c in 0..2 {
            x[c] += n[i] * b[i][c];
            dx[c] += dn[i] * b[i][c];
        }
    }
    let det_j = (dx[0] * dx[0] + dx[1] * dx[1]).sqrt();
    let tangent = [dx[0] / det_j, dx[1] / det_j];
    InterfacePoint {
        n,
        tangent,
        normal: [-tangent[1], tangent[0]],
        da: w * det_j * analysis.measure(x[0]),
        x,
    }
}

/// An interface element as stored in the model.
#[derive(Clone, Copy, Debug)]
pub struct InterfaceElement {
    /// [a0, a1, a_mid, b0, b1, b_mid].
    pub nodes: [u32; 6],
    /// Coordinates of the B nodes (line order).
    pub b_coords: [[f64; 2]; 3],
    /// Initial relative positions x_B − x_A of the node pairs.
    pub offsets: [[f64; 2]; 3],
    /// Index of the contact pair (law, interference).
    pub pair: u32,
    pub rule: InterfaceRule,
    /// Normal compliance of the two bodies' surfaces under the shortest pressure wave the
    /// element resolves (mm/MPa): ℓ / (π E*), see [`surface_compliance`]. Only the cycle-jump
    /// stability limit uses it.
    pub body_compliance: f64,
}

/// Length (mm) of an interface element with B-side coordinates `b` (line order: ends, then
/// mid node): the chord between its end nodes.
pub fn chord_length(b: &[[f64; 2]; 3]) -> f64 {
    let [b0, b1, _] = b;
    (b1[0] - b0[0]).hypot(b1[1] - b0[1])
}

/// Normal compliance (mm/MPa) of the surfaces of two bodies with moduli `surface_moduli`
/// (each E / (1 − ν²), or E in plane stress) to a pressure wave of wavelength `wavelength`:
/// the faces approach by λ / (π E*) per unit pressure amplitude, 1/E* = 1/E'_A + 1/E'_B
/// (Westergaard's wavy surface, Johnson, *Contact Mechanics*, 1985, §13.2: a pressure
/// amplitude p* = π E* Δ / λ flattens a wave of amplitude Δ).
pub fn surface_compliance(surface_moduli: [f64; 2], wavelength: f64) -> f64 {
    wavelength / std::f64::consts::PI * (1.0 / surface_moduli[0] + 1.0 / surface_moduli[1])
}

/// Relative displacement operator of point `p` for an element whose nodes carry `D` dofs,
/// with `R` components (2: u_T, u_N; 3: and u_θ when `D` = 3) and `W` ≥ 6·D columns in
/// element dof order D·i + c: u_T = Σ N_i (u_B,i − u_A,i)·t, u_N the same with n, u_θ = Σ N_i
/// (u_θ,B,i − u_θ,A,i).
fn operator<const D: usize, const R: usize, const W: usize>(
    p: &InterfacePoint,
) -> SMatrix<f64, R, W> {
    let mut b = SMatrix::<f64, R, W>::zeros();
    for i in 0..3 {
        let (a_dof, b_dof) = (D * i, D * (3 + i));
        for c in 0..2 {
            b[(0, a_dof + c)] = -p.n[i] * p.tangent[c];
            b[(1, a_dof + c)] = -p.n[i] * p.normal[c];
            b[(0, b_dof + c)] = p.n[i] * p.tangent[c];
            b[(1, b_dof + c)] = p.n[i] * p.normal[c];
        }
        if R == 3 {
            b[(2, a_dof + 2)] = -p.n[i];
            b[(2, b_dof + 2)] = p.n[i];
        }
    }
    b
}

/// Relative displacement operator of point `p` without twist: (u_T, u_N) from the 12 dofs
/// (in a 2×16, the leading columns of [`ElementVector`]).
pub fn relative_operator(p: &InterfacePoint) -> SMatrix<f64, 2, 16> {
    operator::<2, 2, 16>(p)
}

/// Relative displacement operator of point `p` with twist: (u_T, u_N, u_θ) from the 18 dofs
/// (3 per node).
pub fn twist_relative_operator(p: &InterfacePoint) -> SMatrix<f64, 3, 18> {
    operator::<3, 3, 18>(p)
}

/// The relative displacement (u_T, u_N, u_θ) at point `p` of element nodal displacements `u`
/// (dof order of `analysis`), u_θ = 0 without twist; without the gap and wear terms.
pub fn relative_displacement(
    analysis: &Analysis,
    p: &InterfacePoint,
    u: &ElementVector,
) -> [f64; 3] {
    if analysis.has_twist() {
        let jump = twist_relative_operator(p) * u.fixed_rows::<18>(0);
        [jump[0], jump[1], jump[2]]
    } else {
        let jump = relative_operator(p) * u.fixed_rows::<16>(0);
        [jump[0], jump[1], 0.0]
    }
}

/// Tangent and internal force of one interface element for nodal displacements `input.u`
/// (dofs of [a0, a1, a_mid, b0, b1, b_mid], `analysis.dofs_per_node()` per node), updating the
/// trial states from the committed
/// ones, with their fretting and wear history ([`crate::contact::PointHistory`]; `wear` is the
/// pair's wear model); the law sees the gap opened by the committed wear. The tangent is the one of `input.algorithm`
/// (the consistent one, Buczkowski & Kleiber (1994), Eq. 21, for Newton).
pub fn evaluate_interface(
    analysis: &Analysis,
    element: &InterfaceElement,
    interference: f64,
    law: &dyn InterfaceLaw,
    wear: Option<&WearModel>,
    input: &ElementInput<InterfaceState>,
    output: ElementOutput<InterfaceState>,
) {
    let pair = PairOfElement {
        element,
        interference,
        law,
        wear,
    };
    if analysis.has_twist() {
        evaluate_points::<3, 3, 18>(analysis, &pair, input, output);
    } else {
        evaluate_points::<2, 2, 16>(analysis, &pair, input, output);
    }
}

/// An element with what its pair gives it.
struct PairOfElement<'a> {
    element: &'a InterfaceElement,
    interference: f64,
    law: &'a dyn InterfaceLaw,
    wear: Option<&'a WearModel>,
}

/// [`evaluate_interface`] for `D` dofs per node, `R` relative components and `W` operator
/// columns (see [`operator`]).
fn evaluate_points<const D: usize, const R: usize, const W: usize>(
    analysis: &Analysis,
    pair: &PairOfElement,
    input: &ElementInput<InterfaceState>,
    output: ElementOutput<InterfaceState>,
) {
    let PairOfElement {
        element,
        interference,
        law,
        wear,
    } = *pair;
    let ElementInput {
        u,
        committed,
        algorithm,
    } = *input;
    let ElementOutput {
        trial,
        mut k,
        mut f,
    } = output;
    for (g, &(xi, w)) in element.rule.points().iter().enumerate() {
        let p = interface_point(analysis, &element.b_coords, xi, w);
        let b = operator::<D, R, W>(&p);
        let jump = b * u.fixed_rows::<W>(0);
        let mut gap = [0.0; 2];
        for i in 0..3 {
            gap[0] += p.n[i] * element.offsets[i][0];
            gap[1] += p.n[i] * element.offsets[i][1];
        }
        let g0 = gap[0] * p.normal[0] + gap[1] * p.normal[1];
        // Worn material opens the gap; the committed depth keeps the wear explicit, so the
        // law's tangent needs no wear term.
        let before = &committed[g];
        let worn = before.history.depth();
        let circumferential = if R == 3 { jump[2] } else { 0.0 };
        let relative = [jump[0], jump[1] + g0 - interference + worn, circumferential];
        let (state, tangent) = law.update(relative, before);
        let stress = SVector::<f64, R>::from_fn(|i, _| state.stress[i]);
        if let Some(f) = f.as_deref_mut() {
            f.fixed_rows_mut::<W>(0).gemv_tr(p.da, &b, &stress, 1.0);
        }
        let used = algorithm.tangent(law, &state, tangent);
        let used: SMatrix<f64, R, R> = used.fixed_view::<R, R>(0, 0).into_owned();
        if let Some(k) = k.as_deref_mut() {
            let eb = used * b;
            k.fixed_view_mut::<W, W>(0, 0).gemm_tr(p.da, &b, &eb, 1.0);
        }
        let mut state = state;
        state.unsymmetric = used != used.transpose();
        state.history = before.history.advanced(
            before.plastic_slip,
            &state,
            wear,
            worn,
            element.body_compliance,
        );
        trial[g] = state;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::ContactAlgorithm;
    use crate::contact::linear::LinearCoulomb;
    use crate::element::{ElementMatrix, ElementVector};

    /// Evaluates `e` (no interference) with the Newton tangent; trial states are discarded.
    fn newton(
        analysis: &Analysis,
        e: &InterfaceElement,
        law: &dyn InterfaceLaw,
        u: &ElementVector,
        committed: &[InterfaceState],
        k: Option<&mut ElementMatrix>,
        f: &mut ElementVector,
    ) {
        let mut trial = [InterfaceState::default(); 3];
        let input = ElementInput {
            u,
            committed,
            algorithm: ContactAlgorithm::Newton,
        };
        let output = ElementOutput {
            trial: &mut trial,
            k,
            f: Some(f),
        };
        evaluate_interface(analysis, e, 0.0, law, None, &input, output);
    }

    /// A straight horizontal element from x = 1 to x = 3 at y = 0 (B walks +x, so n = +y).
    fn element(rule: InterfaceRule) -> InterfaceElement {
        InterfaceElement {
            nodes: [0, 1, 2, 3, 4, 5],
            b_coords: [[1.0, 0.0], [3.0, 0.0], [2.0, 0.0]],
            offsets: [[0.0; 2]; 3],
            pair: 0,
            rule,
            body_compliance: 0.0,
        }
    }

    #[test]
    fn uniform_closure_gives_newton_cotes_nodal_forces() {
        // Body B pushed down by 1e-3 onto A: p_N = −k_N·1e-3 on length 2, thickness 1.
        let law = LinearCoulomb::new(1e4, 1e4, 0.0).unwrap();
        let analysis = Analysis::PlaneStrain { thickness: 1.0 };
        let mut u = ElementVector::zeros();
        for i in 3..6 {
            u[2 * i + 1] = -1e-3;
        }
        let mut f = ElementVector::zeros();
        let e = element(InterfaceRule::NewtonCotes);
        newton(
            &analysis,
            &e,
            &law,
            &u,
            &[InterfaceState::default(); 3],
            None,
            &mut f,
        );
        // Total force 10 MPa × 2 mm; Simpson shares (1/6, 1/6, 2/3) for end, end, middle.
        for (i, share) in [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0].into_iter().enumerate() {
            assert!(
                (f[6 + 2 * i + 1] + 20.0 * share).abs() < 1e-12,
                "B node {i}: {}",
                f[6 + 2 * i + 1]
            );
            assert!((f[2 * i + 1] - 20.0 * share).abs() < 1e-12);
        }
    }

    #[test]
    fn newton_cotes_tangent_is_lumped_and_gauss_is_not() {
        let law = LinearCoulomb::new(1e4, 1e4, 0.0).unwrap();
        let analysis = Analysis::PlaneStrain { thickness: 1.0 };
        let mut u = ElementVector::zeros();
        u[7] = -1e-3;
        u[9] = -1e-3;
        u[11] = -1e-3;
        for (rule, lumped) in [
            (InterfaceRule::NewtonCotes, true),
            (InterfaceRule::Gauss, false),
        ] {
            let mut k = ElementMatrix::zeros();
            let mut f = ElementVector::zeros();
            newton(
                &analysis,
                &element(rule),
                &law,
                &u,
                &[InterfaceState::default(); 3],
                Some(&mut k),
                &mut f,
            );
            // Coupling between the two end nodes of side B (dofs 7 and 9, vertical).
            assert_eq!(k[(7, 9)] == 0.0, lumped, "{rule:?}");
        }
    }

    #[test]
    fn tangent_matches_finite_differences_in_stick_slip_and_open() {
        let law = LinearCoulomb::new(2e4, 1e4, 0.3).unwrap();
        let analysis = Analysis::Axisymmetric;
        let e = InterfaceElement {
            b_coords: [[1.0, 0.0], [2.0, 0.5], [1.5, 0.3]],
            ..element(InterfaceRule::Gauss)
        };
        let committed = [InterfaceState {
            plastic_slip: [1e-4, 0.0],
            ..Default::default()
        }; 3];
        let cases: [(f64, f64); 3] = [(5e-5, -1e-3), (3e-3, -1e-3), (1e-3, 2e-3)];
        for (slide, press) in cases {
            let mut u = ElementVector::zeros();
            for i in 3..6 {
                u[2 * i] = slide;
                u[2 * i + 1] = press;
            }
            u[7] += 1e-4;
            let label = format!("state ({slide},{press})");
            assert_tangent_is_differences(&analysis, &e, &law, &u, &committed, 12, &label);
        }
    }

    /// The element's Newton tangent at `u` against central differences of its force over
    /// its first `dofs` dofs.
    fn assert_tangent_is_differences(
        analysis: &Analysis,
        e: &InterfaceElement,
        law: &LinearCoulomb,
        u: &ElementVector,
        committed: &[InterfaceState; 3],
        dofs: usize,
        label: &str,
    ) {
        let mut k = ElementMatrix::zeros();
        let mut f = ElementVector::zeros();
        newton(analysis, e, law, u, committed, Some(&mut k), &mut f);
        let h = 1e-9;
        for j in 0..dofs {
            let (mut up, mut um) = (*u, *u);
            up[j] += h;
            um[j] -= h;
            let (mut fp, mut fm) = (ElementVector::zeros(), ElementVector::zeros());
            newton(analysis, e, law, &up, committed, None, &mut fp);
            newton(analysis, e, law, &um, committed, None, &mut fm);
            for i in 0..dofs {
                let fd = (fp[i] - fm[i]) / (2.0 * h);
                // Absolute scale of the closed-state entries (k_N × area ≈ 1e5); the open
                // state's regularising tangent (1e-9 of it) is far below the tolerance.
                assert!(
                    (fd - k[(i, j)]).abs() < 1e-6 * 1e5,
                    "{label} K[{i},{j}] = {} vs fd {fd}",
                    k[(i, j)]
                );
            }
        }
    }

    #[test]
    fn twist_tangent_matches_finite_differences_with_circumferential_slip() {
        let law = LinearCoulomb::new(2e4, 1e4, 0.3).unwrap();
        let analysis = Analysis::AxisymmetricTwist;
        let e = InterfaceElement {
            b_coords: [[1.0, 0.0], [2.0, 0.5], [1.5, 0.3]],
            ..element(InterfaceRule::Gauss)
        };
        let committed = [InterfaceState {
            plastic_slip: [1e-4, -2e-4],
            ..Default::default()
        }; 3];
        // (x slide, y approach, circumferential slide of B): stick, slip mostly
        // circumferential, slip in both, open. (Away from u_N = 0, where the stress has its
        // open/closed kink: the element is tilted, n = (−0.45, 0.89).)
        let cases: [[f64; 3]; 4] = [
            [5e-5, -1e-3, -1e-4],
            [1e-4, -1e-3, 3e-3],
            [-1e-3, -2e-3, 2e-3],
            [1e-3, 2e-3, 1e-3],
        ];
        for [slide, press, turn] in cases {
            let mut u = ElementVector::zeros();
            for i in 3..6 {
                u[3 * i] = slide;
                u[3 * i + 1] = press;
                u[3 * i + 2] = turn * (1.0 + 0.1 * i as f64);
            }
            u[10] += 1e-4;
            let label = format!("state ({slide},{press},{turn})");
            assert_tangent_is_differences(&analysis, &e, &law, &u, &committed, 18, &label);
        }
    }

    #[test]
    fn twist_element_without_circumferential_motion_is_the_axisymmetric_one() {
        let law = LinearCoulomb::new(2e4, 1e4, 0.3).unwrap();
        let e = element(InterfaceRule::NewtonCotes);
        let committed = [InterfaceState::default(); 3];
        let (mut u2, mut u3) = (ElementVector::zeros(), ElementVector::zeros());
        for i in 0..6 {
            let v = [1e-4 * i as f64, -3e-4 * (i as f64 - 2.5)];
            for c in 0..2 {
                u2[2 * i + c] = v[c];
                u3[3 * i + c] = v[c];
            }
        }
        let (mut k2, mut f2) = (ElementMatrix::zeros(), ElementVector::zeros());
        let (mut k3, mut f3) = (ElementMatrix::zeros(), ElementVector::zeros());
        newton(
            &Analysis::Axisymmetric,
            &e,
            &law,
            &u2,
            &committed,
            Some(&mut k2),
            &mut f2,
        );
        newton(
            &Analysis::AxisymmetricTwist,
            &e,
            &law,
            &u3,
            &committed,
            Some(&mut k3),
            &mut f3,
        );
        for a in 0..12 {
            let a3 = 3 * (a / 2) + a % 2;
            assert_eq!(f2[a], f3[a3]);
            for b in 0..12 {
                assert_eq!(k2[(a, b)], k3[(a3, 3 * (b / 2) + b % 2)]);
            }
        }
        // The circumferential dofs carry k_T between the node pairs and no force.
        for i in 0..6 {
            assert_eq!(f3[3 * i + 2], 0.0);
        }
        assert!(k3[(2, 2)] > 0.0 && k3[(2, 11)] < 0.0);
    }

    #[test]
    fn surface_compliance_is_that_of_two_half_spaces_under_a_pressure_wave() {
        // A plane-strain half-space under p cos(κx) sinks by 2 p (1 − ν²) / (E κ), κ = 2π/λ
        // (the Flamant solution integrated over the Fourier load; Johnson, Contact Mechanics,
        // §13.2); the two faces add up.
        let (ea, nua, eb, nub) = (110_000.0, 0.3, 210_000.0, 0.29);
        let wavelength = 0.4;
        let kappa = 2.0 * std::f64::consts::PI / wavelength;
        let sink = |e: f64, nu: f64| 2.0 * (1.0 - nu * nu) / (e * kappa);
        let moduli = [ea / (1.0 - nua * nua), eb / (1.0 - nub * nub)];
        let expected = sink(ea, nua) + sink(eb, nub);
        let got = surface_compliance(moduli, wavelength);
        assert!(
            (got - expected).abs() <= 1e-14 * expected,
            "{got} vs {expected}"
        );
        // A rigid face adds nothing.
        let rigid = surface_compliance([moduli[0], f64::INFINITY], wavelength);
        assert!((rigid - sink(ea, nua)).abs() <= 1e-14 * rigid);
    }
}
