//! The inner solver `newton`: Alart–Curnier semismooth Newton on the frozen-S step problem
//! (spec/model.md §4.4), condensed on the contact DOFs.
//!
//! All residuals are written in velocity units so one norm and one tolerance apply:
//!   (N.1) F_y = y − y_free + W r(y, λ, t)
//!   (N.2) F_λ,i = (λ_i − [λ_i + ρ_ν,i (y_ν,i − β_i)]_+) / ρ_ν,i
//!   (N.3) F_t,i = (t_i − Proj_[−S_i, S_i](t_i + ρ_τ,i v̄_i)) / (ρ_τ,i a_v)
//!         (in 3-D t_i, v̄_i are tangent-plane vectors and the projection is onto the disk
//!         ‖t‖ ≤ S_i; ρ_τ,i uses the mean of the node's two tangential diagonal entries of W)
//! where y_ν ≤ β_i ⟺ d^{n+1} ≤ g, and ρ_ν = r_ν a_d, ρ_τ = r_τ relate to spec/model.md's r_ν, r_τ.
//! The solution does not depend on ρ (tested); the default ρ_ν,i = 1/(ω_i W_νν,ii) and
//! ρ_τ,i = 1/(a_v ω_i W_ττ,ii) make the trial values exact for an isolated node.
//!
//! The direction, by the first form that applies:
//! - **velocity form** (`velocity_direction`; a dense, well-conditioned W of ≥ 256 unknowns with
//!   W⁻¹ kept, and no Co.3 coupling): conjugate gradients on [(W⁻¹)_FF + ω Ĝ_F] Δy_F = b over the
//!   free components, node-block preconditioned — matrix–vector products only. It takes the 3-D
//!   slip blocks as they are and the unfrozen bound of N.4 (symmetrized: v̂ = ẑ), positive
//!   definite wherever the step problem is convex;
//! - **force form** (`reduced_direction`; frozen S, monotone normal law): Cholesky on the force
//!   unknowns, each slipping 3-D node read in its (ẑ, ẑ^⊥) frame (its force is known along ẑ and
//!   follows the slip rate across it), the factor reused exactly while U, D and the frames hold
//!   and as the preconditioner of conjugate gradients while U holds (`DelassusFactors`);
//! - **general** (`general_direction`): the full m × m LU — Co.3's coupling of the friction force
//!   to the normal force, N.4 where no velocity form is kept, and the reference the others are
//!   tested against.
//!
//! Conjugate gradients stop at the Eisenstat–Walker forcing min(1e-3, 0.1 ‖F‖/scale), which keeps
//! Newton's quadratic convergence.

use faer::Mat;

use super::delassus::{DelassusFactors, DirectionForm, InverseDelassus, SlipFrames};
use super::{ContactSolution, NodeStatus, StepData};
use crate::defaults::{ARMIJO, LINE_SEARCH_HALVINGS, MAX_ITERATIONS, NEWTON_TOLERANCE};
use crate::failure::{NewtonFailure, NewtonStatus};
use crate::linalg;
use crate::model::laws::FrictionCoefficient;

/// The friction bound the Newton solve sees.
#[derive(Debug, Clone, Copy)]
pub enum SlipBound<'a> {
    /// S_i frozen (the convex problem (S.6) of one F.1 iteration)
    Frozen(&'a [f64]),
    /// (N.4) S_i = μ(|v̄_i|) p̂_i, a function of the unknowns (no fixed point)
    Law { mu: &'a FrictionCoefficient, p_hat: &'a [f64] },
    /// (Co.3) S_i = μ(|v̄_i|)(q_i + λ_i)_+: Coulomb's disk whose radius follows the normal force
    /// of the iterate (GetFEM's coupled projection), with the slip rate in μ too
    Coulomb { mu: &'a FrictionCoefficient },
}

/// The friction bound at node i and its derivatives: with respect to the slip rate v̄_i and
/// to the normal force N_i = q_i + λ_i. In 2-D v̄_i is the signed slip rate along τ; in 3-D
/// `ds_dv` is the derivative with respect to the slip speed ‖v̄_i‖ (S depends on v̄ only
/// through it).
#[derive(Debug, Clone, Copy)]
struct NodeBound {
    s: f64,
    ds_dv: f64,
    ds_dn: f64,
}

impl SlipBound<'_> {
    /// S_i and its derivatives at the iterate (y, λ).
    fn at(&self, step: &StepData, i: usize, y: &[f64], lambda: &[f64]) -> NodeBound {
        // μ(|v̄|) and dμ/dv̄ (2-D, signed) or dμ/d‖v̄‖ (3-D)
        let mu_at = |mu: &FrictionCoefficient| {
            if step.tdim() == 1 {
                let vbar = step.slip(i, y);
                (mu.mu(vbar.abs()), mu.dmu(vbar.abs()) * vbar.signum())
            } else {
                let speed = step.slip_norm(i, y);
                (mu.mu(speed), mu.dmu(speed))
            }
        };
        match self {
            SlipBound::Frozen(s) => NodeBound { s: s[i], ds_dv: 0.0, ds_dn: 0.0 },
            SlipBound::Law { mu, p_hat } => {
                let (m, dm) = mu_at(mu);
                NodeBound { s: m * p_hat[i], ds_dv: dm * p_hat[i], ds_dn: 0.0 }
            }
            SlipBound::Coulomb { mu } => {
                let n = step.q(i, y) + lambda[i];
                let (m, dm) = mu_at(mu);
                if n > 0.0 {
                    NodeBound { s: m * n, ds_dv: dm * n, ds_dn: m }
                } else {
                    NodeBound { s: 0.0, ds_dv: 0.0, ds_dn: 0.0 }
                }
            }
        }
    }
    /// S_i at every node for the iterate (y, λ).
    pub fn values(&self, step: &StepData, y: &[f64], lambda: &[f64]) -> Vec<f64> {
        (0..step.n()).map(|i| self.at(step, i, y, lambda).s).collect()
    }
}

