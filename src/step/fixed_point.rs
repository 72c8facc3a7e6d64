//! (F.1) The sequence of convex problems: freeze the friction bound S, solve the convex step
//! problem (S.6) with an inner solver, update S from the new slip rate, repeat (model.md §4.5).
//!
//! The normal part p_τ(û) of the bound is evaluated at the predictor û = d^n + p_d v_ν^n (see
//! `ContactRule`), so S depends on the unknowns only through μ(‖v̄‖): a constant μ needs one
//! convex solve, and for the exponential law each solve minimizes a convex majorant of the
//! true step functional (the majorization–minimization argument of §4.5).

use super::conic::{self, ConicSettings};
use super::newton::{self, NewtonSettings};
use super::{ContactSolution, StepData};
use crate::linalg;
use crate::model::laws::FrictionCoefficient;

/// Which solver handles each frozen problem.
#[derive(Debug, Clone, Copy)]
pub enum Inner {
    Newton(NewtonSettings),
    Conic(ConicSettings),
    /// (N.4): Newton on the unfrozen problem, falling back to F.1 with `newton` on failure
    NewtonUnfrozen(NewtonSettings),
}

/// Settings of the fixed point.
#[derive(Debug, Clone, Copy)]
pub struct FixedPointSettings {
    pub tolerance: f64,
    pub max_iterations: usize,
    /// θ of S ← θ S_new + (1 − θ) S
    pub relaxation: f64,
}

/// What the step did (one history.csv row's worth of solver facts).
#[derive(Debug, Clone, Default)]
pub struct StepReport {
    /// Newton iterations summed over the convex solves (conic: interior-point iterations)
    pub inner_iterations: usize,
    /// convex solves inside the fixed point (0 when there is no friction to iterate on)
    pub fixed_point_iterations: usize,
    pub fixed_point_converged: bool,
    /// last relative change of S (or of y)
    pub fixed_point_change: f64,
    /// final relative residual of the last inner solve
    pub inner_residual: f64,
    /// unknowns of the step problem: multipliers λ (exact constraint) and friction forces t
    pub multipliers: usize,
    pub friction_unknowns: usize,
    /// `newton-unfrozen` only: the unfrozen Newton solved the step (no fixed point)
    pub unfrozen: bool,
    /// `newton-unfrozen` only: it failed and the step fell back to F.1 (why, in `fallback_reason`)
    pub fallback: bool,
    pub fallback_reason: String,
}

/// Why the step failed.
#[derive(Debug, Clone)]
pub struct InnerFailure {
    pub solver: &'static str,
    pub iterations: usize,
    pub residual: f64,
    pub reason: String,
    pub fixed_point_iteration: usize,
}

fn inner_solve(
    step: &StepData,
    s: &[f64],
    lambda0: &[f64],
    t0: &[f64],
    inner: &Inner,
) -> Result<ContactSolution, (&'static str, usize, f64, String)> {
    match inner {
        Inner::Newton(set) => newton::solve(step, s, lambda0, t0, set).map_err(|f| ("newton", f.iterations, f.residual, f.reason)),
        Inner::Conic(set) => conic::solve(step, s, set).map_err(|f| ("conic", f.iterations, f.residual, f.reason)),
        // inside the fixed point (frictionless steps, fallback) the frozen Newton is used
        Inner::NewtonUnfrozen(set) => newton::solve(step, s, lambda0, t0, set).map_err(|f| ("newton", f.iterations, f.residual, f.reason)),
    }
}

/// (S.5) The friction bound S_i = μ(‖v̄_i‖) p_τ(û_i), with v̄_i the slip rate of the contact
/// velocities y and û_i the (fixed) predictor of u_ν,i^{n+½}.
pub fn friction_bound(step: &StepData, mu: &FrictionCoefficient, p_tau_hat: &[f64], y: &[f64]) -> Vec<f64> {
    (0..step.n()).map(|i| mu.mu(step.slip(i, y).abs()) * p_tau_hat[i]).collect()
}

