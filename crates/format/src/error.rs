//! What can go wrong reading or writing jamkit's files: each error names
//! the file or field the user can fix.

use thiserror::Error;

/// An error of the file layer. The experiment layer's `ExperimentError`
/// takes each one over unchanged, message for message.
#[derive(Debug, Error)]
pub enum FormatError {
    /// The file is not what it claims to be (not JSON, not a packing).
    #[error("{file}: {message}")]
    Parse { file: String, message: String },
    /// A field has a value outside what is allowed.
    #[error("{field} = {value}: {allowed}")]
    Invalid {
        field: String,
        value: String,
        allowed: String,
    },
    /// Reading or writing a file failed. The cause is part of the message
    /// and not a separate `source`, so that a chain of errors printed whole
    /// (`{:#}`) names it once.
    #[error("{path}: {error}")]
    Io { path: String, error: std::io::Error },
}

impl FormatError {
    /// Wrap an I/O error with its path.
    pub fn io(path: impl AsRef<std::path::Path>, error: std::io::Error) -> Self {
        Self::Io {
            path: path.as_ref().display().to_string(),
            error,
        }
    }
}