/// Settings of the Newton solve.
#[derive(Debug, Clone, Copy)]
pub struct NewtonSettings {
    /// stop when ‖F‖_∞ ≤ tolerance · (velocity scale) and the active/stick sets are stable
    pub tolerance: f64,
    pub max_iterations: usize,
    /// multiplies the default ρ_ν, ρ_τ (the solution must not depend on them)
    pub scale_normal: f64,
    pub scale_tangent: f64,
    /// solve the symmetric cases' Newton systems on the force unknowns by Cholesky with the
    /// factorization reused (`reduced_direction`, the default); false: the full m × m LU for
    /// every direction (the reference the reduced system is tested against)
    pub reduced: bool,
    /// an inexact solve of the fixed point (F.1): its answer is only a step towards the bound's
    /// fixed point (the accepted one is solved again to the full tolerance), so every direction
    /// may be loose (`DirectionForm::Loose`) and Newton may stop after a loose one
    pub inexact: bool,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        NewtonSettings {
            tolerance: NEWTON_TOLERANCE,
            max_iterations: MAX_ITERATIONS,
            scale_normal: 1.0,
            scale_tangent: 1.0,
            reduced: true,
            inexact: false,
        }
    }
}

struct Params {
    rho_n: Vec<f64>,
    rho_t: Vec<f64>,
}

/// (N.1) Momentum residual of the condensed step: F_y = y − y_free + W r(y, λ, t).
pub fn momentum_residual(step: &StepData, y: &[f64], lambda: &[f64], t: &[f64]) -> Vec<f64> {
    let r = step.forces(y, lambda, t);
    let resp = step.response(&r);
    y.iter().zip(&resp).map(|(a, b)| a - b).collect()
}

/// (N.2) Alart–Curnier residual of the normal constraint (S.4):
/// F_λ = (λ − [λ + ρ_ν (y_ν − β)]_+)/ρ_ν; zero iff λ ≥ 0, y_ν ≤ β, λ (y_ν − β) = 0.
pub fn normal_residual(lambda: f64, y_n: f64, beta: f64, rho_n: f64) -> f64 {
    (lambda - (lambda + rho_n * (y_n - beta)).max(0.0)) / rho_n
}

/// (N.3) Alart–Curnier residual of the friction law (S.5) with S frozen:
/// F_t = (t − Proj_[−S,S](t + ρ_τ v̄))/(ρ_τ a_v); zero iff |t| ≤ S and t = S v̄/|v̄| when v̄ ≠ 0.
pub fn friction_residual(t: f64, slip: f64, s: f64, rho_t: f64, a_v: f64) -> f64 {
    (t - (t + rho_t * slip).clamp(-s, s)) / (rho_t * a_v)
}

/// (N.3) in 3-D: F_t = (t − Proj_D(S)(t + ρ_τ v̄))/(ρ_τ a_v), Proj_D(S) the projection onto the
/// disk of radius S in the tangent plane; zero iff ‖t‖ ≤ S and t = S v̄/‖v̄‖ when v̄ ≠ 0.
pub fn friction_residual_disk(t: [f64; 2], slip: [f64; 2], s: f64, rho_t: f64, a_v: f64) -> [f64; 2] {
    let z = [t[0] + rho_t * slip[0], t[1] + rho_t * slip[1]];
    let nz = z[0].hypot(z[1]);
    let scale = if nz > s { s / nz } else { 1.0 };
    std::array::from_fn(|j| (t[j] - scale * z[j]) / (rho_t * a_v))
}

/// Node i's friction forces as a pair (the second 0 in 2-D).
fn t_of(step: &StepData, t: &[f64], i: usize) -> [f64; 2] {
    let td = step.tdim();
    std::array::from_fn(|j| if j < td { t[td * i + j] } else { 0.0 })
}

fn residual(step: &StepData, s: &SlipBound, p: &Params, y: &[f64], lambda: &[f64], t: &[f64]) -> Vec<f64> {
    let n = step.n();
    let mut f = momentum_residual(step, y, lambda, t);
    f.reserve(2 * n); // F_λ and F_t per node
    for i in 0..n {
        f.push(match step.beta(i) {
            Some(beta) => normal_residual(lambda[i], y[step.nu(i)], beta, p.rho_n[i]),
            None => 0.0,
        });
    }
    if step.tdim() == 1 {
        for i in 0..n {
            let vbar = step.slip(i, y);
            f.push(if step.friction {
                friction_residual(t[i], vbar, s.at(step, i, y, lambda).s, p.rho_t[i], step.a_v)
            } else {
                0.0
            });
        }
    } else {
        for i in 0..n {
            let ft = if step.friction {
                friction_residual_disk(
                    t_of(step, t, i),
                    step.slip_vec(i, y),
                    s.at(step, i, y, lambda).s,
                    p.rho_t[i],
                    step.a_v,
                )
            } else {
                [0.0; 2]
            };
            f.extend(ft);
        }
    }
    f
}

/// Active normal constraints and stick nodes at an iterate.
fn sets(step: &StepData, s: &SlipBound, p: &Params, y: &[f64], lambda: &[f64], t: &[f64]) -> (Vec<bool>, Vec<bool>) {
    let n = step.n();
    let active = (0..n)
        .map(|i| step.beta(i).is_some_and(|beta| lambda[i] + p.rho_n[i] * (y[step.nu(i)] - beta) > 0.0))
        .collect();
    let stick = (0..n)
        .map(|i| {
            if !step.friction {
                return false;
            }
            let bound = s.at(step, i, y, lambda).s;
            if step.tdim() == 1 {
                (t[i] + p.rho_t[i] * step.slip(i, y)).abs() <= bound
            } else {
                let (ti, v) = (t_of(step, t, i), step.slip_vec(i, y));
                (ti[0] + p.rho_t[i] * v[0]).hypot(ti[1] + p.rho_t[i] * v[1]) <= bound
            }
        })
        .collect();
    (active, stick)
}

