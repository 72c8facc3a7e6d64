//! (F.1) The sequence of convex problems: freeze the friction bound S, solve the convex step
//! problem (S.6) with an inner solver, update S from the new slip rate, repeat (spec/model.md §4.5).
//!
//! The normal part N of S = μ(‖v̄‖) N is one of three ([`NormalPart`]): p_τ at the predictor
//! û = d^n + p_d v_ν^n (the default; see `ContactKinematics`), where S depends on the unknowns only
//! through μ(‖v̄‖), so a constant μ needs one convex solve and for the exponential law each solve
//! minimizes a convex majorant of the true step functional (the majorization–minimization
//! argument of §4.5); p_τ at u_ν^{n+½} of the iterate (Co.2); or the whole contact force q + λ of
//! the iterate (Co.1, Coulomb's law), where S also follows the normal solution and a constant μ
//! iterates too.

use super::conic::{self, ConicSettings};
use super::delassus::DelassusFactors;
use super::newton::{self, NewtonSettings};
use super::{ContactSolution, StepData};
use crate::failure::{ContactFailure, FixedPointStatus, InnerFailure, NewtonFailure};
use crate::linalg;
use crate::model::laws::{FrictionBoundLaw, FrictionCoefficient};

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
    /// Anderson(m) extrapolation of S (m = ANDERSON_DEPTH, with θ = 1): the same fixed point and
    /// the same stopping test, fewer convex solves; false: the plain iteration (the paper's F.1)
    pub anderson: bool,
    /// where F.1 starts each step
    pub start: F1Start,
}

/// Where (F.1) starts each step (`solver.fixed_point_start`, resolved by
/// [`f1_start`](crate::simulation::f1_start)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum F1Start {
    /// S at the predictor's velocities (the paper's start)
    Predictor,
    /// S at the root of the unfrozen Newton (N.4); the predictor's where N.4 fails
    Root,
    /// `Root` if (Ck.1) finds every step problem strictly convex, `Predictor` otherwise: the test
    /// needs W, so the simulation's setup decides; a step handed it unresolved starts at the
    /// predictor
    RootIfSharpConvex,
}

/// What the step did (one history.csv row's worth of solver facts).
#[derive(Debug, Clone, Default)]
pub struct StepReport {
    /// Newton iterations summed over the convex solves (conic: interior-point iterations)
    pub inner_iterations: usize,
    /// convex solves inside the fixed point (0 when there is no friction to iterate on)
    pub fixed_point_iterations: usize,
    pub fixed_point: FixedPointStatus,
    /// last relative change of S (or of y)
    pub fixed_point_change: f64,
    /// final relative residual of the last inner solve
    pub inner_residual: f64,
    /// unknowns of the step problem: multipliers λ (exact constraint) and friction forces t
    pub multipliers: usize,
    pub friction_unknowns: usize,
    /// `newton-unfrozen` only: the unfrozen Newton solved the step (no fixed point)
    pub unfrozen: bool,
    /// `newton-unfrozen`, or F.1's root start: the unfrozen Newton failed and the step fell back
    /// to F.1 from the predictor (why)
    pub fallback: Option<NewtonFailure>,
    /// F.1 started at the unfrozen Newton's root (`FixedPointSettings::start`)
    pub started_unfrozen: bool,
}

impl StepReport {
    pub fn fixed_point_converged(&self) -> bool {
        self.fixed_point == FixedPointStatus::Converged
    }
}

/// One frozen-S solve with the chosen inner solver; `y0`: the last convex solve's contact
/// velocities, where F.1's Newton starts (the conic solver, and the frozen Newton inside N.4's
/// fallback, start from their own).
fn inner_solve(
    step: &StepData,
    factors: &mut DelassusFactors,
    s_bound: &[f64],
    y0: Option<&[f64]>,
    lambda0: &[f64],
    t0: &[f64],
    inner: &Inner,
) -> Result<ContactSolution, InnerFailure> {
    match inner {
        Inner::Newton(set) => match y0 {
            Some(y0) => newton::solve_from(step, factors, s_bound, y0, lambda0, t0, set),
            None => newton::solve(step, factors, s_bound, lambda0, t0, set),
        }
        .map_err(InnerFailure::Newton),
        Inner::Conic(set) => conic::solve(step, s_bound, set).map_err(InnerFailure::Conic),
        // inside the fixed point (frictionless steps, fallback) the frozen Newton is used
        Inner::NewtonUnfrozen(set) => {
            newton::solve(step, factors, s_bound, lambda0, t0, set).map_err(InnerFailure::Newton)
        }
    }
}

