//! The crate's layers (ARCHITECTURE.md, "Layers") are acyclic: a module may import only from
//! the layers below it. This test reads every `crate::` path of every file under `src/` —
//! `use crate::…` declarations (single, grouped, multi-line) and paths written inline — and
//! fails on one that points upwards, naming the file, the line and both layers.
//!
//! The `testing` module (test machinery behind the `testing` feature) sits outside the order:
//! it may import anything, and only test code (after a file's `#[cfg(test)]`) may import it.

use std::path::{Path, PathBuf};

/// The layers from the bottom up; each top-level module of `src/` is in exactly one.
const LAYERS: &[&str] = &[
    "error",
    "math",
    "spectral",
    "sampling",
    "imageio",
    "geometry",
    "accel",
    "desc",
    "bxdf",
    "texture",
    "material",
    "light",
    "sensor",
    "scene",
    "integrator",
    "session",
    "converge",
    "output",
    "cli",
];

/// Test machinery, outside the order.
const TESTING: &str = "testing";

/// An import from one layer into a higher one.
#[derive(Debug, PartialEq)]
struct Violation {
    file: String,
    line: usize,
    from: String,
    to: String,
}

/// The layer index of a top-level module, or None for the crate root and `testing`.
fn layer(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| *l == module)
}

/// The top-level module a file under `src/` belongs to (`light/emit.rs` → `light`,
/// `error.rs` → `error`); None for `lib.rs` and `main.rs`.
fn module_of(relative: &str) -> Option<String> {
    let first = relative.split('/').next()?;
    let name = first.trim_end_matches(".rs");
    (!matches!(name, "lib" | "main")).then(|| name.to_string())
}

/// The source with comments blanked out (line structure kept), so that doc examples and
/// prose naming `crate::x` do not count.
fn strip_comments(source: &str) -> String {
    source
        .lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// (line, first-level module) of every `crate::` path in `code`, including each branch of a
/// grouped `use crate::{a::x, b::{y, z}};`.
fn crate_paths(code: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    let mut from = 0;
    while let Some(i) = code[from..].find("crate::") {
        let start = from + i;
        from = start + "crate::".len();
        // `spectral_render::…`, `my_crate::…`: not this crate's `crate` keyword.
        if start > 0 && (bytes[start - 1].is_ascii_alphanumeric() || bytes[start - 1] == b'_') {
            continue;
        }
        let line = code[..start].matches('\n').count() + 1;
        let rest = &code[from..];
        if let Some(group) = rest.strip_prefix('{') {
            let end = matching_brace(group);
            for name in top_names(&group[..end]) {
                out.push((line, name));
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.push((line, name));
            }
        }
    }
    out
}

/// The index of the `}` closing a group whose `{` was just consumed.
fn matching_brace(s: &str) -> usize {
    let mut depth = 1;
    for (i, c) in s.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return i;
                }
            }
            _ => {}
        }
    }
    s.len()
}

/// The first path segment of every comma-separated branch at depth 0 of a group.
fn top_names(group: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut depth = 0;
    let mut at_branch_start = true;
    let mut current = String::new();
    for c in group.chars() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                if !current.is_empty() {
                    names.push(std::mem::take(&mut current));
                }
                at_branch_start = true;
                continue;
            }
            _ => {}
        }
        if depth == 0 && at_branch_start {
            if c.is_ascii_alphanumeric() || c == '_' {
                current.push(c);
                continue;
            }
            if !current.is_empty() {
                names.push(std::mem::take(&mut current));
                at_branch_start = false;
            }
        }
    }
    if !current.is_empty() {
        names.push(current);
    }
    names.retain(|n| n != "self");
    names
}

/// Every upward import among `files` (path relative to `src/`, source text).
fn upward_imports(files: &[(String, String)]) -> Vec<Violation> {
    let mut out = Vec::new();
    for (relative, source) in files {
        let Some(from) = module_of(relative) else {
            continue;
        };
        let code = strip_comments(source);
        let test_from_line = code
            .lines()
            .position(|l| l.trim_start().starts_with("#[cfg(test)]"))
            .map_or(usize::MAX, |i| i + 1);
        for (line, to) in crate_paths(&code) {
            if to == from || from == TESTING {
                continue;
            }
            let upward = if to == TESTING {
                line < test_from_line
            } else {
                match (layer(&from), layer(&to)) {
                    (Some(a), Some(b)) => b > a,
                    // A module missing from LAYERS is itself an error the caller reports.
                    _ => false,
                }
            };
            if upward {
                out.push(Violation {
                    file: relative.clone(),
                    line,
                    from: from.clone(),
                    to,
                });
            }
        }
    }
    out
}

/// Every `.rs` file under `dir`, with its path relative to `root`.
fn sources(root: &Path, dir: &Path, out: &mut Vec<(String, String)>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            sources(root, &p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            let relative = p
                .strip_prefix(root)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            out.push((relative, std::fs::read_to_string(&p).unwrap()));
        }
    }
}

fn crate_sources() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&root, &root, &mut files);
    files
}

