//! The `spectral-render` command line; everything lives in the library's `cli` module.

fn main() -> std::process::ExitCode {
    spectral_render::cli::main()
}
