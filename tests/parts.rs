//! Issue 15: partial renders (`--part K/N`) merged by `spectral-render merge` equal the single
//! render bit for bit, for every integrator, with N not dividing spp and N = 1; merge refuses
//! parts that are missing, given twice or of another render with one line naming the part.

mod common;

use common::{cbox_path, spectral_render, stderr, temp_dir};
use spectral_render::output::exr;
use std::path::Path;

const RES: &str = "24x16";

/// Renders the Cornell box with `extra` options into `dir/name` (exit code 0 asserted).
fn render(dir: &Path, name: &str, extra: &[&str]) {
    let stage = cbox_path().display().to_string();
    let mut args = vec![stage.as_str(), "--resolution", RES, "-o", name];
    args.extend_from_slice(extra);
    let o = spectral_render(&args, dir);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
}

/// Runs `merge` with `args` in `dir`.
fn merge(dir: &Path, args: &[&str]) -> std::process::Output {
    let mut all = vec!["merge"];
    all.extend_from_slice(args);
    spectral_render(&all, dir)
}

/// The bits of every channel, by name.
fn channel_bits(path: &Path) -> Vec<(String, Vec<u32>)> {
    let img = exr::read(path).unwrap();
    img.channels
        .iter()
        .map(|(k, v)| (k.clone(), v.iter().map(|x| x.to_bits()).collect()))
        .collect()
}

/// Renders `spp` samples whole and as `n` parts (rendered in reverse order, merged from a
/// shuffled list), and compares the merged EXR with the single one.
fn assert_merge_equals_single(dir: &Path, integrator: &str, spp: u32, n: u32) {
    let spp_s = spp.to_string();
    let common = [
        "--spp",
        spp_s.as_str(),
        "--integrator",
        integrator,
        "--seed",
        "3",
    ];
    let single = format!("single-{integrator}-{n}.exr");
    render(dir, &single, &common);
    let names: Vec<String> = (0..n)
        .map(|k| format!("{integrator}-{k}-of-{n}.exr"))
        .collect();
    for k in (0..n).rev() {
        let part = format!("{k}/{n}");
        let mut args = common.to_vec();
        args.extend_from_slice(&["--part", part.as_str(), "--threads", "1"]);
        render(dir, &names[k as usize], &args);
    }
    let merged = format!("merged-{integrator}-{n}.exr");
    let mut args: Vec<&str> = names.iter().skip(1).map(String::as_str).collect();
    args.push(&names[0]);
    args.extend_from_slice(&["-o", &merged, "--preview", "merged.png"]);
    let o = merge(dir, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    let (a, b) = (
        channel_bits(&dir.join(&single)),
        channel_bits(&dir.join(&merged)),
    );
    assert_eq!(a.len(), 6);
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        let differ = x.iter().zip(y).filter(|(p, q)| p != q).count();
        assert_eq!(
            differ, 0,
            "{integrator} {n} parts: {name} differs in {differ} pixels"
        );
    }
    let lit = a[0].1.iter().filter(|&&v| f32::from_bits(v) > 0.0).count();
    assert!(lit > 100, "{integrator}: only {lit} lit pixels");
    let (s, m) = (
        exr::read(&dir.join(&single)).unwrap(),
        exr::read(&dir.join(&merged)).unwrap(),
    );
    for key in [
        exr::SPP_ATTRIBUTE,
        exr::INTEGRATOR_ATTRIBUTE,
        exr::MIS_ATTRIBUTE,
        exr::SEED_ATTRIBUTE,
        exr::MAX_DEPTH_ATTRIBUTE,
        exr::SCENE_ATTRIBUTE,
        "worldToNDC",
        "whiteLuminance",
    ] {
        assert_eq!(s.attributes.get(key), m.attributes.get(key), "{key}");
    }
    assert!(dir.join("merged.png").is_file());
}

#[test]
fn merged_parts_equal_the_single_render_for_every_integrator() {
    let dir = temp_dir("parts");
    for integrator in ["path", "light", "bdpt", "vcm"] {
        // 3 does not divide 10: parts of 3, 3 and 4 samples per pixel.
        assert_merge_equals_single(&dir, integrator, 10, 3);
        assert_merge_equals_single(&dir, integrator, 4, 1);
    }
}

