//! Issue 15: partial renders (`--part K/N`) merged by `spectral-render merge` equal the single
//! render bit for bit, for every integrator, with N not dividing spp and N = 1; merge refuses
//! parts that are missing, given twice or of another render with one line naming the part.
//! Crop windows (`--crop`, pixels or NDC) that tile the image, alone or crossed with sample
//! parts, merge into the single render bit for bit for path, light, bdpt and vcm; a crop's EXR
//! has the crop as its data window and the full image as its display window; merge refuses
//! overlapping and missing windows. A stage's RenderSettings `dataWindowNDC` is rendered as a
//! window (not a part), its sample parts merge into it, and `--crop` replaces it.

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

/// Asserts that the EXRs `a` and `b` in `dir` have the six channels, equal bit for bit;
/// returns `a`'s.
fn assert_same_channels(dir: &Path, a: &str, b: &str, what: &str) -> Vec<(String, Vec<u32>)> {
    let (x, y) = (channel_bits(&dir.join(a)), channel_bits(&dir.join(b)));
    assert_eq!((x.len(), y.len()), (6, 6), "{what}");
    for ((name, p), (_, q)) in x.iter().zip(&y) {
        let differ = p.iter().zip(q).filter(|(u, v)| u != v).count();
        assert_eq!(differ, 0, "{what}: {name} differs in {differ} pixels");
    }
    x
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
    let a = assert_same_channels(dir, &single, &merged, &format!("{integrator} {n} parts"));
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
        exr::SAMPLER_ATTRIBUTE,
        exr::SEED_ATTRIBUTE,
        exr::MAX_DEPTH_ATTRIBUTE,
        exr::RR_DEPTH_ATTRIBUTE,
        exr::SCENE_ATTRIBUTE,
        "worldToNDC",
        "whiteLuminance",
    ] {
        assert_eq!(s.attributes.get(key), m.attributes.get(key), "{key}");
    }
    // The merge names the sampler from the parts' identity, as the single render does.
    let sampler = if integrator == "light" {
        "independent"
    } else {
        "zsobol"
    };
    assert_eq!(m.attributes[exr::SAMPLER_ATTRIBUTE], sampler);
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

/// Three windows that tile 24×16, one given in NDC (⌈24·0.4⌉ = 10, ⌈16·0.4375⌉ = 7).
const CROPS: [&str; 3] = ["0,0,10,16", "0.4,0,1.0,0.4375", "10,7,24,16"];

