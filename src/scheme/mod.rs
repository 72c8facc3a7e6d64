//! Time schemes (spec/model.md §4.2, decision 3): the midpoint rule in velocity form (S.1–S.2, the
//! default), the trapezoidal variant (identical without contact; end-point-averaged contact
//! forces) and backward Euler in velocity (first order, the baseline).
//!
//! The matrix of the velocity unknown w = v^{n+1} is constant for a fixed k, so it is
//! factored once per run (the fast path of the README's design notes).

use crate::error::Result;
use crate::fem::Operators;
use crate::fem::thickness::{ThicknessStep, ThicknessStrain};
use crate::linalg::{self, Cholesky, SpMat};
use crate::model::kinds::SchemeKind;
use crate::model::laws::NormalForceRule;

/// How the contact quantities of one step depend on the unknown contact velocity y = H w:
/// d^{n+1} = d^n + a_d (y_ν + b_d v_ν^n) and v̄ = a_v (y_τ + b_v v_τ^n).
#[derive(Debug, Clone, Copy)]
pub struct ContactKinematics {
    /// d^{n+1} = d^n + a_d (y_ν + b_d v_ν^n)
    pub a_d: f64,
    pub b_d: f64,
    /// v̄ = a_v (y_τ + b_v v_τ^n): the slip rate the friction law sees
    pub a_v: f64,
    pub b_v: f64,
    /// the normal force of the step
    pub force: NormalForceRule,
    /// û = d^n + p_d v_ν^n: the (known) point where p_τ is evaluated at the predictor
    pub p_d: f64,
    /// d̂ = d^n + p_w (d^{n+1} − d^n): where p_τ is evaluated at the iterate (`friction_bound_at =
    /// "midpoint"`): u_ν^{n+½} (p_w = ½), or u_ν^{n+1} for backward Euler (p_w = 1)
    pub p_w: f64,
}

/// The factored step matrix A_k.
pub struct StepOperator {
    pub kind: SchemeKind,
    pub k: f64,
    /// A_k, factored once
    a: Cholesky,
    /// A_k itself, kept through the setup for the Schur complement on the contact unknowns
    /// (`delassus::delassus_pair`), then released
    matrix: Option<SpMat>,
    /// (Ps.1) the out-of-plane strain's coefficients for this k, where it is a variable (its
    /// operator G is the operators' `thickness`)
    pub thickness: Option<ThicknessStep>,
}

/// The operator products of a state (u, v): K u, K v, C v and M v. The time loop forms them once
/// per step, at the end of the step, for the (E.1) increments of that step; the next step's
/// right-hand side (S.2) reads the same vectors, so a step costs one pass over the pattern of K
/// and C instead of three sparse products.
#[derive(Debug, Clone)]
pub struct StateProducts {
    pub ku: Vec<f64>,
    pub kv: Vec<f64>,
    pub cv: Vec<f64>,
    pub mv: Vec<f64>,
    /// (Ps.1) e = G u and ė = G v per triangle (empty without the thickness variable)
    pub eu: Vec<f64>,
    pub ev: Vec<f64>,
}

impl StateProducts {
    /// K u, K v, C v (one pass when K and C share a pattern, as P1 assembly gives) and M v.
    pub fn of(ops: &Operators, u: &[f64], v: &[f64]) -> StateProducts {
        let (ku, kv, cv) = linalg::sym_mul3(&ops.k, &ops.c, u, v);
        let (eu, ev) = ops.thickness.as_ref().map(|th| (th.trace(u), th.trace(v))).unwrap_or_default();
        StateProducts { ku, kv, cv, mv: linalg::mul(&ops.m, v), eu, ev }
    }
}

impl StepOperator {
    /// (S.2) The constant step matrix A_k = M/k + C/2 + (k/4) K of the midpoint rule
    /// (A = M/k + C + k K for backward Euler), factored once by sparse Cholesky (ordered by
    /// nested dissection of the DOFs' positions where that factor is the smaller, `ordering`);
    /// with the out-of-plane strain as a variable (Ps.1), plus −(a²/b) k α D.
    pub fn new(ops: &Operators, kind: SchemeKind, k: f64) -> Result<StepOperator> {
        let alpha = if kind == SchemeKind::BackwardEuler { 1.0 } else { 0.5 };
        let thickness = ops.thickness.as_ref().map(|th| th.step(alpha, k));
        let d = ops.thickness.as_ref().map(|th| th.d_matrix(ops.m.nrows())).transpose()?;
        let mut terms = match kind {
            SchemeKind::Midpoint | SchemeKind::Trapezoid => vec![(1.0 / k, &ops.m), (0.5, &ops.c), (0.25 * k, &ops.k)],
            SchemeKind::BackwardEuler => vec![(1.0 / k, &ops.m), (1.0, &ops.c), (k, &ops.k)],
        };
        if let (Some(st), Some(d)) = (&thickness, &d) {
            terms.push((-st.a * st.a / st.b * k * alpha, d));
        }
        let a = linalg::combine(&terms)?;
        let factor = Cholesky::new(&a, "the step matrix A_k", Some(&ops.positions))?;
        Ok(StepOperator { kind, k, a: factor, matrix: Some(a), thickness })
    }

