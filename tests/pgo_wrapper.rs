//! `pgo/rustc-wrapper` (docs/design.md §8, "Profile-guided optimisation") adds the committed
//! profile to exactly the compilations it fits and runs every other one unchanged. It is run
//! here with `echo` in place of rustc, so that the command it would run is its output, over
//! the cases a build meets: this crate's release build, a dependency, a test build, `cargo
//! check`, an unoptimised build, a build whose hash the profile was not written for, and the
//! switch `SPECTRAL_RENDER_PGO=0`. Also: the committed profile is an indexed LLVM profile and
//! `pgo/METADATA` lists at least one hash.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn wrapper() -> PathBuf {
    root().join("pgo/rustc-wrapper")
}

/// The build hashes the committed profile was written for.
fn listed_hashes() -> Vec<String> {
    let text = std::fs::read_to_string(root().join("pgo/METADATA")).expect("pgo/METADATA");
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .map(String::from)
        .collect()
}

/// What the wrapper runs (echo's stdout) and what it says (stderr) for rustc `args`.
fn run(args: &[&str], pgo: Option<&str>) -> (String, String) {
    // Run as Cargo runs it: by its own `#!` line.
    let mut cmd = Command::new(wrapper());
    cmd.arg("echo").args(args);
    cmd.env_remove("SPECTRAL_RENDER_PGO");
    if let Some(v) = pgo {
        cmd.env("SPECTRAL_RENDER_PGO", v);
    }
    let out = cmd.output().expect("the wrapper runs");
    assert!(out.status.success(), "the wrapper failed: {out:?}");
    (
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

/// Cargo's arguments for a compilation of `crate_name` (the parts the wrapper reads).
fn rustc_args<'a>(crate_name: &'a str, opt: &'a str, emit: &'a str, hash: &'a str) -> Vec<&'a str> {
    vec![
        "--crate-name",
        crate_name,
        "--edition=2021",
        "src/lib.rs",
        emit,
        "-C",
        opt,
        "-C",
        hash,
        "--crate-type",
        "lib",
    ]
}

/// This crate's release build, as Cargo compiles its library.
fn release_args(hash: &str) -> Vec<&str> {
    rustc_args(
        "spectral_render",
        "opt-level=3",
        "--emit=dep-info,link",
        hash,
    )
}

/// A test build of this crate's release-profile library: the `testing` feature on.
fn test_build_args(hash: &str) -> Vec<&str> {
    let mut args = release_args(hash);
    args.extend(["--cfg", "feature=\"testing\""]);
    args
}

fn profile_flag(out: &str) -> bool {
    out.contains("-Cprofile-use=")
}

#[test]
fn the_release_build_of_this_crate_gets_the_profile() {
    let hash = format!("metadata={}", listed_hashes()[0]);
    let args = release_args(&hash);
    let (out, err) = run(&args, None);
    let profile = root().join("pgo/spectral-render.profdata");
    let profile = profile.canonicalize().unwrap();
    assert!(
        out.contains(&format!("-Cprofile-use={}", profile.display())),
        "{out}"
    );
    assert!(out.contains("-no-pgo-warn-mismatch"), "{out}");
    // The original arguments come first, unchanged.
    assert!(out.starts_with(&args.join(" ")), "{out}");
    assert!(err.is_empty(), "{err}");
}

#[test]
fn other_crates_and_builds_run_unchanged_and_silently() {
    let hash = format!("metadata={}", listed_hashes()[0]);
    let cases: [(&str, Vec<&str>, Option<&str>); 5] = [
        (
            "a dependency",
            rustc_args("glam", "opt-level=3", "--emit=dep-info,link", &hash),
            None,
        ),
        (
            "cargo check",
            rustc_args(
                "spectral_render",
                "opt-level=3",
                "--emit=dep-info,metadata",
                &hash,
            ),
            None,
        ),
        (
            "a debug build",
            rustc_args(
                "spectral_render",
                "opt-level=0",
                "--emit=dep-info,link",
                &hash,
            ),
            None,
        ),
        ("SPECTRAL_RENDER_PGO=0", release_args(&hash), Some("0")),
        ("a test build", test_build_args(&hash), None),
    ];
    for (what, args, pgo) in cases {
        let (out, err) = run(&args, pgo);
        assert_eq!(
            out.trim_end(),
            args.join(" "),
            "{what}: changed the command"
        );
        assert!(err.is_empty(), "{what}: said {err}");
    }
}

/// Cargo's variables reach rustc whole, the ones whose names are not shell identifiers too
/// (`CARGO_BIN_EXE_spectral-render`, which the integration tests read at compile time).
#[test]
fn every_environment_variable_reaches_the_compiler() {
    let hash = format!("metadata={}", listed_hashes()[0]);
    let name = "CARGO_BIN_EXE_pgo-wrapper-test";
    let cases = [
        vec!["--crate-name", "glam"],
        release_args(&hash),
        test_build_args(&hash),
    ];
    for args in cases {
        // printenv prints the variable it is asked for (the other arguments name none).
        let out = Command::new(wrapper())
            .arg("printenv")
            .arg(name)
            .args(&args)
            .env(name, "/the/binary")
            .output()
            .unwrap();
        let stdout = String::from_utf8(out.stdout).unwrap();
        assert_eq!(stdout.lines().next(), Some("/the/binary"), "{args:?}");
    }
}

#[test]
fn a_build_the_profile_was_not_written_for_is_plain_and_says_so() {
    let mut hash = String::from("metadata=");
    // A hash that pgo/METADATA does not list.
    hash.push_str(if listed_hashes().iter().any(|h| h == "0") {
        "1"
    } else {
        "0"
    });
    let args = release_args(&hash);
    let (out, err) = run(&args, None);
    assert!(!profile_flag(&out), "{out}");
    assert_eq!(out.trim_end(), args.join(" "));
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("built without its PGO profile"), "{err}");
    assert!(err.contains("pgo/train.sh"), "{err}");
}

#[test]
fn generate_mode_instruments_and_records_the_hash() {
    let dir = std::env::temp_dir().join(format!("pgo_wrapper_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mode = format!("generate:{}", dir.display());
    let args = rustc_args(
        "spectral_render",
        "opt-level=3",
        "--emit=dep-info,link",
        "metadata=abc123",
    );
    let (out, _) = run(&args, Some(&mode));
    assert!(
        out.contains(&format!("-Cprofile-generate={}", dir.display())),
        "{out}"
    );
    assert!(!profile_flag(&out), "{out}");
    let recorded = std::fs::read_to_string(dir.join("METADATA")).unwrap();
    assert_eq!(recorded, "abc123\n");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_committed_profile_is_an_indexed_llvm_profile() {
    let bytes = std::fs::read(Path::new(&root()).join("pgo/spectral-render.profdata")).unwrap();
    // IndexedInstrProf::Magic, "\xfflprofi\x81" as a little-endian u64 (LLVM's
    // include/llvm/ProfileData/InstrProf.h).
    assert!(bytes.len() > 16);
    assert_eq!(
        u64::from_le_bytes(bytes[..8].try_into().unwrap()),
        0x8169_666f_7270_6cff
    );
    assert!(!listed_hashes().is_empty());
}
