//! (Ps.1) The out-of-plane strain of plane stress as an internal variable (spec/model.md
//! decision 11, §10.8): one s = ε_zz per triangle (P1 strains are constant on a triangle), with
//! σ_zz = 0 discretized by the scheme's own rule —
//!
//!   midpoint, trapezoid:  Λ s^{n+½} + Θ (s^{n+1} − s^n)/k = −λ e^{n+½} − θ (e^{n+1} − e^n)/k,
//!   backward Euler:       Λ s^{n+1} + Θ (s^{n+1} − s^n)/k = −λ e^{n+1} − θ (e^{n+1} − e^n)/k,
//!
//! e = ε_xx + ε_yy = (G u)_T. The trace stress q = λ s + θ ṡ acts on the momentum balance as
//! Gᵀ |T| q. With α = ½ (midpoint) or 1 (backward Euler), a = αλ + θ/k and b = αΛ + Θ/k, the
//! update is s^{n+1} − s^n = −(Λ s^n + λ e^n)/b − (a/b)(e^{n+1} − e^n), so
//! q = λ s^n − a (Λ s^n + λ e^n)/b − (a²/b)(e^{n+1} − e^n): the step matrix gains
//! −(a²/b) k α D (D = Gᵀ |T| G, the Schur complement of s: A_k stays positive definite) and the
//! right-hand side the known part. The energy of s, ∫ λ e s + ½ Λ s², and its dissipation,
//! ∫ 2θ ė ṡ + Θ ṡ², complete (E.1), which holds exactly for the midpoint rule.

use crate::error::Result;
use crate::linalg::{self, SpMat};
use crate::mesh::PlaneMesh;
use crate::model::material::ThicknessLaw;

use super::{Dofs, element};

/// The divergence rows of every triangle and the law of s.
#[derive(Debug, Clone)]
pub struct ThicknessStrain {
    pub law: ThicknessLaw,
    /// |T| per triangle
    pub area: Vec<f64>,
    /// e_T = Σ coefficient · x[free DOF] over the triangle's (vertex, component) pairs that are free
    rows: Vec<Vec<(usize, f64)>>,
}

/// The scheme's coefficients of one step: α = ½ (midpoint, trapezoid) or 1 (backward Euler),
/// a = αλ + θ/k, b = αΛ + Θ/k.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThicknessStep {
    pub alpha: f64,
    pub k: f64,
    pub a: f64,
    pub b: f64,
}

impl ThicknessStrain {
    /// G on the free DOFs: (G u)_T = ∂u_x/∂x + ∂u_y/∂y on triangle T.
    pub fn new(mesh: &PlaneMesh, law: ThicknessLaw, dofs: &Dofs) -> ThicknessStrain {
        let mut area = Vec::with_capacity(mesh.cells.len());
        let mut rows = Vec::with_capacity(mesh.cells.len());
        for tri in &mesh.cells {
            let (grad, signed) = element::gradients([mesh.nodes[tri[0]], mesh.nodes[tri[1]], mesh.nodes[tri[2]]]);
            area.push(signed.abs());
            let mut row = Vec::with_capacity(6);
            for (v, g) in tri.iter().zip(&grad) {
                for c in 0..2 {
                    if let Some(i) = dofs.map[2 * v + c] {
                        row.push((i, g[c]));
                    }
                }
            }
            rows.push(row);
        }
        ThicknessStrain { law, area, rows }
    }

    /// e = G x per triangle.
    pub fn trace(&self, x: &[f64]) -> Vec<f64> {
        self.rows.iter().map(|row| row.iter().map(|&(i, g)| g * x[i]).sum()).collect()
    }

    /// y += Gᵀ (|T| q): the nodal forces of a trace stress q per triangle.
    pub fn add_forces(&self, q: &[f64], y: &mut [f64]) {
        for ((row, area), q) in self.rows.iter().zip(&self.area).zip(q) {
            for &(i, g) in row {
                y[i] += g * area * q;
            }
        }
    }

