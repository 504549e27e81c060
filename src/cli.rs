//! Conventions shared by every subcommand: exit codes and the error type that carries them.
//!
//! Exit codes: 0 all work succeeded, 1 some work failed (a row with status `error`, a stage that
//! failed), 2 bad usage (bad flag value, malformed pipeline or `scene.toml`, missing input).

use std::process::ExitCode;

/// Error of a subcommand, carrying its exit code.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Bad usage or malformed input files: exit code 2. The message names the key or flag.
    #[error("{0}")]
    Usage(String),
    /// The work itself failed: exit code 1.
    #[error(transparent)]
    Failed(#[from] anyhow::Error),
}

impl CliError {
    pub fn usage(msg: impl Into<String>) -> Self {
        CliError::Usage(msg.into())
    }

    pub fn exit_code(&self) -> ExitCode {
        match self {
            CliError::Usage(_) => ExitCode::from(2),
            CliError::Failed(_) => ExitCode::from(1),
        }
    }
}

/// What a subcommand reports when it ran to the end: everything ok, or some items failed
/// (e.g. images with status `error`), which maps to exit code 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    Ok,
    SomeFailed,
}

impl Outcome {
    pub fn exit_code(self) -> ExitCode {
        match self {
            Outcome::Ok => ExitCode::SUCCESS,
            Outcome::SomeFailed => ExitCode::from(1),
        }
    }
}

pub type CliResult = Result<Outcome, CliError>;
