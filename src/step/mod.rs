//! The per-step contact problem (spec/model.md §4.3–§4.5) on the contact DOFs only.
//!
//! With A_k factored and W = H A_k⁻¹ Hᵀ (the Delassus operator, computed once), the step
//! (S.2)–(S.5) reduces to: find the contact velocities y = H w, multipliers λ and friction
//! forces t with
//!
//!   y = y_free − W r,   r_ν,i = ω_i (q_i(y) + λ_i),   r_τ,i = ω_i t_i,
//!
//! q_i the normal force of the scheme (S.3), λ complementary to d_i^{n+1} ≤ g (S.4), and t_i
//! in the friction law with the bound S_i frozen (S.5). The inner solvers (`newton`, `conic`)
//! solve that frozen problem; the fixed point (F.1) updates S.

pub mod conic;
pub mod delassus;
pub mod fixed_point;
pub mod newton;

use crate::model::laws::{NormalForceRule, NormalLaw};

/// Data of one contact node for one step.
#[derive(Debug, Clone, Copy)]
pub struct NodeData {
    pub omega: f64,
    /// d^n
    pub d_n: f64,
    /// d^{n+1} = d_aff + a_d y_ν
    pub d_aff: f64,
    /// v̄ = v_aff + a_v y_τ, per tangential component (the second is 0 in 2-D)
    pub v_aff: [f64; 2],
    /// Some(g): the exact constraint d^{n+1} ≤ g (Problem P)
    pub bound: Option<f64>,
}

/// The frozen-S contact problem of one step, condensed on the contact DOFs. Data only: the
/// Newton solves' factor cache, whose state a solve changes for the next one, is passed beside it
/// (`&mut delassus::DelassusFactors`).
pub struct StepData<'a> {
    /// Delassus operator W = H A_k⁻¹ Hᵀ, components interleaved (ν_1, τ_1, ν_2, τ_2, …)
    pub delassus: &'a delassus::Delassus,
    pub y_free: Vec<f64>,
    pub nodes: Vec<NodeData>,
    pub a_d: f64,
    pub a_v: f64,
    pub force_rule: NormalForceRule,
    pub law: &'a NormalLaw,
    /// friction is modelled (t variables exist)
    pub friction: bool,
    /// components per contact node (ν, τ_1, …): the space dimension d
    pub dim: usize,
    /// W⁻¹ for Newton directions in velocity form (a dense, well-conditioned W), or None
    pub inverse: Option<&'a delassus::InverseDelassus>,
}

/// Contact status of a node after a step (contact.csv `status`, VTU `contact_status` code).
/// Stick and slip are the two states of a friction law; without one a node that carries load is
/// in [`NodeStatus::Contact`], neither sticking nor slipping.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeStatus {
    Separated,
    Stick,
    Slip,
    /// in contact (q + λ > 0) under no friction law (frictionless)
    Contact,
}

impl NodeStatus {
    /// The one rule for a node's status after a step: separated when its contact force
    /// q_i + λ_i is at most `separated_below` (0 for the exact active sets of Newton, a small
    /// fraction of the largest force for an interior point), else stick or slip as the solver's
    /// friction set says (`stick`), or in contact when there is no friction law (`stick` None).
    pub fn classify(force: f64, separated_below: f64, stick: Option<bool>) -> NodeStatus {
        match stick {
            _ if force <= separated_below => NodeStatus::Separated,
            None => NodeStatus::Contact,
            Some(true) => NodeStatus::Stick,
            Some(false) => NodeStatus::Slip,
        }
    }
    pub const ALL: [NodeStatus; 4] = [NodeStatus::Separated, NodeStatus::Stick, NodeStatus::Slip, NodeStatus::Contact];

    /// The status named `name` in contact.csv.
    pub fn from_name(name: &str) -> Option<NodeStatus> {
        NodeStatus::ALL.into_iter().find(|s| s.as_str() == name)
    }

    /// The contact.csv name of the status: separated, stick, slip, contact.
    pub fn as_str(self) -> &'static str {
        match self {
            NodeStatus::Separated => "separated",
            NodeStatus::Stick => "stick",
            NodeStatus::Slip => "slip",
            NodeStatus::Contact => "contact",
        }
    }

    /// The VTU `contact_status` code: 0 separated, 1 stick, 2 slip, 3 contact without friction
    /// (−1 marks the nodes off Γ3).
    pub fn code(self) -> i32 {
        match self {
            NodeStatus::Separated => 0,
            NodeStatus::Stick => 1,
            NodeStatus::Slip => 2,
            NodeStatus::Contact => 3,
        }
    }
}

/// The solution of the frozen problem.
#[derive(Debug, Clone)]
pub struct ContactSolution {
    pub y: Vec<f64>,
    pub lambda: Vec<f64>,
    /// friction forces, d − 1 components per node (in the node's tangent frame)
    pub t: Vec<f64>,
    /// normal force q_i of the scheme at the solution
    pub q: Vec<f64>,
    pub status: Vec<NodeStatus>,
    /// Newton iterations (or conic solves)
    pub iterations: usize,
    /// final ‖residual‖_∞ relative to the velocity scale
    pub residual: f64,
    /// whether the solution has landed to round-off: after an exact direction (`DirectionForm`)
    /// or with its residual below NEWTON_LANDING; always, but for an inexact convex solve of F.1
    /// that stopped after a loose one above it — F.1 solves such an answer again before
    /// accepting it
    pub exact: bool,
}

