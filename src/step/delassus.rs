//! The Delassus operator W = H A_k⁻¹ Hᵀ (the fast path of the README's design notes): the response of
//! the contact velocities to unit contact forces. Computed once per run with d n_c solves.

use faer::Mat;

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