#[test]
fn a_part_of_a_capped_render_merges_exactly_too() {
    // A depth cap: the parts' continuations past it merge into the warning's figures.
    let dir = temp_dir("parts-capped");
    render(
        &dir,
        "single.exr",
        &["--spp", "6", "--integrator", "bdpt", "--max-depth", "2"],
    );
    for k in 0..4 {
        let part = format!("{k}/4");
        let args = [
            "--spp",
            "6",
            "--integrator",
            "bdpt",
            "--max-depth",
            "2",
            "--part",
            &part,
        ];
        render(&dir, &format!("p{k}.exr"), &args);
    }
    let o = merge(
        &dir,
        &["p0.exr", "p1.exr", "p2.exr", "p3.part", "-o", "m.exr"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("--max-depth 2 cut"), "{}", stderr(&o));
    assert_eq!(
        channel_bits(&dir.join("single.exr")),
        channel_bits(&dir.join("m.exr"))
    );
}

/// Asserts `merge` failed with exit code 1 and one `error:` line containing every `want`.
fn assert_refused(dir: &Path, args: &[&str], want: &[&str]) {
    let o = merge(dir, args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    for w in want {
        assert!(lines[0].contains(w), "{args:?}: {} lacks {w}", lines[0]);
    }
    assert!(!dir.join("out.exr").exists(), "{args:?} wrote an output");
}

#[test]
fn merge_refuses_missing_duplicated_and_mismatched_parts() {
    let dir = temp_dir("parts-refused");
    let base = ["--spp", "4", "--integrator", "path"];
    for k in 0..3 {
        let part = format!("{k}/3");
        let mut args = base.to_vec();
        args.extend_from_slice(&["--part", &part]);
        render(&dir, &format!("p{k}.exr"), &args);
    }
    render(
        &dir,
        "seed.exr",
        &[
            "--spp",
            "4",
            "--integrator",
            "path",
            "--part",
            "2/3",
            "--seed",
            "1",
        ],
    );
    render(
        &dir,
        "bdpt.exr",
        &["--spp", "4", "--integrator", "bdpt", "--part", "2/3"],
    );
    render(
        &dir,
        "four.exr",
        &["--spp", "4", "--integrator", "path", "--part", "3/4"],
    );
    render(&dir, "whole.exr", &base);
    assert_refused(
        &dir,
        &["p0.exr", "p1.exr", "-o", "out.exr"],
        &["missing part 2/3"],
    );
    assert_refused(
        &dir,
        &["p0.exr", "p1.exr", "p1.exr", "p2.exr", "-o", "out.exr"],
        &["p1.exr", "part 1/3 given twice"],
    );
    assert_refused(
        &dir,
        &["p0.exr", "p1.exr", "seed.exr", "-o", "out.exr"],
        &["seed.exr", "seed 1 there"],
    );
    assert_refused(
        &dir,
        &["p0.exr", "p1.exr", "bdpt.exr", "-o", "out.exr"],
        &["bdpt.exr", "integrator"],
    );
    assert_refused(
        &dir,
        &["p0.exr", "p1.exr", "four.exr", "-o", "out.exr"],
        &["four.exr", "split into 4"],
    );
    assert_refused(
        &dir,
        &["p0.exr", "p1.exr", "whole.exr", "-o", "out.exr"],
        &["whole.exr", "whole.part"],
    );
    // A damaged part file.
    let mut bytes = std::fs::read(dir.join("p2.part")).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 1;
    std::fs::write(dir.join("bad.part"), bytes).unwrap();
    assert_refused(
        &dir,
        &["p0.exr", "p1.exr", "bad.part", "-o", "out.exr"],
        &["bad.part", "damaged"],
    );
    // Parts that cannot be one: auto, a time budget.
    let stage = cbox_path().display().to_string();
    for (extra, want) in [
        (&["--part", "0/2"][..], "named --integrator"),
        (
            &["--part", "0/2", "--integrator", "path", "--time", "1"],
            "needs --spp",
        ),
        (
            &["--part", "2/2", "--integrator", "path"],
            "K must be in 0..N",
        ),
    ] {
        let mut args = vec![stage.as_str(), "-o", "x.exr"];
        args.extend_from_slice(extra);
        let o = spectral_render(&args, &dir);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains(want), "{}", stderr(&o));
    }
}
