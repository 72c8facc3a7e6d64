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
