//! Thin wrappers over faer: sparse matrices from triplets, products, the sparse Cholesky
//! factor that the time loop reuses, and a dense LU for the unsymmetric contact systems.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::LltError;
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky};
use faer::sparse::{FaerError, SparseColMat, Triplet};
use faer::{Conj, Mat, Side};

use crate::error::{Error, Result};
use crate::failure::LinearAlgebraFailure;
use crate::ordering::FillOrder;

/// Compressed sparse column matrix of f64.
pub type SpMat = SparseColMat<usize, f64>;

/// Build an n × m matrix from (row, col, value) triplets; duplicates are summed.
pub fn from_triplets(n: usize, m: usize, trip: &[(usize, usize, f64)]) -> Result<SpMat> {
    let t: Vec<Triplet<usize, usize, f64>> = trip.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
    SparseColMat::try_new_from_triplets(n, m, &t).map_err(|e| Error::LinearAlgebra(LinearAlgebraFailure::Assembly(e)))
}

/// All stored entries (row, col, value).
pub fn triplets(a: &SpMat) -> Vec<(usize, usize, f64)> {
    let r = a.as_ref();
    let (cp, ri, v) = (r.symbolic().col_ptr(), r.symbolic().row_idx(), r.val());
    let mut out = Vec::with_capacity(v.len());
    for j in 0..a.ncols() {
        for p in cp[j]..cp[j + 1] {
            out.push((ri[p], j, v[p]));
        }
    }
    out
}

/// y += alpha A x.
pub fn mul_add(a: &SpMat, x: &[f64], alpha: f64, y: &mut [f64]) {
    let r = a.as_ref();
    let (cp, ri, v) = (r.symbolic().col_ptr(), r.symbolic().row_idx(), r.val());
    for j in 0..a.ncols() {
        let xj = alpha * x[j];
        if xj == 0.0 {
            continue;
        }
        let span = cp[j]..cp[j + 1];
        for (&i, &a) in ri[span.clone()].iter().zip(&v[span]) {
            y[i] += a * xj;
        }
    }
}

/// Whether A and B store the same sparsity pattern (one pass can then form products of both).
pub fn same_pattern(a: &SpMat, b: &SpMat) -> bool {
    let (sa, sb) = (a.as_ref().symbolic(), b.as_ref().symbolic());
    a.nrows() == b.nrows() && a.ncols() == b.ncols() && sa.col_ptr() == sb.col_ptr() && sa.row_idx() == sb.row_idx()
}

/// (A x, A y, B y) for symmetric A and B: column j gathers (A x)_j = Σ_p A_pj x_p, and when A
/// and B share a pattern the three sums read the indices of column j once. Equal to
/// [`mul`] up to the order of the sums.
pub fn sym_mul3(a: &SpMat, b: &SpMat, x: &[f64], y: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    if !same_pattern(a, b) {
        return (mul(a, x), mul(a, y), mul(b, y));
    }
    let n = a.ncols();
    let (mut ax, mut ay, mut by) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (ra, rb) = (a.as_ref(), b.as_ref());
    let (cp, ri, va, vb) = (ra.symbolic().col_ptr(), ra.symbolic().row_idx(), ra.val(), rb.val());
    for j in 0..n {
        let span = cp[j]..cp[j + 1];
        let (mut s1, mut s2, mut s3) = (0.0, 0.0, 0.0);
        for ((&i, &a), &b) in ri[span.clone()].iter().zip(&va[span.clone()]).zip(&vb[span]) {
            s1 += a * x[i];
            s2 += a * y[i];
            s3 += b * y[i];
        }
        ax[j] = s1;
        ay[j] = s2;
        by[j] = s3;
    }
    (ax, ay, by)
}

/// A x.
pub fn mul(a: &SpMat, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.nrows()];
    mul_add(a, x, 1.0, &mut y);
    y
}

/// xᵀ A y, column by column: Σ_j y_j (Σ_p A_pj x_p) — reads A once and writes nothing.
pub fn quad(a: &SpMat, x: &[f64], y: &[f64]) -> f64 {
    quad_by(a, |i| x[i], |j| y[j])
}

