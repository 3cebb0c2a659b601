//! Issue 15: light-meter studies split by readings (`meter --part K/N -o PART.json`) and
//! merged (`spectral-render merge PART.json… -o OUT`) equal the single run byte for byte:
//! the `--json` document of point meters (values, ci95, sample counts) and a grid's map
//! files; merge refuses missing, duplicated and mismatched parts with one line.

mod common;

use common::{cbox_path, spectral_render, stderr, temp_dir};
use std::path::Path;

/// Five illuminance meters in the Cornell box (stage units: metres, Y up).
const POINTS: [(&str, &str); 5] = [
    ("0,-0.99,0", "0,1,0"),
    ("0.5,-0.99,0.5", "0,1,0"),
    ("-0.99,0,0", "1,0,0"),
    ("0,0.5,-0.99", "0,0,1"),
    ("0.3,-0.3,0.2", "0,1,0"),
];

fn run(dir: &Path, args: &[&str]) -> std::process::Output {
    let stage = cbox_path().display().to_string();
    let mut all = vec!["meter", stage.as_str()];
    all.extend_from_slice(args);
    let o = spectral_render(&all, dir);
    assert!(o.status.success(), "{all:?}: {}", stderr(&o));
    o
}

fn point_args(extra: &[&'static str]) -> Vec<&'static str> {
    let mut args = Vec::new();
    for (at, n) in POINTS {
        args.extend_from_slice(&["--at", at, "--normal", n]);
    }
    args.extend_from_slice(extra);
    args
}

fn merge(dir: &Path, args: &[&str]) -> std::process::Output {
    let mut all = vec!["merge"];
    all.extend_from_slice(args);
    spectral_render(&all, dir)
}

/// The single run's `--json` and the merge of `n` parts (rendered in reverse, given shuffled).
fn assert_points_merge(dir: &Path, tag: &str, extra: &[&'static str], n: u32) {
    let mut single = point_args(extra);
    single.push("--json");
    let want = String::from_utf8(run(dir, &single).stdout).unwrap();
    let names: Vec<String> = (0..n).map(|k| format!("{tag}-{k}.json")).collect();
    for k in (0..n).rev() {
        let part = format!("{k}/{n}");
        let mut args = point_args(extra);
        args.extend_from_slice(&["--part", &part, "-o", &names[k as usize], "--threads", "1"]);
        run(dir, &args);
    }
    let merged = format!("{tag}-merged.json");
    let mut args: Vec<&str> = names.iter().skip(1).map(String::as_str).collect();
    args.push(&names[0]);
    args.extend_from_slice(&["-o", &merged]);
    let o = merge(dir, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    let got = std::fs::read_to_string(dir.join(&merged)).unwrap();
    assert_eq!(
        got, want,
        "{tag}: merged JSON differs from the single run's"
    );
    assert_eq!(want.matches("\"ci95\"").count(), POINTS.len(), "{want}");
}

#[test]
fn merged_point_parts_equal_the_single_run() {
    let dir = temp_dir("meter-parts");
    assert_points_merge(
        &dir,
        "path",
        &["--spp", "600", "--integrator", "path", "--seed", "5"],
        3,
    );
    assert_points_merge(&dir, "one", &["--spp", "300", "--integrator", "path"], 1);
    // A relative-error target: each reading stops on its own statistics.
    assert_points_merge(
        &dir,
        "rel",
        &[
            "--rel-error",
            "0.05",
            "--max-spp",
            "8192",
            "--integrator",
            "bdpt",
        ],
        2,
    );
    assert_points_merge(&dir, "vcm", &["--spp", "256", "--integrator", "vcm"], 2);
}

#[test]
fn merged_grid_parts_equal_the_single_map() {
    let dir = temp_dir("meter-parts-grid");
    let grid = [
        "--grid",
        "-0.9,-0.999,-0.9",
        "--u",
        "1.8,0,0",
        "--v",
        "0,0,1.8",
        "--n",
        "4,4",
        "--normal",
        "0,1,0",
        "--spp",
        "512",
        "--integrator",
        "path",
    ];
    let mut single = grid.to_vec();
    single.extend_from_slice(&["-o", "single"]);
    run(&dir, &single);
    for k in 0..4 {
        let (part, name) = (format!("{k}/4"), format!("g{k}.json"));
        let mut args = grid.to_vec();
        args.extend_from_slice(&["--part", &part, "-o", &name]);
        run(&dir, &args);
    }
    let o = merge(
        &dir,
        &["g2.json", "g0.json", "g3.json", "g1.json", "-o", "merged"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    for ext in ["csv", "json", "png"] {
        let (a, b) = (
            std::fs::read(dir.join(format!("single.{ext}"))).unwrap(),
            std::fs::read(dir.join(format!("merged.{ext}"))).unwrap(),
        );
        assert!(a == b, "map.{ext} differs");
    }
    let csv = std::fs::read_to_string(dir.join("merged.csv")).unwrap();
    assert_eq!(csv.lines().count(), 17, "{csv}");
}

#[test]
fn merge_refuses_missing_duplicated_and_foreign_meter_parts() {
    let dir = temp_dir("meter-parts-refused");
    let base = ["--spp", "64", "--integrator", "path"];
    for k in 0..3 {
        let (part, name) = (format!("{k}/3"), format!("p{k}.json"));
        let mut args = point_args(&base);
        args.extend_from_slice(&["--part", &part, "-o", &name]);
        run(&dir, &args);
    }
    let mut args = point_args(&["--spp", "64", "--integrator", "path", "--seed", "9"]);
    args.extend_from_slice(&["--part", "2/3", "-o", "seed.json"]);
    run(&dir, &args);
    let refused = |args: &[&str], want: &[&str]| {
        let o = merge(&dir, args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
        assert_eq!(lines.len(), 1, "{err}");
        for w in want {
            assert!(lines[0].contains(w), "{} lacks {w}", lines[0]);
        }
        assert!(!dir.join("m.json").exists());
    };
    refused(
        &["p0.json", "p1.json", "-o", "m.json"],
        &["missing part 2/3"],
    );
    refused(
        &["p0.json", "p1.json", "p1.json", "p2.json", "-o", "m.json"],
        &["p1.json", "given twice"],
    );
    refused(
        &["p0.json", "p1.json", "seed.json", "-o", "m.json"],
        &["seed.json", "another study"],
    );
    std::fs::write(dir.join("bad.json"), "{\"format\": 1}").unwrap();
    refused(
        &["p0.json", "p1.json", "bad.json", "-o", "m.json"],
        &["bad.json", "not a meter part"],
    );
    // Parts that cannot be one: a time cap, auto, no -o.
    let stage = cbox_path().display().to_string();
    for (extra, want) in [
        (
            &[
                "--part",
                "0/2",
                "-o",
                "x.json",
                "--integrator",
                "path",
                "--time",
                "1",
            ][..],
            "--time",
        ),
        (&["--part", "0/2", "-o", "x.json"][..], "named --integrator"),
        (
            &["--part", "0/2", "--integrator", "path"][..],
            "-o PART.json",
        ),
    ] {
        let mut args = vec![
            "meter",
            stage.as_str(),
            "--at",
            "0,0,0",
            "--normal",
            "0,1,0",
        ];
        args.extend_from_slice(extra);
        let o = spectral_render(&args, &dir);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains(want), "{want}: {}", stderr(&o));
    }
}
