//! The one error type users see: always one line naming the file, the prim path (when there
//! is one) and the reason, with a kind that says what went wrong.

use std::fmt;
use std::path::Path;

/// What kind of failure an [`Error`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// A file could not be read or written (missing, not a file, permissions, disk), or a
    /// resource of the machine is missing (worker threads).
    Io,
    /// A file is not a stage the USD reader can open (syntax, composition, format).
    Usd,
    /// The stage opens but describes something invalid or unsupported (a prim's attribute,
    /// a spectrum, an IES profile, a texture).
    Scene,
    /// An option given on the command line or to the library is invalid.
    Option,
}

/// A user-facing error. `Display` is a single line: `FILE: PRIM: reason`, `FILE: reason`, or
/// the reason alone for an option error.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct Error {
    pub kind: ErrorKind,
    pub file: Option<String>,
    pub prim: Option<String>,
    pub reason: String,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let reason = one_line(&self.reason);
        match (&self.file, &self.prim) {
            (Some(file), Some(prim)) => write!(f, "{file}: {prim}: {reason}"),
            (Some(file), None) => write!(f, "{file}: {reason}"),
            (None, Some(prim)) => write!(f, "{prim}: {reason}"),
            (None, None) => write!(f, "{reason}"),
        }
    }
}

impl Error {
    fn new(kind: ErrorKind, file: Option<&Path>, reason: impl Into<String>) -> Error {
        Error {
            kind,
            file: file.map(|f| f.display().to_string()),
            prim: None,
            reason: reason.into(),
        }
    }

    /// A file that cannot be read or written.
    pub fn io(file: impl AsRef<Path>, reason: impl Into<String>) -> Error {
        Error::new(ErrorKind::Io, Some(file.as_ref()), reason)
    }

    /// A file the USD reader cannot open or traverse as a whole.
    pub fn usd(file: impl AsRef<Path>, reason: impl Into<String>) -> Error {
        Error::new(ErrorKind::Usd, Some(file.as_ref()), reason)
    }

    /// Invalid content of a file as a whole (a stage's settings, an asset it references).
    pub fn scene(file: impl AsRef<Path>, reason: impl Into<String>) -> Error {
        Error::new(ErrorKind::Scene, Some(file.as_ref()), reason)
    }

    /// Invalid content of one prim of a stage.
    pub fn prim(
        file: impl AsRef<Path>,
        prim: impl Into<String>,
        reason: impl Into<String>,
    ) -> Error {
        Error {
            prim: Some(prim.into()),
            ..Error::new(ErrorKind::Scene, Some(file.as_ref()), reason)
        }
    }

    /// A resource of the machine that is not there (worker threads, memory).
    pub fn resource(reason: impl Into<String>) -> Error {
        Error::new(ErrorKind::Io, None, reason)
    }

    /// An invalid option.
    pub fn option(reason: impl Into<String>) -> Error {
        Error::new(ErrorKind::Option, None, reason)
    }
}

/// Folds a multi-line message (e.g. from a parser) into one line.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

pub type Result<T> = std::result::Result<T, Error>;

/// A failure's reason alone, from a function that does not know the file or prim it concerns;
/// its caller attaches them ([`Error::prim`], [`Error::io`], …).
pub type Reason<T> = std::result::Result<T, String>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_displays_on_one_line() {
        let cases = [
            (Error::io("a.usda", "no such file"), "a.usda: no such file"),
            (
                Error::usd("a.usda", "line 3:\n  bad token"),
                "a.usda: line 3: bad token",
            ),
            (
                Error::prim("a.usda", "/World/Box", "bad\nindex"),
                "a.usda: /World/Box: bad index",
            ),
            (
                Error::option("--spp must be at least 1"),
                "--spp must be at least 1",
            ),
        ];
        for (e, text) in cases {
            assert_eq!(e.to_string(), text);
        }
        assert_eq!(Error::scene("x.ies", "r").kind, ErrorKind::Scene);
    }
}
