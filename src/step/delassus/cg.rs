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

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;
    use faer::matrix_free::IdentityPrecond;

    /// A symmetric positive definite n × n matrix (diagonally dominant: the off-diagonal row sums
    /// stay below 2 Σ 1/k² < 3.3 < 4) and a rectangular companion K.
    fn system(n: usize) -> (Mat<f64>, Mat<f64>, Vec<f64>) {
        let a = Mat::from_fn(n, n, |i, j| {
            if i == j { 4.0 + 0.1 * i as f64 } else { 1.0 / (1.0 + (i as f64 - j as f64).abs()).powi(2) }
        });
        let k = Mat::from_fn(n + 5, n, |i, j| ((i * 7 + j * 3) % 11) as f64 - 5.0);
        let b = (0..n).map(|l| ((l * 7919 + 13) % 101) as f64 / 101.0 - 0.5).collect();
        (a, k, b)
    }

    fn product(m: &Mat<f64>, v: &[f64]) -> Vec<f64> {
        (0..m.nrows()).map(|i| (0..m.ncols()).map(|j| m[(i, j)] * v[j]).sum()).collect()
    }

    /// (N.1) The tracked conjugate gradients (the velocity form's directions) stop at their
    /// relative residual, and the companion they sum is K applied to the x they return: to
    /// 1e-13 of ‖K‖∞‖x‖∞ (round-off of the ~30 sums; the companion is never formed from x);
    /// on a negative definite matrix they stop at the first curvature test.
    #[test]
    fn tracked_conjugate_gradients_sum_the_companion_of_their_answer() {
        let n = 30;
        let (a, k, b) = system(n);
        let apply = |p: &[f64], ap: &mut [f64], kp: &mut [f64]| {
            ap.copy_from_slice(&product(&a, p));
            kp.copy_from_slice(&product(&k, p));
        };
        let (mut x, mut kx) = (vec![1.0; n], vec![1.0; n + 5]);
        let prec = IdentityPrecond { dim: n };
        let iterations = conjugate_gradients_tracked(apply, &prec, &b, (&mut x, &mut kx), 1e-12, 100)
            .expect("an SPD system converges");
        assert!(iterations > 1 && iterations < n, "{iterations} iterations");
        let ax = product(&a, &x);
        let residual = ax.iter().zip(&b).map(|(p, q)| (p - q).powi(2)).sum::<f64>().sqrt();
        let b_norm = b.iter().map(|v| v * v).sum::<f64>().sqrt();
        // the stopping test on the recurrence's residual; recomputed from x it carries the
        // round-off of one product more (~n u ‖A‖ ‖x‖ ≈ 1e-14 ‖b‖ here)
        assert!(residual <= 2e-12 * b_norm, "‖b − A x‖ = {residual:e}");
        let exact = product(&k, &x);
        let k_norm = (0..k.nrows()).map(|i| (0..n).map(|j| k[(i, j)].abs()).sum::<f64>()).fold(0.0, f64::max);
        let x_norm = x.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        let err = exact.iter().zip(&kx).fold(0.0f64, |s, (p, q)| s.max((p - q).abs()));
        assert!(err <= 1e-13 * k_norm * x_norm, "‖K x − Σ α K p‖∞ = {err:e}");

        let negative = |p: &[f64], ap: &mut [f64], kp: &mut [f64]| {
            ap.iter_mut().zip(product(&a, p)).for_each(|(o, v)| *o = -v);
            kp.copy_from_slice(&product(&k, p));
        };
        assert_eq!(conjugate_gradients_tracked(negative, &prec, &b, (&mut x, &mut kx), 1e-12, 100), None);
    }
}