#[test]
fn no_module_imports_from_a_layer_above_it() {
    let files = crate_sources();
    let violations = upward_imports(&files);
    let listing: Vec<String> = violations
        .iter()
        .map(|v| format!("src/{}:{}: {} imports {}", v.file, v.line, v.from, v.to))
        .collect();
    assert!(
        violations.is_empty(),
        "upward imports:\n{}",
        listing.join("\n")
    );
}

#[test]
fn every_module_has_a_layer() {
    let files = crate_sources();
    let mut missing: Vec<String> = files
        .iter()
        .filter_map(|(f, _)| module_of(f))
        .filter(|m| m != TESTING && layer(m).is_none())
        .collect();
    missing.sort();
    missing.dedup();
    assert!(missing.is_empty(), "modules not in LAYERS: {missing:?}");
}

#[test]
fn the_checker_finds_upward_imports_in_every_form() {
    let file = |path: &str, text: &str| (path.to_string(), text.to_string());
    let files = [
        // Upward: a plain use, one branch of a multi-line group, an inline path, and the
        // test machinery outside test code.
        file(
            "light/bad.rs",
            "use crate::scene::Scene;\n\
             use crate::{\n    math::Frame,\n    integrator::Integrator,\n};\n\
             fn f() { crate::session::run(); }\n\
             use crate::testing::rng::Rng;\n",
        ),
        // Fine: downward, within the module, comments, other crates, test code.
        file(
            "session/good.rs",
            "use crate::scene::Scene;\nuse crate::session::PassStats;\n\
             // use crate::cli::main;\n/// [`crate::cli`]\n\
             use spectral_render::cli;\n\
             #[cfg(test)]\nmod tests {\n    use crate::testing::rng::Rng;\n}\n",
        ),
        file("testing/anything.rs", "use crate::cli::main;\n"),
        file("lib.rs", "pub use crate::cli::main;\n"),
    ];
    let found: Vec<(usize, &str)> = upward_imports(&files)
        .iter()
        .map(|v| {
            assert_eq!(
                (v.file.as_str(), v.from.as_str()),
                ("light/bad.rs", "light")
            );
            (
                v.line,
                LAYERS
                    .iter()
                    .chain([&TESTING])
                    .find(|l| **l == v.to)
                    .copied()
                    .unwrap(),
            )
        })
        .collect();
    assert_eq!(
        found,
        [
            (1, "scene"),
            (2, "integrator"),
            (6, "session"),
            (7, "testing")
        ]
    );
}

#[test]
fn group_parsing_takes_the_first_segment_of_each_branch() {
    assert_eq!(
        top_names("a::b, c::{d, e::f}, self, g"),
        ["a", "c", "g"].map(String::from)
    );
    assert_eq!(crate_paths("use crate::{x::{y, z}, w};").len(), 2);
}

/// Prints the module graph (edges with their import counts) and the upward imports of the
/// tree under `$LAYERS_SRC` (default: this crate's `src/`); `$LAYERS_ALIAS` maps modules of
/// another tree onto layers, e.g. `render=session`. For the record of a restructuring:
/// `LAYERS_SRC=/tmp/old/src cargo test --release --test layers -- --ignored --nocapture`.
#[test]
#[ignore]
fn print_module_graph() {
    let root = std::env::var("LAYERS_SRC").map_or_else(
        |_| Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
        PathBuf::from,
    );
    let alias: Vec<(String, String)> = std::env::var("LAYERS_ALIAS")
        .unwrap_or_default()
        .split(',')
        .filter_map(|p| p.split_once('='))
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    let rename = |m: String| {
        alias
            .iter()
            .find(|(a, _)| *a == m)
            .map_or(m, |(_, b)| b.clone())
    };
    let mut files = Vec::new();
    sources(&root, &root, &mut files);
    let mut edges = std::collections::BTreeMap::<(String, String), usize>::new();
    for (relative, source) in &files {
        let Some(from) = module_of(relative).map(rename) else {
            continue;
        };
        for (_, to) in crate_paths(&strip_comments(source)) {
            let to = rename(to);
            if to != from && (layer(&to).is_some() || to == TESTING) {
                *edges.entry((from.clone(), to)).or_default() += 1;
            }
        }
    }
    for ((a, b), n) in &edges {
        let up = matches!((layer(a), layer(b)), (Some(x), Some(y)) if y > x);
        println!("{a} -> {b} ({n}){}", if up { "  UPWARD" } else { "" });
    }
    let renamed: Vec<(String, String)> = files
        .into_iter()
        .map(|(f, s)| {
            let (first, rest) = f.split_once('/').unwrap_or((&f, ""));
            let stem = first.trim_end_matches(".rs").to_string();
            let m = rename(stem.clone());
            let f = if rest.is_empty() {
                format!("{m}.rs")
            } else {
                format!("{m}/{rest}")
            };
            let s = alias.iter().fold(s, |s, (a, b)| {
                s.replace(&format!("crate::{a}::"), &format!("crate::{b}::"))
            });
            (f, s)
        })
        .collect();
    println!("upward imports: {}", upward_imports(&renamed).len());
}