    /// D = Gᵀ diag(|T|) G on the free DOFs (K's pattern: the λ part of the stiffness at λ = 1).
    pub fn d_matrix(&self, n_free: usize) -> Result<SpMat> {
        let mut trip = Vec::with_capacity(36 * self.rows.len());
        for (row, area) in self.rows.iter().zip(&self.area) {
            for &(i, gi) in row {
                for &(j, gj) in row {
                    trip.push((i, j, area * gi * gj));
                }
            }
        }
        linalg::from_triplets(n_free, n_free, &trip)
    }

    /// (Ps.1) s^0 = −(λ/Λ) e^0 per triangle, from e^0 = G u^0.
    pub fn initial(&self, e0: &[f64]) -> Vec<f64> {
        e0.iter().map(|&e| self.law.initial(e)).collect()
    }

    /// The coefficients of a step of size k: α = ½ for the midpoint rule and the trapezoid, 1
    /// for backward Euler.
    pub fn step(&self, alpha: f64, k: f64) -> ThicknessStep {
        let l = &self.law;
        ThicknessStep { alpha, k, a: alpha * l.lambda + l.theta / k, b: alpha * l.big_lambda() + l.big_theta() / k }
    }

    /// (Ps.1) The known part of the step's trace stress, λ s^n − a (Λ s^n + λ e^n)/b, plus for
    /// the midpoint rule the v^n half of −(a²/b) Δe, (a²/b)(k/2) ė(v^n) — what moves to the
    /// right-hand side as −Gᵀ |T| (…) (α = 1 has no v^n term).
    pub fn add_rhs(&self, st: &ThicknessStep, s: &[f64], e: &[f64], e_v: &[f64], b: &mut [f64]) {
        let l = &self.law;
        let c = st.a * st.a / st.b;
        for (t, (row, area)) in self.rows.iter().zip(&self.area).enumerate() {
            let old = if st.alpha < 1.0 { c * st.k * (1.0 - st.alpha) * e_v[t] } else { 0.0 };
            let known = -(l.lambda * s[t] - st.a * (l.big_lambda() * s[t] + l.lambda * e[t]) / st.b) + old;
            for &(i, g) in row {
                b[i] += g * area * known;
            }
        }
    }

    /// (Ps.1) s^{n+1} = s^n − (Λ s^n + λ e^n)/b − (a/b)(e^{n+1} − e^n).
    pub fn advance(&self, st: &ThicknessStep, s: &[f64], e: &[f64], e_new: &[f64]) -> Vec<f64> {
        let l = &self.law;
        (0..s.len())
            .map(|t| s[t] - (l.big_lambda() * s[t] + l.lambda * e[t]) / st.b - st.a / st.b * (e_new[t] - e[t]))
            .collect()
    }

    /// ∫ λ e s + ½ Λ s²: the part of the stored energy ½ ∫ Bε:ε that s adds to ½ uᵀKu.
    pub fn energy(&self, s: &[f64], e: &[f64]) -> f64 {
        let l = &self.law;
        (0..s.len()).map(|t| self.area[t] * (l.lambda * e[t] * s[t] + 0.5 * l.big_lambda() * s[t] * s[t])).sum()
    }

    /// The increment of [`energy`](Self::energy) from increments (decision 10):
    /// ∫ λ (Δe s̄ + ē Δs) + Λ s̄ Δs with x̄ = (x + x')/2.
    pub fn energy_increment(&self, s: &[f64], e: &[f64], s_new: &[f64], e_new: &[f64]) -> f64 {
        let l = &self.law;
        (0..s.len())
            .map(|t| {
                let (ds, de) = (s_new[t] - s[t], e_new[t] - e[t]);
                let (sm, em) = (0.5 * (s[t] + s_new[t]), 0.5 * (e[t] + e_new[t]));
                self.area[t] * (l.lambda * (de * sm + em * ds) + l.big_lambda() * sm * ds)
            })
            .sum()
    }

