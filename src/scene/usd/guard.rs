//! Turns a panic inside openusd into a one-line [`Error`]: malformed input can still reach
//! an index or an `unwrap` in its reader that the checks before it do not foresee. While
//! the guarded call runs, the panic hook of this thread stays silent (the message becomes
//! part of the error instead of a backtrace on stderr); other threads keep the usual hook.

use std::cell::Cell;
use std::panic::{self, AssertUnwindSafe};
use std::path::Path;
use std::sync::Once;

use crate::error::{Error, Result};

thread_local! {
    /// Set while a guarded call runs on this thread.
    static QUIET: Cell<bool> = const { Cell::new(false) };
}

/// Runs `read` (the whole USD read of `file`); a panic becomes an [`Error::usd`].
pub(super) fn catch_panics<T>(file: &Path, read: impl FnOnce() -> Result<T>) -> Result<T> {
    install_hook();
    let outer = QUIET.with(|q| q.replace(true));
    let result = panic::catch_unwind(AssertUnwindSafe(read));
    QUIET.with(|q| q.set(outer));
    result.unwrap_or_else(|payload| {
        let message = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown failure".into());
        Err(Error::usd(
            file,
            format!("the USD reader failed on malformed data ({message})"),
        ))
    })
}

/// Wraps the process's panic hook, once, so that it says nothing on a quiet thread.
fn install_hook() {
    static INSTALL: Once = Once::new();
    INSTALL.call_once(|| {
        let previous = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            if !QUIET.with(Cell::get) {
                previous(info);
            }
        }));
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_a_usd_error() {
        let e = catch_panics(Path::new("x.usdc"), || -> Result<()> {
            let v: Vec<u8> = Vec::new();
            let i = v.len() + 3;
            let _ = v[i];
            Ok(())
        })
        .unwrap_err();
        assert_eq!(e.kind, crate::error::ErrorKind::Usd);
        assert!(
            e.to_string().starts_with("x.usdc: the USD reader failed"),
            "{e}"
        );
        assert_eq!(catch_panics(Path::new("x"), || Ok(7)).unwrap(), 7);
    }
}
