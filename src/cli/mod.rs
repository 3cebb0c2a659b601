//! The command line: `spectral-render STAGE [options]` renders (`render` may also be named);
//! a first argument naming a subcommand runs that instead (docs/design.md §1), and
//! `spectral-render help [COMMAND]` prints a command's help. Every error, clap's usage
//! errors included, is printed as one line `error: FILE: PRIM: reason` (or `error: reason`
//! for an option) with exit code 1; a command stopped by SIGINT or SIGTERM (`interrupt.rs`)
//! exits with 130 or 143 after writing what it has.

mod checkpoints;
mod color;
mod common;
mod converge;
mod crop;
mod falsecolor;
mod frames;
mod info;
mod interrupt;
mod layers;
mod lights;
mod merge;
mod meter;
mod meter_parts;
mod parts;
mod progress;
mod render;

use crate::error::{Error, Result};
use std::ffi::OsString;
use std::process::ExitCode;

/// The subcommands: (name, entry point taking the arguments after the program name).
type Command = fn(Vec<OsString>) -> Result<()>;

/// Subcommands by name (each lives in its own file of this module); `--help` and `help`
/// list them from here.
const SUBCOMMANDS: &[(&str, Command)] = &[
    ("converge", converge::main),
    ("falsecolor", falsecolor::main),
    ("info", info::main),
    ("lights", lights::main),
    ("merge", merge::main),
    ("meter", meter::main),
];

/// The default command, also reachable by name.
const RENDER: &str = "render";

fn subcommand(name: &str) -> Option<Command> {
    SUBCOMMANDS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, c)| *c)
}

/// The text after the render command's options in `--help`: the commands there are.
fn commands_help() -> String {
    let names: Vec<&str> = SUBCOMMANDS.iter().map(|(n, _)| *n).collect();
    format!(
        "Commands:\n  spectral-render [{RENDER}] STAGE [OPTIONS]   render a stage (the default)\n  \
         spectral-render COMMAND ...                 one of: {}\n  \
         spectral-render help [COMMAND]              a command's options",
        names.join(", ")
    )
}

/// `spectral-render help [COMMAND]`: the command's `--help`.
fn help(argv: &[OsString]) -> Result<()> {
    let name = argv.get(2).and_then(|a| a.to_str());
    match name {
        None | Some(RENDER) => {
            render::command().print_help().ok();
            Ok(())
        }
        Some(n) => match subcommand(n) {
            Some(cmd) => cmd(vec![n.into(), "--help".into()]),
            None => {
                let mut names = vec![RENDER];
                names.extend(SUBCOMMANDS.iter().map(|(n, _)| *n));
                Err(Error::option(format!(
                    "unknown command '{n}' (available: {})",
                    names.join(", ")
                )))
            }
        },
    }
}

pub fn main() -> ExitCode {
    let argv: Vec<OsString> = std::env::args_os().collect();
    let first = argv.get(1).and_then(|a| a.to_str());
    let result = match (first, first.and_then(subcommand)) {
        // clap sees "spectral-render meter …" as program + its own arguments.
        (_, Some(cmd)) => cmd(argv[1..].to_vec()),
        (Some("help"), None) => help(&argv),
        (Some(RENDER), None) => {
            let mut rest = argv;
            rest.remove(1);
            render::main(rest)
        }
        _ => render::main(argv),
    };
    let failed = match result {
        Ok(()) => false,
        Err(e) => {
            eprintln!("error: {e}");
            true
        }
    };
    match (interrupt::exit_code(), failed) {
        (Some(code), _) => ExitCode::from(code),
        (None, true) => ExitCode::FAILURE,
        (None, false) => ExitCode::SUCCESS,
    }
}
