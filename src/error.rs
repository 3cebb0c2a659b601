//! The one error type users see: always one line naming the file, the prim path (when there
//! is one) and the reason.

use std::fmt;
use std::path::Path;

/// A user-facing error. `Display` is a single line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct Error {
    pub file: String,
    pub prim: Option<String>,
    pub reason: String,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let reason = one_line(&self.reason);
        match &self.prim {
            Some(prim) => write!(f, "{}: {}: {}", self.file, prim, reason),
            None => write!(f, "{}: {}", self.file, reason),
        }
    }
}

impl Error {
    /// An error about a whole file (missing, unreadable, malformed).
    pub fn file(file: impl AsRef<Path>, reason: impl Into<String>) -> Error {
        Error {
            file: file.as_ref().display().to_string(),
            prim: None,
            reason: reason.into(),
        }
    }

    /// An error about one prim of a file.
    pub fn prim(
        file: impl AsRef<Path>,
        prim: impl Into<String>,
        reason: impl Into<String>,
    ) -> Error {
        Error {
            file: file.as_ref().display().to_string(),
            prim: Some(prim.into()),
            reason: reason.into(),
        }
    }
}

/// Folds a multi-line message (e.g. from a parser) into one line.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

pub type Result<T> = std::result::Result<T, Error>;
