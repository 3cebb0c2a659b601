//! The `spectral-render meter` command line: JSON readings in stage units, the
//! `--integrator` flag, grid outputs (CSV, JSON, PNG) and their summary, one-line errors,
//! and readings stopped by a cap. The library-level meter checks are in `tests/meters.rs`.

mod common;
use common::meters::{lambert, TOL};
use common::*;
use glam::DVec3;

/// The raw JSON text of `"key":` in `entry` (a number, string, bool or flat array).
fn field<'a>(entry: &'a str, key: &str) -> &'a str {
    let pat = format!("\"{key}\":");
    let start = entry
        .find(&pat)
        .unwrap_or_else(|| panic!("no {key} in {entry}"))
        + pat.len();
    let rest = entry[start..].trim_start();
    let end = if rest.starts_with('[') {
        rest.find(']').unwrap() + 1
    } else {
        rest.find([',', '}']).unwrap()
    };
    rest[..end].trim()
}

fn number(entry: &str, key: &str) -> f64 {
    field(entry, key)
        .parse()
        .unwrap_or_else(|_| panic!("{key} is not a number in {entry}"))
}

fn numbers(entry: &str, key: &str) -> Vec<f64> {
    let a = field(entry, key);
    a[1..a.len() - 1]
        .split(',')
        .map(|x| x.trim().parse().unwrap())
        .collect()
}

/// A Z-up stage in centimetres: a normalized 100 × 50 cm RectLight of 1000 "nits" (so
/// L = 1000 / 0.5 m² = 2000 cd/m² in world units) 250 cm up, facing down (its local −Z).
fn cm_stage() -> String {
    stage_header(0.01, "Z")
        + &prim(
            "RectLight",
            "Panel",
            &(String::from("    float inputs:width = 100\n    float inputs:height = 50\n    float inputs:intensity = 1000\n    bool inputs:normalize = 1\n")
                + &xform(&[("translate", "(0, 0, 250)".into())])),
        )
}

/// Lambert's formula is scale-free, so the reference is computed in stage coordinates.
fn cm_stage_exact(at: DVec3, n: DVec3) -> f64 {
    let c = [(-50.0, -25.0), (50.0, -25.0), (50.0, 25.0), (-50.0, 25.0)]
        .map(|(x, y)| DVec3::new(x, y, 250.0));
    2000.0 * lambert(at, n, &c)
}

