//! Issue 15: crop windows (`--crop`, pixels or NDC) as parts of a render. Crops that tile the
//! image, alone or crossed with sample parts (`--part K/N`), merge into the single render bit
//! for bit for path, light, bdpt and vcm; a crop's EXR has the crop as its data window and
//! the full image as its display window; merge refuses overlapping and missing windows.

mod common;

use common::{cbox_path, spectral_render, stderr, temp_dir};
use spectral_render::output::exr;
use std::path::Path;

const RES: &str = "24x16";

fn render(dir: &Path, name: &str, extra: &[&str]) {
    let stage = cbox_path().display().to_string();
    let mut args = vec![stage.as_str(), "--resolution", RES, "-o", name];
    args.extend_from_slice(extra);
    let o = spectral_render(&args, dir);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
}

fn merge(dir: &Path, args: &[&str]) -> std::process::Output {
    let mut all = vec!["merge"];
    all.extend_from_slice(args);
    spectral_render(&all, dir)
}

fn channel_bits(path: &Path) -> Vec<(String, Vec<u32>)> {
    let img = exr::read(path).unwrap();
    img.channels
        .iter()
        .map(|(k, v)| (k.clone(), v.iter().map(|x| x.to_bits()).collect()))
        .collect()
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
    let (a, b) = (
        channel_bits(&dir.join(&single)),
        channel_bits(&dir.join(&merged)),
    );
    assert_eq!(a.len(), 6);
    assert_eq!(a.len(), b.len());
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        let differ = x.iter().zip(y).filter(|(p, q)| p != q).count();
        assert_eq!(
            differ, 0,
            "{integrator} × {n}: {name} differs in {differ} pixels"
        );
    }
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
    let refused = |args: &[&str], want: &[&str]| {
        let o = merge(&dir, args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
        assert_eq!(lines.len(), 1, "{err}");
        for w in want {
            assert!(lines[0].contains(w), "{} lacks {w}", lines[0]);
        }
    };
    refused(
        &["l.exr", "o.exr", "-o", "m.exr"],
        &["o.exr", "overlaps", "(11, 0)"],
    );
    refused(&["l.exr", "-o", "m.exr"], &["missing pixels", "(12, 0)"]);
    refused(
        &["l.exr", "r.exr", "l.exr", "-o", "m.exr"],
        &["l.exr", "given twice"],
    );
    assert!(!dir.join("m.exr").exists());
    let o = merge(&dir, &["r.exr", "l.exr", "-o", "m.exr"]);
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
