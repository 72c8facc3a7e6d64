//! (Ck.1) the sharp form of (C.k): the unfrozen step problem's convexity tested through the
//! Delassus operator W instead of the lumped masses.
//!
//! With the bound at the predictor, the step functional in w is a quadratic whose Hessian is A_k
//! (S.2), plus convex normal terms, plus Σ_i (ω_i/a_v) p_τ(û_i) ψ(‖v̄_i‖), whose Hessian in w is
//! at least −a_v ω_i p_τ(û_i) L_μ on node i's tangent components (ψ'' = μ' ≥ −L_μ, ψ' = μ ≥ 0).
//! So the whole is strictly convex when A_k − Tᵀ D T ≻ 0, D = diag(a_v L_μ ω_i p̄_τ) per tangent
//! and T the tangent rows of the slip frames at the contact DOFs; by the Schur complement that is
//! D^½ T W Tᵀ D^½ ≺ I, W = H A_k⁻¹ Hᵀ. (C.k) is the same test with A_k replaced by its lower
//! bound diag(m_i)/k (the lumped masses; over d + 2 with the consistent mass): W ⪯ k diag(m_i)⁻¹
//! on the contact DOFs, so (C.k) implies (Ck.1); the converse fails by as much as the stiffness
//! and the viscosity stiffen A_k beyond diag(m_i)/k.

use faer::Mat;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{LltRegularization, cholesky_in_place, cholesky_in_place_scratch};

use crate::model::contact::ContactModel;
use crate::model::kinds::FrictionBound;

/// The margin δ of the test (1 − δ) I − B ≻ 0: it covers W's solve error and the Cholesky
/// factorization's backward error (≤ m u ‖B‖ ≈ 5e-13 ‖B‖ at m = 4,224 unknowns), and gives up a
/// millionth of the admissible range.
pub const SHARP_CONVEXITY_MARGIN: f64 = 1e-6;

/// (Ck.1) a_v L_μ p̄_τ Ω^½ T W Tᵀ Ω^½ ≺ (1 − δ) I (Ω = diag ω_i, T W Tᵀ = W_ττ the tangent
/// block of W in the slip frames, δ = [`SHARP_CONVEXITY_MARGIN`]), decided by a Cholesky
/// factorization of the difference: Some(true) when every pivot is positive, so every step problem with the bound at
/// the predictor is strictly convex and F.1 has one fixed point; Some(false) when a pivot is not;
/// None where the test does not apply (no friction, constant μ, the total bound, p̄_τ = 0 or
/// unbounded). `w`: the exact (dense) Delassus operator, m × m with m = d n_c in each node's frame
/// components (ν, τ_1, τ_2), node after node, as [`ContactModel::restrict`] orders them.
/// Memory: the (d − 1) n_c square matrix B, factored in place.
pub fn sharp_convex(w: &Mat<f64>, c: &ContactModel, a_v: f64) -> Option<bool> {
    let mu = c.friction.as_ref()?;
    let (p_bar, l_mu) = (c.p_tau.sup(), mu.lipschitz());
    if c.friction_bound == FrictionBound::Total || l_mu == 0.0 || p_bar == 0.0 || !p_bar.is_finite() {
        return None;
    }
    let (d, n_c) = (c.dim, c.n());
    let nt = (d - 1) * n_c;
    // D^½ per node
    let s: Vec<f64> = c.omega.iter().map(|&omega| (a_v * l_mu * omega * p_bar).sqrt()).collect();
    // (1 − δ) I − B, B = D^½ W_ττ D^½: W's rows and columns are each node's frame components
    // (ν, τ_1, τ_2), so its tangent block is the components 1 … d − 1 of every node
    let mut b = Mat::<f64>::zeros(nt, nt);
    for j in 0..n_c {
        for bj in 0..d - 1 {
            let w_col = w.col_as_slice(j * d + 1 + bj);
            let col = b.col_as_slice_mut(j * (d - 1) + bj);
            for i in 0..n_c {
                for a in 0..d - 1 {
                    col[i * (d - 1) + a] = -s[i] * s[j] * w_col[i * d + 1 + a];
                }
            }
        }
    }
    for l in 0..nt {
        b[(l, l)] += 1.0 - SHARP_CONVEXITY_MARGIN;
    }
    let par = faer::get_global_parallelism();
    let mut mem = MemBuffer::try_new(cholesky_in_place_scratch::<f64>(nt, par, Default::default())).ok()?;
    let factored =
        cholesky_in_place(b.as_mut(), LltRegularization::default(), par, MemStack::new(&mut mem), Default::default());
    Some(factored.is_ok())
}
