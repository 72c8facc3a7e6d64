//! Why a solver or a run stopped, as plain enums with the residuals beside them (in the manner
//! of Clarabel.rs's `SolverStatus`), and the one place where they are rendered as messages.
//!
//! The solvers return these values; nothing matches on message text. `Display` here is the only
//! place a failure becomes words (the CLI, summary.json and the errors print these).

use std::fmt;

use serde::{Deserialize, Serialize};

/// Why the Alart–Curnier Newton solve (N.1–N.3, N.4) stopped without a solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NewtonStatus {
    /// the iteration cap `solver.max_newton_iterations` was reached
    MaxIterations,
    /// the generalized Jacobian of the reduced system was singular
    SingularJacobian,
    /// the residual became NaN or infinite
    NonFinite,
}

/// A failed Newton solve: why, after how many iterations, and the last residual.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonFailure {
    pub status: NewtonStatus,
    pub iterations: usize,
    /// ‖F‖_∞ / velocity scale at the last iterate
    pub residual: f64,
}

/// Why the conic twin (Clarabel) stopped without a solution.
#[derive(Debug, Clone, PartialEq)]
pub enum ConicStatus {
    /// Clarabel refused its settings (the text is Clarabel's)
    Settings(String),
    /// Clarabel refused the problem data (the text is Clarabel's)
    Setup(String),
    /// Clarabel ended with a status other than Solved / AlmostSolved
    Stopped(clarabel::solver::SolverStatus),
    /// the majorization of the logarithmic branches did not settle within `rounds`
    MajorizationUnsettled { rounds: usize },
}

/// A failed conic solve.
#[derive(Debug, Clone, PartialEq)]
pub struct ConicFailure {
    pub status: ConicStatus,
    /// interior-point iterations summed over the rounds
    pub iterations: usize,
    /// Clarabel's max(primal, dual) residual, or the last move of the touching points
    pub residual: f64,
}

/// A failed inner (frozen-S) solve.
#[derive(Debug, Clone, PartialEq)]
pub enum InnerFailure {
    Newton(NewtonFailure),
    Conic(ConicFailure),
}

impl InnerFailure {
    pub fn solver(&self) -> &'static str {
        match self {
            InnerFailure::Newton(_) => "newton",
            InnerFailure::Conic(_) => "conic",
        }
    }
    pub fn iterations(&self) -> usize {
        match self {
            InnerFailure::Newton(f) => f.iterations,
            InnerFailure::Conic(f) => f.iterations,
        }
    }
    pub fn residual(&self) -> f64 {
        match self {
            InnerFailure::Newton(f) => f.residual,
            InnerFailure::Conic(f) => f.residual,
        }
    }
}

/// A failed contact solve of one step: the inner failure and the (F.1) iteration it happened
/// in (0: the single solve of a frictionless step, or the unfrozen Newton of N.4).
#[derive(Debug, Clone, PartialEq)]
pub struct ContactFailure {
    pub fixed_point_iteration: usize,
    pub inner: InnerFailure,
}

/// Why a step could not be completed.
#[derive(Debug, Clone, PartialEq)]
pub enum StepFailureCause {
    /// the contact solve failed
    Contact(ContactFailure),
    /// a NaN or an infinity appeared in the new velocity or displacement (entry of the free DOFs)
    NonFinite { entry: usize },
    /// (E.1) The step's energy residual exceeded `solver.energy_residual_limit` of the energy
    /// scale (midpoint scheme, where the balance is an identity): the step's equations were not
    /// solved, whatever the solvers reported
    EnergyBalance { relative: f64, limit: f64 },
    /// a term of (E.1) is not finite while the state is: the scene's magnitudes (initial data,
    /// loads) are beyond the range of f64 once squared
    NonFiniteEnergy,
}

/// The full report of a failed step: where, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct SolverFailure {
    pub step: usize,
    pub time: f64,
    pub cause: StepFailureCause,
}

/// A failure of faer (a sparse assembly or a Cholesky factorization), with faer's own error value.
#[derive(Debug, Clone)]
pub enum LinearAlgebraFailure {
    /// faer refused the triplets of a sparse matrix (an index out of bounds, no memory)
    Assembly(faer::sparse::CreationError),
    /// the symbolic Cholesky analysis of `matrix` failed (an index overflow, no memory)
    SymbolicCholesky { matrix: String, cause: faer::sparse::FaerError },
    /// the numeric Cholesky factorization of `matrix` failed: it is not positive definite (or no memory)
    Cholesky { matrix: String, cause: faer::sparse::linalg::LltError },
}

/// What kind of stop a failure is (summary.json `failure_kind`; the sweep classifies points by it,
/// the command line chooses its exit code by it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FailureKind {
    /// a NaN or an infinity in the state
    NonFinite,
    /// a solver could not continue
    Solver,
    /// a factorization failed
    LinearAlgebra,
    /// the scene, the mesh or another input file is wrong
    Input,
    /// stopped by a signal or a step limit
    Interrupted,
    /// the run folder is not the run's, is in use, or its files disagree
    Folder,
    /// an output could not be written
    Output,
    /// a defect of dyncontact (a panic in a run or in a writer thread)
    Internal,
}

