//! W and W⁻¹ from the Schur complement of A_k on the contact unknowns, without forming
//! A_k⁻¹ Hᵀ: one sparse Cholesky factorization of A_k with the contact unknowns ordered last.
//!
//! With the free unknowns split into the interior I and the contact nodes' unknowns C (d per
//! contact node, in contact order), A_k = [A_II A_IC; A_CI A_CC] and
//!   (A_k⁻¹)_CC = S⁻¹,   S = A_CC − A_CI A_II⁻¹ A_IC
//! (the trailing Schur complement). H = R E, with E the selection of C and R the block-diagonal
//! rotation of every contact node into its frame (ν_i, τ_i) — orthogonal, d × d per node — so
//!   W = H A_k⁻¹ Hᵀ = R S⁻¹ Rᵀ,   W⁻¹ = R S Rᵀ.
//! A Cholesky factor L of P A_k Pᵀ whose permutation P puts C last (the interior in the
//! approximate-minimum-degree order of A_II) ends in the block L_CC with L_CC L_CCᵀ = S:
//!   W⁻¹ = R L_CC L_CCᵀ Rᵀ,   W = R L_CC⁻ᵀ L_CC⁻¹ Rᵀ.
//! The cost is that of one factorization of A_k (its last m × m block dense) and ~m³ dense
//! flops, against d n_c solve pairs with A_k's factor for the columns of W.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::linalg::matmul::triangular::{BlockStructure, matmul as tri_matmul};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::{CholeskySymbolicParams, SymbolicCholeskyRaw};
use faer::{Accum, Mat, MatRef, Side};

use crate::linalg::SpMat;
use crate::model::contact::ContactModel;

/// W and W⁻¹ (dense, m × m, contact components (ν_1, τ_1, …)) of A_k `a` (its unknowns at
/// `positions`, for the nested dissection) and the contact model, by the Schur complement (see
/// the module's doc); None when a factorization fails
/// (A_k not positive definite in floating point, or memory), or when the second factor and
/// three m × m matrices (their exact size is known after the symbolic factorization) would
/// exceed `budget` bytes — the caller then takes the solves, which need no second factor.
pub fn delassus_pair(
    a: &SpMat,
    positions: Option<&[[f64; 3]]>,
    contact: &ContactModel,
    budget: Option<f64>,
) -> Option<(Mat<f64>, Mat<f64>)> {
    let l_cc = contact_block_of_factor(a, positions, &contact.dofs, budget)?;
    let m = l_cc.nrows();
    let par = faer::get_global_parallelism();
    // S = L_CC L_CCᵀ (lower triangle), then mirrored
    let mut s = Mat::<f64>::zeros(m, m);
    tri_matmul(
        s.as_mut(),
        BlockStructure::TriangularLower,
        Accum::Replace,
        l_cc.as_ref(),
        BlockStructure::TriangularLower,
        l_cc.transpose(),
        BlockStructure::TriangularUpper,
        1.0,
        par,
    );
    // S⁻¹ = X ᵀ X with X = L_CC⁻¹
    let mut x = Mat::<f64>::zeros(m, m);
    faer::linalg::triangular_inverse::invert_lower_triangular(x.as_mut(), l_cc.as_ref(), par);
    drop(l_cc);
    let mut s_inv = Mat::<f64>::zeros(m, m);
    tri_matmul(
        s_inv.as_mut(),
        BlockStructure::TriangularLower,
        Accum::Replace,
        x.transpose(),
        BlockStructure::TriangularUpper,
        x.as_ref(),
        BlockStructure::TriangularLower,
        1.0,
        par,
    );
    drop(x);
    let winv = rotate(s.as_ref(), contact);
    drop(s);
    let w = rotate(s_inv.as_ref(), contact);
    (w.as_ref().is_all_finite() && winv.as_ref().is_all_finite()).then_some((w, winv))
}

