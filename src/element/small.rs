//! Small dense products of the cell kernel (B u, D B, Bᵀ σ dV, Bᵀ D B dV) with exactly the
//! operations of nalgebra's own, in nalgebra's order, so that their results are the same bits,
//! but written out: nalgebra's `Mul`, `gemv_tr` and `gemm_tr` are out-of-line calls built for
//! plain x86-64 even when the kernel calling them is compiled for AVX2
//! ([`super::continuum::evaluate_cell`]), and took a large share of its time. Inlined, they
//! compile into each variant of the kernel.

use nalgebra::{Const, Matrix, RawStorage, RawStorageMut, SMatrix, SVector};

/// M v with the operations of nalgebra's product, in its order (the first column scaled,
/// then each next one added: the same bits), written out so that it is compiled into the
/// caller: nalgebra's `Mul` is an out-of-line call, built for plain x86-64 even from the
/// AVX2 kernel, and took a sixth of a state evaluation's time.
#[inline(always)]
pub(crate) fn product<const R: usize, const C: usize, S>(
    m: &Matrix<f64, Const<R>, Const<C>, S>,
    v: impl std::ops::Index<usize, Output = f64>,
) -> SVector<f64, R>
where
    S: RawStorage<f64, Const<R>, Const<C>>,
{
    let mut y = SVector::<f64, R>::from_fn(|r, _| m[(r, 0)] * v[0]);
    for c in 1..C {
        for r in 0..R {
            y[r] += m[(r, c)] * v[c];
        }
    }
    y
}

/// y += α Mᵀ x with the operations of nalgebra's `gemv_tr(α, M, x, 1)`, in its order (each
/// y_j = α (m_j · x) + 1 y_j, the dot product of a 2- or 4-row column as nalgebra's small
/// cases sum it: the same bits), written out so that it is compiled into the caller:
/// nalgebra's is an out-of-line call built for plain x86-64, and took 30 % of a state
/// evaluation of the tapered press fit.
#[inline(always)]
pub(crate) fn add_transposed_product<const R: usize, const C: usize, S, SX, SY>(
    y: &mut Matrix<f64, Const<C>, Const<1>, SY>,
    alpha: f64,
    m: &Matrix<f64, Const<R>, Const<C>, S>,
    x: &Matrix<f64, Const<R>, Const<1>, SX>,
) where
    S: RawStorage<f64, Const<R>, Const<C>>,
    SX: RawStorage<f64, Const<R>, Const<1>>,
    SY: RawStorageMut<f64, Const<C>, Const<1>>,
{
    const { assert!(R == 2 || R == 4, "columns of 2 or 4 rows only") };
    for j in 0..C {
        let dot = match R {
            2 => m[(0, j)] * x[0] + m[(1, j)] * x[1],
            4 => {
                let (mut a, mut b) = (m[(0, j)] * x[0], m[(1, j)] * x[1]);
                a += m[(2, j)] * x[2];
                b += m[(3, j)] * x[3];
                a + b
            }
            _ => unreachable!(),
        };
        y[j] = alpha * dot + 1.0 * y[j];
    }
}

/// Y += α Aᵀ B with the operations of nalgebra's `gemm_tr(α, A, B, 1)` (each column of Y as
/// [`add_transposed_product`] of B's column: the same bits), compiled into the caller.
#[inline(always)]
pub(crate) fn add_transposed_matrix_product<
    const R: usize,
    const CA: usize,
    const CB: usize,
    SY,
    SA,
    SB,
>(
    y: &mut Matrix<f64, Const<CA>, Const<CB>, SY>,
    alpha: f64,
    a: &Matrix<f64, Const<R>, Const<CA>, SA>,
    b: &Matrix<f64, Const<R>, Const<CB>, SB>,
) where
    SY: RawStorageMut<f64, Const<CA>, Const<CB>>,
    SA: RawStorage<f64, Const<R>, Const<CA>>,
    SB: RawStorage<f64, Const<R>, Const<CB>>,
{
    for j in 0..CB {
        add_transposed_product(
            &mut y.fixed_view_mut::<CA, 1>(0, j),
            alpha,
            a,
            &b.fixed_view::<R, 1>(0, j),
        );
    }
}

/// M B as nalgebra's product of small fixed matrices makes it (column by column, each as
/// [`product`]), compiled into the caller.
#[inline(always)]
pub(crate) fn matrix_product<const R: usize, const K: usize, const C: usize, S>(
    m: &Matrix<f64, Const<R>, Const<K>, S>,
    b: &SMatrix<f64, K, C>,
) -> SMatrix<f64, R, C>
where
    S: RawStorage<f64, Const<R>, Const<K>>,
{
    let mut out = SMatrix::<f64, R, C>::zeros();
    for c in 0..C {
        out.set_column(c, &product(m, b.column(c)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::kinematics::StrainDisplacement;
    use crate::material::Tangent;

    /// The written-out products give nalgebra's bits (the kernel's outputs must not move),
    /// also from a view as the tangent's in-plane block is, on values whose sums round.
    #[test]
    fn written_out_products_give_nalgebras_bits() {
        let value = |k: usize| ((k as f64 + 1.0) * 0.731).sin() * 10f64.powi(k as i32 % 7 - 3);
        let b = StrainDisplacement::from_fn(|r, c| value(16 * r + c));
        let u = SVector::<f64, 16>::from_fn(|r, _| value(r + 101));
        let d = Tangent::from_fn(|r, c| value(6 * r + c + 37));
        let d_plane = d.fixed_view::<4, 4>(0, 0);
        let bits = |m: &[f64]| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(product(&b, u).as_slice()), bits((b * u).as_slice()));
        assert_eq!(
            bits(matrix_product(&d_plane, &b).as_slice()),
            bits((d_plane * b).as_slice())
        );
        // Bᵀ σ dV and Bᵀ (D B) dV added to what is there, for 4- and 2-row operands.
        let stress = SVector::<f64, 4>::from_fn(|r, _| value(r + 211));
        let start = SVector::<f64, 16>::from_fn(|r, _| value(r + 307));
        let (mut ours, mut theirs) = (start, start);
        add_transposed_product(&mut ours, 0.37, &b, &stress);
        theirs.gemv_tr(0.37, &b, &stress, 1.0);
        assert_eq!(bits(ours.as_slice()), bits(theirs.as_slice()));
        let twist = SMatrix::<f64, 2, 8>::from_fn(|r, c| value(8 * r + c + 401));
        let db = matrix_product(&d_plane, &b);
        let start = SMatrix::<f64, 8, 16>::from_fn(|r, c| value(16 * r + c + 503));
        let (mut ours, mut theirs) = (start, start);
        let rows = db.fixed_view::<2, 16>(1, 0);
        add_transposed_matrix_product(&mut ours, 0.37, &twist, &rows);
        theirs.gemm_tr(0.37, &twist, &rows, 1.0);
        assert_eq!(bits(ours.as_slice()), bits(theirs.as_slice()));
        let start = SMatrix::<f64, 16, 16>::from_fn(|r, c| value(16 * r + c + 601));
        let (mut ours, mut theirs) = (start, start);
        add_transposed_matrix_product(&mut ours, 0.37, &b, &db);
        theirs.gemm_tr(0.37, &b, &db, 1.0);
        assert_eq!(bits(ours.as_slice()), bits(theirs.as_slice()));
    }
}
