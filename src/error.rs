//! One error type for the whole library. Every message names what is wrong and where
//! (a scene key path, a mesh entity, a time step) and, where there is one, the fix.

use std::path::PathBuf;

pub use crate::failure::{FailureKind, LinearAlgebraFailure, SolverFailure};

/// Why a run or a validation stopped.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene value is wrong. `path` is the TOML key path, e.g. `contact.friction.decay`.
    #[error("{path}: {message}")]
    Scene { path: String, message: String },

    /// The scene file is not valid TOML or does not match the schema. `message` is one line
    /// (summary.json, sweep.csv); `diagram` holds TOML's lines that quote the source with a caret
    /// under the place (empty when there is none), which the command line prints under it;
    /// `path` is the key path the error is at (empty for a syntax error), also at the start of
    /// `message`.
    #[error("{file}: {message}")]
    SceneSyntax { file: String, message: String, diagram: String, path: String },

    /// A mesh file or a mesh entity is wrong.
    #[error("mesh {file}: {message}")]
    Mesh { file: String, message: String },

    /// An expression string does not parse or does not evaluate to a finite number.
    #[error("{path}: {message}")]
    Expression { path: String, message: String },

    /// A sparse assembly or factorization failed (the step matrix is not positive definite),
    /// with faer's error.
    #[error("linear algebra: {0}")]
    LinearAlgebra(LinearAlgebraFailure),

    /// The solver did not converge on a step; carries the step, the time and the residuals.
    #[error("{0}")]
    Solver(Box<SolverFailure>),

    /// An output could not be produced (a chart, a JSON or TOML file).
    #[error("output: {0}")]
    Output(String),

    /// A checkpoint that does not fit the problem it is restored into (its sizes, or a step
    /// beyond the scene's end): the folder's files do not belong together.
    #[error("checkpoint: {0}")]
    Checkpoint(String),

    /// A study cannot be made from what it was given: a scene it does not apply to, a sweep
    /// without the point it compares with, a point that did not complete.
    #[error("study: {0}")]
    Study(String),

    /// A defect of dyncontact: a run or a writer thread panicked. The message says where.
    #[error("internal error (a defect of dyncontact: please report it): {0}")]
    Internal(String),

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
    /// a defect of dyncontact (a thread panicked; EX_SOFTWARE of sysexits.h): please report it
    pub const INTERNAL: u8 = 70;
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
    /// The scene key path this error names (`contact.friction.decay`), if it names one: the
    /// `key` of the Python package's `SceneError`.
    pub fn key(&self) -> Option<&str> {
        match self {
            Error::Scene { path, .. } | Error::Expression { path, .. } | Error::SceneSyntax { path, .. } => {
                (!path.is_empty() && path != ".").then_some(path.as_str())
            }
            _ => None,
        }
    }

    /// The exit code of the command line for this error ([`exit`]); an interruption exits as
    /// its signal asks (the caller knows which signal it was).
    pub fn exit_code(&self) -> u8 {
        match self.kind() {
            FailureKind::NonFinite | FailureKind::Solver | FailureKind::LinearAlgebra => exit::SOLVER,
            FailureKind::Input => exit::INPUT,
            FailureKind::Interrupted => exit::INTERRUPTED,
            FailureKind::Folder => exit::FOLDER,
            FailureKind::Output => exit::OUTPUT,
            FailureKind::Internal => exit::INTERNAL,
        }
    }

    /// What kind of stop this is, for summary.json's `failure_kind` (the sweep's collectors
    /// classify runs by it): a checkpoint that does not fit is a folder whose files disagree, a
    /// study's unmet precondition is bad input.
    pub fn kind(&self) -> FailureKind {
        match self {
            Error::Solver(f)
                if matches!(
                    f.cause,
                    crate::failure::StepFailureCause::NonFinite { .. }
                        | crate::failure::StepFailureCause::NonFiniteEnergy
                ) =>
            {
                FailureKind::NonFinite
            }
            Error::Solver(_) => FailureKind::Solver,
            Error::LinearAlgebra(_) => FailureKind::LinearAlgebra,
            Error::Scene { .. }
            | Error::SceneSyntax { .. }
            | Error::Mesh { .. }
            | Error::Expression { .. }
            | Error::Read { .. }
            | Error::Study(_) => FailureKind::Input,
            Error::Interrupted { .. } | Error::SweepInterrupted { .. } => FailureKind::Interrupted,
            Error::Folder { .. } | Error::Checkpoint(_) => FailureKind::Folder,
            Error::Output(_) | Error::Io { .. } => FailureKind::Output,
            Error::Internal(_) => FailureKind::Internal,
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;