/// (F.1) Solve one step: fixed point on the frozen friction bound S around the inner solver.
/// `y0` is the initial guess of the contact velocities (v^n), `lambda0`, `t0` warm starts.
/// Returns the solution, the bound S used by the last convex solve (the one (E.1) needs), and
/// the report. Hitting the iteration cap is not an error: the report says so.
#[allow(clippy::too_many_arguments)]
pub fn solve(
    step: &StepData,
    mu: Option<&FrictionCoefficient>,
    p_tau_hat: &[f64],
    y0: &[f64],
    lambda0: &[f64],
    t0: &[f64],
    inner: &Inner,
    fp: &FixedPointSettings,
    mut trace: Option<&mut Vec<Vec<f64>>>,
) -> Result<(ContactSolution, Vec<f64>, StepReport), InnerFailure> {
    let n = step.n();
    let fail = |l: usize, e: (&'static str, usize, f64, String)| InnerFailure {
        solver: e.0,
        iterations: e.1,
        residual: e.2,
        reason: e.3,
        fixed_point_iteration: l,
    };
    let mut report = StepReport {
        multipliers: step.nodes.iter().filter(|nd| nd.bound.is_some()).count(),
        friction_unknowns: if step.friction { n } else { 0 },
        ..StepReport::default()
    };
    let Some(mu) = mu.filter(|_| step.friction) else {
        // frictionless: one convex solve, no fixed point
        let s = vec![0.0; n];
        let sol = inner_solve(step, &s, lambda0, t0, inner).map_err(|e| fail(0, e))?;
        if let Some(tr) = trace {
            tr.push(sol.y.clone());
        }
        report.inner_iterations = sol.iterations;
        report.fixed_point_converged = true;
        report.inner_residual = sol.residual;
        return Ok((sol, s, report));
    };
    if let Inner::NewtonUnfrozen(set) = inner {
        match newton::solve_unfrozen(step, mu, p_tau_hat, lambda0, t0, set) {
            Ok(sol) => {
                let s = friction_bound(step, mu, p_tau_hat, &sol.y);
                if let Some(tr) = trace.as_deref_mut() {
                    tr.push(sol.y.clone());
                }
                report.inner_iterations = sol.iterations;
                report.inner_residual = sol.residual;
                report.fixed_point_converged = true;
                report.unfrozen = true;
                return Ok((sol, s, report));
            }
            Err(f) => {
                report.fallback = true;
                report.fallback_reason = format!("{} (relative residual {:.2e})", f.reason, f.residual);
                report.inner_iterations = f.iterations;
            }
        }
    }
    let mut s = friction_bound(step, mu, p_tau_hat, y0);
    let mut y_prev = y0.to_vec();
    let (mut lam, mut tf) = (lambda0.to_vec(), t0.to_vec());
    let mut last: Option<(ContactSolution, Vec<f64>)> = None;
    for l in 1..=fp.max_iterations {
        let sol = inner_solve(step, &s, &lam, &tf, inner).map_err(|e| fail(l, e))?;
        if let Some(tr) = trace.as_deref_mut() {
            tr.push(sol.y.clone());
        }
        report.inner_iterations += sol.iterations;
        report.fixed_point_iterations = l;
        report.inner_residual = sol.residual;
        let s_new = friction_bound(step, mu, p_tau_hat, &sol.y);
        let ds = s_new.iter().zip(&s).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let s_scale = linalg::norm_inf(&s_new).max(linalg::norm_inf(&s));
        let dy = sol.y.iter().zip(&y_prev).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let y_scale = step.velocity_scale(&sol.y);
        let s_converged = ds <= fp.tolerance * s_scale;
        let y_converged = l > 1 && dy <= fp.tolerance * y_scale;
        report.fixed_point_change = if s_scale > 0.0 { ds / s_scale } else { 0.0 };
        if s_converged || y_converged {
            report.fixed_point_converged = true;
            return Ok((sol, s, report));
        }
        let s_used = s.clone();
        for i in 0..n {
            s[i] = fp.relaxation * s_new[i] + (1.0 - fp.relaxation) * s[i];
        }
        y_prev.clone_from(&sol.y);
        lam.clone_from(&sol.lambda);
        tf.clone_from(&sol.t);
        last = Some((sol, s_used));
    }
    // cap reached: return the last solve and the S it used (the report carries the warning)
    last.map(|(sol, s_used)| (sol, s_used, report))
        .ok_or_else(|| fail(0, ("fixed point", 0, f64::NAN, "max_fixed_point_iterations is 0".into())))
}