    /// The viscous work of s over a step, k ∫ 2θ ė ṡ + Θ ṡ² with the step's rates Δe/k, Δs/k:
    /// (1/k) ∫ 2θ Δe Δs + Θ Δs² (with C's in-plane part, k ∫ Aε̇:ε̇ ≥ 0 per triangle).
    pub fn viscous_work(&self, k: f64, s: &[f64], e: &[f64], s_new: &[f64], e_new: &[f64]) -> f64 {
        let l = &self.law;
        (0..s.len())
            .map(|t| {
                let (ds, de) = (s_new[t] - s[t], e_new[t] - e[t]);
                self.area[t] * (2.0 * l.theta * de * ds + l.big_theta() * ds * ds) / k
            })
            .sum()
    }

    /// The step's trace stress per triangle, q = λ s̄ + θ Δs/k with s̄ the scheme's average
    /// (s^{n+½}, or s^{n+1} for α = 1): the force Gᵀ|T|q the step balanced ((V.1) reads it).
    pub fn step_stress(&self, st: &ThicknessStep, s: &[f64], s_new: &[f64]) -> Vec<f64> {
        let l = &self.law;
        (0..s.len())
            .map(|t| l.lambda * ((1.0 - st.alpha) * s[t] + st.alpha * s_new[t]) + l.theta * (s_new[t] - s[t]) / st.k)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit square's two triangles, no clamped DOF; `advance` is driven by a prescribed e(t).
    fn square(law: ThicknessLaw) -> ThicknessStrain {
        let mesh = PlaneMesh::rectangle(1.0, 1.0, 1, 1);
        ThicknessStrain::new(&mesh, law, &Dofs::with_dim(4, &[false; 4], 2))
    }

    /// (Ps.1) The update integrates Λ s + Θ ṡ = −λ e − θ ė at the scheme's order: for
    /// e(t) = sin 3t, s(0) = 0, the exact s(t) = ∫ e^{−(t−τ)/τ_s} (−λ e − θ ė)(τ)/Θ dτ with
    /// τ_s = Θ/Λ; the midpoint rule's error at t = 1 falls by 4 per halving of k (order 2 ± 0.05:
    /// the next term of the error expansion), backward Euler's by 2 (order 1 ± 0.05).
    #[test]
    fn ps1_thickness_strain_update_converges_at_the_scheme_order() {
        // τ_s = Θ/Λ = 2.5 resolved by every k below (a stiffer law only delays the asymptotic range)
        let law = ThicknessLaw { lambda: 1.0, mu: 0.5, theta: 2.0, zeta: 1.5 };
        let th = square(law);
        let (big_l, big_t) = (law.big_lambda(), law.big_theta());
        let e = |t: f64| (3.0 * t).sin();
        let e_dot = |t: f64| 3.0 * (3.0 * t).cos();
        // the exact solution by the convolution, integrated by Simpson's rule on 20,000 panels
        let exact = {
            let (n, t1) = (20_000, 1.0);
            let h = t1 / n as f64;
            let g = |tau: f64| {
                (-(t1 - tau) * big_l / big_t).exp() * (-law.lambda * e(tau) - law.theta * e_dot(tau)) / big_t
            };
            (0..=n)
                .map(|i| {
                    g(i as f64 * h)
                        * if i == 0 || i == n {
                            1.0
                        } else if i % 2 == 1 {
                            4.0
                        } else {
                            2.0
                        }
                })
                .sum::<f64>()
                * h
                / 3.0
        };
        for (alpha, order) in [(0.5, 2.0), (1.0, 1.0)] {
            let errors: Vec<f64> = [200usize, 400, 800]
                .iter()
                .map(|&n| {
                    let k = 1.0 / n as f64;
                    let st = th.step(alpha, k);
                    let mut s = vec![0.0];
                    for i in 0..n {
                        s = th.advance(&st, &s, &[e(i as f64 * k)], &[e((i + 1) as f64 * k)]);
                    }
                    (s[0] - exact).abs()
                })
                .collect();
            for w in errors.windows(2) {
                let p = (w[0] / w[1]).log2();
                assert!((p - order).abs() < 0.05, "α = {alpha}: order {p} from errors {errors:?}");
            }
        }
    }
}