/// Renders `integrator` whole and as `CROPS` × `n` sample parts, merges them, compares.
fn assert_crops_merge_to_single(dir: &Path, integrator: &str, n: u32) {
    let common = ["--spp", "5", "--integrator", integrator, "--seed", "7"];
    let single = format!("single-{integrator}.exr");
    render(dir, &single, &common);
    let mut names = Vec::new();
    for (c, crop) in CROPS.iter().enumerate() {
        for k in 0..n {
            let name = format!("{integrator}-c{c}-p{k}of{n}.exr");
            let part = format!("{k}/{n}");
            let mut args = common.to_vec();
            args.extend_from_slice(&["--crop", crop, "--threads", "1"]);
            if n > 1 {
                args.extend_from_slice(&["--part", &part]);
            }
            render(dir, &name, &args);
            names.push(name);
        }
    }
    names.reverse();
    let merged = format!("merged-{integrator}-{n}.exr");
    let mut args: Vec<&str> = names.iter().map(String::as_str).collect();
    args.extend_from_slice(&["-o", &merged]);
    let o = merge(dir, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_same_channels(dir, &single, &merged, &format!("{integrator} crops × {n}"));
    let (s, m) = (
        exr::read(&dir.join(&single)).unwrap(),
        exr::read(&dir.join(&merged)).unwrap(),
    );
    assert_eq!(
        s.attributes.get(exr::SPP_ATTRIBUTE),
        m.attributes.get(exr::SPP_ATTRIBUTE)
    );
}

#[test]
fn crops_merge_into_the_single_render_for_every_integrator() {
    let dir = temp_dir("crops");
    for integrator in ["path", "light", "bdpt", "vcm"] {
        assert_crops_merge_to_single(&dir, integrator, 1);
    }
    // Crops × sample parts, 2 not dividing 5.
    assert_crops_merge_to_single(&dir, "bdpt", 2);
}

#[test]
fn a_crop_writes_its_window_as_the_data_window() {
    let dir = temp_dir("crops-window");
    let base = ["--spp", "4", "--integrator", "path"];
    render(&dir, "whole.exr", &base);
    let mut args = base.to_vec();
    args.extend_from_slice(&["--crop", "3,2,13,9", "--preview", "crop.png"]);
    render(&dir, "crop.exr", &args);
    let (whole, crop) = (
        exr::read(&dir.join("whole.exr")).unwrap(),
        exr::read(&dir.join("crop.exr")).unwrap(),
    );
    assert_eq!((crop.width, crop.height), (10, 7));
    let windows = format!("{:?}", crop.attributes);
    assert!(
        windows.contains("dataWindow") && windows.contains("displayWindow"),
        "{windows}"
    );
    assert_ne!(
        crop.attributes.get("dataWindow"),
        whole.attributes.get("dataWindow")
    );
    assert_eq!(
        crop.attributes.get("displayWindow"),
        whole.attributes.get("displayWindow")
    );
    // Its pixels are the single render's there (a path tracer's pixel is its own samples).
    let y = |img: &exr::ExrImage| img.channels["XYZ.Y"].clone();
    let (w, c) = (y(&whole), y(&crop));
    for row in 0..7 {
        for col in 0..10 {
            let v = w[(row + 2) * 24 + col + 3];
            assert_eq!(c[row * 10 + col].to_bits(), v.to_bits(), "({col}, {row})");
        }
    }
    assert!(dir.join("crop.part").is_file() && dir.join("crop.png").is_file());
}

#[test]
fn merge_refuses_overlapping_and_missing_windows() {
    let dir = temp_dir("crops-refused");
    let base = ["--spp", "2", "--integrator", "path"];
    for (name, crop) in [("l", "0,0,12,16"), ("r", "12,0,24,16"), ("o", "11,0,24,16")] {
        let mut args = base.to_vec();
        args.extend_from_slice(&["--crop", crop]);
        render(&dir, &format!("{name}.exr"), &args);
    }
    assert_refused(
        &dir,
        &["l.exr", "o.exr", "-o", "out.exr"],
        &["o.exr", "overlaps", "(11, 0)"],
    );
    assert_refused(
        &dir,
        &["l.exr", "-o", "out.exr"],
        &["missing pixels", "(12, 0)"],
    );
    assert_refused(
        &dir,
        &["l.exr", "r.exr", "l.exr", "-o", "out.exr"],
        &["l.exr", "given twice"],
    );
    let o = merge(&dir, &["r.exr", "l.exr", "-o", "out.exr"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let stage = cbox_path().display().to_string();
    for (crop, want) in [
        ("0,0,25,16", "not within"),
        ("0,0,0.5", "x0,y0,x1,y1"),
        ("3,3,3,9", "empty"),
    ] {
        let args = [
            stage.as_str(),
            "--resolution",
            RES,
            "-o",
            "x.exr",
            "--spp",
            "1",
            "--integrator",
            "path",
            "--crop",
            crop,
        ];
        let o = spectral_render(&args, &dir);
        assert_eq!(o.status.code(), Some(1), "{crop}: {}", stderr(&o));
        assert!(stderr(&o).contains(want), "{crop}: {}", stderr(&o));
    }
}

/// The Cornell box with a RenderSettings `dataWindowNDC` (y up): on 24×16, NDC y down
/// (0.25, 0.125, 0.75, 0.75), pixels ⌈24·0.25⌉.. ⌈24·0.75⌉ × ⌈16·0.125⌉.. ⌈16·0.75⌉ =
/// 6..18 × 2..12.
fn windowed_stage(dir: &Path) -> String {
    let text = std::fs::read_to_string(cbox_path()).unwrap();
    let settings = "\ndef RenderSettings \"Settings\" {\n    \
                    float4 dataWindowNDC = (0.25, 0.25, 0.75, 0.875)\n}\n";
    let path = dir.join("windowed.usda");
    std::fs::write(&path, format!("{text}{settings}")).unwrap();
    path.display().to_string()
}

/// Renders `stage` with `extra` into `dir/name`; its stderr.
fn render_stage(dir: &Path, stage: &str, name: &str, extra: &[&str]) -> String {
    let mut args = vec![stage, "--resolution", RES, "-o", name];
    args.extend_from_slice(extra);
    let o = spectral_render(&args, dir);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    stderr(&o)
}

#[test]
fn a_stage_data_window_is_rendered_as_a_window_and_its_parts_merge() {
    let dir = temp_dir("data-window");
    let stage = windowed_stage(&dir);
    let base = ["--spp", "4", "--integrator", "path", "--seed", "2"];
    render(&dir, "whole.exr", &base);
    let said = render_stage(&dir, &stage, "window.exr", &base);
    assert!(said.contains("data window 6,2,18,12"), "{said}");
    let (whole, window) = (
        exr::read(&dir.join("whole.exr")).unwrap(),
        exr::read(&dir.join("window.exr")).unwrap(),
    );
    assert_eq!((window.width, window.height), (12, 10));
    assert_eq!(
        window.attributes.get("displayWindow"),
        whole.attributes.get("displayWindow")
    );
    let (w, c) = (&whole.channels["XYZ.Y"], &window.channels["XYZ.Y"]);
    for row in 0..10 {
        for col in 0..12 {
            let v = w[(row + 2) * 24 + col + 6];
            assert_eq!(c[row * 12 + col].to_bits(), v.to_bits(), "({col}, {row})");
        }
    }
    // Not a part: no sidecar, and the default integrator (auto, its pilot in the window)
    // and extra layers go with it.
    assert!(!dir.join("window.part").exists());
    render_stage(
        &dir,
        &stage,
        "auto.exr",
        &["--spp", "4", "--spectral-bins", "4"],
    );
    let auto = exr::read(&dir.join("auto.exr")).unwrap();
    assert_eq!((auto.width, auto.height), (12, 10));
    assert_eq!(
        auto.channels
            .keys()
            .filter(|k| k.starts_with("S0."))
            .count(),
        4
    );
    // Sample parts of the windowed render merge into it bit for bit.
    let bdpt = ["--spp", "5", "--integrator", "bdpt", "--seed", "4"];
    render_stage(&dir, &stage, "single.exr", &bdpt);
    for k in 0..2 {
        let part = format!("{k}/2");
        let mut args = bdpt.to_vec();
        args.extend_from_slice(&["--part", &part]);
        render_stage(&dir, &stage, &format!("p{k}.exr"), &args);
    }
    let o = merge(&dir, &["p1.exr", "p0.exr", "-o", "merged.exr"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_same_channels(&dir, "single.exr", "merged.exr", "windowed bdpt, 2 parts");
    // A --crop replaces the stage's window, said on the console; a crop outside the window
    // does not merge into the windowed render.
    let mut args = base.to_vec();
    args.extend_from_slice(&["--crop", "0,0,6,16"]);
    let said = render_stage(&dir, &stage, "left.exr", &args);
    assert!(
        said.contains("--crop replaces the data window 6,2,18,12"),
        "{said}"
    );
    assert_refused(
        &dir,
        &["left.exr", "-o", "out.exr"],
        &["left.exr", "outside the render's window 6,2,18,12"],
    );
}
