//! The variational forms of spec/model.md §3 in their discrete (midpoint) form, evaluated on a
//! computed step: the margin by which a test function z satisfies the inequality. A
//! non-negative margin for every admissible z is what "the discrete solution solves the
//! discrete inequality" means; the tests draw random admissible z.
//!
//! For one step from (u^n, v^n) to (u^{n+1}, v^{n+1} = w), with v̄ = (v^n + w)/2 and the
//! discrete-gradient force q_i = DP(d_i^n, d_i^{n+1}) (penalty included for P_ε), let
//!   R(z) = ⟨M(w − v^n)/k + C v̄ + K u^{n+½} + Σ_i ω_i q_i ν_i − f^{n+½}, z⟩.
//! The margin is R(z) + Σ_i ω_i p_τ(û_i) ψ⁰(v̄_τ,i; z_τ,i), with the Clarke derivative
//! ψ⁰(ξ; η) = μ(|ξ|) sgn(ξ) η for ξ ≠ 0 and μ(0)|η| for ξ = 0 (in 3-D, in the tangent plane:
//! μ(‖ξ‖) ξ·η/‖ξ‖ and μ(0)‖η‖).

use crate::linalg;
use crate::simulation::Simulation;

/// A computed step: the state before it (u^n, v^n) and after it is in `sim`.
pub struct StepPair<'a> {
    pub sim: &'a Simulation<'a>,
    pub u_before: &'a [f64],
    pub v_before: &'a [f64],
    /// (Ps.1) s^n where ε_zz is an internal variable (the state's `eps_zz` before the step), else empty
    pub eps_zz_before: &'a [f64],
}

/// ψ⁰(ξ; η): the Clarke directional derivative of ψ(ξ) = ∫_0^|ξ| μ; a slip rate |ξ| ≤ `zero`
/// (zero to the solver's tolerance: a stuck node's v̄ is ~1e-17, not 0) takes the ξ = 0 branch.
fn psi0(mu: &crate::model::laws::FrictionCoefficient, xi: f64, eta: f64, zero: f64) -> f64 {
    if xi.abs() > zero { mu.mu(xi.abs()) * xi.signum() * eta } else { mu.mu(0.0) * eta.abs() }
}

/// ψ⁰(ξ; η) in the tangent plane (3-D): μ(‖ξ‖) ξ·η/‖ξ‖ for ‖ξ‖ > `zero`, μ(0)‖η‖ otherwise.
fn psi0_plane(mu: &crate::model::laws::FrictionCoefficient, xi: [f64; 2], eta: [f64; 2], zero: f64) -> f64 {
    let n = xi[0].hypot(xi[1]);
    if n > zero { mu.mu(n) * (xi[0] * eta[0] + xi[1] * eta[1]) / n } else { mu.mu(0.0) * eta[0].hypot(eta[1]) }
}

/// The margin R(z) + Σ ω p_τ ψ⁰(v̄; z_τ) and a scale to judge it against
/// (the sum of the absolute values of its terms).
fn margin(pair: &StepPair, z: &[f64]) -> (f64, f64) {
    let sim = pair.sim;
    let p = sim.problem;
    let k = p.k;
    let (u0, v0, u1, w) = (pair.u_before, pair.v_before, &sim.state.u, &sim.state.v);
    let f = p.loads.at(p.load_time(sim.state.n - 1));
    let vbar: Vec<f64> = v0.iter().zip(w.iter()).map(|(a, b)| 0.5 * (a + b)).collect();
    let uhalf: Vec<f64> = u0.iter().zip(u1.iter()).map(|(a, b)| 0.5 * (a + b)).collect();
    let dv: Vec<f64> = w.iter().zip(v0).map(|(a, b)| (a - b) / k).collect();
    let terms = [
        linalg::quad(&sim.ops.m, &dv, z),
        linalg::quad(&sim.ops.c, &vbar, z),
        linalg::quad(&sim.ops.k, &uhalf, z),
        -linalg::dot(&f, z),
    ];
    let mut total: f64 = terms.iter().sum();
    let mut scale: f64 = terms.iter().map(|t| t.abs()).sum();
    if let Some((th, st)) = sim.thickness() {
        // (Ps.1) the trace stress of the step, ⟨Gᵀ|T| q, z⟩
        let mut force = vec![0.0; z.len()];
        th.add_forces(&th.step_stress(st, pair.eps_zz_before, &sim.state.eps_zz), &mut force);
        let term = linalg::dot(&force, z);
        total += term;
        scale += term.abs();
    }
    if let Some(c) = &p.contact {
        let (d0, d1) = (c.penetration(u0), c.penetration(u1));
        // stick is v̄ = 0 to the Newton tolerance (1e-10 of the velocity scale)
        let zero = 1e-9 * linalg::norm_inf(v0).max(linalg::norm_inf(w));
        for i in 0..c.n() {
            let (zn, zt) = c.components(i, z);
            let q = sim.kinematics.force.force(&c.normal, d0[i], d1[i]);
            let contact = c.omega[i] * q * zn;
            total += contact;
            scale += contact.abs();
            if let Some(mu) = &c.friction {
                let vn0 = c.components(i, v0).0;
                let p_hat = c.p_tau.p_tau(d0[i] + sim.kinematics.p_d * vn0);
                let psi = if c.dim == 2 {
                    psi0(mu, c.components(i, &vbar).1, zt, zero)
                } else {
                    psi0_plane(mu, c.tangential(i, &vbar), c.tangential(i, z), zero)
                };
                let fr = c.omega[i] * p_hat * psi;
                total += fr;
                scale += fr.abs();
            }
        }
    }
    (total, scale)
}

/// (V.1) The hemivariational inequality of P_ε in discrete form: for every z ∈ V^h,
/// ⟨M(w − v^n)/k + C v̄ + K u^{n+½} + Σ ω q_ε ν − f^{n+½}, z⟩ + Σ ω p_τ ψ⁰(v̄_τ; z_τ) ≥ 0
/// (plus ⟨Gᵀ|T| q, z⟩ with the trace stress of the out-of-plane strain where it is a variable, Ps.1).
/// Returns (margin, scale).
pub fn hemivariational_margin(pair: &StepPair, z: &[f64]) -> (f64, f64) {
    margin(pair, z)
}

/// (V.2) The variational–hemivariational inequality of P (the constraint on u) in discrete
/// form: the same expression is ≥ 0 for every z with u_ν,i^{n+1} + z_ν,i ≤ g at the contact
/// nodes (the multiplier term λ z_ν ≤ 0 drops out of the mixed form). `admissible` projects a
/// test function onto that set. Returns (margin, scale).
pub fn variational_margin(pair: &StepPair, z: &[f64]) -> (f64, f64) {
    margin(pair, z)
}

/// Make z admissible for (V.2): z_ν,i ≤ g − d_i^{n+1} at every contact node (the tangential
/// part is kept).
pub fn admissible(pair: &StepPair, z: &mut [f64]) {
    let p = pair.sim.problem;
    let Some(c) = &p.contact else { return };
    let Some(g) = c.constraint else { return };
    let d1 = c.penetration(&pair.sim.state.u);
    for i in 0..c.n() {
        let (zn, _) = c.components(i, z);
        let excess = zn - (g - d1[i]);
        if excess > 0.0 {
            let n = c.frames[i].normal;
            for (k, &dof) in c.node_dofs(i).iter().enumerate() {
                z[dof] -= excess * n[k];
            }
        }
    }
}