/// R X Rᵀ for a symmetric X of which the lower triangle is read (node blocks of the contact
/// nodes' global unknowns), R the rotation of each contact node into its frame: the full
/// symmetric result in contact components.
fn rotate(x: MatRef<'_, f64>, contact: &ContactModel) -> Mat<f64> {
    let d = contact.dim;
    let n = contact.n();
    // R_i: rows ν, τ_1, (τ_2) of node i's frame
    let r: Vec<[[f64; 3]; 3]> = contact
        .frames
        .iter()
        .map(|f| {
            let mut ri = [[0.0; 3]; 3];
            ri[0] = f.normal;
            ri[1..d].copy_from_slice(&f.tangents[..d - 1]);
            ri
        })
        .collect();
    let sym = |i: usize, j: usize| if i >= j { x[(i, j)] } else { x[(j, i)] };
    let mut out = Mat::<f64>::zeros(d * n, d * n);
    for bj in 0..n {
        for bi in bj..n {
            // block (bi, bj): R_bi X_(bi,bj) R_bjᵀ
            let mut xb = [[0.0; 3]; 3];
            for (a, row) in xb.iter_mut().enumerate().take(d) {
                for (b, v) in row.iter_mut().enumerate().take(d) {
                    *v = sym(d * bi + a, d * bj + b);
                }
            }
            for p in 0..d {
                for q in 0..d {
                    let mut v = 0.0;
                    for a in 0..d {
                        let mut t = 0.0;
                        for b in 0..d {
                            t += xb[a][b] * r[bj][q][b];
                        }
                        v += r[bi][p][a] * t;
                    }
                    out[(d * bi + p, d * bj + q)] = v;
                    out[(d * bj + q, d * bi + p)] = v;
                }
            }
        }
    }
    out
}

/// The last block L_CC (m × m, lower triangular) of the Cholesky factor of P A Pᵀ, P the
/// approximate-minimum-degree order of A — or, where `positions` are given and its factor is the
/// smaller by a margin, the nested dissection (`ordering::analyse`) — with the unknowns `last`
/// moved to the end (in that order), the others keeping their relative order. (Measured on
/// academic3d 48×24×16: the factor holds 104 M entries this way under AMD against 115 M with
/// the interior ordered by the minimum degree of A_II alone, and 62 M without the constraint;
/// 77 M under the nested dissection, and at 64×32×24 280 M against AMD's 498 M.)
pub fn contact_block_of_factor(
    a: &SpMat,
    positions: Option<&[[f64; 3]]>,
    last: &[usize],
    budget: Option<f64>,
) -> Option<Mat<f64>> {
    let n = a.nrows();
    let m = last.len();
    let n_i = n - m;
    let mut is_last = vec![false; n];
    for &l in last {
        // an unknown listed twice (it cannot be: contact nodes are distinct) has no ordering
        if l >= n || std::mem::replace(&mut is_last[l], true) {
            return None;
        }
    }
    let params = CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
        ..Default::default()
    };
    let (symbolic, _) = crate::ordering::analyse(a.symbolic(), positions, last, params).ok()?;
    let needed = 8.0 * (symbolic.len_val() as f64 + 3.0 * (m as f64) * (m as f64));
    if budget.is_some_and(|b| needed > b) {
        return None;
    }
    let par = faer::get_global_parallelism();
    let mut values = Vec::new();
    values.try_reserve_exact(symbolic.len_val()).ok()?;
    values.resize(symbolic.len_val(), 0.0);
    {
        let mut mem =
            MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default())).ok()?;
        symbolic
            .factorize_numeric_llt(
                &mut values,
                a.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .ok()?;
    }
    let SymbolicCholeskyRaw::Supernodal(sym) = symbolic.raw() else { return None };
    let l = SupernodalLltRef::new(sym, &values);
    let mut l_cc = Mat::<f64>::zeros(m, m);
    for s in 0..sym.n_supernodes() {
        let node = l.supernode(s);
        let (start, val, pattern) = (node.start(), node.val(), node.pattern());
        let ncols = val.ncols();
        if start + ncols <= n_i {
            continue;
        }
        for jj in 0..ncols {
            let j = start + jj;
            if j < n_i {
                continue;
            }
            for ii in jj..ncols {
                l_cc[(start + ii - n_i, j - n_i)] = val[(ii, jj)];
            }
            for (p, &r) in pattern.iter().enumerate() {
                l_cc[(r - n_i, j - n_i)] = val[(ncols + p, jj)];
            }
        }
    }
    Some(l_cc)
}
