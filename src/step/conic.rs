//! The inner solver `conic`: the frozen-S step problem (S.6) handed to Clarabel, the
//! independent twin of `newton` (the README's design notes: two solvers that must agree).
//!
//! Condensed on the contact DOFs, (S.6) is: minimize over (r, y)
//!   ½ rᵀ W r + Σ_i (ω_i S_i/a_v) |v̄_i(y)| + Σ_i (ω_i/a_d) F_i(d_i^{n+1}(y))
//!   subject to y + W r = y_free and y_ν,i ≤ β_i (exact constraint),
//! whose optimality conditions are exactly (N.1)–(N.3) (r = ∇G(y) + multipliers). The friction
//! term is an epigraph (two inequalities in 2-D, a second-order cone per node in 3-D: the
//! disk's support function S‖v̄‖), the bound a nonnegative cone. F_i' = q_i is
//! the scheme's normal force, hinge by hinge (c/2)(r − s)_+², with z = d^{n+1} − s, A = d^n − s:
//!
//! * trapezoid and backward Euler: F = (cA_+/2) z + (c/4) z_+², resp. (c/2) z_+²: exact;
//! * discrete gradient, A ≥ 0: F = (cA/2) z + (c/4) z_+² + ψ_L(min(z, 0)),
//!   ψ_L(z) = (cA²/2)(−ln(1 − z/A) − z/A);
//! * discrete gradient, A < 0: F = ψ_R(max(z, 0)), ψ_R(z) = (c/2)(z²/2 + Az + A² ln(1 − z/A)).
//!
//! ψ_R is a convex quadratic plus a concave logarithm, which no standard cone represents;
//! ψ_L fits an exponential cone, but that cone made Clarabel stall (InsufficientProgress)
//! whenever d^n sat just above the hinge, because its scale cA² vanishes there. Both log
//! branches are therefore handled the same way: since F'' ≤ c/2 on every branch, the quadratic
//! ψ(z_l) + ψ'(z_l)(z − z_l) + (c/4)(z − z_l)² majorizes ψ and touches it at z_l;
//! the program is re-solved with updated touching points until they stop moving
//! (majorization–minimization: monotone, and contracting by about ω a_d c W_νν/2 per round,
//! ≈ 2e-3 on the academic scene). Quadratic pieces are exact, so a node that stays on one
//! side of every hinge needs one round.
//!
//! Clarabel has no warm start, so each solve starts from scratch.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};

use super::{ContactSolution, NodeStatus, StepData};
use crate::defaults::{
    CLARABEL_MAX_ITER, CLARABEL_STATIC_REGULARIZATION, CLARABEL_TOL_KTRATIO, CONIC_FAR as FAR, CONIC_MAX_ROUNDS,
    CONIC_SEPARATION_FLOOR as SEPARATION_FLOOR, CONIC_STICK_FLOOR as STICK_FLOOR, NEWTON_TOLERANCE,
};
use crate::failure::{ConicFailure, ConicStatus};
use crate::linalg;
use crate::model::laws::NormalForceRule;

/// Settings of the conic solve.
#[derive(Debug, Clone, Copy)]
pub struct ConicSettings {
    /// Clarabel's gap and feasibility tolerances
    pub tolerance: f64,
    /// majorization–minimization rounds for the logarithmic branches
    pub max_rounds: usize,
    /// print Clarabel's iteration log (for debugging a stalled program)
    pub verbose: bool,
}

impl Default for ConicSettings {
    fn default() -> Self {
        ConicSettings { tolerance: NEWTON_TOLERANCE, max_rounds: CONIC_MAX_ROUNDS, verbose: false }
    }
}

/// A row of a conic program: the sparse a (variable, coefficient) and b of b − a·x.
type ConeRow = (Vec<(usize, f64)>, f64);

/// Clarabel's problem data: P, q, A, b and the cones.
type Program = (CscMatrix<f64>, Vec<f64>, CscMatrix<f64>, Vec<f64>, Vec<SupportedConeT<f64>>);

