//! The contact model a scene switches on (spec/model.md §1, §2, §4.1): the contact nodes of Γ̄3 \ Γ̄1
//! with their frames (normal and tangents) and weights, the gap, and the laws — normal compliance with the
//! bound g (exact, Problem P) or its penalty (Problem P_ε), and friction.

use crate::mesh::BoundaryNodes;

use super::Enforcement;
use super::kinds::{Bound, BoundAt, FrictionBound};
use super::laws::{FrictionBoundLaw, FrictionCoefficient, NormalLaw};

/// The local frame of a contact node: the outward unit normal ν and d − 1 unit tangents τ_j,
/// stored with three components (z = 0 in two dimensions) so that the same code serves d = 2, 3.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub normal: [f64; 3],
    /// τ_1 (and τ_2 in three dimensions); in 2-D τ_1 = (−ν_2, ν_1)
    pub tangents: [[f64; 3]; 2],
}

impl Frame {
    /// The 2-D frame of a unit normal ν: τ = (−ν_2, ν_1).
    pub fn planar(n: [f64; 2]) -> Frame {
        Frame { normal: [n[0], n[1], 0.0], tangents: [[-n[1], n[0], 0.0], [0.0; 3]] }
    }

    /// The 3-D frame of a unit normal ν: τ_1 = e × ν/‖e × ν‖ with e the coordinate axis least
    /// aligned with ν (so ‖e × ν‖ ≥ √(2/3)), τ_2 = ν × τ_1; (τ_1, τ_2, ν) is orthonormal and
    /// right-handed. The friction law does not depend on the choice of the tangent pair: the
    /// friction set is a disk in the tangent plane.
    pub fn spatial(n: [f64; 3]) -> Frame {
        let axis = (0..3).min_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs())).unwrap_or(0);
        let mut e = [0.0; 3];
        e[axis] = 1.0;
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        };
        let t1 = cross(e, n);
        let norm = (t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]).sqrt();
        let t1 = t1.map(|c| c / norm);
        Frame { normal: n, tangents: [t1, cross(n, t1)] }
    }
}

/// What the foundation does at one contact node.
#[derive(Debug, Clone)]
pub struct ContactModel {
    /// the space dimension d: unknowns per node, and components per contact node (ν, τ_1, …)
    pub dim: usize,
    /// mesh node of contact node i
    pub nodes: Vec<usize>,
    /// the frame (ν_i, τ_i) of contact node i
    pub frames: Vec<Frame>,
    /// weight ω_i = ∫_Γ3 φ_i
    pub omega: Vec<f64>,
    /// gap(x_i): the laws see d_i = u(x_i)·ν_i − gap_i (decision 8)
    pub gap: Vec<f64>,
    /// free DOFs of contact node i at [d i, d i + d) (never on Γ̄1)
    pub dofs: Vec<usize>,
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
    /// the normal part of the friction bound: p_τ of the compliance (capped or uncapped), or the
    /// whole contact force (total)
    pub friction_bound: FrictionBound,
    /// where p_τ's argument is taken (compliance bounds)
    pub bound_at: BoundAt,
    pub p_tau: FrictionBoundLaw,
}

impl ContactModel {
    pub fn n(&self) -> usize {
        self.nodes.len()
    }

    /// The free DOFs of contact node i (d of them).
    pub fn node_dofs(&self, i: usize) -> &[usize] {
        &self.dofs[self.dim * i..self.dim * (i + 1)]
    }

    /// e · x at contact node i for a direction e of its frame (x a free-DOF vector).
    pub fn project(&self, i: usize, e: &[f64; 3], x: &[f64]) -> f64 {
        let d = self.node_dofs(i);
        let mut s = e[0] * x[d[0]];
        for c in 1..self.dim {
            s += e[c] * x[d[c]];
        }
        s
    }

    /// Normal and (first) tangential components (x_ν, x_τ) at contact node i of a free-DOF vector.
    pub fn components(&self, i: usize, x: &[f64]) -> (f64, f64) {
        let f = &self.frames[i];
        (self.project(i, &f.normal, x), self.project(i, &f.tangents[0], x))
    }