/// Solve the frozen-S step problem by semismooth Newton with a backtracking line search on
/// ‖F‖₂. `s` is the frozen friction bound per node (ignored when frictionless); `lambda0`,
/// `t0` warm-start the multipliers; `factors` is the factor cache of the force form (reused,
/// replaced and counted: the next solve's path depends on it).
pub fn solve(
    step: &StepData,
    factors: &mut DelassusFactors,
    s: &[f64],
    lambda0: &[f64],
    t0: &[f64],
    set: &NewtonSettings,
) -> Result<ContactSolution, NewtonFailure> {
    solve_with(step, factors, &SlipBound::Frozen(s), None, lambda0, t0, set)
}

/// [`solve`] started at the contact velocities `y0` (with `lambda0`, `t0`) instead of the ones
/// the warm-started forces give at the free motion: F.1's next convex problem from the last
/// one's solution, which differs from it by the change of S (the solution itself does not
/// depend on the start: the frozen problem is convex with a unique y).
pub fn solve_from(
    step: &StepData,
    factors: &mut DelassusFactors,
    s: &[f64],
    y0: &[f64],
    lambda0: &[f64],
    t0: &[f64],
    set: &NewtonSettings,
) -> Result<ContactSolution, NewtonFailure> {
    solve_with(step, factors, &SlipBound::Frozen(s), Some(y0), lambda0, t0, set)
}

/// (N.4) Semismooth Newton on the unfrozen Alart–Curnier system: the friction bound
/// S_i = μ(|v̄_i|) p_τ(û_i) is a function of the unknowns inside the projection of (N.3), and
/// the slip branch of the generalized Jacobian carries ∂t_i/∂y_τ,i = σ_i S'(v̄_i) a_v
/// (S' = p̂ μ'(|v̄|) sgn v̄); no fixed point. Globalized by the line search on ‖F‖₂.
pub fn solve_unfrozen(
    step: &StepData,
    factors: &mut DelassusFactors,
    mu: &FrictionCoefficient,
    p_hat: &[f64],
    lambda0: &[f64],
    t0: &[f64],
    set: &NewtonSettings,
) -> Result<ContactSolution, NewtonFailure> {
    solve_with(step, factors, &SlipBound::Law { mu, p_hat }, None, lambda0, t0, set)
}

/// (Co.3) Semismooth Newton on the coupled Alart–Curnier system of Coulomb's law with the
/// whole contact force: the bound S_i = μ(|v̄_i|)(q_i + λ_i) is a function of the unknowns inside
/// the projection of (N.3), so the slip branch carries ∂t_i/∂N_i = σ_i μ(|v̄_i|) (the disk radius
/// follows the normal force, as in GetFEM's coupled projection) and ∂t_i/∂y_τ,i = σ_i μ' N_i a_v;
/// no fixed point. Globalized by the line search on ‖F‖₂.
pub fn solve_coulomb(
    step: &StepData,
    factors: &mut DelassusFactors,
    mu: &FrictionCoefficient,
    lambda0: &[f64],
    t0: &[f64],
    set: &NewtonSettings,
) -> Result<ContactSolution, NewtonFailure> {
    solve_with(step, factors, &SlipBound::Coulomb { mu }, None, lambda0, t0, set)
}

/// An iterate of the Newton solve: contact velocities, multipliers, friction forces, and the
/// residual F at them.
struct Iterate {
    y: Vec<f64>,
    lambda: Vec<f64>,
    t: Vec<f64>,
    f: Vec<f64>,
}

/// Semismooth Newton for either friction bound (frozen: the convex problem of F.1; law: the
/// unfrozen problem of N.4): stop test, Newton direction on the reduced system, line search.
/// `y0`: the contact velocities to start from (None: those the warm-started forces give).
pub fn solve_with(
    step: &StepData,
    factors: &mut DelassusFactors,
    bound: &SlipBound,
    y0: Option<&[f64]>,
    lambda0: &[f64],
    t0: &[f64],
    set: &NewtonSettings,
) -> Result<ContactSolution, NewtonFailure> {
    let s = bound;
    let p = Params::new(step, set);
    let mut x = initial_iterate(step, s, &p, y0, lambda0, t0);
    let mut prev_sets: Option<(Vec<bool>, Vec<bool>)> = None;
    let mut prev_ok = false;
    // the velocity form's loose directions (see `DirectionForm`): while the sets move, and
    // throughout an inexact solve; Newton stops otherwise only after an exact direction or once
    // the residual has landed below NEWTON_LANDING of the velocity scale
    let loose_form = step.inverse.is_some_and(InverseDelassus::has_loose_form);
    let mut last_exact = true;
    for it in 0..=set.max_iterations {
        let scale = step.velocity_scale(&x.y);
        let res = linalg::norm_inf(&x.f);
        let ok = res <= set.tolerance * scale;
        let cur_sets = sets(step, s, &p, &x.y, &x.lambda, &x.t);
        let stable = prev_sets.as_ref() == Some(&cur_sets);
        if loose_form && it == 1 {
            // whether the next solve starts with a loose direction
            factors.first_sets_moved = !stable;
        }
        // landed to round-off: the iterate solves (N.1)–(N.3) as closely as an exact direction
        // lands, whatever direction got it there (at the start too: a warm start already there)
        let landed = loose_form && res <= crate::defaults::NEWTON_LANDING * scale;
        if landed || ok && (stable || prev_ok || it == 0 && res == 0.0) && (last_exact || set.inexact) {
            let relative = if scale > 0.0 { res / scale } else { res };
            return Ok(solution(step, x, &cur_sets.1, it, relative, last_exact || landed));
        }
        if it == set.max_iterations {
            break;
        }
        prev_ok = ok;
        // exact once the sets hold (or the residual is within the tolerance already), and at the
        // start unless the last solve's first sets moved
        let settled = stable || ok || (it == 0 && !factors.first_sets_moved);
        let form = if loose_form && (set.inexact || !settled) { DirectionForm::Loose } else { DirectionForm::Exact };
        let Some((dy, dm)) = direction(step, factors, s, &p, &x, &cur_sets, (set.reduced, form)) else {
            return Err(NewtonFailure {
                status: NewtonStatus::SingularJacobian,
                iterations: it,
                residual: res / scale.max(f64::MIN_POSITIVE),
            });
        };
        last_exact = form == DirectionForm::Exact;
        prev_sets = Some(cur_sets);
        x = line_search(step, s, &p, x, &dy, &dm);
    }
    let scale = step.velocity_scale(&x.y);
    let res = linalg::norm_inf(&x.f);
    Err(NewtonFailure {
        status: if res.is_finite() { NewtonStatus::MaxIterations } else { NewtonStatus::NonFinite },
        iterations: set.max_iterations,
        residual: if scale > 0.0 { res / scale } else { res },
    })
}

