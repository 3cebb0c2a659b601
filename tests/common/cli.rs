//! Running the `spectral-render` binary from the integration tests.

use std::path::Path;
use std::process::{Command, Output};

/// Runs `spectral-render ARGS` in `cwd`.
pub fn run_cli(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_spectral-render"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("run spectral-render")
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}
