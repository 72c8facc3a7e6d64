//! The contact model a scene switches on (spec/model.md §1, §2, §4.1): the contact nodes of Γ̄3 \ Γ̄1
//! with their normals, tangents and weights, the gap, and the laws — normal compliance with the
//! bound g (exact, Problem P) or its penalty (Problem P_ε), and friction.

use crate::mesh::SideNodes;

use super::kinds::Bound;
use super::laws::{FrictionBoundLaw, FrictionCoefficient, NormalLaw};
use super::Enforcement;

/// What the foundation does at one contact node.
#[derive(Debug, Clone)]
pub struct ContactModel {
    /// mesh node of contact node i
    pub nodes: Vec<usize>,
    /// outward unit normal ν_i
    pub normals: Vec<[f64; 2]>,
    /// weight ω_i = ∫_Γ3 φ_i
    pub omega: Vec<f64>,
    /// gap(x_i): the laws see d_i = u(x_i)·ν_i − gap_i (decision 8)
    pub gap: Vec<f64>,
    /// free DOFs (x, y) of each contact node (never on Γ̄1)
    pub dofs: Vec<[usize; 2]>,
    /// the normal response of the step: p (P.5), or p_ε (Pe.5) with `enforcement = "penalty"`
    pub normal: NormalLaw,
    /// the compliance law p alone (for p_τ and for reporting)
    pub compliance: NormalLaw,
    /// Some(g) when the constraint d ≤ g is enforced exactly with multipliers (Problem P)
    pub constraint: Option<f64>,
    /// the penetration bound of the scene
    pub bound: Bound,
    pub enforcement: Enforcement,
    /// None: frictionless
    pub friction: Option<FrictionCoefficient>,
    pub p_tau: FrictionBoundLaw,
}

impl ContactModel {
    pub fn n(&self) -> usize {
        self.nodes.len()
    }

    /// Tangent τ_i = (−ν_2, ν_1).
    pub fn tangent(&self, i: usize) -> [f64; 2] {
        let n = self.normals[i];
        [-n[1], n[0]]
    }

    /// Normal and tangential components (x_ν, x_τ) at contact node i of a free-DOF vector.
    pub fn components(&self, i: usize, x: &[f64]) -> (f64, f64) {
        let [dx, dy] = self.dofs[i];
        let (n, t) = (self.normals[i], self.tangent(i));
        (n[0] * x[dx] + n[1] * x[dy], t[0] * x[dx] + t[1] * x[dy])
    }

    /// H x: the contact components [x_ν,1, x_τ,1, x_ν,2, x_τ,2, …] of a free-DOF vector.
    pub fn restrict(&self, x: &[f64]) -> Vec<f64> {
        let mut y = Vec::with_capacity(2 * self.n());
        for i in 0..self.n() {
            let (a, b) = self.components(i, x);
            y.push(a);
            y.push(b);
        }
        y
    }

    /// out += Hᵀ r: scatter contact components r = [r_ν,i, r_τ,i, …] to the free DOFs.
    pub fn scatter_add(&self, r: &[f64], out: &mut [f64]) {
        for i in 0..self.n() {
            let [dx, dy] = self.dofs[i];
            let (n, t) = (self.normals[i], self.tangent(i));
            out[dx] += n[0] * r[2 * i] + t[0] * r[2 * i + 1];
            out[dy] += n[1] * r[2 * i] + t[1] * r[2 * i + 1];
        }
    }

    /// d_i = u_ν,i − gap_i for every contact node.
    pub fn penetration(&self, u: &[f64]) -> Vec<f64> {
        (0..self.n()).map(|i| self.components(i, u).0 - self.gap[i]).collect()
    }

    /// Assemble from the boundary data of Γ3 (Γ̄1 nodes already excluded) and the free DOFs
    /// (x, y) of each of its nodes.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        side: SideNodes,
        gap: Vec<f64>,
        node_dofs: Vec<[usize; 2]>,
        normal: NormalLaw,
        compliance: NormalLaw,
        constraint: Option<f64>,
        bound: Bound,
        enforcement: Enforcement,
        friction: Option<FrictionCoefficient>,
        p_tau: FrictionBoundLaw,
    ) -> ContactModel {
        ContactModel {
            nodes: side.nodes,
            normals: side.normals,
            omega: side.omega,
            gap,
            dofs: node_dofs,
            normal,
            compliance,
            constraint,
            bound,
            enforcement,
            friction,
            p_tau,
        }
    }
}

impl ContactModel {
    /// (C.k) The largest step for which the unfrozen step problem is convex:
    /// k ≤ 2 m_i/(ω_i p̄_τ L_μ) for every contact node (midpoint), with m_i the diagonal nodal
    /// mass, p̄_τ = sup p_τ and L_μ = sup|μ'|. In general the friction term's curvature in the
    /// contact velocity is −ω p̄ a_v L_μ against the inertia's m/k, where a_v is the scheme's
    /// slip-rate factor (v̄ = a_v y + …: ½ for midpoint and trapezoid, 1 for backward Euler), so
    /// k ≤ m_i/(a_v ω_i p̄_τ L_μ). Returns (k_max, the limiting contact node) — k_max = 0 when a
    /// contact node has no mass (the modified mass) — or None when no bound applies:
    /// frictionless, μ constant or p_τ ≡ 0 (always convex), or p_τ unbounded (g = inf or
    /// uncapped with the penalty: no step is small enough for every state).
    pub fn convex_step_limit(&self, masses: &[f64], a_v: f64) -> Option<(f64, usize)> {
        let mu = self.friction.as_ref()?;
        let (p_bar, l_mu) = (self.p_tau.sup(), mu.lipschitz());
        if l_mu == 0.0 || p_bar == 0.0 || !p_bar.is_finite() {
            return None;
        }
        (0..self.n())
            .map(|i| (masses[self.dofs[i][0]] / (a_v * self.omega[i] * p_bar * l_mu), i))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }
}