impl Params {
    /// ρ_ν,i = 1/(ω_i W_νν,ii) and ρ_τ,i = 1/(a_v ω_i W_ττ,ii), times the settings' scales.
    fn new(step: &StepData, set: &NewtonSettings) -> Params {
        let n = step.n();
        Params {
            rho_n: (0..n)
                .map(|i| set.scale_normal / (step.nodes[i].omega * step.delassus[(step.nu(i), step.nu(i))]))
                .collect(),
            rho_t: (0..n)
                .map(|i| {
                    // the mean of the node's tangential diagonal entries (one in 2-D)
                    let w_tt = if step.tdim() == 1 {
                        step.delassus[(step.tau(i), step.tau(i))]
                    } else {
                        (0..step.tdim()).map(|j| step.delassus[(step.tau_j(i, j), step.tau_j(i, j))]).sum::<f64>()
                            / step.tdim() as f64
                    };
                    set.scale_tangent / (step.a_v * step.nodes[i].omega * w_tt)
                })
                .collect(),
        }
    }
}

/// The start: the warm-started λ (≥ 0) and t (inside the bound at the free motion), and the
/// contact velocities `y0` when given, else those the forces give at the free motion.
fn initial_iterate(
    step: &StepData,
    s: &SlipBound,
    p: &Params,
    y0: Option<&[f64]>,
    lambda0: &[f64],
    t0: &[f64],
) -> Iterate {
    let n = step.n();
    let lambda: Vec<f64> =
        (0..n).map(|i| if step.nodes[i].bound.is_some() { lambda0[i].max(0.0) } else { 0.0 }).collect();
    let s_start = s.values(step, &step.y_free, &lambda);
    let t: Vec<f64> = if step.tdim() == 1 {
        (0..n).map(|i| if step.friction { t0[i].clamp(-s_start[i], s_start[i]) } else { 0.0 }).collect()
    } else {
        // the warm start projected onto each node's disk
        (0..n)
            .flat_map(|i| {
                let ti = t_of(step, t0, i);
                let norm = ti[0].hypot(ti[1]);
                let scale = if !step.friction {
                    0.0
                } else if norm > s_start[i] {
                    s_start[i] / norm
                } else {
                    1.0
                };
                [scale * ti[0], scale * ti[1]]
            })
            .collect()
    };
    let y = match y0 {
        Some(y0) => y0.to_vec(),
        None => step.response(&step.forces(&step.y_free, &lambda, &t)),
    };
    let f = residual(step, s, p, &y, &lambda, &t);
    Iterate { y, lambda, t, f }
}

/// The converged iterate as a solution, with each node's status.
fn solution(
    step: &StepData,
    x: Iterate,
    stick: &[bool],
    iterations: usize,
    residual: f64,
    exact: bool,
) -> ContactSolution {
    let n = step.n();
    let q: Vec<f64> = (0..n).map(|i| step.q(i, &x.y)).collect();
    // exact active sets: a node is separated when it carries no force at all
    let status =
        (0..n).map(|i| NodeStatus::classify(q[i] + x.lambda[i], 0.0, step.friction.then_some(stick[i]))).collect();
    ContactSolution { y: x.y, lambda: x.lambda, t: x.t, q, status, iterations, residual, exact }
}

/// A slipping node on the disk (3-D) linearized: with z = t + ρ v̄, ẑ = z/‖z‖, κ = S/‖z‖ < 1
/// and Π = I − ẑẑᵀ, (N.3) gives
///   Δt = (ẑẑᵀ + Π/(1 − κ))(S ẑ − t) + ρ a_v κ/(1 − κ) Π Δy_τ + ẑ (a_v ∂S/∂‖v̄‖ v̂ᵀ Δy_τ + ∂S/∂N ΔN),
/// the last term only for a bound that follows the unknowns (N.4: μ′ along v̂ = v̄/‖v̄‖; Co.3:
/// μ ΔN). Along ẑ the change is known (but for that term); across it (ẑ^⊥ = (−ẑ_2, ẑ_1)) the
/// force follows the slip rate with the stiffness `gain` = ρ a_v κ/(1 − κ) ≥ 0.
#[derive(Debug, Clone, Copy)]
struct DiskSlip {
    i: usize,
    zhat: [f64; 2],
    /// the known change of t along ẑ and across it
    along: f64,
    across: f64,
    gain: f64,
    /// a_v ∂S/∂‖v̄‖ v̂ (N.4, Co.3; 0 for a frozen bound): the row of ∂t·ẑ/∂y_τ beyond the gain
    ds_dy: [f64; 2],
    /// a_v ∂S/∂‖v̄‖ (its size; v̂ = ẑ at the solution)
    ds_dspeed: f64,
    /// ∂S/∂N (Co.3; 0 otherwise)
    ds_dn: f64,
}

