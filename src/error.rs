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
    #[error(
        "interrupted after step {step} (t = {time}); the outputs are valid up to that step and checkpoint.json holds it"
    )]
    Interrupted { step: usize, time: f64 },

    /// A sweep was stopped (SIGINT): the points that finished stay, the rest run when the same
    /// sweep is run again.
    #[error(
        "interrupted: {finished} of {total} points are done (sweep.csv has them); run the same sweep again to resume — completed points are skipped"
    )]
    SweepInterrupted { finished: usize, total: usize },

    /// A run or sweep folder that is not this run's to write, is in use by another process, or
    /// whose files do not belong together (a checkpoint that does not match its history, a sweep
    /// point whose files disagree). Nothing in it was changed.
    #[error("{}: {message}", path.display())]
    Folder { path: PathBuf, message: String },

    /// Reading an input (a scene, a mesh, a sweep file) failed.
    #[error("{path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// Writing an output failed (a full disk, a folder without write permission).
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// The process exit codes of the command line (the README, "Exit codes").
pub mod exit {
    /// the command did what it was asked
    pub const OK: u8 = 0;
    /// bad input: the message names the scene key, the mesh entity or the file
    pub const INPUT: u8 = 1;
    /// the solver could not continue: the message gives the step, time, residuals, a suggestion
    pub const SOLVER: u8 = 2;
    /// an output could not be written (disk full, no permission): the files already written stay valid
    pub const OUTPUT: u8 = 3;
    /// a folder that is not the run's to write, in use by another process, or whose files do not
    /// belong together (resume refused, a corrupt sweep point): nothing in it was changed
    pub const FOLDER: u8 = 4;
    /// the command line itself is wrong (an unknown flag, a missing argument)
    pub const USAGE: u8 = 64;
    /// stopped by SIGINT (Ctrl-C) after a completed step; a checkpoint of that step is written
    pub const INTERRUPTED: u8 = 130;
    /// stopped by SIGTERM, as by SIGINT
    pub const TERMINATED: u8 = 143;
}

impl Error {
    pub fn scene(path: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Scene { path: path.into(), message: message.into() }
    }
    pub fn mesh(file: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Mesh { file: file.into(), message: message.into() }
    }
    /// Writing `path` failed.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }
    /// Reading the input `path` failed.
    pub fn read(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Read { path: path.into(), source }
    }
    pub fn folder(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Folder { path: path.into(), message: message.into() }
    }
    /// True for failures of the numerical method (exit code 2), false for bad input.
    pub fn is_solver_failure(&self) -> bool {
        matches!(self, Error::Solver(_) | Error::LinearAlgebra(_))
    }

    /// The exit code of the command line for this error ([`exit`]); an interruption exits as
    /// its signal asks (the caller knows which signal it was).
    pub fn exit_code(&self) -> u8 {
        match self.kind() {
            "non_finite" | "solver" | "linear_algebra" => exit::SOLVER,
            "input" => exit::INPUT,
            "interrupted" => exit::INTERRUPTED,
            "folder" => exit::FOLDER,
            _ => exit::OUTPUT,
        }
    }

    /// What kind of stop this is, for summary.json's `failure_kind` (the sweep's collectors
    /// classify runs by it): `non_finite` (a NaN or infinity in the state), `solver` (a solver
    /// could not continue), `linear_algebra` (a factorization failed), `input` (the scene or
    /// the mesh, an input file), `interrupted`, `folder` (the run folder is not the run's, is
    /// in use, or its files disagree) or `output` (an output could not be written).
    pub fn kind(&self) -> &'static str {
        match self {
            Error::Solver(f) if matches!(f.cause, crate::failure::StepFailureCause::NonFinite { .. }) => "non_finite",
            Error::Solver(_) => "solver",
            Error::LinearAlgebra(_) => "linear_algebra",
            Error::Scene { .. }
            | Error::SceneSyntax { .. }
            | Error::Mesh { .. }
            | Error::Expression { .. }
            | Error::Read { .. } => "input",
            Error::Interrupted { .. } | Error::SweepInterrupted { .. } => "interrupted",
            Error::Folder { .. } => "folder",
            Error::Output(_) | Error::Io { .. } => "output",
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;
