//! The inner solver `conic`: the frozen-S step problem (S.6) handed to Clarabel, the
//! independent twin of `newton` (ARCHITECTURE.md, "two solvers that must agree").
//!
//! Condensed on the contact DOFs, (S.6) is: minimize over (r, y)
//!   ½ rᵀ W r + Σ_i (ω_i S_i/a_v) |v̄_i(y)| + Σ_i (ω_i/a_d) F_i(d_i^{n+1}(y))
//!   subject to y + W r = y_free and y_ν,i ≤ β_i (exact constraint),
//! whose optimality conditions are exactly (N.1)–(N.3) (r = ∇G(y) + multipliers). Here
//! F_i' = q_i(d^n, ·) is the scheme's normal force, written hinge by hinge (c/2)(r − s)_+²:
//!
//! * d^n above the hinge (A = d^n − s ≥ 0), discrete gradient: F = q0 z + (c/4) z_+² + ψ_L(z)
//!   with ψ_L(z) = κ(−ln(1 − z/A) − z/A) for z < 0, κ = cA²/2: a quadratic epigraph and one
//!   exponential cone — exact;
//! * d^n below the hinge (δ = s − d^n > 0), discrete gradient: F = (c/2)(z²/2 − δz + δ² ln(1 + z/δ))
//!   for z > 0 is convex but a convex quadratic *plus a concave logarithm*, which no standard
//!   cone represents. It is handled by majorization–minimization: the logarithm is replaced
//!   by its tangent at the current z (a convex quadratic majorant, exact at the touching
//!   point), and the program is re-solved until the touching points stop moving;
//! * trapezoid and backward-Euler forces are exact quadratics.
//!
//! Clarabel has no warm start, so each solve starts from scratch.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};

use super::{ContactSolution, NodeStatus, StepData};
use crate::linalg;
use crate::model::laws::NormalForceRule;

/// Settings of the conic solve.
#[derive(Debug, Clone, Copy)]
pub struct ConicSettings {
    /// Clarabel's gap and feasibility tolerances
    pub tolerance: f64,
    /// majorization–minimization rounds for hinges crossed within the step
    pub max_rounds: usize,
}

impl Default for ConicSettings {
    fn default() -> Self {
        ConicSettings { tolerance: 1e-10, max_rounds: 100 }
    }
}

/// Why the conic solve failed.
#[derive(Debug, Clone)]
pub struct ConicFailure {
    pub iterations: usize,
    pub residual: f64,
    pub reason: String,
}

/// A growing sparse problem: variables, objective, and constraint rows by cone.
#[derive(Default)]
struct Builder {
    nvar: usize,
    p: Vec<(usize, usize, f64)>,
    q: Vec<f64>,
    zero: Vec<(Vec<(usize, f64)>, f64)>,
    nonneg: Vec<(Vec<(usize, f64)>, f64)>,
    exp: Vec<[(Vec<(usize, f64)>, f64); 3]>,
}

impl Builder {
    fn var(&mut self) -> usize {
        self.nvar += 1;
        self.q.push(0.0);
        self.nvar - 1
    }
    /// Σ a_j x_j ≤ b
    fn le(&mut self, a: Vec<(usize, f64)>, b: f64) {
        self.nonneg.push((a, b));
    }
    fn build(self) -> (CscMatrix<f64>, Vec<f64>, CscMatrix<f64>, Vec<f64>, Vec<SupportedConeT<f64>>) {
        let n = self.nvar;
        let p = csc(n, n, self.p);
        let mut trip = Vec::new();
        let mut b = Vec::new();
        let mut row = 0;
        let mut push = |a: &Vec<(usize, f64)>, bi: f64, trip: &mut Vec<(usize, usize, f64)>, b: &mut Vec<f64>| {
            for &(j, v) in a {
                trip.push((row, j, v));
            }
            b.push(bi);
            row += 1;
        };
        for (a, bi) in &self.zero {
            push(a, *bi, &mut trip, &mut b);
        }
        for (a, bi) in &self.nonneg {
            push(a, *bi, &mut trip, &mut b);
        }
        for cone in &self.exp {
            for (a, bi) in cone {
                push(a, *bi, &mut trip, &mut b);
            }
        }
        let mut cones = vec![SupportedConeT::ZeroConeT(self.zero.len())];
        if !self.nonneg.is_empty() {
            cones.push(SupportedConeT::NonnegativeConeT(self.nonneg.len()));
        }
        cones.extend(self.exp.iter().map(|_| SupportedConeT::ExponentialConeT()));
        let a = csc(row, n, trip);
        (p, self.q, a, b, cones)
    }
}