/// xᵀ A y with x and y given entry by entry (no temporary vectors: the (E.1) terms of a large
/// mesh form x and y from the states on the fly); the same sums as [`quad`].
pub fn quad_by(a: &SpMat, x: impl Fn(usize) -> f64, y: impl Fn(usize) -> f64) -> f64 {
    let r = a.as_ref();
    let (cp, ri, v) = (r.symbolic().col_ptr(), r.symbolic().row_idx(), r.val());
    let mut total = 0.0;
    for j in 0..a.ncols() {
        let yj = y(j);
        if yj == 0.0 {
            continue;
        }
        let span = cp[j]..cp[j + 1];
        let col: f64 = ri[span.clone()].iter().zip(&v[span]).map(|(&i, &a)| a * x(i)).sum();
        total += col * yj;
    }
    total
}

pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

pub fn norm_inf(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// Σ_k c_k A_k for matrices of equal shape.
pub fn combine(terms: &[(f64, &SpMat)]) -> Result<SpMat> {
    let (n, m) = (terms[0].1.nrows(), terms[0].1.ncols());
    let mut trip = Vec::new();
    for (c, a) in terms {
        if *c != 0.0 {
            trip.extend(triplets(a).into_iter().map(|(i, j, v)| (i, j, c * v)));
        }
    }
    from_triplets(n, m, &trip)
}

/// Sparse Cholesky factor L Lᵀ of a symmetric positive definite matrix, computed once, its
/// unknowns ordered by `ordering::analyse` (AMD, or nested dissection where the unknowns'
/// positions are given and its factor is the smaller by a margin).
pub struct Cholesky {
    symbolic: SymbolicCholesky<usize>,
    /// the factor's values, in `symbolic`'s layout
    values: Vec<f64>,
    order: FillOrder,
}

impl Cholesky {
    /// Factor `a` (only its lower triangle is read); `positions`: where each unknown sits (one
    /// per row), for the nested dissection.
    pub fn new(a: &SpMat, what: &str, positions: Option<&[[f64; 3]]>) -> Result<Cholesky> {
        let (symbolic, order) =
            crate::ordering::analyse(a.symbolic(), positions, &[], Default::default()).map_err(|cause| {
                Error::LinearAlgebra(LinearAlgebraFailure::SymbolicCholesky { matrix: what.to_string(), cause })
            })?;
        let numeric = |symbolic: &SymbolicCholesky<usize>| -> std::result::Result<Vec<f64>, LltError> {
            let mut values = Vec::new();
            values.try_reserve_exact(symbolic.len_val()).map_err(|_| FaerError::OutOfMemory)?;
            values.resize(symbolic.len_val(), 0.0);
            let par = faer::get_global_parallelism();
            let mut mem = MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
                .map_err(|_| FaerError::OutOfMemory)?;
            symbolic.factorize_numeric_llt(
                &mut values,
                a.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )?;
            Ok(values)
        };
        let values = numeric(&symbolic).map_err(|cause| {
            Error::LinearAlgebra(LinearAlgebraFailure::Cholesky { matrix: what.to_string(), cause })
        })?;
        Ok(Cholesky { symbolic, values, order })
    }

    pub fn dim(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Stored entries of the factor L.
    pub fn factor_len(&self) -> usize {
        self.symbolic.len_val()
    }

    /// How the factor's unknowns are ordered.
    pub fn fill_order(&self) -> FillOrder {
        self.order
    }

    /// B ← A⁻¹ B for a dense block of right-hand sides.
    pub fn solve_mat_in_place(&self, b: &mut Mat<f64>) {
        let par = faer::get_global_parallelism();
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(b.ncols(), par));
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            b.as_mut(),
            par,
            MemStack::new(&mut mem),
        );
    }

    /// b ← A⁻¹ b.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let par = faer::get_global_parallelism();
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(1, par));
        let col = faer::ColMut::from_slice_mut(b);
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            col.as_mat_mut(),
            par,
            MemStack::new(&mut mem),
        );
    }
}

/// Solve the dense system J x = r by LU with partial pivoting; None if J is singular or the
/// result is not finite.
pub fn dense_solve(j: &Mat<f64>, r: &[f64]) -> Option<Vec<f64>> {
    let n = r.len();
    let lu = j.partial_piv_lu();
    let rhs = Mat::<f64>::from_fn(n, 1, |i, _| r[i]);
    let x = lu.solve(&rhs);
    let out: Vec<f64> = (0..n).map(|i| x[(i, 0)]).collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}