impl DiskSlip {
    fn new(step: &StepData, s: &SlipBound, p: &Params, x: &Iterate, i: usize) -> DiskSlip {
        let (ti, v) = (t_of(step, &x.t, i), step.slip_vec(i, &x.y));
        let rho = p.rho_t[i];
        let z = [ti[0] + rho * v[0], ti[1] + rho * v[1]];
        let nz = z[0].hypot(z[1]);
        let zhat = [z[0] / nz, z[1] / nz];
        let b = s.at(step, i, &x.y, &x.lambda);
        let kappa = b.s / nz;
        let e = [b.s * zhat[0] - ti[0], b.s * zhat[1] - ti[1]];
        let perp = [-zhat[1], zhat[0]];
        let speed = v[0].hypot(v[1]);
        let vhat = if speed > 0.0 { [v[0] / speed, v[1] / speed] } else { zhat };
        DiskSlip {
            i,
            zhat,
            along: zhat[0] * e[0] + zhat[1] * e[1],
            across: (perp[0] * e[0] + perp[1] * e[1]) / (1.0 - kappa),
            gain: rho * step.a_v * kappa / (1.0 - kappa),
            ds_dy: [step.a_v * b.ds_dv * vhat[0], step.a_v * b.ds_dv * vhat[1]],
            ds_dspeed: step.a_v * b.ds_dv,
            ds_dn: b.ds_dn,
        }
    }
    fn frozen(&self) -> bool {
        self.ds_dy == [0.0; 2] && self.ds_dn == 0.0
    }
    /// The known change of t in the node's (τ_1, τ_2) components.
    fn known(&self) -> [f64; 2] {
        let perp = [-self.zhat[1], self.zhat[0]];
        [self.along * self.zhat[0] + self.across * perp[0], self.along * self.zhat[1] + self.across * perp[1]]
    }
    /// gain Π + a_v ∂S/∂‖v̄‖ ẑẑᵀ: ∂t/∂y_τ with v̂ taken as ẑ (equal at the solution), symmetric.
    fn symmetric_block(&self) -> [[f64; 2]; 2] {
        let z = self.zhat;
        std::array::from_fn(|j| {
            std::array::from_fn(|k| {
                self.gain * (f64::from(u8::from(j == k)) - z[j] * z[k]) + self.ds_dspeed * z[j] * z[k]
            })
        })
    }
    /// ∂t/∂y_τ = gain Π + ẑ ds_dyᵀ (a 2 × 2 block; symmetric when frozen).
    fn block(&self) -> [[f64; 2]; 2] {
        let z = self.zhat;
        std::array::from_fn(|j| {
            std::array::from_fn(|k| self.gain * (f64::from(u8::from(j == k)) - z[j] * z[k]) + z[j] * self.ds_dy[k])
        })
    }
}

/// The Newton direction (Δy, Δm) on the reduced system, one unknown per contact component:
/// prescribed-velocity components (active normal, stick) carry a force unknown Δm (Δλ_i at 2i,
/// Δt_i at 2i+1); the others carry a velocity unknown Δy with the force change known.
/// None when the reduced matrix is singular.
fn direction(
    step: &StepData,
    factors: &mut DelassusFactors,
    s: &SlipBound,
    p: &Params,
    x: &Iterate,
    sets: &(Vec<bool>, Vec<bool>),
    // the settings' choice of system, and which products with W⁻¹ the velocity form takes
    (reduced, form): (bool, DirectionForm),
) -> Option<(Vec<f64>, Vec<f64>)> {
    let (n, m) = (step.n(), step.m());
    let (active, stick) = sets;
    let (y, lambda, t, f) = (&x.y, &x.lambda, &x.t, &x.f);
    let mut dy = vec![0.0; m];
    let mut dm = vec![0.0; m];
    let mut prescribed = vec![false; m];
    let mut g = vec![0.0; m]; // ∂q/∂y on normal components
    // ∂t_i/∂N_i on slipping nodes whose bound follows the normal force (Co.3), per tangential
    // component (d − 1 of them), else 0
    let mut coupling = vec![[0.0; 2]; n];
    // (3-D) slipping nodes on the disk
    let mut slips: Vec<DiskSlip> = Vec::new();
    for i in 0..n {
        let (jn, jt) = (step.nu(i), step.tau(i));
        g[jn] = step.dq(i, y);
        if active[i] {
            prescribed[jn] = true;
            dy[jn] = f[m + i]; // F_λ = β − y on the active set
        } else {
            dm[jn] = -lambda[i];
        }
        if step.friction && step.tdim() == 2 {
            if stick[i] {
                for j in 0..2 {
                    prescribed[step.tau_j(i, j)] = true;
                    dy[step.tau_j(i, j)] = f[m + n + 2 * i + j]; // F_t = y_stick − y on the stick set
                }
            } else {
                slips.push(DiskSlip::new(step, s, p, x, i));
            }
        } else if step.friction {
            if stick[i] {
                prescribed[jt] = true;
                dy[jt] = f[m + n + i]; // F_t = y_stick − y on the stick set
            } else {
                // slip: t_new = σ S(v̄); with the unfrozen bound (N.4) S varies with y_τ,
                // which adds ω σ S'(v̄) a_v to the column of Δy_τ
                let vbar = step.slip(i, y);
                let sigma = (t[i] + p.rho_t[i] * vbar).signum();
                let b = s.at(step, i, y, lambda);
                dm[jt] = b.s * sigma - t[i];
                g[jt] = sigma * b.ds_dv * step.a_v;
                coupling[i][0] = sigma * b.ds_dn;
            }
        }
    }
    // Eisenstat–Walker: a direction by conjugate gradients only as exact as the residual is small
    let scale = step.velocity_scale(y);
    let forcing = if scale > 0.0 {
        (crate::defaults::PCG_FORCING * linalg::norm_inf(&f[..m]).max(linalg::norm_inf(f)) / scale)
            .min(crate::defaults::PCG_FORCING_MAX)
    } else {
        0.0
    };
    // an exact direction's conjugate gradients stop once the iterate it lands on is within
    // PCG_TOLERANCE of the velocity scale (in velocity units; `velocity_direction` turns it into
    // a tolerance on its system's residual)
    let landing = crate::defaults::PCG_TOLERANCE * scale;
    let coupled = coupling.iter().any(|c| *c != [0.0; 2]) || slips.iter().any(|d| d.ds_dn != 0.0);
    if let (true, false, Some(inverse)) = (reduced, coupled, step.inverse)
        && let Some(d) =
            velocity_direction(step, factors, inverse, f, &prescribed, &g, &slips, &dy, &dm, (forcing, landing), form)
    {
        return Some(d);
    }
    let symmetric = slips.iter().all(DiskSlip::frozen)
        && coupling.iter().all(|c| *c == [0.0; 2])
        && (0..m).all(|l| prescribed[l] || g[l] >= 0.0);
    if reduced && symmetric {
        // each slipping node read along (ẑ, ẑ^⊥): a free component with a known force change
        // and one whose force follows the slip rate with the stiffness `gain` (joins U)
        let mut frames = SlipFrames::identity(step.dim, n);
        for d in &slips {
            frames.rotate(d.i, d.zhat);
            (dm[step.tau_j(d.i, 0)], dm[step.tau_j(d.i, 1)]) = (d.along, d.across);
            g[step.tau_j(d.i, 1)] = d.gain;
        }
        let mut f_local = f[..m].to_vec();
        frames.to_local(&mut f_local);
        let sol = reduced_direction(step, factors, &frames, &f_local, &prescribed, &g, &dy, &dm, forcing)?;
        for l in 0..m {
            if prescribed[l] {
                dm[l] = sol[l];
            } else {
                dy[l] = sol[l];
            }
        }
        for d in &slips {
            dm[step.tau_j(d.i, 1)] += d.gain * dy[step.tau_j(d.i, 1)];
        }
        frames.to_global(&mut dy);
        frames.to_global(&mut dm);
        return Some((dy, dm));
    }
    // the general system in the nodes' own components: a slipping node's friction change is its
    // known part plus the 2 × 2 block G Δy_τ (and, for Co.3, ẑ ∂S/∂N ΔN)
    let mut blocks: Vec<(usize, [[f64; 2]; 2])> = Vec::new();
    for d in &slips {
        let known = d.known();
        for (j, kj) in known.iter().enumerate() {
            dm[step.tau_j(d.i, j)] = *kj;
        }
        blocks.push((d.i, d.block()));
        coupling[d.i] = [d.zhat[0] * d.ds_dn, d.zhat[1] * d.ds_dn];
    }
    let sol = general_direction(step, f, &prescribed, &g, (&coupling, &blocks), &dy, &dm)?;
    for l in 0..m {
        if prescribed[l] {
            dm[l] = sol[l];
        } else {
            dy[l] = sol[l];
        }
    }
    // (2-D) a slipping node's friction change beyond its known part: ∂t/∂y_τ Δy_τ (N.4) and
    // ∂t/∂N ΔN (Co.3), as the linear system assumed
    if step.tdim() == 1 {
        for i in 0..n {
            let jt = step.tau(i);
            if !prescribed[jt] && (g[jt] != 0.0 || coupling[i][0] != 0.0) {
                let jn = step.nu(i);
                // ΔN = Δλ + ∂q/∂y Δy_ν (one of the two is the solved unknown)
                let delta_n = dm[jn] + g[jn] * dy[jn];
                dm[jt] += g[jt] * dy[jt] + coupling[i][0] * delta_n;
            }
        }
    }
    for (i, gb) in &blocks {
        let dyt = [dy[step.tau_j(*i, 0)], dy[step.tau_j(*i, 1)]];
        let dn = coupling[*i];
        // ΔN = Δλ + ∂q/∂y Δy_ν (Co.3)
        let delta_n = if dn == [0.0; 2] { 0.0 } else { dm[step.nu(*i)] + g[step.nu(*i)] * dy[step.nu(*i)] };
        for j in 0..2 {
            dm[step.tau_j(*i, j)] += gb[j][0] * dyt[0] + gb[j][1] * dyt[1] + dn[j] * delta_n;
        }
    }
    Some((dy, dm))
}