/// CSC from triplets (duplicates summed).
fn csc(m: usize, n: usize, mut t: Vec<(usize, usize, f64)>) -> CscMatrix<f64> {
    t.sort_by(|a, b| (a.1, a.0).cmp(&(b.1, b.0)));
    let mut colptr = vec![0usize; n + 1];
    let (mut rowval, mut nzval): (Vec<usize>, Vec<f64>) = (Vec::new(), Vec::new());
    let mut last: Option<(usize, usize)> = None;
    for (i, j, v) in t {
        if last == Some((i, j)) {
            if let Some(x) = nzval.last_mut() {
                *x += v;
            }
            continue;
        }
        rowval.push(i);
        nzval.push(v);
        colptr[j + 1] += 1;
        last = Some((i, j));
    }
    for j in 0..n {
        colptr[j + 1] += colptr[j];
    }
    CscMatrix::new(m, n, colptr, rowval, nzval)
}

/// A hinge crossed from below within the step, majorized at z_l.
struct Crossing {
    node: usize,
    c: f64,
    s: f64,
    /// δ = s − d^n > 0
    delta: f64,
}

/// Solve the frozen-S problem with Clarabel (majorization rounds where needed).
pub fn solve(step: &StepData, s: &[f64], set: &ConicSettings) -> Result<ContactSolution, ConicFailure> {
    let n = step.n();
    // hinges crossed from below need majorization; their touching points start at 0
    let mut crossings = Vec::new();
    if step.rule == NormalForceRule::DiscreteGradient {
        for i in 0..n {
            for h in &step.law.hinges {
                let a = step.nodes[i].d_n - h.s;
                if a < 0.0 {
                    crossings.push(Crossing { node: i, c: h.c, s: h.s, delta: -a });
                }
            }
        }
    }
    let mut z_l = vec![0.0; crossings.len()];
    let mut iterations = 0usize;
    for round in 0..set.max_rounds.max(1) {
        let (y, r, its) = solve_once(step, s, set, &crossings, &z_l)?;
        iterations += its;
        let z_new: Vec<f64> = crossings.iter().map(|c| (step.d_end(c.node, &y) - c.s).max(0.0)).collect();
        let moved = z_new.iter().zip(&z_l).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let z_scale = step.a_d * step.velocity_scale(&y);
        z_l = z_new;
        if moved <= set.tolerance * z_scale || crossings.is_empty() || round + 1 == set.max_rounds {
            if !crossings.is_empty() && moved > set.tolerance * z_scale {
                return Err(ConicFailure {
                    iterations,
                    residual: moved / z_scale.max(f64::MIN_POSITIVE),
                    reason: format!("majorization did not settle in {} rounds", set.max_rounds),
                });
            }
            return Ok(finish(step, s, y, r, iterations));
        }
    }
    Err(ConicFailure { iterations, residual: f64::NAN, reason: "no majorization round ran".into() })
}