impl FailureKind {
    /// The name summary.json stores (`non_finite`, `solver`, …).
    pub fn as_str(self) -> &'static str {
        match self {
            FailureKind::NonFinite => "non_finite",
            FailureKind::Solver => "solver",
            FailureKind::LinearAlgebra => "linear_algebra",
            FailureKind::Input => "input",
            FailureKind::Interrupted => "interrupted",
            FailureKind::Folder => "folder",
            FailureKind::Output => "output",
            FailureKind::Internal => "internal",
        }
    }
}

impl fmt::Display for FailureKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// How a run ended (summary.json `status`; sweep.csv's `status` of a point that ran).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RunStatus {
    /// written when the run takes its folder; left by a run killed outright
    Running,
    Completed,
    Failed,
    Interrupted,
}

impl RunStatus {
    /// The word summary.json and sweep.csv write (`running`, `completed`, `failed`, `interrupted`).
    pub fn as_str(self) -> &'static str {
        match self {
            RunStatus::Running => "running",
            RunStatus::Completed => "completed",
            RunStatus::Failed => "failed",
            RunStatus::Interrupted => "interrupted",
        }
    }
}

impl fmt::Display for RunStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Whether (F.1) met its tolerance on a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FixedPointStatus {
    /// converged (or no fixed point was needed)
    #[default]
    Converged,
    /// `solver.max_fixed_point_iterations` was reached: the step uses the last iterate
    CapReached,
}

// ------------------------------------------------------------------------------------------
// Messages: the only place failures become words.

impl fmt::Display for NewtonStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NewtonStatus::MaxIterations => "no convergence within the iteration cap",
            NewtonStatus::SingularJacobian => "singular Newton matrix",
            NewtonStatus::NonFinite => "the residual is not finite",
        })
    }
}

impl fmt::Display for ConicStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConicStatus::Settings(e) => write!(f, "Clarabel settings: {e}"),
            ConicStatus::Setup(e) => write!(f, "Clarabel setup: {e}"),
            ConicStatus::Stopped(s) => write!(f, "Clarabel stopped with status {s:?}"),
            ConicStatus::MajorizationUnsettled { rounds } => {
                write!(f, "majorization did not settle in {rounds} rounds")
            }
        }
    }
}

impl fmt::Display for InnerFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            InnerFailure::Newton(n) if n.status == NewtonStatus::MaxIterations => {
                write!(f, "no convergence in {} iterations", n.iterations)
            }
            InnerFailure::Newton(n) => write!(f, "{}", n.status),
            InnerFailure::Conic(c) => write!(f, "{}", c.status),
        }
    }
}

impl StepFailureCause {
    /// What to try instead.
    pub fn suggestion(&self) -> &'static str {
        match self {
            StepFailureCause::Contact(c) => match c.inner {
                InnerFailure::Newton(_) => {
                    "a smaller time.step, solver.relaxation < 1 or more solver.max_newton_iterations (with enforcement = \"penalty\": \
                     a larger contact.penalty)"
                }
                InnerFailure::Conic(_) => {
                    "a smaller time.step or solver.relaxation < 1 (with enforcement = \"penalty\": a larger contact.penalty)"
                }
            },
            StepFailureCause::NonFinite { .. } => "check the load expressions and use a smaller time.step",
            StepFailureCause::NonFiniteEnergy => {
                "check the magnitudes of the initial data and the loads: their energies overflow f64 (beyond ~1e308)"
            }
            StepFailureCause::EnergyBalance { .. } => {
                "check the scene's magnitudes (friction coefficients, compliances, loads) and use a smaller time.step; \
                 solver.energy_residual_action = \"warn\" lets the run go on"
            }
        }
    }
}

impl fmt::Display for StepFailureCause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StepFailureCause::Contact(c) => write!(
                f,
                "the {} solver failed in fixed-point iteration {} ({}); after {} iterations the relative residual is {:.3e}",
                c.inner.solver(),
                c.fixed_point_iteration,
                c.inner,
                c.inner.iterations(),
                c.inner.residual()
            ),
            StepFailureCause::NonFinite { entry } => write!(
                f,
                "a non-finite value appeared in the solution (entry {entry}); the loads or the step produced NaN or infinity"
            ),
            StepFailureCause::NonFiniteEnergy => write!(
                f,
                "an energy term of (E.1) is not finite: the step's displacement and velocity are finite, but their energies overflow"
            ),
            StepFailureCause::EnergyBalance { relative, limit } => write!(
                f,
                "the energy balance (E.1) fails by {relative:.3e} of the energy scale (solver.energy_residual_limit = {limit:e}): \
                 the step's equations are not solved to the solvers' tolerance"
            ),
        }
    }
}

impl fmt::Display for LinearAlgebraFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinearAlgebraFailure::Assembly(e) => write!(f, "assembly failed: {e:?}"),
            LinearAlgebraFailure::SymbolicCholesky { matrix, cause } => {
                write!(f, "symbolic Cholesky of {matrix} failed: {cause:?}")
            }
            LinearAlgebraFailure::Cholesky { matrix, cause } => write!(
                f,
                "Cholesky factorization of {matrix} failed ({cause:?}): the matrix is not positive definite \
                 (check density > 0, the material constants and that the body is held or has mass)"
            ),
        }
    }
}

impl fmt::Display for SolverFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "step {} (t = {:.6e}): {}. Suggestion: {}", self.step, self.time, self.cause, self.cause.suggestion())
    }
}