/// The Newton direction in velocity form, with W⁻¹ (`InverseDelassus`): the prescribed
/// components' velocities Δy_P are known, the free ones' forces change by
/// Δr_F = ω (dm_F + Ĝ Δy_F) (Ĝ: ∂q/∂y on normals, the slip branch's ∂t/∂y on tangents — a 2 × 2
/// block per slipping 3-D node, symmetrized with v̂ = ẑ), and W⁻¹ applied to the linearized
/// (N.1) rows Δy + W Δr = −F_y gives
///   [(W⁻¹)_FF + ω Ĝ_F] Δy_F = −(W⁻¹ (F_y + Δy_P))_F − r_k,F,   ω Δm_P = −(W⁻¹ (F_y + Δy))_P − r_k,P,
/// r_k the known force change (ω dm on F, the compliance part ω g Δy on P). The matrix is
/// symmetric and, when the step problem is convex, positive definite: conjugate gradients
/// preconditioned by the near field of W⁻¹ to `landing` for an exact direction (the landed
/// iterate within PCG_TOLERANCE of the velocity scale, `landing` in velocity units: their
/// residual ρ within landing / ‖W‖_∞ in 2-norm), else (node blocks, loose directions) to
/// the relative residual `forcing`. None (another form is used) when they do not converge or meet
/// a non-positive curvature.
#[allow(clippy::too_many_arguments)]
fn velocity_direction(
    step: &StepData,
    factors: &mut DelassusFactors,
    inverse: &InverseDelassus,
    f: &[f64],
    prescribed: &[bool],
    g: &[f64],
    slips: &[DiskSlip],
    dy: &[f64],
    dm: &[f64],
    (forcing, landing): (f64, f64),
    form: DirectionForm,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let (n, m) = (step.n(), step.m());
    let omega = |l: usize| step.nodes[step.node_of(l)].omega;
    let mut dm = dm.to_vec();
    let mut dy = dy.to_vec();
    // Ĝ (times ω): the diagonal, and the slipping nodes' blocks with their known change
    let diag: Vec<f64> = (0..m).map(|l| if prescribed[l] { 0.0 } else { omega(l) * g[l] }).collect();
    let mut blocks: Vec<Option<[[f64; 2]; 2]>> = vec![None; n];
    let mut slip_block: Vec<Option<[[f64; 2]; 2]>> = vec![None; n];
    for d in slips {
        let known = d.known();
        dm[step.tau_j(d.i, 0)] = known[0];
        dm[step.tau_j(d.i, 1)] = known[1];
        let gb = d.symmetric_block();
        let w = step.nodes[d.i].omega;
        blocks[d.i] = Some(gb.map(|row| row.map(|v| w * v)));
        slip_block[d.i] = Some(gb);
    }
    let r_k: Vec<f64> = (0..m).map(|l| omega(l) * if prescribed[l] { g[l] * dy[l] } else { dm[l] }).collect();
    // W⁻¹ (F_y + Δy_P)
    let mut fy_p: Vec<f64> = f[..m].to_vec();
    for l in (0..m).filter(|&l| prescribed[l]) {
        fy_p[l] += dy[l];
    }
    let u0 = inverse.apply(&fy_p, form);
    let free: Vec<usize> = (0..m).filter(|&l| !prescribed[l]).collect();
    let mut b = vec![0.0; m];
    for &l in &free {
        b[l] = -u0[l] - r_k[l];
    }
    let (mut x, mut winv_x) = (vec![0.0; m], vec![0.0; m]);
    let iterations = inverse.solve(
        &mut factors.near,
        &free,
        &diag,
        &blocks,
        &b,
        // with the near field an exact direction lands to round-off of the velocity scale, which
        // keeps Newton's finite termination on fixed sets (exact complementarity: d ≤ g to
        // round-off, so the constraint dissipation never decreases): the system's residual ρ (force
        // units, zero on the prescribed rows) moves the linearized (N.1) rows by W ρ, and
        // ‖W ρ‖_∞ ≤ ‖W‖_∞ ‖ρ‖₂ ≤ `landing` once ‖ρ‖₂ ≤ landing / ‖W‖_∞ — relative to ‖b‖₂, never
        // tighter than LANDING_FLOOR (round-off of the conjugate gradients' recurrence) nor looser
        // than PCG_FORCING_MAX; node blocks, and loose directions (inexact already), stop at the
        // forcing
        if inverse.has_near_field() && form == DirectionForm::Exact {
            let norm_b = linalg::dot(&b, &b).sqrt();
            let wb = inverse.w_norm_inf() * norm_b;
            if wb > 0.0 {
                (landing / wb).clamp(crate::defaults::LANDING_FLOOR, crate::defaults::PCG_FORCING_MAX)
            } else {
                crate::defaults::PCG_TOLERANCE
            }
        } else {
            forcing.max(crate::defaults::PCG_TOLERANCE)
        },
        crate::defaults::VELOCITY_FORM_MAX_ITERATIONS,
        form,
        (&mut x, &mut winv_x),
    )?;
    factors.record_velocity_solve(iterations, form == DirectionForm::Loose && inverse.has_loose_form());
    for &l in &free {
        dy[l] = x[l];
    }
    // the prescribed components' force changes (W⁻¹ x on those rows, summed by the conjugate
    // gradients beside x)
    for l in (0..m).filter(|&l| prescribed[l]) {
        dm[l] = (-(u0[l] + winv_x[l]) - r_k[l]) / omega(l);
    }
    // the free tangential components' force changes beyond the known part: Ĝ Δy (normals keep
    // Δλ; their compliance force follows y through q)
    for i in 0..n {
        if let Some(gb) = slip_block[i] {
            let (a, c) = (step.tau_j(i, 0), step.tau_j(i, 1));
            let (ya, yc) = (dy[a], dy[c]);
            dm[a] += gb[0][0] * ya + gb[0][1] * yc;
            dm[c] += gb[1][0] * ya + gb[1][1] * yc;
        } else if step.friction && step.tdim() == 1 {
            let jt = step.tau(i);
            if !prescribed[jt] {
                dm[jt] += g[jt] * dy[jt];
            }
        }
    }
    (dy.iter().chain(&dm).all(|v| v.is_finite())).then_some((dy, dm))
}