fn solve_once(
    step: &StepData,
    s: &[f64],
    set: &ConicSettings,
    crossings: &[Crossing],
    z_l: &[f64],
) -> Result<(Vec<f64>, Vec<f64>, usize), ConicFailure> {
    let n = step.n();
    let m = 2 * n;
    let mut b = Builder::default();
    let r: Vec<usize> = (0..m).map(|_| b.var()).collect();
    let y: Vec<usize> = (0..m).map(|_| b.var()).collect();
    // ½ rᵀ W r (upper triangle)
    for j in 0..m {
        for i in 0..=j {
            b.p.push((r[i], r[j], step.w[(i, j)]));
        }
    }
    // y + W r = y_free
    for j in 0..m {
        let mut row = vec![(y[j], 1.0)];
        row.extend((0..m).map(|l| (r[l], step.w[(j, l)])));
        b.zero.push((row, step.y_free[j]));
    }
    for i in 0..n {
        let nd = step.nodes[i];
        let (yn, yt) = (y[2 * i], y[2 * i + 1]);
        // exact constraint y_ν ≤ β
        if let Some(beta) = step.beta(i) {
            b.le(vec![(yn, 1.0)], beta);
        }
        // friction (ω S/a_v)|v̄|, v̄ = v_aff + a_v y_τ, via s ≥ ±v̄
        if step.friction && s[i] > 0.0 {
            let sv = b.var();
            b.q[sv] = nd.omega * s[i] / step.a_v;
            b.le(vec![(yt, step.a_v), (sv, -1.0)], -nd.v_aff);
            b.le(vec![(yt, -step.a_v), (sv, -1.0)], nd.v_aff);
        }
        // normal force, hinge by hinge; z = d^{n+1} − s = (d_aff − s) + a_d y_ν
        let wd = nd.omega / step.a_d;
        for h in &step.law.hinges {
            let a = nd.d_n - h.s;
            let z0 = nd.d_aff - h.s;
            // F on this hinge = lin_z·z + quad·zR² + lin_zr·zR with zR ≥ max(z, 0)
            let (lin_z, quad, lin_zr) = match step.rule {
                NormalForceRule::DiscreteGradient if a >= 0.0 => (0.5 * h.c * a, 0.25 * h.c, 0.0),
                NormalForceRule::DiscreteGradient => {
                    let k = crossings.iter().position(|c| c.node == i && c.s == h.s && c.c == h.c);
                    let (zl, delta) = k.map(|k| (z_l[k], crossings[k].delta)).unwrap_or((0.0, -a));
                    // tangent majorant (c/4) zR² + ℓ zR, ℓ = −(c/2) δ z_l/(z_l + δ)
                    (0.0, 0.25 * h.c, -0.5 * h.c * delta * zl / (zl + delta))
                }
                NormalForceRule::Average => (0.5 * h.c * a.max(0.0), 0.25 * h.c, 0.0),
                NormalForceRule::EndPoint => (0.0, 0.5 * h.c, 0.0),
            };
            // linear part on z: coefficient wd·lin_z·a_d on y_ν
            b.q[yn] += wd * lin_z * step.a_d;
            // quadratic part on zR ≥ max(z, 0)
            let zr = b.var();
            b.p.push((zr, zr, 2.0 * wd * quad));
            b.q[zr] += wd * lin_zr;
            b.le(vec![(yn, step.a_d), (zr, -1.0)], -z0);
            b.le(vec![(zr, -1.0)], 0.0);
            // the logarithmic branch below the hinge when d^n is above it
            if step.rule == NormalForceRule::DiscreteGradient && a > 1e-14 * (1.0 + h.s.abs()) {
                let kappa = 0.5 * h.c * a * a;
                let tl = b.var(); // τ̃ ≥ −ln(1 − z̃) − z̃
                let zt = b.var(); // z̃ = z_L/A ≤ min(z/A, 0)
                b.q[tl] = wd * kappa;
                b.le(vec![(zt, a), (yn, -step.a_d)], z0);
                b.le(vec![(zt, 1.0)], 0.0);
                // (−τ̃ − z̃, 1, 1 − z̃) ∈ K_exp  ⟺  e^{−τ̃ − z̃} ≤ 1 − z̃
                b.exp.push([(vec![(tl, 1.0), (zt, 1.0)], 0.0), (vec![], 1.0), (vec![(zt, 1.0)], 1.0)]);
            }
        }
    }
    let (p, q, a, bb, cones) = b.build();
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(set.tolerance)
        .tol_gap_rel(set.tolerance)
        .tol_feas(set.tolerance)
        .tol_ktratio(1e-8)
        .max_iter(400)
        .build()
        .map_err(|e| ConicFailure { iterations: 0, residual: f64::NAN, reason: format!("Clarabel settings: {e:?}") })?;
    let mut solver = DefaultSolver::new(&p, &q, &a, &bb, &cones, settings)
        .map_err(|e| ConicFailure { iterations: 0, residual: f64::NAN, reason: format!("Clarabel setup: {e:?}") })?;
    solver.solve();
    let sol = &solver.solution;
    match sol.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        other => {
            return Err(ConicFailure {
                iterations: sol.iterations as usize,
                residual: sol.r_prim.max(sol.r_dual),
                reason: format!("Clarabel stopped with status {other:?}"),
            });
        }
    }
    let yv: Vec<f64> = y.iter().map(|&j| sol.x[j]).collect();
    let rv: Vec<f64> = r.iter().map(|&j| sol.x[j]).collect();
    Ok((yv, rv, sol.iterations as usize))
}

/// Multipliers, forces and status from the conic solution.
fn finish(step: &StepData, s: &[f64], y: Vec<f64>, r: Vec<f64>, iterations: usize) -> ContactSolution {
    let n = step.n();
    let scale = step.velocity_scale(&y);
    let q: Vec<f64> = (0..n).map(|i| step.q(i, &y)).collect();
    let lambda: Vec<f64> = (0..n)
        .map(|i| if step.nodes[i].bound.is_some() { (r[2 * i] / step.nodes[i].omega - q[i]).max(0.0) } else { 0.0 })
        .collect();
    let t: Vec<f64> = (0..n).map(|i| if step.friction { r[2 * i + 1] / step.nodes[i].omega } else { 0.0 }).collect();
    let status = (0..n)
        .map(|i| {
            let force = q[i] + lambda[i];
            if force <= 1e-9 * (1.0 + q.iter().fold(0.0f64, |m, v| m.max(v.abs()))) {
                NodeStatus::Separated
            } else if step.friction && s[i] > 0.0 && step.slip(i, &y).abs() <= 1e-7 * step.a_v * scale {
                NodeStatus::Stick
            } else {
                NodeStatus::Slip
            }
        })
        .collect();
    // relative consistency of y with y_free − W r (the equality constraint)
    let resp = step.response(&r);
    let res = y.iter().zip(&resp).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    ContactSolution { y, lambda, t, q, status, iterations, residual: if scale > 0.0 { res / scale } else { linalg::norm_inf(&resp) } }
}