#[test]
fn cli_json_readings_in_stage_units() {
    let dir = temp_dir("cli-meter");
    write(&dir, "room.usda", &cm_stage());
    let o = spectral_render(
        &[
            "meter",
            "room.usda",
            "--at",
            "30,-40,0",
            "--normal",
            "0,0,1",
            "--at",
            "-20,10,120",
            "--normal",
            "0,-1,1",
            "--rel-error",
            "0.002",
            "--seed",
            "3",
            "--json",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("loaded"), "no load summary");
    let out = stdout(&o);
    assert!(
        out.trim_start().starts_with("{\"meters\":[") && out.trim_end().ends_with("]}"),
        "{out}"
    );
    let entries: Vec<&str> = out.split("{\"kind\"").skip(1).collect();
    assert_eq!(entries.len(), 2, "{out}");
    for (entry, (at, n)) in entries.iter().zip([
        (DVec3::new(30.0, -40.0, 0.0), DVec3::new(0.0, 0.0, 1.0)),
        (DVec3::new(-20.0, 10.0, 120.0), DVec3::new(0.0, -1.0, 1.0)),
    ]) {
        assert!(entry.starts_with(":\"illuminance\","), "{entry}");
        let keys = [
            "\"at\"",
            "\"normal\"",
            "\"value\"",
            "\"unit\"",
            "\"ci95\"",
            "\"samples\"",
        ];
        let pos: Vec<usize> = keys.iter().map(|k| entry.find(k).unwrap()).collect();
        assert!(pos.windows(2).all(|w| w[0] < w[1]), "key order in {entry}");
        assert_eq!(numbers(entry, "at"), [at.x, at.y, at.z]);
        assert_eq!(numbers(entry, "normal"), [n.x, n.y, n.z]);
        assert_eq!(field(entry, "unit"), "\"lx\"");
        assert_eq!(field(entry, "converged"), "true");
        let (value, ci95) = (number(entry, "value"), number(entry, "ci95"));
        assert!(number(entry, "samples") >= 1024.0 && ci95 > 0.0 && ci95 / value < 0.002);
        let exact = cm_stage_exact(at, n.normalize());
        eprintln!("CLI, Z-up cm stage at {at}: {value} vs {exact} (ci95 {ci95})");
        assert!((value / exact - 1.0).abs() < TOL, "{value} vs {exact}");
    }
    // A luminance meter looking up at the panel reads its luminance; one looking down, 0.
    let o = spectral_render(
        &[
            "meter",
            "room.usda",
            "--luminance",
            "--at",
            "0,0,100",
            "--dir",
            "0,0,1",
            "--at",
            "0,0,100",
            "--dir",
            "0,0,-1",
            "--spp",
            "4096",
            "--json",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let entries: Vec<&str> = out.split("{\"kind\"").skip(1).collect();
    assert_eq!(entries.len(), 2, "{out}");
    for e in &entries {
        assert!(e.starts_with(":\"luminance\","), "{e}");
        assert_eq!(field(e, "unit"), "\"cd/m2\"");
        assert_eq!(number(e, "samples"), 4096.0);
    }
    assert_eq!(numbers(entries[0], "dir"), [0.0, 0.0, 1.0]);
    let (l, ci) = (number(entries[0], "value"), number(entries[0], "ci95"));
    assert!(
        (l - 2000.0).abs() < 4.0 * ci / 1.96 + 1e-9 && ci / l < 0.002,
        "{l} ± {ci}"
    );
    assert_eq!(
        (number(entries[1], "value"), number(entries[1], "ci95")),
        (0.0, 0.0)
    );
}

/// `--integrator light|bdpt` (and `--mis`) give the same JSON, with readings within the
/// analytic tolerance; a luminance meter asked of light tracing is refused in one line that
/// says why and what to use instead, before the stage is even loaded.
#[test]
fn cli_integrator_flag_selects_light_tracing_or_bdpt() {
    let dir = temp_dir("cli-meter-integrator");
    write(&dir, "room.usda", &cm_stage());
    let (at, n) = (DVec3::new(30.0, -40.0, 0.0), DVec3::Z);
    let exact = cm_stage_exact(at, n);
    for extra in [
        &["--integrator", "light"][..],
        &["--integrator", "bdpt", "--mis", "balance"][..],
        &["--integrator", "bdpt"][..],
    ] {
        let base = [
            "meter",
            "room.usda",
            "--at",
            "30,-40,0",
            "--normal",
            "0,0,1",
            "--rel-error",
            "0.002",
            "--seed",
            "4",
            "--json",
        ];
        let o = spectral_render(&[&base[..], extra].concat(), &dir);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        let out = stdout(&o);
        assert!(out.trim_start().starts_with("{\"meters\":[") && out.trim_end().ends_with("]}"));
        assert_eq!(field(&out, "kind"), "\"illuminance\"");
        assert_eq!(numbers(&out, "at"), [at.x, at.y, at.z]);
        assert_eq!(field(&out, "unit"), "\"lx\"");
        assert_eq!(field(&out, "converged"), "true");
        let (value, ci95) = (number(&out, "value"), number(&out, "ci95"));
        eprintln!("CLI {extra:?}: {value} ± {ci95} vs {exact}");
        assert!(ci95 / value < 0.002 && (value / exact - 1.0).abs() < TOL);
    }
    let lum = [
        "meter",
        "room.usda",
        "--luminance",
        "--at",
        "0,0,100",
        "--dir",
        "0,0,1",
        "--spp",
        "2048",
        "--json",
    ];
    let o = spectral_render(&[&lum[..], &["--integrator", "bdpt"]].concat(), &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let (l, ci) = (number(&stdout(&o), "value"), number(&stdout(&o), "ci95"));
    assert!((l - 2000.0).abs() < 4.0 * ci / 1.96 + 1e-9, "{l} ± {ci}");
    let o = spectral_render(&[&lum[..], &["--integrator", "light"]].concat(), &dir);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    for must in [
        "error: ",
        "luminance",
        "delta sensor",
        "light tracing",
        "path",
        "bdpt",
    ] {
        assert!(err.contains(must), "{must:?} missing: {err}");
    }
    assert!(
        !err.contains("loaded"),
        "refused after loading the stage: {err}"
    );
    assert!(stdout(&o).is_empty());
}

#[test]
fn cli_grid_writes_csv_json_and_png_with_a_consistent_summary() {
    let dir = temp_dir("cli-grid");
    write(&dir, "room.usda", &cm_stage());
    std::fs::create_dir_all(dir.join("out")).unwrap();
    let o = spectral_render(
        &[
            "meter",
            "room.usda",
            "--grid",
            "-150,-100,0",
            "--u",
            "300,0,0",
            "--v",
            "0,200,0",
            "--n",
            "12,8",
            "--normal",
            "0,0,1",
            "-o",
            "out/floor",
            "--spp",
            "256",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let console = stdout(&o);
    for k in ["E_min", "E_avg", "E_max", "U0"] {
        assert!(console.contains(k), "{k} missing from {console}");
    }
    let csv = std::fs::read_to_string(dir.join("out/floor.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("i,j,x,y,z,lux,ci95"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 96);
    assert_eq!(rows[0][..5], [0.0, 0.0, -137.5, -87.5, 0.0]);
    assert_eq!(rows[95][..5], [11.0, 7.0, 137.5, 87.5, 0.0]);
    let lux: Vec<f64> = rows.iter().map(|r| r[5]).collect();
    let (min, max) = lux
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    let avg = lux.iter().sum::<f64>() / lux.len() as f64;
    // Every cell is near its exact value (here a loose 5σ check of the whole map).
    for r in &rows {
        let exact = cm_stage_exact(DVec3::new(r[2], r[3], r[4]), DVec3::Z);
        assert!(
            (r[5] - exact).abs() < 5.0 * r[6] / 1.96,
            "cell {r:?} vs {exact}"
        );
    }
    let json = std::fs::read_to_string(dir.join("out/floor.json")).unwrap();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
    assert!(close(number(&json, "E_min"), min) && close(number(&json, "E_max"), max));
    assert!(close(number(&json, "E_avg"), avg) && close(number(&json, "U0"), min / avg));
    let doc: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(doc["summary"]["E_min"], doc["E_min"], "{json}");
    assert_eq!(doc["summary"]["U0"], doc["U0"], "{json}");
    assert_eq!(doc["cells"].as_array().map(Vec::len), Some(96));
    assert_eq!(json.matches("\"ci95\"").count(), 96);
    let png = std::fs::read(dir.join("out/floor.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let leftovers: Vec<_> = std::fs::read_dir(dir.join("out"))
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers.len(), 3, "{leftovers:?}");
}

#[test]
fn cli_errors_are_one_line_with_exit_code_1() {
    let dir = temp_dir("cli-meter-errors");
    write(&dir, "room.usda", &cm_stage());
    write(&dir, "broken.usda", MALFORMED_USDA);
    let cases: &[(&[&str], &str)] = &[
        (
            &[
                "room.usda",
                "--at",
                "1,2,3",
                "--at",
                "0,0,0",
                "--normal",
                "0,0,1",
            ],
            "--normal",
        ),
        (
            &["room.usda", "--at", "1,2,3", "--normal", "0,0,0"],
            "zero length",
        ),
        (&["room.usda", "--at", "1,2", "--normal", "0,0,1"], "--at"),
        (
            &["room.usda", "--at", "nan,0,0", "--normal", "0,0,1"],
            "--at",
        ),
        (
            &[
                "room.usda",
                "--at",
                "0,0,0",
                "--normal",
                "0,0,1",
                "--spp",
                "8",
                "--rel-error",
                "0.01",
            ],
            "--rel-error",
        ),
        (
            &[
                "room.usda",
                "--at",
                "0,0,0",
                "--normal",
                "0,0,1",
                "--rel-error",
                "-1",
            ],
            "--rel-error",
        ),
        (
            &[
                "room.usda",
                "--at",
                "0,0,0",
                "--normal",
                "0,0,1",
                "--spp",
                "1",
            ],
            "--spp",
        ),
        (&["room.usda"], "nothing to measure"),
        (
            &[
                "room.usda",
                "--luminance",
                "--at",
                "0,0,0",
                "--normal",
                "0,0,1",
            ],
            "--dir",
        ),
        (
            &[
                "room.usda",
                "--grid",
                "0,0,0",
                "--u",
                "1,0,0",
                "--v",
                "2,0,0",
                "--n",
                "4,4",
                "--normal",
                "0,0,1",
            ],
            "--v",
        ),
        (
            &[
                "room.usda",
                "--grid",
                "0,0,0",
                "--u",
                "1,0,0",
                "--v",
                "0,1,0",
                "--n",
                "0,4",
                "--normal",
                "0,0,1",
            ],
            "--n",
        ),
        (
            &[
                "room.usda",
                "--grid",
                "0,0,0",
                "--u",
                "1,0,0",
                "--n",
                "4,4",
                "--normal",
                "0,0,1",
            ],
            "--v",
        ),
        (
            &[
                "room.usda",
                "--at",
                "0,0,0",
                "--normal",
                "0,0,1",
                "--integrator",
                "vcn",
            ],
            "unknown integrator",
        ),
        (
            &[
                "room.usda",
                "--at",
                "0,0,0",
                "--normal",
                "0,0,1",
                "--mis",
                "cutoff",
            ],
            "unknown MIS heuristic",
        ),
        (
            &[
                "room.usda",
                "--luminance",
                "--at",
                "0,0,0",
                "--dir",
                "0,0,1",
                "--integrator",
                "light",
            ],
            "delta sensor",
        ),
        (
            &["missing.usda", "--at", "0,0,0", "--normal", "0,0,1"],
            "missing.usda",
        ),
        (
            &["broken.usda", "--at", "0,0,0", "--normal", "0,0,1"],
            "broken.usda",
        ),
    ];
    for (args, must) in cases {
        let mut all = vec!["meter"];
        all.extend_from_slice(args);
        let o = spectral_render(&all, &dir);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        let lines: Vec<&str> = err.lines().filter(|l| !l.starts_with("loaded ")).collect();
        assert_eq!(lines.len(), 1, "{args:?}: {err}");
        assert!(
            lines[0].starts_with("error: ") && lines[0].contains(must),
            "{args:?}: {err}"
        );
        assert!(stdout(&o).is_empty(), "{args:?}");
    }
}

#[test]
fn cli_reports_readings_stopped_by_a_cap() {
    let dir = temp_dir("cli-caps");
    write(&dir, "room.usda", &cm_stage());
    let base = [
        "meter",
        "room.usda",
        "--at",
        "30,-40,0",
        "--normal",
        "0,0,1",
        "--json",
        "--rel-error",
        "1e-7",
    ];
    for (extra, warning) in [
        (["--max-spp", "2048"], "sample cap"),
        (["--time", "0.3"], "time cap"),
    ] {
        let t = std::time::Instant::now();
        let o = spectral_render(&[&base[..], &extra[..]].concat(), &dir);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            t.elapsed().as_secs_f64() < 20.0,
            "the cap did not stop sampling"
        );
        assert!(stderr(&o).contains(warning), "{}", stderr(&o));
        let out = stdout(&o);
        assert_eq!(field(&out, "converged"), "false", "{out}");
        if warning == "sample cap" {
            assert_eq!(number(&out, "samples"), 2048.0);
        }
    }
}
