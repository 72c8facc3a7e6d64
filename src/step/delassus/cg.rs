//! Conjugate gradients, the driver both the force form's preconditioned solves (`factors`) and
//! the velocity form (`inverse`) use.

use faer::Par;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::matrix_free::conjugate_gradient::{CgParams, conjugate_gradient, conjugate_gradient_scratch};
use faer::matrix_free::{InitialGuessStatus, LinOp, Precond};

/// Conjugate gradients (faer's `matrix_free::conjugate_gradient`) on `op` x = b preconditioned
/// by `prec`, from the initial guess in `x`, to the relative residual `tolerance` within
/// `max_iterations`: the iterations, or None (x unspecified) when they did not get there or met
/// a non-positive curvature.
pub(super) fn conjugate_gradients(
    op: &impl LinOp<f64>,
    prec: &impl Precond<f64>,
    b: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
) -> Option<usize> {
    let n = b.len();
    let params = CgParams {
        initial_guess: InitialGuessStatus::MaybeNonZero,
        abs_tolerance: 0.0,
        rel_tolerance: tolerance,
        max_iters: max_iterations,
        ..CgParams::default()
    };
    let mut mem = MemBuffer::new(conjugate_gradient_scratch(prec, op, 1, Par::Seq));
    let info = conjugate_gradient(
        faer::MatMut::from_column_major_slice_mut(x, n, 1),
        prec,
        op,
        faer::MatRef::from_column_major_slice(b, n, 1),
        params,
        |_| {},
        Par::Seq,
        MemStack::new(&mut mem),
    )
    .ok()?;
    x.iter().all(|v| v.is_finite()).then_some(info.iter_count)
}

/// Preconditioned conjugate gradients from x = 0 on A x = b, where each product A p comes with
/// a companion K p (linear in p, `apply(p, A p, K p)`): K x = Σ α_k K p_k is summed beside
/// x = Σ α_k p_k, so the caller has K x without another product. The velocity form's products
/// give (W⁻¹)_FF p + Ĝ_F p and the whole W⁻¹ p, and its Newton direction needs W⁻¹ x on the
/// prescribed rows too (written by hand: faer's conjugate gradients above do not expose their
/// search directions' products). Stops like them: relative residual ‖b − A x‖₂ < `tolerance`
/// ‖b‖₂ within `max_iterations`. The iterations, or None (x and K x unspecified) when they did
/// not get there, met a non-positive curvature pᵀ A p ≤ 0, or a value that is not finite.
pub(super) fn conjugate_gradients_tracked(
    apply: impl Fn(&[f64], &mut [f64], &mut [f64]),
    prec: &impl LinOp<f64>,
    b: &[f64],
    (x, kx): (&mut [f64], &mut [f64]),
    tolerance: f64,
    max_iterations: usize,
) -> Option<usize> {
    let n = b.len();
    x.iter_mut().for_each(|v| *v = 0.0);
    kx.iter_mut().for_each(|v| *v = 0.0);
    let dot = |a: &[f64], c: &[f64]| a.iter().zip(c).map(|(a, c)| a * c).sum::<f64>();
    let threshold = tolerance * dot(b, b).sqrt();
    if threshold == 0.0 && b.iter().all(|v| *v == 0.0) {
        return Some(0);
    }
    let precondition = |r: &[f64], z: &mut [f64]| {
        prec.apply(
            faer::MatMut::from_column_major_slice_mut(z, n, 1),
            faer::MatRef::from_column_major_slice(r, n, 1),
            Par::Seq,
            MemStack::new(&mut []),
        )
    };
    let mut r = b.to_vec();
    let mut z = vec![0.0; n];
    precondition(&r, &mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let (mut ap, mut kp) = (vec![0.0; n], vec![0.0; kx.len()]);
    for iteration in 0..max_iterations {
        apply(&p, &mut ap, &mut kp);
        let pap = dot(&p, &ap);
        if !(pap > 0.0 && pap.is_finite()) {
            return None;
        }
        let alpha = rz / pap;
        for l in 0..n {
            x[l] += alpha * p[l];
            r[l] -= alpha * ap[l];
        }
        for (k, v) in kx.iter_mut().zip(&kp) {
            *k += alpha * v;
        }
        let residual = dot(&r, &r).sqrt();
        if !residual.is_finite() {
            return None;
        }
        if residual < threshold {
            return Some(iteration + 1);
        }
        precondition(&r, &mut z);
        let rz_next = dot(&r, &z);
        let beta = rz_next / rz;
        rz = rz_next;
        for l in 0..n {
            p[l] = z[l] + beta * p[l];
        }
    }
    None
}