/// The normal part N_i of the friction bound S_i = μ(‖v̄_i‖) N_i, as the scene chose it.
#[derive(Debug, Clone, Copy)]
pub enum NormalPart<'a> {
    /// (S.5) p_τ(û_i) at the predictor û_i of u_ν,i^{n+½}, fixed during the step
    Predictor(&'a [f64]),
    /// p_τ(d̂_i(y)) with d̂ = d^n + w (d^{n+1}(y) − d^n): u_ν^{n+½} of the iterate
    /// (w = ½; w = 1, the end point, for backward Euler)
    Midpoint { law: &'a FrictionBoundLaw, weight: f64 },
    /// (q_i(y) + λ_i)_+: the whole contact force of the iterate (Coulomb's law)
    Total,
}

impl NormalPart<'_> {
    /// N_i at the contact velocities y and multipliers λ.
    pub fn at(&self, step: &StepData, i: usize, y: &[f64], lambda: &[f64]) -> f64 {
        match self {
            NormalPart::Predictor(p_hat) => p_hat[i],
            NormalPart::Midpoint { law, weight } => bound_at_iterate(step, law, *weight, i, y),
            NormalPart::Total => total_contact_force(step, i, y, lambda),
        }
    }
}

/// (Co.1) The normal part of Coulomb's bound: the whole contact force of the iterate,
/// N_i = (q_i(y) + λ_i)_+ (compliance force of the scheme plus the multiplier of the constraint;
/// a solve may leave λ_i a round-off below 0, and a bound is never negative).
pub fn total_contact_force(step: &StepData, i: usize, y: &[f64], lambda: &[f64]) -> f64 {
    (step.q(i, y) + lambda[i]).max(0.0)
}

/// (Co.2) p_τ at the iterate: N_i = p_τ(d^n + w (d^{n+1}(y) − d^n)), u_ν^{n+½} for w = ½ (the
/// midpoint rule), u_ν^{n+1} for w = 1 (backward Euler); updated in every (F.1) iteration.
pub fn bound_at_iterate(step: &StepData, law: &FrictionBoundLaw, weight: f64, i: usize, y: &[f64]) -> f64 {
    let d_n = step.nodes[i].d_n;
    law.p_tau(d_n + weight * (step.d_end(i, y) - d_n))
}

/// (S.5) The friction bound S_i = μ(‖v̄_i‖) N_i, with v̄_i the slip rate of the contact
/// velocities y and N_i the normal part (p_τ at the predictor, at the iterate's midpoint, or
/// the whole contact force q_i + λ_i).
pub fn friction_bound(
    step: &StepData,
    mu: &FrictionCoefficient,
    normal: &NormalPart,
    y: &[f64],
    lambda: &[f64],
) -> Vec<f64> {
    (0..step.n()).map(|i| mu.mu(step.slip_norm(i, y)) * normal.at(step, i, y, lambda)).collect()
}

/// (F.1) Solve one step: fixed point on the frozen friction bound S around the inner solver.
/// `y0` is the initial guess of the contact velocities (v^n), `lambda0`, `t0` warm starts;
/// `factors` is the Newton solves' factor cache (it carries over to the next step). Returns the solution, the bound S used by the last convex solve (the one (E.1) needs), and
/// the report. Hitting the iteration cap is not an error: the report says so.
#[allow(clippy::too_many_arguments)]
pub fn solve(
    step: &StepData,
    factors: &mut DelassusFactors,
    mu: Option<&FrictionCoefficient>,
    normal: &NormalPart,
    y0: &[f64],
    lambda0: &[f64],
    t0: &[f64],
    inner: &Inner,
    fp: &FixedPointSettings,
    mut trace: Option<&mut Vec<Vec<f64>>>,
) -> Result<(ContactSolution, Vec<f64>, StepReport), ContactFailure> {
    let n = step.n();
    let fail = |l: usize| move |inner: InnerFailure| ContactFailure { fixed_point_iteration: l, inner };
    let mut report = StepReport {
        multipliers: step.nodes.iter().filter(|nd| nd.bound.is_some()).count(),
        friction_unknowns: if step.friction { n } else { 0 },
        ..StepReport::default()
    };
    let Some(mu) = mu.filter(|_| step.friction) else {
        // frictionless: one convex solve, no fixed point
        let s_bound = vec![0.0; n];
        let sol = inner_solve(step, factors, &s_bound, None, lambda0, t0, inner).map_err(fail(0))?;
        if let Some(tr) = trace {
            tr.push(sol.y.clone());
        }
        report.inner_iterations = sol.iterations;
        report.inner_residual = sol.residual;
        return Ok((sol, s_bound, report));
    };
    // (N.4) for the bound at the predictor, (Co.3) for the total bound: Newton on the unfrozen
    // problem, F.1 as the fallback; the bound at the iterate's midpoint goes to F.1 directly
    if let Inner::NewtonUnfrozen(set) = inner {
        let unfrozen = match normal {
            NormalPart::Predictor(p_tau_hat) => {
                Some(newton::solve_unfrozen(step, factors, mu, p_tau_hat, lambda0, t0, set))
            }
            NormalPart::Total => Some(newton::solve_coulomb(step, factors, mu, lambda0, t0, set)),
            NormalPart::Midpoint { .. } => None,
        };
        match unfrozen {
            Some(Ok(sol)) => {
                let s_bound = friction_bound(step, mu, normal, &sol.y, &sol.lambda);
                if let Some(tr) = trace.as_deref_mut() {
                    tr.push(sol.y.clone());
                }
                report.inner_iterations = sol.iterations;
                report.inner_residual = sol.residual;
                report.unfrozen = true;
                return Ok((sol, s_bound, report));
            }
            Some(Err(f)) => {
                report.inner_iterations = f.iterations;
                report.fallback = Some(f);
            }
            None => {}
        }
    }
    if let (F1Start::Root, Inner::Newton(set), NormalPart::Predictor(p_tau_hat)) = (fp.start, inner, normal) {
        match newton::solve_unfrozen(step, factors, mu, p_tau_hat, lambda0, t0, set) {
            Ok(root) => {
                report.inner_iterations = root.iterations;
                report.started_unfrozen = true;
                return iterate(step, factors, mu, normal, Start::Root(&root), (lambda0, t0), inner, fp, trace, report);
            }
            Err(f) => {
                report.inner_iterations = f.iterations;
                report.fallback = Some(f);
            }
        }
    }
    iterate(step, factors, mu, normal, Start::Predictor(y0), (lambda0, t0), inner, fp, trace, report)
}

