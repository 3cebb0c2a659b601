//! The command line as a user meets it: rendering writes a calibrated EXR (and a preview),
//! and bad input gives one clear line naming the file and the prim, a non-zero exit and
//! no panic.

mod common;
use common::*;
use std::path::Path;

/// A small lit scene: a grey plane under a dome, seen by a camera.
fn small_stage() -> String {
    let mut s = header();
    s += &camera(1.0, 0.5, 0.0);
    s += "def DomeLight \"Sky\"\n{\n    float inputs:intensity = 10\n}\n\n";
    s += &quad("Plane", 0.0, 1.0, "", "");
    s
}

#[test]
fn renders_an_exr_with_calibrated_channels_and_a_preview() {
    let dir = temp_dir("cli-render");
    write(&dir, "small.usda", &small_stage());
    let o = spectral_render(
        &[
            "small.usda",
            "--spp",
            "4",
            "--resolution",
            "8x6",
            "--preview",
            "p.png",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        !stderr(&o).contains('\u{1b}'),
        "progress bar drawn although stderr is not a terminal"
    );
    let img = spectral_render::output::exr::read(&dir.join("small.exr")).unwrap();
    assert_eq!((img.width, img.height), (8, 6));
    for ch in ["R", "G", "B", "XYZ.X", "XYZ.Y", "XYZ.Z"] {
        let values = &img.channels[ch];
        assert_eq!(values.len(), 48, "{ch}");
        assert!(values.iter().all(|v| v.is_finite() && *v > 0.0), "{ch}");
    }
    assert!(dir.join("p.png").exists());
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers.len(), 3, "unexpected files: {leftovers:?}");
}

