//! Quadrature rules, named by what they integrate exactly.

use crate::mesh::CellKind;

/// One quadrature point in natural coordinates with its weight.
#[derive(Clone, Copy, Debug)]
pub struct QuadPoint {
    pub xi: f64,
    pub eta: f64,
    pub weight: f64,
}

/// 3-point Gauss-Legendre on [−1, 1]: exact for polynomials of degree 5.
pub const GAUSS3: [(f64, f64); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

/// 3-point Newton-Cotes (Lobatto, Simpson) on [−1, 1]: nodes at −1, 0, 1, weights 1/3, 4/3,
/// 1/3 (Buczkowski & Kleiber (1994), §3.3.1: W_g = 2/6, 8/6, 2/6); exact for degree 3.
pub const LOBATTO3: [(f64, f64); 3] = [(-1.0, 1.0 / 3.0), (0.0, 4.0 / 3.0), (1.0, 1.0 / 3.0)];

/// 3×3 Gauss rule on the square (Buczkowski & Kleiber (1994), §3.2: 3×3 sampling points for
/// quad8), exact for degree 5 in each direction.
pub const QUAD_GAUSS_3X3: [QuadPoint; 9] = {
    let mut pts = [QuadPoint {
        xi: 0.0,
        eta: 0.0,
        weight: 0.0,
    }; 9];
    let mut k = 0;
    while k < 9 {
        let (xi, wx) = GAUSS3[k % 3];
        let (eta, wy) = GAUSS3[k / 3];
        pts[k] = QuadPoint {
            xi,
            eta,
            weight: wx * wy,
        };
        k += 1;
    }
    pts
};

/// 6-point rule on the triangle (Strang-Fix / Dunavant degree 4), the matching rule for
/// tri6 (integrates the stiffness of straight-sided tri6 exactly, with margin for the 1/r
/// and r terms of axisymmetry). Weights sum to the reference area 1/2.
pub const TRI_DEGREE4: [QuadPoint; 6] = {
    const A: f64 = 0.445_948_490_915_965;
    const WA: f64 = 0.223_381_589_678_011 / 2.0;
    const B: f64 = 0.091_576_213_509_771;
    const WB: f64 = 0.109_951_743_655_322 / 2.0;
    [
        QuadPoint {
            xi: A,
            eta: A,
            weight: WA,
        },
        QuadPoint {
            xi: 1.0 - 2.0 * A,
            eta: A,
            weight: WA,
        },
        QuadPoint {
            xi: A,
            eta: 1.0 - 2.0 * A,
            weight: WA,
        },
        QuadPoint {
            xi: B,
            eta: B,
            weight: WB,
        },
        QuadPoint {
            xi: 1.0 - 2.0 * B,
            eta: B,
            weight: WB,
        },
        QuadPoint {
            xi: B,
            eta: 1.0 - 2.0 * B,
            weight: WB,
        },
    ]
};

/// The continuum rule of a cell kind.
pub fn cell_rule(kind: CellKind) -> &'static [QuadPoint] {
    match kind {
        CellKind::Quad8 => &QUAD_GAUSS_3X3,
        CellKind::Tri6 => &TRI_DEGREE4,
    }
}

/// Largest number of points of any cell rule (size of per-cell state arrays).
pub const MAX_CELL_POINTS: usize = 9;

#[cfg(test)]
mod tests {
    use super::*;

    fn integrate(rule: &[QuadPoint], f: impl Fn(f64, f64) -> f64) -> f64 {
        rule.iter().map(|p| p.weight * f(p.xi, p.eta)).sum()
    }

    #[test]
    fn gauss_3x3_is_exact_to_degree_five() {
        // ∫∫ x^4 y^2 over [-1,1]^2 = (2/5)(2/3)
        let v = integrate(&QUAD_GAUSS_3X3, |x, y| x.powi(4) * y.powi(2));
        assert!((v - 4.0 / 15.0).abs() < 1e-14);
    }

    #[test]
    fn triangle_rule_is_exact_to_degree_four() {
        // ∫ x^a y^b over the unit triangle = a! b! / (a + b + 2)!
        let v = integrate(&TRI_DEGREE4, |x, y| x.powi(2) * y.powi(2));
        assert!((v - 4.0 / 720.0).abs() < 1e-12);
        let v = integrate(&TRI_DEGREE4, |x, _| x.powi(4));
        assert!((v - 24.0 / 720.0).abs() < 1e-12);
    }

    #[test]
    fn lobatto_is_simpson() {
        let v: f64 = LOBATTO3.iter().map(|(x, w)| w * x.powi(2)).sum();
        assert!((v - 2.0 / 3.0).abs() < 1e-15);
    }
}