/// Where (F.1) starts: S at the initial guess of the contact velocities (the predictor), or at
/// the root of the unfrozen Newton (its velocities and forces also start the first convex solve).
#[derive(Clone, Copy)]
enum Start<'a> {
    Predictor(&'a [f64]),
    Root(&'a ContactSolution),
}

/// The fixed-point iterations of (F.1) proper: solve with S frozen, update S from the new slip
/// rates (relaxed by θ), stop when S or y settles; at the cap, the last solve and its S.
#[allow(clippy::too_many_arguments)]
fn iterate(
    step: &StepData,
    factors: &mut DelassusFactors,
    mu: &FrictionCoefficient,
    normal: &NormalPart,
    start: Start,
    (lambda0, t0): (&[f64], &[f64]),
    inner: &Inner,
    fp: &FixedPointSettings,
    mut trace: Option<&mut Vec<Vec<f64>>>,
    mut report: StepReport,
) -> Result<(ContactSolution, Vec<f64>, StepReport), ContactFailure> {
    let n = step.n();
    let fail = |l: usize| move |inner: InnerFailure| ContactFailure { fixed_point_iteration: l, inner };
    let (y0, lambda0, t0, from_root) = match start {
        Start::Predictor(y0) => (y0, lambda0, t0, false),
        Start::Root(root) => (root.y.as_slice(), root.lambda.as_slice(), root.t.as_slice(), true),
    };
    let mut s_bound = friction_bound(step, mu, normal, y0, lambda0);
    let mut y_prev = y0.to_vec();
    let (mut lam, mut tf) = (lambda0.to_vec(), t0.to_vec());
    let mut last: Option<(ContactSolution, Vec<f64>)> = None;
    // G(S) and G(S) − S of the last ANDERSON_DEPTH iterations, oldest first, for the extrapolation
    let mut history: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    // the relative change of S the last iteration saw (the inner solves' forcing)
    // (from the root, whose S is expected to be the fixed point: the first solve exact)
    let mut change = if from_root { 0.0 } else { crate::defaults::INNER_FORCING_START };
    for l in 1..=fp.max_iterations.max(1) {
        let loose = inexact(inner, change);
        // from the second convex solve on (from the first, started at the root), Newton starts
        // at the last one's solution
        let start = (l > 1 || from_root).then_some(y_prev.as_slice());
        let mut sol = inner_solve(step, factors, &s_bound, start, &lam, &tf, &loose).map_err(fail(l))?;
        if let Some(tr) = trace.as_deref_mut() {
            tr.push(sol.y.clone());
        }
        report.inner_iterations += sol.iterations;
        report.fixed_point_iterations = l;
        report.inner_residual = sol.residual;
        let s_new = friction_bound(step, mu, normal, &sol.y, &sol.lambda);
        let ds = s_new.iter().zip(&s_bound).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let s_scale = linalg::norm_inf(&s_new).max(linalg::norm_inf(&s_bound));
        let dy = sol.y.iter().zip(&y_prev).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let y_scale = step.velocity_scale(&sol.y);
        let s_converged = ds <= fp.tolerance * s_scale;
        let y_converged = l > 1 && dy <= fp.tolerance * y_scale;
        report.fixed_point_change = if s_scale > 0.0 { ds / s_scale } else { 0.0 };
        if s_converged || y_converged {
            // the accepted solve to the Newton tolerance itself ((E.1) holds to it), landed by an
            // exact direction or below NEWTON_LANDING (complementarity to round-off: the
            // constraint dissipation stays monotone)
            if let Inner::Newton(set) = inner
                && (sol.residual > set.tolerance || !sol.exact)
            {
                let polished =
                    inner_solve(step, factors, &s_bound, Some(&sol.y), &sol.lambda, &sol.t, inner).map_err(fail(l))?;
                report.inner_iterations += polished.iterations;
                report.inner_residual = polished.residual;
                sol = polished;
            }
            return Ok((sol, s_bound, report));
        }
        change = report.fixed_point_change;
        let s_used = s_bound.clone();
        let residual: Vec<f64> = s_new.iter().zip(&s_used).map(|(g, s)| g - s).collect();
        let extrapolated =
            if fp.anderson && fp.relaxation == 1.0 { anderson(&s_new, &residual, &history) } else { None };
        match extrapolated {
            Some(s_next) => s_bound = s_next,
            None => {
                for i in 0..n {
                    s_bound[i] = fp.relaxation * s_new[i] + (1.0 - fp.relaxation) * s_bound[i];
                }
            }
        }
        if history.len() == crate::defaults::ANDERSON_DEPTH {
            history.remove(0);
        }
        history.push((s_new, residual));
        y_prev.clone_from(&sol.y);
        lam.clone_from(&sol.lambda);
        tf.clone_from(&sol.t);
        last = Some((sol, s_used));
    }
    // cap reached: return the last solve and the S it used (the report carries the warning);
    report.fixed_point = FixedPointStatus::CapReached;
    let (sol, s_used) = last.expect("the loop above runs at least once and either returns or sets `last`");
    Ok((sol, s_used, report))
}

/// The inner solver for an (F.1) iteration whose bound moved by `change` (relative) in the last
/// iteration: Newton solves it only to [`INNER_FORCING`](crate::defaults::INNER_FORCING) × that
/// change (never looser than `INNER_FORCING` × `INNER_FORCING_START`, never tighter than its own
/// tolerance) — the fixed point does not need a convex problem solved far below the change its
/// next update will make (an inexact fixed-point iteration); the solve that is accepted is
/// brought to the full tolerance (see `iterate`). The conic twin always solves fully.
fn inexact(inner: &Inner, change: f64) -> Inner {
    match inner {
        Inner::Newton(set) => {
            let forcing = crate::defaults::INNER_FORCING * change.min(crate::defaults::INNER_FORCING_START);
            Inner::Newton(NewtonSettings {
                tolerance: set.tolerance.max(forcing),
                inexact: forcing > set.tolerance,
                ..*set
            })
        }
        other => *other,
    }
}

/// (F.1) Anderson(m) step for the fixed point S = G(S): with f = G(S) − S at this iterate and at
/// the earlier ones of `history` ((G_j, f_j), at most ANDERSON_DEPTH), the coefficients γ
/// minimize ‖f − Σ_j γ_j (f − f_j)‖₂ and S_next = G − Σ_j γ_j (G − G_j), clamped at 0 (a bound
/// is never negative); with one earlier iterate γ = f·(f − f_1)/‖f − f_1‖², Anderson(1). None —
/// take the plain step — when the residual did not decrease from the last iterate (the safeguard
/// that keeps the plain iteration's convergence) or the differences are degenerate (the least
/// squares drop directions below 1e-10 of the largest singular value).
fn anderson(g: &[f64], f: &[f64], history: &[(Vec<f64>, Vec<f64>)]) -> Option<Vec<f64>> {
    let (_, f_last) = history.last()?;
    if linalg::dot(f, f) >= linalg::dot(f_last, f_last) {
        return None;
    }
    let differences = nalgebra::DMatrix::from_fn(f.len(), history.len(), |i, j| f[i] - history[j].1[i]);
    let svd = differences.svd(true, true);
    let largest = svd.singular_values.max();
    if !(largest > 0.0 && largest.is_finite()) {
        return None;
    }
    let gamma = svd.solve(&nalgebra::DVector::from_column_slice(f), 1e-10 * largest).ok()?;
    let mut s = g.to_vec();
    for ((g_j, _), gamma_j) in history.iter().zip(gamma.iter()) {
        for (s_i, (g_i, g_ji)) in s.iter_mut().zip(g.iter().zip(g_j)) {
            *s_i -= gamma_j * (g_i - g_ji);
        }
    }
    s.iter_mut().for_each(|v| *v = v.max(0.0));
    s.iter().all(|v| v.is_finite()).then_some(s)
}
