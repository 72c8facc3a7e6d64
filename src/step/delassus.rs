//! The Delassus operator W = H A_k⁻¹ Hᵀ (the fast path of the README's design notes): the response of
//! the contact velocities to unit contact forces. Computed once per run with d n_c solves.

use std::cell::RefCell;

use faer::linalg::solvers::{Llt, Solve};
use faer::{Mat, Side};

use crate::linalg::Cholesky;
use crate::model::contact::ContactModel;

/// W (d n_c × d n_c, symmetric positive definite), components (ν_1, τ_1, …, ν_2, τ_2, …).
pub fn delassus(a: &Cholesky, contact: &ContactModel) -> Mat<f64> {
    let m = contact.dim * contact.n();
    let n = a.dim();
    let mut w = Mat::<f64>::zeros(m, m);
    const BLOCK: usize = 64;
    let mut start = 0;
    while start < m {
        let cols = BLOCK.min(m - start);
        let mut rhs = Mat::<f64>::zeros(n, cols);
        for c in 0..cols {
            let mut e = vec![0.0; m];
            e[start + c] = 1.0;
            let mut col = vec![0.0; n];
            contact.scatter_add(&e, &mut col);
            for (i, v) in col.iter().enumerate() {
                if *v != 0.0 {
                    rhs[(i, c)] = *v;
                }
            }
        }
        a.solve_mat_in_place(&mut rhs);
        for c in 0..cols {
            let x: Vec<f64> = (0..n).map(|i| rhs[(i, c)]).collect();
            let hx = contact.restrict(&x);
            for (j, v) in hx.iter().enumerate() {
                w[(j, start + c)] = *v;
            }
        }
        start += cols;
    }
    // symmetrize the round-off
    for i in 0..m {
        for j in 0..i {
            let s = 0.5 * (w[(i, j)] + w[(j, i)]);
            w[(i, j)] = s;
            w[(j, i)] = s;
        }
    }
    w
}

/// Cholesky factorizations of W_UU + D (a principal submatrix of the Delassus operator plus a
/// nonnegative diagonal), the Newton matrix of the frozen step problem (see
/// `newton::reduced_direction`). The last one is kept with its key (U, D): Newton, the F.1
/// iterations and the next steps reuse it while their active and stick sets, and so the matrix,
/// are unchanged. A reuse is bit-identical to refactoring: the cache changes the cost, never the
/// answer.
#[derive(Default)]
pub struct DelassusFactors {
    last: RefCell<Option<Factor>>,
    /// factorizations computed and reused (for the benchmark's accounting)
    counts: RefCell<(usize, usize)>,
}

struct Factor {
    unknown: Vec<usize>,
    diag: Vec<f64>,
    llt: Llt<f64>,
}

impl DelassusFactors {
    /// Solve (W_UU + D) x = b in place, U = `unknown` (indices into W), D = `diag`. None when
    /// the matrix is not numerically positive definite.
    pub fn solve(&self, w: &Mat<f64>, unknown: &[usize], diag: &[f64], b: &mut [f64]) -> Option<()> {
        let mut last = self.last.borrow_mut();
        let hit = last.as_ref().is_some_and(|f| f.unknown == unknown && f.diag == diag);
        if !hit {
            let k = unknown.len();
            let a = Mat::<f64>::from_fn(k, k, |i, j| w[(unknown[i], unknown[j])] + if i == j { diag[i] } else { 0.0 });
            let llt = a.llt(Side::Lower).ok()?;
            *last = Some(Factor { unknown: unknown.to_vec(), diag: diag.to_vec(), llt });
            self.counts.borrow_mut().0 += 1;
        } else {
            self.counts.borrow_mut().1 += 1;
        }
        let f = last.as_ref()?;
        let mut rhs = faer::MatMut::from_column_major_slice_mut(b, unknown.len(), 1);
        f.llt.solve_in_place(rhs.as_mut());
        b.iter().all(|v| v.is_finite()).then_some(())
    }

    /// (factorizations computed, factorizations reused) so far.
    pub fn counts(&self) -> (usize, usize) {
        *self.counts.borrow()
    }
}