/// A growing sparse problem: variables, objective, and constraint rows by cone.
#[derive(Default)]
struct Builder {
    nvar: usize,
    p: Vec<(usize, usize, f64)>,
    q: Vec<f64>,
    zero: Vec<ConeRow>,
    nonneg: Vec<ConeRow>,
    /// second-order cones: each a list of rows (a, b) with b − a·x in the cone
    soc: Vec<Vec<ConeRow>>,
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
    fn build(self) -> Program {
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
        for cone in &self.soc {
            for (a, bi) in cone {
                push(a, *bi, &mut trip, &mut b);
            }
        }
        let mut cones = vec![SupportedConeT::ZeroConeT(self.zero.len())];
        if !self.nonneg.is_empty() {
            cones.push(SupportedConeT::NonnegativeConeT(self.nonneg.len()));
        }
        cones.extend(self.soc.iter().map(|c| SupportedConeT::SecondOrderConeT(c.len())));
        let a = csc(row, n, trip);
        (p, self.q, a, b, cones)
    }
}

/// CSC from triplets (duplicates summed).
fn csc(m: usize, n: usize, mut t: Vec<(usize, usize, f64)>) -> CscMatrix<f64> {
    t.sort_by_key(|a| (a.1, a.0));
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

/// A logarithmic branch, majorized at the touching point z_l.
struct Majorized {
    node: usize,
    c: f64,
    /// A = d^n − s (A > 0: left branch ψ_L on z ≤ 0; A < 0: right branch ψ_R on z ≥ 0)
    a: f64,
    s: f64,
}

impl Majorized {
    /// ψ'(z) on the branch: ψ_L' = cAz/(2(A − z)), ψ_R' = cz²/(2(z − A)).
    fn dpsi(&self, z: f64) -> f64 {
        if self.a > 0.0 { self.c * self.a * z / (2.0 * (self.a - z)) } else { self.c * z * z / (2.0 * (z - self.a)) }
    }
    /// the touching point kept on the branch's half-line
    fn clip(&self, z: f64) -> f64 {
        if self.a > 0.0 { z.min(0.0) } else { z.max(0.0) }
    }
}

/// (S.6) Minimize the frozen-S step functional Φ_n^S over C_n = {y_ν,i ≤ β_i} with Clarabel,
/// in the condensed form of this module's header (majorization rounds for the log branches).
pub fn solve(step: &StepData, s: &[f64], set: &ConicSettings) -> Result<ContactSolution, ConicFailure> {
    let n = step.n();
    let mut pieces = Vec::new();
    if step.force_rule == NormalForceRule::DiscreteGradient {
        for i in 0..n {
            for h in &step.law.hinges {
                let a = step.nodes[i].d_n - h.s;
                if a != 0.0 {
                    pieces.push(Majorized { node: i, c: h.c, a, s: h.s });
                }
            }
        }
    }
    // first touching points: the free motion
    let mut z_l: Vec<f64> = pieces.iter().map(|m| m.clip(step.d_end(m.node, &step.y_free) - m.s)).collect();
    // the program is solved in units of the step's velocity scale V (y = V ỹ, r = V r̃, the
    // objective divided by V²), so Clarabel's tolerances act relative to the motion even
    // when everything is nearly at rest
    let v_scale = step.velocity_scale(&step.y_free);
    if v_scale == 0.0 {
        // at rest with no load: y = 0 and r = 0 solve the problem exactly
        let m = step.m();
        return Ok(finish(step, s, vec![0.0; m], vec![0.0; m], 0));
    }
    // constraints and pieces inactive by more than FAR velocity scales are left out (a huge
    // right-hand side stalls the interior point, e.g. the bound β = 80 m/s against a motion of
    // 1e-10 m/s at the first step); any the solution reaches is put back and the program re-solved
    let nh = step.law.hinges.len();
    let z0 = |i: usize, h: usize| (step.nodes[i].d_aff - step.law.hinges[h].s) / (step.a_d * v_scale);
    let mut active = Active {
        bound: (0..n).map(|i| step.beta(i).is_some_and(|b| b / v_scale <= FAR)).collect(),
        quad: (0..n * nh).map(|j| z0(j / nh, j % nh) >= -FAR).collect(),
        piece: pieces
            .iter()
            .map(|m| {
                let h = step.law.hinges.iter().position(|h| h.s == m.s && h.c == m.c).unwrap_or(0);
                if m.a > 0.0 { z0(m.node, h) <= FAR } else { z0(m.node, h) >= -FAR }
            })
            .collect(),
    };
    let mut iterations = 0usize;
    let mut moved = f64::INFINITY;
    let mut z_scale = 0.0;
    for _ in 0..set.max_rounds.max(1) {
        let (y, r, its) = solve_once(step, s, set, &pieces, &z_l, v_scale, &active)?;
        iterations += its;
        let z_new: Vec<f64> = pieces.iter().map(|m| m.clip(step.d_end(m.node, &y) - m.s)).collect();
        moved = z_new.iter().zip(&z_l).fold(0.0f64, |acc, (a, b)| acc.max((a - b).abs()));
        z_scale = step.a_d * step.velocity_scale(&y);
        z_l = z_new;
        if moved <= set.tolerance * z_scale && !active.reinstate(step, &pieces, &y) {
            return Ok(finish(step, s, y, r, iterations));
        }
    }
    Err(ConicFailure {
        status: ConicStatus::MajorizationUnsettled { rounds: set.max_rounds },
        iterations,
        residual: moved / z_scale.max(f64::MIN_POSITIVE),
    })
}

/// Which constraints and pieces the program includes (the others are inactive far away).
struct Active {
    /// the bound y_ν,i ≤ β_i
    bound: Vec<bool>,
    /// the exact quadratic part of hinge h at node i (index i·hinges + h)
    quad: Vec<bool>,
    /// the majorized log branches
    piece: Vec<bool>,
}

impl Active {
    /// Put back every left-out constraint or piece that the solution `y` reaches; true if any.
    fn reinstate(&mut self, step: &StepData, pieces: &[Majorized], y: &[f64]) -> bool {
        let nh = step.law.hinges.len();
        let mut changed = false;
        for i in 0..step.n() {
            if !self.bound[i] && step.beta(i).is_some_and(|b| y[step.nu(i)] > b) {
                self.bound[i] = true;
                changed = true;
            }
            for (h, hinge) in step.law.hinges.iter().enumerate() {
                if !self.quad[i * nh + h] && step.d_end(i, y) > hinge.s {
                    self.quad[i * nh + h] = true;
                    changed = true;
                }
            }
        }
        for (k, m) in pieces.iter().enumerate() {
            let z = step.d_end(m.node, y) - m.s;
            if !self.piece[k] && ((m.a > 0.0 && z < 0.0) || (m.a < 0.0 && z > 0.0)) {
                self.piece[k] = true;
                changed = true;
            }
        }
        changed
    }
}

/// One conic program (the majorized S.6 at touching points `z_l`) solved by Clarabel, in units
/// of the velocity scale `v`; returns (y, r, interior-point iterations).
fn solve_once(
    step: &StepData,
    s: &[f64],
    set: &ConicSettings,
    pieces: &[Majorized],
    z_l: &[f64],
    v: f64,
    active: &Active,
) -> Result<(Vec<f64>, Vec<f64>, usize), ConicFailure> {
    let (b, r, y) = program(step, s, pieces, z_l, v, active);
    let (p, q, a, bb, cones) = b.build();
    let settings = DefaultSettingsBuilder::default()
        .verbose(set.verbose)
        .tol_gap_abs(set.tolerance)
        .tol_gap_rel(set.tolerance)
        .tol_feas(set.tolerance)
        .tol_ktratio(CLARABEL_TOL_KTRATIO)
        .max_iter(CLARABEL_MAX_ITER)
        .static_regularization_constant(CLARABEL_STATIC_REGULARIZATION)
        .build()
        .map_err(|e| ConicFailure {
            status: ConicStatus::Settings(format!("{e:?}")),
            iterations: 0,
            residual: f64::NAN,
        })?;
    let mut solver = DefaultSolver::new(&p, &q, &a, &bb, &cones, settings).map_err(|e| ConicFailure {
        status: ConicStatus::Setup(format!("{e:?}")),
        iterations: 0,
        residual: f64::NAN,
    })?;
    solver.solve();
    let sol = &solver.solution;
    match sol.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        other => {
            return Err(ConicFailure {
                status: ConicStatus::Stopped(other),
                iterations: sol.iterations as usize,
                residual: sol.r_prim.max(sol.r_dual),
            });
        }
    }
    let yv: Vec<f64> = y.iter().map(|&j| v * sol.x[j]).collect();
    let rv: Vec<f64> = r.iter().map(|&j| v * sol.x[j]).collect();
    Ok((yv, rv, sol.iterations as usize))
}