    /// The tangential components (x_τ1, x_τ2) at contact node i (x_τ2 = 0 in 2-D).
    pub fn tangential(&self, i: usize, x: &[f64]) -> [f64; 2] {
        let f = &self.frames[i];
        std::array::from_fn(|j| if j + 1 < self.dim { self.project(i, &f.tangents[j], x) } else { 0.0 })
    }

    /// The tangential part of x at node i as contact.csv writes it: the component along τ
    /// (signed) in 2-D, the magnitude in the tangent plane in 3-D.
    pub fn tangential_size(&self, i: usize, x: &[f64]) -> f64 {
        let t = self.tangential(i, x);
        if self.dim == 2 { t[0] } else { t[0].hypot(t[1]) }
    }

    /// Global components Σ_j a_j τ_j of tangential components a at node i.
    pub fn global(&self, i: usize, a: &[f64; 2]) -> [f64; 3] {
        let f = &self.frames[i];
        std::array::from_fn(|c| (0..self.dim - 1).map(|j| a[j] * f.tangents[j][c]).sum())
    }

    /// H x: the contact components [x_ν,1, x_τ,1, (x_τ2,1,) x_ν,2, …] of a free-DOF vector.
    pub fn restrict(&self, x: &[f64]) -> Vec<f64> {
        let mut y = Vec::with_capacity(self.dim * self.n());
        for (i, f) in self.frames.iter().enumerate() {
            y.push(self.project(i, &f.normal, x));
            for t in &f.tangents[..self.dim - 1] {
                y.push(self.project(i, t, x));
            }
        }
        y
    }

    /// out += Hᵀ r: scatter contact components r = [r_ν,i, r_τ,i, …] to the free DOFs.
    pub fn scatter_add(&self, r: &[f64], out: &mut [f64]) {
        let dim = self.dim;
        for (i, f) in self.frames.iter().enumerate() {
            let ri = &r[dim * i..dim * (i + 1)];
            for (c, &dof) in self.node_dofs(i).iter().enumerate() {
                let mut v = f.normal[c] * ri[0];
                for (j, t) in f.tangents[..dim - 1].iter().enumerate() {
                    v += t[c] * ri[1 + j];
                }
                out[dof] += v;
            }
        }
    }

    /// d_i = u_ν,i − gap_i for every contact node.
    pub fn penetration(&self, u: &[f64]) -> Vec<f64> {
        (0..self.n()).map(|i| self.components(i, u).0 - self.gap[i]).collect()
    }

    /// Assemble from the boundary data of Γ3 (Γ̄1 nodes already excluded) and the free DOFs
    /// of each of its nodes (d per node, in order).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        side: BoundaryNodes,
        dim: usize,
        gap: Vec<f64>,
        node_dofs: Vec<usize>,
        normal: NormalLaw,
        compliance: NormalLaw,
        constraint: Option<f64>,
        bound: Bound,
        enforcement: Enforcement,
        friction: Option<FrictionCoefficient>,
        (friction_bound, bound_at): (FrictionBound, BoundAt),
        p_tau: FrictionBoundLaw,
    ) -> ContactModel {
        ContactModel {
            dim,
            nodes: side.nodes,
            frames: side
                .normals
                .iter()
                .map(|&n| if dim == 3 { Frame::spatial(n) } else { Frame::planar([n[0], n[1]]) })
                .collect(),
            omega: side.omega,
            gap,
            dofs: node_dofs,
            normal,
            compliance,
            constraint,
            bound,
            enforcement,
            friction,
            friction_bound,
            bound_at,
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
        if self.friction_bound == FrictionBound::Total {
            // the bound follows the contact force, which no constant bounds
            return None;
        }
        let (p_bar, l_mu) = (self.p_tau.sup(), mu.lipschitz());
        if l_mu == 0.0 || p_bar == 0.0 || !p_bar.is_finite() {
            return None;
        }
        (0..self.n())
            .map(|i| (masses[self.node_dofs(i)[0]] / (a_v * self.omega[i] * p_bar * l_mu), i))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }
}
