//! The discrete energy balance (E.1) of spec/model.md §6, computed from increments (decision 10):
//!
//! E^{n+1} − E^n = work − viscous − friction − constraint − persistency, with
//! E = ½ vᵀMv + ½ uᵀKu + Σ ω_i P(d_i) (P includes the penalty energy for Problem P_ε), and
//! persistency the kinetic energy ½ m (v_c^{n+1})² the velocity-level persistency (R.2)
//! removes, booked as a dissipation in (E.1) (spec/model.md, (R.2); 0 when it is off).

use crate::linalg::{self, SpMat};

/// The cumulative energy terms after a step (the columns of history.csv).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EnergyTerms {
    pub kinetic: f64,
    pub elastic: f64,
    pub compliance: f64,
    pub external_work: f64,
    pub viscous_dissipation: f64,
    pub friction_dissipation: f64,
    pub constraint_dissipation: f64,
    /// kinetic energy removed by the velocity-level persistency (R.2), cumulative
    pub persistency_dissipation: f64,
    /// the defect of (E.1) on the last step
    pub residual: f64,
}

/// The increments of one step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepEnergy {
    /// ½(w − v)ᵀM(w + v)
    pub d_kinetic: f64,
    /// ½(u' − u)ᵀK(u' + u)
    pub d_elastic: f64,
    /// Σ ω_i (P(d_i') − P(d_i))
    pub d_compliance: f64,
    /// (u' − u)ᵀ f^{n+½}
    pub work: f64,
    /// (u' − u)ᵀ C v̄
    pub viscous: f64,
    /// Σ ω_i S_i |Δu_τ,i| = k Σ ω_i S_i ‖v̄_i‖
    pub friction: f64,
    /// Σ ω_i λ_i (g − d_i^n)
    pub constraint: f64,
    /// ½ Σ m_i (v_c,i^{n+1})² removed by the persistency correction (R.2)
    pub persistency: f64,
}

impl StepEnergy {
    /// (E.1) The per-step defect ΔE − work + viscous + friction + constraint + persistency
    /// (ΔE = Δkinetic + Δelastic + Δcompliance); zero up to solver tolerance for the midpoint
    /// scheme.
    pub fn residual(&self) -> f64 {
        self.d_kinetic + self.d_elastic + self.d_compliance - self.work
            + self.viscous
            + self.friction
            + self.constraint
            + self.persistency
    }
}

/// ½ xᵀ A x.
pub fn half_quad(a: &SpMat, x: &[f64]) -> f64 {
    0.5 * linalg::quad(a, x, x)
}

/// The increment ½ (x' − x)ᵀ (A x' + A x) from dx = x' − x and the products A x, A x'
/// (the elastic term, whose K u the time loop keeps for the next right-hand side).
pub fn increment_with(dx: &[f64], ax: &[f64], ax_new: &[f64]) -> f64 {
    0.5 * dx.iter().zip(ax).zip(ax_new).map(|((d, a), b)| d * (a + b)).sum::<f64>()
}

/// ½ (x' − x)ᵀ A (x' + x), the increment of ½ xᵀAx without differencing large totals.
pub fn increment(a: &SpMat, x: &[f64], x_new: &[f64]) -> f64 {
    0.5 * linalg::quad_by(a, |i| x_new[i] - x[i], |j| x_new[j] + x[j])
}

impl EnergyTerms {
    /// The terms in one fixed order — kinetic, elastic, compliance, external work, viscous,
    /// friction, constraint and persistency dissipation, residual — the order of a checkpoint's
    /// `energy` (history.csv places its columns differently: see output::HISTORY).
    pub fn to_array(&self) -> [f64; 9] {
        [
            self.kinetic,
            self.elastic,
            self.compliance,
            self.external_work,
            self.viscous_dissipation,
            self.friction_dissipation,
            self.constraint_dissipation,
            self.persistency_dissipation,
            self.residual,
        ]
    }

    /// The terms from [`EnergyTerms::to_array`]'s order.
    pub fn from_array(e: [f64; 9]) -> EnergyTerms {
        EnergyTerms {
            kinetic: e[0],
            elastic: e[1],
            compliance: e[2],
            external_work: e[3],
            viscous_dissipation: e[4],
            friction_dissipation: e[5],
            constraint_dissipation: e[6],
            persistency_dissipation: e[7],
            residual: e[8],
        }
    }

    /// Add a step's increments to the totals.
    pub fn advance(&self, s: &StepEnergy) -> EnergyTerms {
        EnergyTerms {
            kinetic: self.kinetic + s.d_kinetic,
            elastic: self.elastic + s.d_elastic,
            compliance: self.compliance + s.d_compliance,
            external_work: self.external_work + s.work,
            viscous_dissipation: self.viscous_dissipation + s.viscous,
            friction_dissipation: self.friction_dissipation + s.friction,
            constraint_dissipation: self.constraint_dissipation + s.constraint,
            persistency_dissipation: self.persistency_dissipation + s.persistency,
            residual: s.residual(),
        }
    }

    /// The scale against which residuals are judged: stored energy plus everything that
    /// crossed the boundary so far.
    pub fn scale(&self) -> f64 {
        (self.kinetic + self.elastic + self.compliance).abs()
            + self.external_work.abs()
            + self.viscous_dissipation
            + self.friction_dissipation
            + self.constraint_dissipation
            + self.persistency_dissipation
    }
}
