//! Shape functions of the quadratic elements in gmsh/VTK node order (see [`crate::mesh`]).

use crate::mesh::CellKind;

/// Values and natural derivatives of up to 8 shape functions at one point.
#[derive(Clone, Copy, Debug, Default)]
pub struct ShapeValues {
    pub n: [f64; 8],
    /// ∂N/∂ξ
    pub dxi: [f64; 8],
    /// ∂N/∂η
    pub deta: [f64; 8],
}

/// The shape functions of `kind` at the points of its integration rule
/// ([`cell_rule`](super::quadrature::cell_rule)), in the rule's order: computed once, read by
/// every evaluation of a cell (the same values [`cell_shape`] gives there, bit for bit).
pub fn rule_shapes(kind: CellKind) -> &'static [ShapeValues] {
    static TABLES: std::sync::LazyLock<[Vec<ShapeValues>; 2]> = std::sync::LazyLock::new(|| {
        [CellKind::Quad8, CellKind::Tri6].map(|kind| {
            super::quadrature::cell_rule(kind)
                .iter()
                .map(|p| cell_shape(kind, p.xi, p.eta))
                .collect()
        })
    });
    match kind {
        CellKind::Quad8 => &TABLES[0],
        CellKind::Tri6 => &TABLES[1],
    }
}

/// Shape functions of `kind` at natural coordinates (ξ, η). Quad8: ξ, η ∈ [−1, 1];
/// tri6: area coordinates ξ, η ≥ 0, ξ + η ≤ 1.
#[inline(always)]
pub fn cell_shape(kind: CellKind, xi: f64, eta: f64) -> ShapeValues {
    match kind {
        CellKind::Quad8 => quad8(xi, eta),
        CellKind::Tri6 => tri6(xi, eta),
    }
}

/// 8-node serendipity quadrilateral.
#[inline(always)]
pub fn quad8(xi: f64, eta: f64) -> ShapeValues {
    const CORNERS: [(f64, f64); 4] = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let mut s = ShapeValues::default();
    for (i, &(xa, ya)) in CORNERS.iter().enumerate() {
        let (a, b) = (1.0 + xa * xi, 1.0 + ya * eta);
        let c = xa * xi + ya * eta - 1.0;
        s.n[i] = 0.25 * a * b * c;
        s.dxi[i] = 0.25 * xa * b * (c + a);
        s.deta[i] = 0.25 * ya * a * (c + b);
    }
    // Mid-side nodes 4..8 on edges η = −1, ξ = +1, η = +1, ξ = −1.
    for (k, &(xa, ya)) in [(0.0, -1.0), (1.0, 0.0), (0.0, 1.0), (-1.0, 0.0)]
        .iter()
        .enumerate()
    {
        let i = 4 + k;
        if xa == 0.0 {
            s.n[i] = 0.5 * (1.0 - xi * xi) * (1.0 + ya * eta);
            s.dxi[i] = -xi * (1.0 + ya * eta);
            s.deta[i] = 0.5 * ya * (1.0 - xi * xi);
        } else {
            s.n[i] = 0.5 * (1.0 + xa * xi) * (1.0 - eta * eta);
            s.dxi[i] = 0.5 * xa * (1.0 - eta * eta);
            s.deta[i] = -eta * (1.0 + xa * xi);
        }
    }
    s
}

/// 6-node triangle in area coordinates L1 = 1 − ξ − η, L2 = ξ, L3 = η.
#[inline(always)]
pub fn tri6(xi: f64, eta: f64) -> ShapeValues {
    let l1 = 1.0 - xi - eta;
    let mut s = ShapeValues::default();
    s.n[..6].copy_from_slice(&[
        l1 * (2.0 * l1 - 1.0),
        xi * (2.0 * xi - 1.0),
        eta * (2.0 * eta - 1.0),
        4.0 * l1 * xi,
        4.0 * xi * eta,
        4.0 * eta * l1,
    ]);
    s.dxi[..6].copy_from_slice(&[
        1.0 - 4.0 * l1,
        4.0 * xi - 1.0,
        0.0,
        4.0 * (l1 - xi),
        4.0 * eta,
        -4.0 * eta,
    ]);
    s.deta[..6].copy_from_slice(&[
        1.0 - 4.0 * l1,
        0.0,
        4.0 * eta - 1.0,
        -4.0 * xi,
        4.0 * xi,
        4.0 * (l1 - eta),
    ]);
    s
}

/// Quadratic line shape functions in gmsh order (end, end, middle) at ξ ∈ [−1, 1], with
/// their derivatives. Buczkowski & Kleiber (1994), Eq. 23, numbers them along the line (N1
/// at ξ = −1, N2 in the middle, N3 at ξ = +1); here index 2 is the middle node.
pub fn line3(xi: f64) -> ([f64; 3], [f64; 3]) {
    (
        [0.5 * xi * (xi - 1.0), 0.5 * xi * (xi + 1.0), 1.0 - xi * xi],
        [xi - 0.5, xi + 0.5, -2.0 * xi],
    )
}

/// Natural coordinates of the nodes of `kind` (used for stress extrapolation).
pub fn node_coordinates(kind: CellKind) -> &'static [(f64, f64)] {
    match kind {
        CellKind::Quad8 => &[
            (-1.0, -1.0),
            (1.0, -1.0),
            (1.0, 1.0),
            (-1.0, 1.0),
            (0.0, -1.0),
            (1.0, 0.0),
            (0.0, 1.0),
            (-1.0, 0.0),
        ],
        CellKind::Tri6 => &[
            (0.0, 0.0),
            (1.0, 0.0),
            (0.0, 1.0),
            (0.5, 0.0),
            (0.5, 0.5),
            (0.0, 0.5),
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_kronecker_and_derivatives(kind: CellKind) {
        let nn = kind.node_count();
        for (j, &(x, y)) in node_coordinates(kind).iter().enumerate() {
            let s = cell_shape(kind, x, y);
            for i in 0..nn {
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!(
                    (s.n[i] - expected).abs() < 1e-14,
                    "{kind:?} N{i} at node {j}"
                );
            }
        }
        // Partition of unity and finite-difference derivatives at an arbitrary point.
        let (x, y, h) = (0.21, 0.17, 1e-6);
        let s = cell_shape(kind, x, y);
        assert!((s.n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        let (sx, sy) = (cell_shape(kind, x + h, y), cell_shape(kind, x, y + h));
        let (mx, my) = (cell_shape(kind, x - h, y), cell_shape(kind, x, y - h));
        for i in 0..nn {
            assert!(((sx.n[i] - mx.n[i]) / (2.0 * h) - s.dxi[i]).abs() < 1e-8);
            assert!(((sy.n[i] - my.n[i]) / (2.0 * h) - s.deta[i]).abs() < 1e-8);
        }
    }

    #[test]
    fn quad8_interpolates_nodes_and_derivatives_match() {
        check_kronecker_and_derivatives(CellKind::Quad8);
    }

    #[test]
    fn tri6_interpolates_nodes_and_derivatives_match() {
        check_kronecker_and_derivatives(CellKind::Tri6);
    }

    #[test]
    fn line3_is_lagrange_on_end_end_middle() {
        for (j, xi) in [-1.0, 1.0, 0.0].into_iter().enumerate() {
            let (n, _) = line3(xi);
            for (i, v) in n.iter().enumerate() {
                assert_eq!(*v, if i == j { 1.0 } else { 0.0 });
            }
        }
    }
}