    /// (S.2) without contact forces: b^n = (M/k − C/2 − kK/4) v^n − K u^n + f^{n+½}
    /// (backward Euler: M v^n/k − K u^n + f^{n+1}), so that A_k w = b^n − Hᵀ r, from the
    /// products `p` of the state (u^n, v^n); with the out-of-plane strain s^n (`eps_zz`, Ps.1)
    /// and its operator (the operators' `thickness`), plus the known part of its trace stress.
    pub fn rhs(&self, p: &StateProducts, f: &[f64], thickness: Option<&ThicknessStrain>, eps_zz: &[f64]) -> Vec<f64> {
        let k = self.k;
        let mut b: Vec<f64> = match self.kind {
            SchemeKind::BackwardEuler => (0..f.len()).map(|i| p.mv[i] / k - p.ku[i] + f[i]).collect(),
            _ => (0..f.len()).map(|i| p.mv[i] / k - 0.5 * p.cv[i] - 0.25 * k * p.kv[i] - p.ku[i] + f[i]).collect(),
        };
        if let (Some(th), Some(st)) = (thickness, &self.thickness) {
            th.add_rhs(st, eps_zz, &p.eu, &p.ev, &mut b);
        }
        b
    }

    /// x ← A_k⁻¹ x.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        self.a.solve_in_place(x);
    }

    pub fn factor(&self) -> &Cholesky {
        &self.a
    }

    /// A_k, until [`release_matrix`](Self::release_matrix).
    pub fn matrix(&self) -> Option<&SpMat> {
        self.matrix.as_ref()
    }

    /// Free A_k's entries (the factor stays): the time loop reads only the factor.
    pub fn release_matrix(&mut self) {
        self.matrix = None;
    }

    /// (S.1) u^{n+1} = u^n + k v^{n+½} with v^{n+½} = (v^n + v^{n+1})/2
    /// (backward Euler: u^{n+1} = u^n + k v^{n+1}).
    pub fn displacement(&self, u: &[f64], v: &[f64], w: &[f64]) -> Vec<f64> {
        match self.kind {
            SchemeKind::BackwardEuler => u.iter().zip(w).map(|(u, w)| u + self.k * w).collect(),
            _ => u.iter().zip(v).zip(w).map(|((u, v), w)| u + 0.5 * self.k * (v + w)).collect(),
        }
    }

    /// The (E.1) viscous term (u^{n+1} − u^n)ᵀ C v̄ with v̄ the velocity at which the viscous
    /// force acts, v^{n+½} = (v^n + v^{n+1})/2 (midpoint) or v^{n+1}, from C v^n and C v^{n+1}.
    pub fn viscous_work(&self, du: &[f64], cv: &[f64], cw: &[f64]) -> f64 {
        match self.kind {
            SchemeKind::BackwardEuler => linalg::dot(du, cw),
            _ => 0.5 * du.iter().zip(cv).zip(cw).map(|((d, a), b)| d * (a + b)).sum::<f64>(),
        }
    }

    /// The contact kinematics of this scheme and step.
    pub fn contact_kinematics(&self) -> ContactKinematics {
        ContactKinematics::of(self.kind, self.k)
    }
}

impl ContactKinematics {
    /// The contact kinematics of this scheme (decisions 2 and 3): friction at v^{n+½} and
    /// p_τ at the predictor d^n + (k/2) v_ν^n of d^{n+½} for midpoint and trapezoid; all
    /// terms at t_{n+1} for backward Euler.
    pub fn of(kind: SchemeKind, k: f64) -> ContactKinematics {
        match kind {
            SchemeKind::Midpoint => ContactKinematics {
                a_d: 0.5 * k,
                b_d: 1.0,
                a_v: 0.5,
                b_v: 1.0,
                force: NormalForceRule::DiscreteGradient,
                p_d: 0.5 * k,
                p_w: 0.5,
            },
            SchemeKind::Trapezoid => ContactKinematics {
                a_d: 0.5 * k,
                b_d: 1.0,
                a_v: 0.5,
                b_v: 1.0,
                force: NormalForceRule::Average,
                p_d: 0.5 * k,
                p_w: 0.5,
            },
            SchemeKind::BackwardEuler => ContactKinematics {
                a_d: k,
                b_d: 0.0,
                a_v: 1.0,
                b_v: 0.0,
                force: NormalForceRule::EndPoint,
                p_d: k,
                p_w: 1.0,
            },
        }
    }
}
