//! Errors a user can cause or meet, each printed as one clear line.

use std::fmt;

/// A problem with a scene: where (file, and line and column when known) and what was expected.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneError {
    pub file: String,
    pub line: Option<usize>,
    pub column: Option<usize>,
    pub message: String,
}

impl SceneError {
    pub fn at(file: &str, line: usize, column: usize, message: impl Into<String>) -> Self {
        SceneError {
            file: file.to_string(),
            line: Some(line),
            column: Some(column),
            message: message.into(),
        }
    }

    pub fn file(file: &str, message: impl Into<String>) -> Self {
        SceneError {
            file: file.to_string(),
            line: None,
            column: None,
            message: message.into(),
        }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.column {
                write!(f, ":{col}")?;
            }
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for SceneError {}

/// Why a running simulation stopped early.
#[derive(Clone, Debug, PartialEq)]
pub struct Fault {
    pub step: u64,
    pub time: f64,
    pub message: String,
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the run stopped at step {} (t = {:.6e} s): {}",
            self.step, self.time, self.message
        )
    }
}

impl std::error::Error for Fault {}

/// Anything the command line can report.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{0}")]
    Scene(#[from] SceneError),
    #[error("{0}")]
    Fault(#[from] Fault),
    #[error("{context}: {source}")]
    Io {
        context: String,
        source: std::io::Error,
    },
    /// A signal asked the run to stop; it finished its step and saved its state.
    #[error(
        "interrupted at t = {} s; summary.json says `interrupted` and checkpoint.bin holds the state: `regolith resume {}` continues the run",
        crate::format::Seconds(*time),
        dir.display()
    )]
    Interrupted { time: f64, dir: std::path::PathBuf },
}

impl Error {
    pub fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        Error::Io {
            context: context.into(),
            source,
        }
    }
}