/// The program of [`solve_once`]: variables r (forces) and y (contact velocities), the
/// objective ½ rᵀ W r + friction + normal-force pieces, and the constraints by cone.
fn program(
    step: &StepData,
    s: &[f64],
    pieces: &[Majorized],
    z_l: &[f64],
    v: f64,
    active: &Active,
) -> (Builder, Vec<usize>, Vec<usize>) {
    let n = step.n();
    let m = step.m();
    let mut b = Builder::default();
    let r: Vec<usize> = (0..m).map(|_| b.var()).collect();
    let y: Vec<usize> = (0..m).map(|_| b.var()).collect();
    // ½ rᵀ W r (upper triangle)
    for j in 0..m {
        for i in 0..=j {
            b.p.push((r[i], r[j], step.delassus[(i, j)]));
        }
    }
    // y + W r = y_free
    for j in 0..m {
        let mut row = vec![(y[j], 1.0)];
        row.extend((0..m).map(|l| (r[l], step.delassus[(j, l)])));
        b.zero.push((row, step.y_free[j] / v));
    }
    let ad = step.a_d;
    for i in 0..n {
        let nd = step.nodes[i];
        let (yn, yt) = (y[step.nu(i)], y[step.tau(i)]);
        // exact constraint y_ν ≤ β
        if let Some(beta) = step.beta(i).filter(|_| active.bound[i]) {
            b.le(vec![(yn, 1.0)], beta / v);
        }
        // friction (ω S/a_v)‖v̄‖, v̄ = v_aff + a_v y_τ: in 2-D via s ≥ ±v̄, in 3-D via the
        // second-order cone s ≥ ‖v̄‖ (the disk's support function)
        if step.friction && s[i] > 0.0 && step.tdim() == 1 {
            let sv = b.var();
            b.q[sv] = nd.omega * s[i] / (step.a_v * v);
            b.le(vec![(yt, step.a_v), (sv, -1.0)], -nd.v_aff[0] / v);
            b.le(vec![(yt, -step.a_v), (sv, -1.0)], nd.v_aff[0] / v);
        } else if step.friction && s[i] > 0.0 {
            let sv = b.var();
            b.q[sv] = nd.omega * s[i] / (step.a_v * v);
            // (s, v̄/V) ∈ SOC: rows b − a·x = (s, a_v ỹ_τj + v_aff,j/V)
            let mut cone = vec![(vec![(sv, -1.0)], 0.0)];
            for j in 0..step.tdim() {
                cone.push((vec![(y[step.tau_j(i, j)], -step.a_v)], nd.v_aff[j] / v));
            }
            b.soc.push(cone);
        }
        // normal force, hinge by hinge. All pieces are written in ξ = z/a_d (velocity units):
        // z = d^{n+1} − s = z0 + a_d y_ν, and (ω/a_d) F(z) becomes ω a_d (·) ξ² + ω (·) ξ.
        for (hi, h) in step.law.hinges.iter().enumerate() {
            let a = nd.d_n - h.s;
            let z0 = nd.d_aff - h.s;
            // exact quadratic part: lin·z + quad·z_+²
            let (lin, quad) = match step.force_rule {
                NormalForceRule::DiscreteGradient => (0.5 * h.c * a.max(0.0), if a >= 0.0 { 0.25 * h.c } else { 0.0 }),
                NormalForceRule::Average => (0.5 * h.c * a.max(0.0), 0.25 * h.c),
                NormalForceRule::EndPoint => (0.0, 0.5 * h.c),
            };
            b.q[yn] += nd.omega * lin / v;
            if quad > 0.0 && active.quad[i * step.law.hinges.len() + hi] {
                let xi = b.var(); // ξ ≥ max(y + z0/a_d, 0)
                b.p.push((xi, xi, 2.0 * nd.omega * ad * quad));
                b.le(vec![(yn, 1.0), (xi, -1.0)], -z0 / (ad * v));
                b.le(vec![(xi, -1.0)], 0.0);
            }
        }
    }
    // majorized log branches: (c/4) x² + (ψ'(z_l) − (c/2) z_l) x, x = z_L ≤ min(z, 0) or z_R ≥ max(z, 0)
    for (k, mj) in pieces.iter().enumerate() {
        if !active.piece[k] {
            continue;
        }
        let nd = step.nodes[mj.node];
        let yn = y[step.nu(mj.node)];
        let z0 = nd.d_aff - mj.s;
        let xi = b.var();
        b.p.push((xi, xi, 2.0 * nd.omega * ad * 0.25 * mj.c));
        b.q[xi] += nd.omega * (mj.dpsi(z_l[k]) - 0.5 * mj.c * z_l[k]) / v;
        if mj.a > 0.0 {
            b.le(vec![(xi, 1.0), (yn, -1.0)], z0 / (ad * v));
            b.le(vec![(xi, 1.0)], 0.0);
        } else {
            b.le(vec![(yn, 1.0), (xi, -1.0)], -z0 / (ad * v));
            b.le(vec![(xi, -1.0)], 0.0);
        }
    }
    (b, r, y)
}

