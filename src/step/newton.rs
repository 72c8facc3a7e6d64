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
//! The direction: in the symmetric cases (frozen S, monotone normal law) a Cholesky solve on the
//! force unknowns with the factor reused while the contact sets hold (`reduced_direction`, dense
//! or sparse as W is); otherwise the full m × m LU (`general_direction`) — in 3-D whenever a node
//! slips, since its force then depends on its velocity across the slip (a 2 × 2 block).

use faer::Mat;

use super::{ContactSolution, NodeStatus, StepData};
use crate::defaults::{ARMIJO, LINE_SEARCH_HALVINGS, MAX_ITERATIONS, NEWTON_TOLERANCE};
use crate::failure::{NewtonFailure, NewtonStatus};
use crate::linalg;
use crate::model::laws::FrictionCoefficient;

/// The friction bound the Newton solve sees.
#[derive(Debug, Clone, Copy)]
pub enum FrictionBound<'a> {
    /// S_i frozen (the convex problem (S.6) of one F.1 iteration)
    Frozen(&'a [f64]),
    /// (N.4) S_i = μ(|v̄_i|) p̂_i, a function of the unknowns (no fixed point)
    Law { mu: &'a FrictionCoefficient, p_hat: &'a [f64] },
    /// (Co.3) S_i = μ(|v̄_i|)(q_i + λ_i)_+: Coulomb's disk whose radius follows the normal force
    /// of the iterate (GetFEM's coupled projection), with the slip rate in μ too
    Coulomb { mu: &'a FrictionCoefficient },
}

/// The friction bound at node i and its derivatives: with respect to the slip rate v̄_i and
/// to the normal force N_i = q_i + λ_i.
#[derive(Debug, Clone, Copy)]
struct BoundAt {
    s: f64,
    ds_dv: f64,
    ds_dn: f64,
}

impl FrictionBound<'_> {
    /// S_i and its derivatives at the iterate (y, λ).
    fn at(&self, step: &StepData, i: usize, y: &[f64], lambda: &[f64]) -> BoundAt {
        let vbar = step.slip(i, y);
        match self {
            FrictionBound::Frozen(s) => BoundAt { s: s[i], ds_dv: 0.0, ds_dn: 0.0 },
            FrictionBound::Law { mu, p_hat } => {
                BoundAt { s: mu.mu(vbar.abs()) * p_hat[i], ds_dv: mu.dmu(vbar.abs()) * vbar.signum() * p_hat[i], ds_dn: 0.0 }
            }
            FrictionBound::Coulomb { mu } => {
                let n = step.q(i, y) + lambda[i];
                let (m, dm) = (mu.mu(vbar.abs()), mu.dmu(vbar.abs()) * vbar.signum());
                if n > 0.0 { BoundAt { s: m * n, ds_dv: dm * n, ds_dn: m } } else { BoundAt { s: 0.0, ds_dv: 0.0, ds_dn: 0.0 } }
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
}

impl Default for NewtonSettings {
    fn default() -> Self {
        NewtonSettings { tolerance: NEWTON_TOLERANCE, max_iterations: MAX_ITERATIONS, scale_normal: 1.0, scale_tangent: 1.0, reduced: true }
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

fn residual(step: &StepData, s: &FrictionBound, p: &Params, y: &[f64], lambda: &[f64], t: &[f64]) -> Vec<f64> {
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
            f.push(if step.friction { friction_residual(t[i], vbar, s.at(step, i, y, lambda).s, p.rho_t[i], step.a_v) } else { 0.0 });
        }
    } else {
        for i in 0..n {
            let ft = if step.friction {
                friction_residual_disk(t_of(step, t, i), step.slip_vec(i, y), s.at(step, i, y, lambda).s, p.rho_t[i], step.a_v)
            } else {
                [0.0; 2]
            };
            f.extend(ft);
        }
    }
    f
}

/// Active normal constraints and stick nodes at an iterate.
fn sets(step: &StepData, s: &FrictionBound, p: &Params, y: &[f64], lambda: &[f64], t: &[f64]) -> (Vec<bool>, Vec<bool>) {
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
/// `t0` warm-start the multipliers.
pub fn solve(
    step: &StepData,
    s: &[f64],
    lambda0: &[f64],
    t0: &[f64],
    set: &NewtonSettings,
) -> Result<ContactSolution, NewtonFailure> {
    solve_with(step, &FrictionBound::Frozen(s), lambda0, t0, set)
}

/// (N.4) Semismooth Newton on the unfrozen Alart–Curnier system: the friction bound
/// S_i = μ(|v̄_i|) p_τ(û_i) is a function of the unknowns inside the projection of (N.3), and
/// the slip branch of the generalized Jacobian carries ∂t_i/∂y_τ,i = σ_i S'(v̄_i) a_v
/// (S' = p̂ μ'(|v̄|) sgn v̄); no fixed point. Globalized by the line search on ‖F‖₂.
pub fn solve_unfrozen(
    step: &StepData,
    mu: &FrictionCoefficient,
    p_hat: &[f64],
    lambda0: &[f64],
    t0: &[f64],
    set: &NewtonSettings,
) -> Result<ContactSolution, NewtonFailure> {
    solve_with(step, &FrictionBound::Law { mu, p_hat }, lambda0, t0, set)
}

/// (Co.3) Semismooth Newton on the coupled Alart–Curnier system of Coulomb's law with the
/// whole contact force: the bound S_i = μ(|v̄_i|)(q_i + λ_i) is a function of the unknowns inside
/// the projection of (N.3), so the slip branch carries ∂t_i/∂N_i = σ_i μ(|v̄_i|) (the disk radius
/// follows the normal force, as in GetFEM's coupled projection) and ∂t_i/∂y_τ,i = σ_i μ' N_i a_v;
/// no fixed point. Globalized by the line search on ‖F‖₂.
pub fn solve_coulomb(
    step: &StepData,
    mu: &FrictionCoefficient,
    lambda0: &[f64],
    t0: &[f64],
    set: &NewtonSettings,
) -> Result<ContactSolution, NewtonFailure> {
    solve_with(step, &FrictionBound::Coulomb { mu }, lambda0, t0, set)
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
pub fn solve_with(
    step: &StepData,
    bound: &FrictionBound,
    lambda0: &[f64],
    t0: &[f64],
    set: &NewtonSettings,
) -> Result<ContactSolution, NewtonFailure> {
    let s = bound;
    let p = Params::new(step, set);
    let mut x = initial_iterate(step, s, &p, lambda0, t0);
    let mut prev_sets: Option<(Vec<bool>, Vec<bool>)> = None;
    let mut prev_ok = false;
    for it in 0..=set.max_iterations {
        let scale = step.velocity_scale(&x.y);
        let res = linalg::norm_inf(&x.f);
        let ok = res <= set.tolerance * scale;
        let cur_sets = sets(step, s, &p, &x.y, &x.lambda, &x.t);
        let stable = prev_sets.as_ref() == Some(&cur_sets);
        if ok && (stable || prev_ok || it == 0 && res == 0.0) {
            return Ok(solution(step, x, &cur_sets.1, it, if scale > 0.0 { res / scale } else { res }));
        }
        if it == set.max_iterations {
            break;
        }
        prev_ok = ok;
        let Some((dy, dm)) = direction(step, s, &p, &x, &cur_sets, set.reduced) else {
            return Err(NewtonFailure {
                status: NewtonStatus::SingularJacobian,
                iterations: it,
                residual: res / scale.max(f64::MIN_POSITIVE),
            });
        };
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
            rho_n: (0..n).map(|i| set.scale_normal / (step.nodes[i].omega * step.delassus[(step.nu(i), step.nu(i))])).collect(),
            rho_t: (0..n)
                .map(|i| {
                    // the mean of the node's tangential diagonal entries (one in 2-D)
                    let w_tt = if step.tdim() == 1 {
                        step.delassus[(step.tau(i), step.tau(i))]
                    } else {
                        (0..step.tdim()).map(|j| step.delassus[(step.tau_j(i, j), step.tau_j(i, j))]).sum::<f64>() / step.tdim() as f64
                    };
                    set.scale_tangent / (step.a_v * step.nodes[i].omega * w_tt)
                })
                .collect(),
        }
    }
}

/// The start: the warm-started λ (≥ 0) and t (inside the bound at the free motion), and the
/// contact velocities they give.
fn initial_iterate(step: &StepData, s: &FrictionBound, p: &Params, lambda0: &[f64], t0: &[f64]) -> Iterate {
    let n = step.n();
    let lambda: Vec<f64> = (0..n).map(|i| if step.nodes[i].bound.is_some() { lambda0[i].max(0.0) } else { 0.0 }).collect();
    let s_start = s.values(step, &step.y_free, &lambda);
    let t: Vec<f64> = if step.tdim() == 1 {
        (0..n).map(|i| if step.friction { t0[i].clamp(-s_start[i], s_start[i]) } else { 0.0 }).collect()
    } else {
        // the warm start projected onto each node's disk
        (0..n)
            .flat_map(|i| {
                let ti = t_of(step, t0, i);
                let norm = ti[0].hypot(ti[1]);
                let scale = if !step.friction { 0.0 } else if norm > s_start[i] { s_start[i] / norm } else { 1.0 };
                [scale * ti[0], scale * ti[1]]
            })
            .collect()
    };
    let y = step.response(&step.forces(&step.y_free, &lambda, &t));
    let f = residual(step, s, p, &y, &lambda, &t);
    Iterate { y, lambda, t, f }
}

/// The converged iterate as a solution, with each node's status.
fn solution(step: &StepData, x: Iterate, stick: &[bool], iterations: usize, residual: f64) -> ContactSolution {
    let n = step.n();
    let q: Vec<f64> = (0..n).map(|i| step.q(i, &x.y)).collect();
    // exact active sets: a node is separated when it carries no force at all
    let status = (0..n).map(|i| NodeStatus::classify(q[i] + x.lambda[i], 0.0, stick[i])).collect();
    ContactSolution { y: x.y, lambda: x.lambda, t: x.t, q, status, iterations, residual }
}

/// The Newton direction (Δy, Δm) on the reduced system, one unknown per contact component:
/// prescribed-velocity components (active normal, stick) carry a force unknown Δm (Δλ_i at 2i,
/// Δt_i at 2i+1); the others carry a velocity unknown Δy with the force change known.
/// None when the reduced matrix is singular.
fn direction(
    step: &StepData,
    s: &FrictionBound,
    p: &Params,
    x: &Iterate,
    sets: &(Vec<bool>, Vec<bool>),
    reduced: bool,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let (n, m) = (step.n(), step.m());
    let (active, stick) = sets;
    let (y, lambda, t, f) = (&x.y, &x.lambda, &x.t, &x.f);
    let mut dy = vec![0.0; m];
    let mut dm = vec![0.0; m];
    let mut prescribed = vec![false; m];
    let mut g = vec![0.0; m]; // ∂q/∂y on normal components
    // ∂t_i/∂N_i on slipping nodes whose bound follows the normal force (Co.3), else 0
    let mut coupling = vec![0.0; n];
    // (3-D) the 2 × 2 blocks ∂t_i/∂y_τ,i of slipping nodes on the disk
    let mut blocks: Vec<(usize, [[f64; 2]; 2])> = Vec::new();
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
            let td = 2;
            if stick[i] {
                for j in 0..td {
                    prescribed[step.tau_j(i, j)] = true;
                    dy[step.tau_j(i, j)] = f[m + n + td * i + j]; // F_t = y_stick − y on the stick set
                }
            } else {
                // slip on the disk: with z = t + ρ v̄, ẑ = z/‖z‖, κ = S/‖z‖ < 1 and Π = I − ẑẑᵀ,
                // the linearized (N.3) gives Δt = (ẑẑᵀ + Π/(1 − κ))(S ẑ − t) + ρ a_v κ/(1 − κ) Π Δy_τ:
                // a known change plus a 2 × 2 block G on the tangential velocities
                let (ti, v) = (t_of(step, t, i), step.slip_vec(i, y));
                let rho = p.rho_t[i];
                let z = [ti[0] + rho * v[0], ti[1] + rho * v[1]];
                let nz = z[0].hypot(z[1]);
                let zh = [z[0] / nz, z[1] / nz];
                let b = s.at(step, i, y, lambda).s;
                let kappa = b / nz;
                let pi = [[1.0 - zh[0] * zh[0], -zh[0] * zh[1]], [-zh[1] * zh[0], 1.0 - zh[1] * zh[1]]];
                let e = [b * zh[0] - ti[0], b * zh[1] - ti[1]];
                for j in 0..td {
                    let along = zh[j] * (zh[0] * e[0] + zh[1] * e[1]);
                    let across = (pi[j][0] * e[0] + pi[j][1] * e[1]) / (1.0 - kappa);
                    dm[step.tau_j(i, j)] = along + across;
                }
                let gain = rho * step.a_v * kappa / (1.0 - kappa);
                blocks.push((i, [[gain * pi[0][0], gain * pi[0][1]], [gain * pi[1][0], gain * pi[1][1]]]));
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
                coupling[i] = sigma * b.ds_dn;
            }
        }
    }
    let symmetric = blocks.is_empty() && coupling.iter().all(|&c| c == 0.0) && (0..m).all(|l| prescribed[l] || g[l] >= 0.0);
    let sol = if reduced && symmetric {
        reduced_direction(step, f, &prescribed, &g, &dy, &dm)?
    } else {
        general_direction(step, f, &prescribed, &g, (&coupling, &blocks), &dy, &dm)?
    };
    for l in 0..m {
        if prescribed[l] {
            dm[l] = sol[l];
        } else {
            dy[l] = sol[l];
        }
    }
    // the slipping nodes' friction change on the disk: the known part plus G Δy_τ
    for (i, gb) in &blocks {
        let dyt = [dy[step.tau_j(*i, 0)], dy[step.tau_j(*i, 1)]];
        for j in 0..2 {
            dm[step.tau_j(*i, j)] += gb[j][0] * dyt[0] + gb[j][1] * dyt[1];
        }
    }
    Some((dy, dm))
}

/// The Newton direction as a symmetric positive definite system in the force increments (the
/// frozen bound of F.1 with a monotone normal law: no Co.3 coupling, ∂q/∂y ≥ 0). With
/// z_l = ω_l Δm_l on prescribed components (P) and z_l = ω_l g_l Δy_l on free components whose
/// force follows y (F_g: g_l > 0), and the known force change r_k,l = ω_l Δm_l on the free ones
/// (ω_l g_l Δy_l on P: the compliance part of an active node's force),
/// the linearized (N.1) rows Δy + W Δr = −F_y read
///   (W_UU + D) z_U = −F_U − Δy_P − (W r_k)_U,   U = P ∪ F_g,   D = diag(0 on P, 1/(ω g) on F_g),
/// and the remaining free rows give Δy_l = −F_l − (W (z + r_k))_l. W_UU + D is a principal
/// submatrix of the Delassus operator plus a nonnegative diagonal: Cholesky, not LU. Its
/// factorization depends only on U and D, so it is reused from `step.factors` while they do not
/// change (bit-identical to refactoring). Returns the unknown of each component (Δm on P, Δy
/// elsewhere), None when W_UU + D is not numerically positive definite.
fn reduced_direction(step: &StepData, f: &[f64], prescribed: &[bool], g: &[f64], dy: &[f64], dm: &[f64]) -> Option<Vec<f64>> {
    let m = step.m();
    let w = step.delassus;
    let omega = |l: usize| step.nodes[step.node_of(l)].omega;
    let unknown: Vec<usize> = (0..m).filter(|&l| prescribed[l] || g[l] > 0.0).collect();
    let diag: Vec<f64> = unknown.iter().map(|&l| if prescribed[l] { 0.0 } else { 1.0 / (omega(l) * g[l]) }).collect();
    // the known force change and its response W r_k
    let r_k: Vec<f64> = (0..m).map(|l| omega(l) * if prescribed[l] { g[l] * dy[l] } else { dm[l] }).collect();
    let w_rk = step.apply_delassus(&r_k);
    let mut b: Vec<f64> = unknown.iter().map(|&j| -f[j] - w_rk[j] - if prescribed[j] { dy[j] } else { 0.0 }).collect();
    if !unknown.is_empty() {
        step.factors.solve(w, &unknown, &diag, &mut b)?;
    }
    let mut z = vec![0.0; m];
    for (&l, &zl) in unknown.iter().zip(&b) {
        z[l] = zl;
    }
    // W z is needed only on the free components whose force is known (g = 0): slipping
    // tangents and separated normals — none while every node sticks on the foundation
    let out: Vec<f64> = (0..m)
        .map(|l| {
            if prescribed[l] {
                z[l] / omega(l)
            } else if g[l] > 0.0 {
                z[l] / (omega(l) * g[l])
            } else {
                -f[l] - step.delassus.row_times(l, &z) - w_rk[l]
            }
        })
        .collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// The Newton direction on the full m × m system (dense LU), for the unsymmetric cases: the
/// Co.3 coupling of the friction force to the normal force, and the unfrozen bound of N.4
/// (∂S/∂v̄ < 0 under velocity weakening). J x = rhs with x_l = Δm_l (prescribed) or Δy_l (free).
fn general_direction(
    step: &StepData,
    f: &[f64],
    prescribed: &[bool],
    g: &[f64],
    (coupling, blocks): (&[f64], &[(usize, [[f64; 2]; 2])]),
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
    // normal unknown's column also acts through the tangential component
    for i in (0..n).filter(|&i| coupling[i] != 0.0) {
        let (jn, jt) = (step.nu(i), step.tau(i));
        let c = coupling[i] * omega(jt);
        // ΔN = Δλ + g Δy_ν (normal prescribed: Δλ unknown, Δy_ν known) or g Δy_ν + Δλ_known (free)
        let (col_factor, known) = if prescribed[jn] { (1.0, g[jn] * dy[jn]) } else { (g[jn], dm[jn]) };
        for j in 0..m {
            jac[(j, jn)] += w[(j, jt)] * c * col_factor;
            rhs[j] -= w[(j, jt)] * c * known;
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
fn line_search(step: &StepData, s: &FrictionBound, p: &Params, x: Iterate, dy: &[f64], dm: &[f64]) -> Iterate {
    let (n, m) = (step.n(), step.m());
    let at = |alpha: f64| {
        let y: Vec<f64> = (0..m).map(|l| x.y[l] + alpha * dy[l]).collect();
        let lambda: Vec<f64> =
            (0..n).map(|i| if step.nodes[i].bound.is_some() { x.lambda[i] + alpha * dm[step.nu(i)] } else { 0.0 }).collect();
        let td = step.tdim();
        let t: Vec<f64> = (0..n * td).map(|l| if step.friction { x.t[l] + alpha * dm[step.tau_j(l / td, l % td)] } else { 0.0 }).collect();
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
