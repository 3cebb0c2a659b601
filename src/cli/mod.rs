//! The command line: `spectral-render STAGE [options]` renders; a first argument naming a
//! subcommand runs that instead (docs/design.md §1). Every error, clap's usage errors
//! included, is printed as one line `error: FILE: PRIM: reason` (or `error: reason` for an
//! option) with exit code 1.

mod common;
mod converge;
mod lights;
mod meter;
mod progress;
mod render;

use crate::error::Result;
use std::ffi::OsString;
use std::process::ExitCode;

/// The subcommands: (name, entry point taking the arguments after the program name).
type Command = fn(Vec<OsString>) -> Result<()>;

/// Subcommands by name (each lives in its own file of this module).
const SUBCOMMANDS: &[(&str, Command)] = &[
    ("converge", converge::main),
    ("lights", lights::main),
    ("meter", meter::main),
];

fn subcommand(name: &str) -> Option<Command> {
    SUBCOMMANDS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, c)| *c)
}

pub fn main() -> ExitCode {
    let argv: Vec<OsString> = std::env::args_os().collect();
    let sub = argv.get(1).and_then(|a| a.to_str()).and_then(subcommand);
    let result = match sub {
        // clap sees "spectral-render meter …" as program + its own arguments.
        Some(cmd) => cmd(argv[1..].to_vec()),
        None => render::main(argv),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
