//! SIGINT and SIGTERM (Ctrl-C, `kill`): the first one asks the running command to stop after
//! its current pass, write what it has (the image with its true sample count, the readings so
//! far marked as interrupted, a checkpoint when one was asked for) and exit with 128 + the
//! signal's number (130, 143); a second one ends the process at once, with the same code and
//! without writing. Signals are flags polled between passes (passes last about a second). The
//! only module that names signal-hook.

use crate::error::{Error, Result};
use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::flag;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The last signal received (0: none).
static RECEIVED: AtomicUsize = AtomicUsize::new(0);
/// Set by the first signal: a second one exits at once.
static ARMED: AtomicBool = AtomicBool::new(false);

/// Installs the handlers (once per process; later calls only install them again).
pub fn install() -> Result<()> {
    for signal in [SIGINT, SIGTERM] {
        let fail = |e: std::io::Error| Error::resource(format!("cannot handle signals: {e}"));
        // Registered first, so that it sees ARMED as the previous signal left it.
        flag::register_conditional_shutdown(signal, 128 + signal, &ARMED).map_err(fail)?;
        flag::register_usize(signal, &RECEIVED, signal as usize).map_err(fail)?;
        flag::register(signal, &ARMED).map_err(fail)?;
    }
    Ok(())
}

/// The name of the signal received, if any.
pub fn received() -> Option<&'static str> {
    match RECEIVED.load(Ordering::SeqCst) as i32 {
        0 => None,
        SIGINT => Some("SIGINT"),
        SIGTERM => Some("SIGTERM"),
        _ => Some("a signal"),
    }
}

/// The exit code after a signal: 128 + its number (130 for SIGINT, 143 for SIGTERM).
pub fn exit_code() -> Option<u8> {
    match RECEIVED.load(Ordering::SeqCst) {
        0 => None,
        s => u8::try_from(128 + s).ok(),
    }
}