impl StepData<'_> {
    pub fn n(&self) -> usize {
        self.nodes.len()
    }
    /// Unknowns of the condensed problem: d per contact node.
    pub fn m(&self) -> usize {
        self.dim * self.n()
    }
    /// The index of node i's normal component in y (and in r).
    pub fn nu(&self, i: usize) -> usize {
        self.dim * i
    }
    /// The index of node i's (first) tangential component in y (and in r).
    pub fn tau(&self, i: usize) -> usize {
        self.dim * i + 1
    }
    /// Tangential components per node: d − 1 (the length of node i's block in t).
    pub fn tdim(&self) -> usize {
        self.dim - 1
    }
    /// The index of node i's tangential component j in y (and in r).
    pub fn tau_j(&self, i: usize, j: usize) -> usize {
        self.dim * i + 1 + j
    }
    /// The contact node of component l.
    pub fn node_of(&self, l: usize) -> usize {
        l / self.dim
    }
    /// d_i^{n+1}(y)
    pub fn d_end(&self, i: usize, y: &[f64]) -> f64 {
        self.nodes[i].d_aff + self.a_d * y[self.nu(i)]
    }
    /// v̄_i(y), the slip rate the friction law sees (the component along τ; 2-D)
    pub fn slip(&self, i: usize, y: &[f64]) -> f64 {
        self.nodes[i].v_aff[0] + self.a_v * y[self.tau(i)]
    }
    /// v̄_i(y) in the tangent plane: d − 1 components (the rest 0).
    pub fn slip_vec(&self, i: usize, y: &[f64]) -> [f64; 2] {
        std::array::from_fn(
            |j| if j < self.tdim() { self.nodes[i].v_aff[j] + self.a_v * y[self.tau_j(i, j)] } else { 0.0 },
        )
    }
    /// ‖v̄_i(y)‖ (|v̄_i| in 2-D).
    pub fn slip_norm(&self, i: usize, y: &[f64]) -> f64 {
        if self.dim == 2 {
            self.slip(i, y).abs()
        } else {
            let v = self.slip_vec(i, y);
            v[0].hypot(v[1])
        }
    }
    /// q_i(y)
    pub fn q(&self, i: usize, y: &[f64]) -> f64 {
        self.force_rule.force(self.law, self.nodes[i].d_n, self.d_end(i, y))
    }
    /// ∂q_i/∂y_ν,i
    pub fn dq(&self, i: usize, y: &[f64]) -> f64 {
        self.a_d * self.force_rule.force_db(self.law, self.nodes[i].d_n, self.d_end(i, y))
    }
    /// (S.4) The nodal constraint d_i^{n+1} ≤ g as a bound on the contact velocity:
    /// d^{n+1} ≤ g ⟺ y_ν,i ≤ β_i = (g − d_aff)/a_d; its multiplier is ω_i λ_i ≥ 0.
    pub fn beta(&self, i: usize) -> Option<f64> {
        self.nodes[i].bound.map(|g| (g - self.nodes[i].d_aff) / self.a_d)
    }
    /// The contact velocity at which v̄_i = 0 (stick; the component along τ).
    pub fn y_stick(&self, i: usize) -> f64 {
        -self.nodes[i].v_aff[0] / self.a_v
    }
    /// r = [ω(q + λ), ω t] per node; t holds d − 1 components per node.
    pub fn forces(&self, y: &[f64], lambda: &[f64], t: &[f64]) -> Vec<f64> {
        let mut r = vec![0.0; self.m()];
        let td = self.tdim();
        for i in 0..self.n() {
            let w = self.nodes[i].omega;
            r[self.nu(i)] = w * (self.q(i, y) + lambda[i]);
            for j in 0..td {
                r[self.tau_j(i, j)] = w * t[td * i + j];
            }
        }
        r
    }
    /// y_free − W r (through W's hierarchical form where the velocity form keeps one).
    pub fn response(&self, r: &[f64]) -> Vec<f64> {
        let mut y = self.y_free.clone();
        match self.inverse.and_then(|i| i.hierarchical_w()) {
            Some(h) => y.iter_mut().zip(h.apply(r)).for_each(|(y, wr)| *y -= wr),
            None => self.delassus.add_times(r, -1.0, &mut y),
        }
        y
    }
    /// A velocity scale for relative tests: the largest of the free velocity, `y`, and the
    /// velocities of the kinematics (v^n terms in d^{n+1} and v̄).
    pub fn velocity_scale(&self, y: &[f64]) -> f64 {
        let mut s = crate::linalg::norm_inf(&self.y_free).max(crate::linalg::norm_inf(y));
        for nd in &self.nodes {
            s = s
                .max((nd.v_aff[0] / self.a_v).abs())
                .max((nd.v_aff[1] / self.a_v).abs())
                .max(((nd.d_aff - nd.d_n) / self.a_d).abs());
        }
        s
    }
}