#[test]
fn renders_the_peers_cornell_box() {
    let dir = temp_dir("cli-cbox");
    let cbox = cbox_path();
    let o = spectral_render(
        &[
            cbox.to_str().unwrap(),
            "-o",
            "c.exr",
            "--spp",
            "2",
            "--resolution",
            "16x16",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("loaded"),
        "no load summary: {}",
        stderr(&o)
    );
    assert!(dir.join("c.exr").exists());
}

/// Runs a bad stage and checks the error contract.
fn assert_clean_error(name: &str, text: Option<&str>, must_mention: &[&str]) {
    let dir = temp_dir("cli-bad");
    if let Some(t) = text {
        write(&dir, name, t);
    }
    let o = spectral_render(&[name, "--spp", "1"], &dir);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{name}: {err}");
    assert!(!err.contains("panicked"), "{name}: {err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{name}: expected one line, got {err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    for m in must_mention {
        assert!(lines[0].contains(m), "{name}: '{m}' not in {err}");
    }
    assert!(!dir.join(Path::new(name).with_extension("exr")).exists());
}

#[test]
fn missing_file() {
    assert_clean_error("nothing-here.usda", None, &["nothing-here.usda"]);
}

#[test]
fn malformed_usda() {
    assert_clean_error("broken.usda", Some(MALFORMED_USDA), &["broken.usda"]);
}

#[test]
fn mesh_with_out_of_range_indices() {
    let s = format!(
        "{}def Mesh \"Bad\"\n{{\n    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 7]\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n}}\n",
        header()
    );
    assert_clean_error("indices.usda", Some(&s), &["indices.usda", "/Bad"]);
}

#[test]
fn unknown_spectral_attribute() {
    let s = format!(
        "{}def RectLight \"Lamp\"\n{{\n    float spectral:brightness = 3\n}}\n",
        header()
    );
    assert_clean_error(
        "attr.usda",
        Some(&s),
        &["attr.usda", "/Lamp", "spectral:brightness"],
    );
}

#[test]
fn unknown_shader_id() {
    let s = format!(
        "{}def Scope \"Looks\"\n{{\n{}}}\n{}",
        header(),
        material("M", "spectral:velvet", ""),
        quad("Q", 0.0, 1.0, &binding("M"), "\"MaterialBindingAPI\"")
    );
    assert_clean_error(
        "shader.usda",
        Some(&s),
        &["shader.usda", "/Looks/M", "spectral:velvet"],
    );
}

#[test]
fn unknown_emission_spectrum() {
    let s = format!(
        "{}def SphereLight \"Bulb\"\n{{\n    token spectral:emission = \"CIE-Q7\"\n}}\n",
        header()
    );
    assert_clean_error("spd.usda", Some(&s), &["spd.usda", "/Bulb", "CIE-Q7"]);
}

#[test]
fn bad_options_are_rejected() {
    let dir = temp_dir("cli-opts");
    write(&dir, "small.usda", &small_stage());
    for args in [
        ["small.usda", "--spp", "0"],
        ["small.usda", "--resolution", "0x5"],
        ["small.usda", "--integrator", "magic"],
        ["small.usda", "--rr-depth", "0"],
        ["small.usda", "--rr-depth", "-2"],
        ["small.usda", "--rr-depth", "automatic"],
    ] {
        let o = spectral_render(&args, &dir);
        assert!(!o.status.success(), "{args:?} accepted");
        assert!(!stderr(&o).contains("panicked"));
    }
}

/// `--rr-depth` (the path tracer's first bounce of Russian roulette) is taken by render and by
/// info's pilot.
#[test]
fn rr_depth_is_an_option_of_render_and_info() {
    let dir = temp_dir("cli-rr");
    write(&dir, "small.usda", &small_stage());
    for args in [
        &[
            "small.usda",
            "--spp",
            "2",
            "--integrator",
            "path",
            "--rr-depth",
            "5",
        ][..],
        &["info", "small.usda", "--spp", "2", "--rr-depth", "5"][..],
    ] {
        let o = spectral_render(args, &dir);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    }
    // The EXR says where the path tracer's roulette started, and says nothing of it for an
    // integrator it does not apply to.
    use spectral_render::output::exr;
    let rr = |dir: &Path| exr::read(&dir.join("small.exr")).unwrap().attributes;
    assert_eq!(rr(&dir)[exr::RR_DEPTH_ATTRIBUTE], "5");
    let o = spectral_render(&["small.usda", "--spp", "2", "--integrator", "bdpt"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!rr(&dir).contains_key(exr::RR_DEPTH_ATTRIBUTE));
    // By default (`auto`) a pilot chooses the start and the split, says so, and the EXR names
    // its choice.
    for args in [
        &["small.usda", "--spp", "2"][..],
        &[
            "small.usda",
            "--spp",
            "2",
            "--rr-depth",
            "auto",
            "--split",
            "auto",
        ],
    ] {
        let o = spectral_render(args, &dir);
        assert!(o.status.success(), "{}", stderr(&o));
        let start: u32 = rr(&dir)[exr::RR_DEPTH_ATTRIBUTE].parse().unwrap();
        let split: u32 = rr(&dir)[exr::SPLIT_ATTRIBUTE].parse().unwrap();
        let paths = match split {
            1 => "paths not split".to_string(),
            n => format!("paths split in {n} at their first vertex"),
        };
        let said =
            format!("note: Russian roulette from bounce {start}, {paths} (chosen by a pilot");
        assert!(stderr(&o).contains(&said), "{}", stderr(&o));
    }
    // A given split is kept (the pilot still chooses the start) and named in the EXR; the
    // split must be a power of two up to 16.
    let o = spectral_render(&["small.usda", "--spp", "2", "--split", "4"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(rr(&dir)[exr::SPLIT_ATTRIBUTE], "4");
    assert!(
        stderr(&o).contains("note: Russian roulette from bounce "),
        "{}",
        stderr(&o)
    );
    assert!(!stderr(&o).contains("paths split"), "{}", stderr(&o));
    for bad in ["3", "0", "32", "two"] {
        let o = spectral_render(&["small.usda", "--spp", "2", "--split", bad], &dir);
        assert!(!o.status.success(), "--split {bad}");
        assert!(stderr(&o).contains("power of two"), "{}", stderr(&o));
    }
}