/// Multipliers, forces and status from the conic solution.
fn finish(step: &StepData, s: &[f64], y: Vec<f64>, r: Vec<f64>, iterations: usize) -> ContactSolution {
    let n = step.n();
    let scale = step.velocity_scale(&y);
    let q: Vec<f64> = (0..n).map(|i| step.q(i, &y)).collect();
    let lambda: Vec<f64> = (0..n)
        .map(
            |i| if step.nodes[i].bound.is_some() { (r[step.nu(i)] / step.nodes[i].omega - q[i]).max(0.0) } else { 0.0 },
        )
        .collect();
    let td = step.tdim();
    let t: Vec<f64> = (0..n * td)
        .map(|l| if step.friction { r[step.tau_j(l / td, l % td)] / step.nodes[l / td].omega } else { 0.0 })
        .collect();
    // an interior point reaches the active sets only to its tolerance: a node is separated when
    // its force is below SEPARATION_FLOOR of the largest, in stick when |v̄| ≤ STICK_FLOOR a_v V
    let f_max = (0..n).fold(0.0f64, |m, i| m.max(q[i] + lambda[i]));
    let status = (0..n)
        .map(|i| {
            let stick = step.friction && s[i] > 0.0 && step.slip_norm(i, &y) <= STICK_FLOOR * step.a_v * scale;
            NodeStatus::classify(q[i] + lambda[i], SEPARATION_FLOOR * f_max, step.friction.then_some(stick))
        })
        .collect();
    // relative consistency of y with y_free − W r (the equality constraint)
    let resp = step.response(&r);
    let res = y.iter().zip(&resp).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    ContactSolution {
        y,
        lambda,
        t,
        q,
        status,
        iterations,
        residual: if scale > 0.0 { res / scale } else { linalg::norm_inf(&resp) },
        exact: true,
    }
}
