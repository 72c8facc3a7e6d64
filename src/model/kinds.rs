//! The enumerated choices of a scene (the README's scene contract), shared by the TOML schema
//! (`crate::scene`) and the typed model: serde names each variant as the scene file writes it,
//! and [`name`] gives that same name back for outputs, so there is one enum→name table.

use serde::{Deserialize, Serialize};

/// The scene-file name of a unit variant (`SchemeKind::BackwardEuler` → "backward-euler"):
/// serde's own renaming, so outputs and messages use exactly the words of the scene file.
pub fn name<T: Serialize>(kind: &T) -> String {
    match serde_json::to_value(kind) {
        Ok(serde_json::Value::String(s)) => s,
        _ => String::from("?"),
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DomainKind {
    Rectangle,
    /// [0, Lx] × [0, Ly] × [0, Lz] cut into nx × ny × nz cells of six tetrahedra
    Box,
    Gmsh,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Plane {
    #[default]
    Strain,
    Stress,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum EnforcementKind {
    #[default]
    Exact,
    Penalty,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum FrictionBound {
    /// S = μ(‖v̄‖) p(min(r_+, g)) (P.6)
    #[default]
    Capped,
    /// S = μ(‖v̄‖) p(r)
    Uncapped,
    /// S = μ(‖v̄‖) (q + λ): Coulomb's law with the whole contact force of the step (C.1);
    /// with compliance 0 and g = 0 this is Signorini–Coulomb
    Total,
}

/// Where the normal part r of a compliance friction bound is taken (S.5, decision 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum BoundAt {
    /// the predictor û = u_ν^n + (k/2) v_ν^n (u_ν^n + k v_ν^n for backward Euler), fixed in the step
    #[default]
    Predictor,
    /// u_ν^{n+½} of the current iterate (u_ν^{n+1} for backward Euler), updated in the fixed point (C.2)
    Midpoint,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum FrictionLaw {
    #[default]
    None,
    Constant,
    Exponential,
    Table,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum SchemeKind {
    #[default]
    Midpoint,
    Trapezoid,
    BackwardEuler,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum InnerSolver {
    #[default]
    Newton,
    Conic,
    /// (N.4) Newton on the unfrozen friction bound, F.1 as fallback
    #[serde(rename = "newton-unfrozen")]
    NewtonUnfrozen,
}

/// What a midpoint step does whose (E.1) residual exceeds `solver.energy_residual_limit`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum EnergyResidualAction {
    /// the run ends with a failure naming the step
    #[default]
    Fail,
    /// the step is counted and the run goes on (summary.json warns)
    Warn,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum MassKind {
    #[default]
    Lumped,
    Consistent,
    /// (R.1) lumped, with zero mass on the contact nodes (redistributed)
    Modified,
}

/// How (F.1) updates the friction bound (`[solver] fixed_point_acceleration`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum FixedPointAcceleration {
    /// Anderson extrapolation of S over the last ANDERSON_DEPTH iterates, safeguarded (θ = 1 only)
    #[default]
    Anderson,
    /// the plain iteration S ← θ G(S) + (1 − θ) S of the paper
    None,
}

/// Where (F.1) starts each step (`[solver] fixed_point_start`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum FixedPointStart {
    /// `unfrozen` where the step problem is convex with a varying μ (its root is then F.1's only
    /// fixed point): inside (C.k), else where the setup finds (Ck.1) through the dense W; and S
    /// is Anderson-extrapolated (θ = 1), the contact has at least ROOT_START_FROM unknowns, the
    /// inner solver is Newton and the bound is p_τ at the predictor; else `predictor`
    #[default]
    Auto,
    /// S at the initial guess of the contact velocities (the paper's start)
    Predictor,
    /// S at the root of the unfrozen Newton (N.4) wherever N.4 applies (Newton inner solver, bound
    /// at the predictor) and converges, beyond (C.k) too
    Unfrozen,
}

/// The form of the Delassus operator and so of the contact solve (`[solver] contact_solve`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ContactSolve {
    /// dense below `defaults::SPARSE_FROM` contact unknowns, sparse from there
    #[default]
    Auto,
    /// the exact m × m operator, dense Cholesky
    Dense,
    /// the probed operator truncated at `defaults::DELASSUS_TRUNCATION`, sparse Cholesky
    Sparse,
}

/// The penetration bound g: finite, or none ("inf", pure normal compliance).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    Finite(f64),
    Infinite,
}