/// The Newton direction as a symmetric positive definite system in the force increments (the
/// frozen bound of F.1 with a monotone normal law: no Co.3 coupling, ∂q/∂y ≥ 0), in the local
/// components of `frames` (slipping 3-D nodes along (ẑ, ẑ^⊥); `f`, `dy`, `dm` local too). With
/// z_l = ω_l Δm_l on prescribed components (P) and z_l = ω_l g_l Δy_l on free components whose
/// force follows y (F_g: g_l > 0 — compliant normals, and across a 3-D slip), and the known
/// force change r_k,l = ω_l Δm_l on the free ones (ω_l g_l Δy_l on P: the compliance part of an
/// active node's force), the linearized (N.1) rows Δy + W' Δr = −F_y read
///   (W'_UU + D) z_U = −F_U − Δy_P − (W' r_k)_U,   U = P ∪ F_g,   D = diag(0 on P, 1/(ω g) on F_g),
/// and the remaining free rows give Δy_l = −F_l − (W' (z + r_k))_l. W'_UU + D is a principal
/// submatrix of the (rotated) Delassus operator plus a nonnegative diagonal: Cholesky, not LU,
/// kept and reused by `factors` (exactly while U, D and the frames hold; as the
/// preconditioner of conjugate gradients while U holds). Returns the unknown of each component
/// (Δm on P, Δy elsewhere), None when W'_UU + D is not numerically positive definite.
/// (Nine arguments: the step's data, the factor cache, and seven different objects of the
/// linearized system; bundling them would only rename them.)
#[allow(clippy::too_many_arguments)]
fn reduced_direction(
    step: &StepData,
    factors: &mut DelassusFactors,
    frames: &SlipFrames,
    f: &[f64],
    prescribed: &[bool],
    g: &[f64],
    dy: &[f64],
    dm: &[f64],
    forcing: f64,
) -> Option<Vec<f64>> {
    let m = step.m();
    let w = step.delassus;
    let omega = |l: usize| step.nodes[step.node_of(l)].omega;
    let unknown: Vec<usize> = (0..m).filter(|&l| prescribed[l] || g[l] > 0.0).collect();
    let diag: Vec<f64> = unknown.iter().map(|&l| if prescribed[l] { 0.0 } else { 1.0 / (omega(l) * g[l]) }).collect();
    // the known force change and its response W' r_k
    let r_k: Vec<f64> = (0..m).map(|l| omega(l) * if prescribed[l] { g[l] * dy[l] } else { dm[l] }).collect();
    let mut w_rk = vec![0.0; m];
    w.add_times_in(frames, &r_k, 1.0, &mut w_rk);
    let mut b: Vec<f64> = unknown.iter().map(|&j| -f[j] - w_rk[j] - if prescribed[j] { dy[j] } else { 0.0 }).collect();
    if !unknown.is_empty() {
        factors.solve_to(w, frames, &unknown, &diag, forcing, &mut b)?;
    }
    let mut z = vec![0.0; m];
    for (&l, &zl) in unknown.iter().zip(&b) {
        z[l] = zl;
    }
    // W' z is needed only on the free components whose force is known (g = 0): slipping
    // tangents and separated normals — none while every node sticks on the foundation
    let w_z = frames.any().then(|| {
        let mut out = vec![0.0; m];
        w.add_times_in(frames, &z, 1.0, &mut out);
        out
    });
    let out: Vec<f64> = (0..m)
        .map(|l| {
            if prescribed[l] {
                z[l] / omega(l)
            } else if g[l] > 0.0 {
                z[l] / (omega(l) * g[l])
            } else {
                -f[l] - w_z.as_ref().map_or_else(|| w.row_times(l, &z), |wz| wz[l]) - w_rk[l]
            }
        })
        .collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// The slip branch's coupling of the friction force to the normal unknown (per component) and
/// its 2 × 2 blocks in the slip frames (node, block).
type SlipCoupling<'a> = (&'a [[f64; 2]], &'a [(usize, [[f64; 2]; 2])]);

/// The Newton direction on the full m × m system (dense LU), for the unsymmetric cases: the
/// Co.3 coupling of the friction force to the normal force, and the unfrozen bound of N.4
/// (∂S/∂v̄ < 0 under velocity weakening). J x = rhs with x_l = Δm_l (prescribed) or Δy_l (free).
fn general_direction(
    step: &StepData,
    f: &[f64],
    prescribed: &[bool],
    g: &[f64],
    (coupling, blocks): SlipCoupling,
    dy: &[f64],
    dm: &[f64],
) -> Option<Vec<f64>> {
    let (n, m) = (step.n(), step.m());
    let w = step.delassus;
    let omega = |l: usize| step.nodes[step.node_of(l)].omega;
    let mut jac = Mat::<f64>::zeros(m, m);
    let mut rhs: Vec<f64> = f[..m].iter().map(|v| -v).collect();
    for l in 0..m {
        let wl = omega(l);
        if prescribed[l] {
            for j in 0..m {
                jac[(j, l)] = w[(j, l)] * wl;
                rhs[j] -= w[(j, l)] * wl * g[l] * dy[l];
            }
            rhs[l] -= dy[l];
        } else {
            for j in 0..m {
                jac[(j, l)] = w[(j, l)] * wl * g[l];
                rhs[j] -= w[(j, l)] * wl * dm[l];
            }
            jac[(l, l)] += 1.0;
        }
    }
    // (Co.3) the friction force of a slipping node follows its normal force N = q + λ: the
    // normal unknown's column also acts through the tangential components
    for i in (0..n).filter(|&i| coupling[i] != [0.0; 2]) {
        let jn = step.nu(i);
        // ΔN = Δλ + g Δy_ν (normal prescribed: Δλ unknown, Δy_ν known) or g Δy_ν + Δλ_known (free)
        let (col_factor, known) = if prescribed[jn] { (1.0, g[jn] * dy[jn]) } else { (g[jn], dm[jn]) };
        for (k, &ck) in coupling[i][..step.tdim()].iter().enumerate() {
            let jt = step.tau_j(i, k);
            let c = ck * omega(jt);
            for j in 0..m {
                jac[(j, jn)] += w[(j, jt)] * c * col_factor;
                rhs[j] -= w[(j, jt)] * c * known;
            }
        }
    }
    // (3-D) a slipping node's friction force follows its tangential velocities through the
    // 2 × 2 block G: column τ_j gains Σ_k W[:, τ_k] ω G_kj
    for (i, gb) in blocks {
        let cols = [step.tau_j(*i, 0), step.tau_j(*i, 1)];
        let wi = step.nodes[*i].omega;
        for (jj, &cj) in cols.iter().enumerate() {
            for (kk, &ck) in cols.iter().enumerate() {
                let c = wi * gb[kk][jj];
                if c != 0.0 {
                    for row in 0..m {
                        jac[(row, cj)] += w[(row, ck)] * c;
                    }
                }
            }
        }
    }
    linalg::dense_solve(&jac, &rhs)
}

/// Backtracking line search on ½‖F‖² along (Δy, Δm): the first Armijo step, else the best
/// decrease seen; with no decrease at all the full step is taken (semismooth Newton on a
/// piecewise-linear system may need to cross a kink) and the iteration cap guards cycling.
fn line_search(step: &StepData, s: &SlipBound, p: &Params, x: Iterate, dy: &[f64], dm: &[f64]) -> Iterate {
    let (n, m) = (step.n(), step.m());
    let at = |alpha: f64| {
        let y: Vec<f64> = (0..m).map(|l| x.y[l] + alpha * dy[l]).collect();
        let lambda: Vec<f64> = (0..n)
            .map(|i| if step.nodes[i].bound.is_some() { x.lambda[i] + alpha * dm[step.nu(i)] } else { 0.0 })
            .collect();
        let td = step.tdim();
        let t: Vec<f64> = (0..n * td)
            .map(|l| if step.friction { x.t[l] + alpha * dm[step.tau_j(l / td, l % td)] } else { 0.0 })
            .collect();
        let f = residual(step, s, p, &y, &lambda, &t);
        Iterate { y, lambda, t, f }
    };
    let merit0 = 0.5 * linalg::dot(&x.f, &x.f);
    let mut best: Option<(f64, Iterate)> = None;
    let mut alpha = 1.0;
    for _ in 0..LINE_SEARCH_HALVINGS {
        let trial = at(alpha);
        let merit = 0.5 * linalg::dot(&trial.f, &trial.f);
        let accept = merit <= (1.0 - ARMIJO * alpha) * merit0;
        if best.as_ref().is_none_or(|b| merit < b.0) {
            best = Some((merit, trial));
        }
        if accept {
            break;
        }
        alpha *= 0.5;
    }
    match best {
        Some((merit, trial)) if merit < merit0 => trial,
        _ => at(1.0),
    }
}
