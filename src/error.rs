//! One error type for the whole library. Every message names what is wrong and where
//! (a scene key path, a mesh entity, a time step) and, where there is one, the fix.

use std::path::PathBuf;

pub use crate::failure::SolverFailure;

/// Why a run or a validation stopped.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene value is wrong. `path` is the TOML key path, e.g. `contact.friction.decay`.
    #[error("{path}: {message}")]
    Scene { path: String, message: String },

    /// The scene file is not valid TOML or does not match the schema.
    #[error("{file}: {message}")]
    SceneSyntax { file: String, message: String },

    /// A mesh file or a mesh entity is wrong.
    #[error("mesh {file}: {message}")]
    Mesh { file: String, message: String },

    /// An expression string does not parse or does not evaluate to a finite number.
    #[error("{path}: {message}")]
    Expression { path: String, message: String },

    /// A sparse factorization failed (the step matrix is not positive definite).
    #[error("linear algebra: {0}")]
    LinearAlgebra(String),

    /// The solver did not converge on a step; carries the step, the time and the residuals.
    #[error("{0}")]
    Solver(Box<SolverFailure>),

    /// An output could not be produced (chart, JSON).
    #[error("output: {0}")]
    Output(String),

    /// The run was stopped (SIGINT or a step limit) after a completed step.
    #[error("interrupted after step {step} (t = {time}); the outputs are valid up to that step and checkpoint.json holds it")]
    Interrupted { step: usize, time: f64 },

    /// A sweep was stopped (SIGINT): the points that finished stay, the rest run when the same
    /// sweep is run again.
    #[error("interrupted: {finished} of {total} points are done (sweep.csv has them); run the same sweep again to resume — completed points are skipped")]
    SweepInterrupted { finished: usize, total: usize },

    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl Error {
    pub fn scene(path: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Scene { path: path.into(), message: message.into() }
    }
    pub fn mesh(file: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Mesh { file: file.into(), message: message.into() }
    }
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }
    /// True for failures of the numerical method (exit code 2), false for bad input.
    pub fn is_solver_failure(&self) -> bool {
        matches!(self, Error::Solver(_) | Error::LinearAlgebra(_))
    }

    /// What kind of stop this is, for summary.json's `failure_kind` (the sweep's collectors
    /// classify runs by it): `non_finite` (a NaN or infinity in the state), `solver` (a solver
    /// could not continue), `linear_algebra` (a factorization failed), `input` (the scene or
    /// the mesh), `interrupted`, or `output`.
    pub fn kind(&self) -> &'static str {
        match self {
            Error::Solver(f) if matches!(f.cause, crate::failure::StepFailureCause::NonFinite { .. }) => "non_finite",
            Error::Solver(_) => "solver",
            Error::LinearAlgebra(_) => "linear_algebra",
            Error::Scene { .. } | Error::SceneSyntax { .. } | Error::Mesh { .. } | Error::Expression { .. } => "input",
            Error::Interrupted { .. } | Error::SweepInterrupted { .. } => "interrupted",
            Error::Output(_) | Error::Io { .. } => "output",
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;
