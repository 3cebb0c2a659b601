//! Real-world USD (issue 16): stages usd-core writes load (every value type animated, every
//! kind of metadata, text and crate files), `--frame` renders equal usd-core's static bake of
//! the same frame bit for bit, `--frames` writes a sequence, splines are refused by name.
//!
//! The stages come from `tools/usd_stages.py`, run with usd-core in the venv `tools/venv.sh`
//! makes.

mod common;
use common::*;
use spectral_render::scene::usd::every_value::read_every_value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `tools/usd_stages.py ARGS` in `dir` with the venv's usd-core.
fn usd_stages(dir: &Path, args: &[&str]) {
    colour_science_venv();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let o = Command::new(root.join(".venv/bin/python"))
        .arg(root.join("tools/usd_stages.py"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run usd_stages.py");
    assert!(
        o.status.success(),
        "usd_stages.py {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The RGB and XYZ channels of an EXR, as bits.
fn pixels(path: &Path) -> Vec<u32> {
    let img = spectral_render::output::exr::read(path).unwrap_or_else(|e| panic!("{e}"));
    let mut bits = Vec::new();
    for ch in ["R", "G", "B", "XYZ.X", "XYZ.Y", "XYZ.Z"] {
        bits.extend(img.channels[ch].iter().map(|v| v.to_bits()));
    }
    bits
}

/// Renders `stage` with `extra` options into `out` (in `dir`); panics on failure.
fn render(dir: &Path, stage: &str, out: &str, extra: &[&str]) -> String {
    let mut args = vec![stage, "-o", out, "--spp", "4", "--resolution", "24x24"];
    args.extend_from_slice(extra);
    let o = spectral_render(&args, dir);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    stderr(&o)
}

#[test]
fn every_value_type_usd_core_writes_is_read_in_text_and_crate_files() {
    let dir = temp_dir("usd-every-type");
    for name in ["every.usda", "every.usdc"] {
        usd_stages(&dir, &["every-type", name]);
        let path = dir.join(name);
        let count = read_every_value(&path, &[0.0, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0])
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        // 54 value types, scalar and array, 8 reads each, besides the other attributes.
        assert!(count > 54 * 2 * 8, "{name}: only {count} values read");
        let o = spectral_render(&["lights", name], &dir);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        assert!(stdout(&o).contains("/World/light"), "{}", stdout(&o));
    }
}

#[test]
fn splines_are_refused_with_the_attribute_named() {
    let dir = temp_dir("usd-spline");
    for name in ["spline.usda", "spline.usdc"] {
        usd_stages(&dir, &["spline", name]);
        let o = spectral_render(&["lights", name], &dir);
        assert_eq!(o.status.code(), Some(1), "{name}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.starts_with(&format!("error: {name}: /World/light: "))
                && e.contains("inputs:intensity")
                && e.contains("spline"),
            "{e}"
        );
    }
}

/// Frames of the light sweep, each changing other inputs: `--frame N` renders equal the
/// render of usd-core's bake of frame N, bit for bit, in text and crate files.
#[test]
fn frames_equal_usd_core_static_bakes_bit_for_bit() {
    let dir = temp_dir("usd-bake");
    usd_stages(&dir, &["sweep", "sweep.usda"]);
    usd_stages(&dir, &["sweep", "sweep.usdc"]);
    let e = render(&dir, "sweep.usda", "default.exr", &[]);
    assert!(
        e.contains("note: the stage is animated; read at its startTimeCode 1"),
        "{e}"
    );
    assert!(!e.contains("texture"), "an empty asset is no texture: {e}");
    for frame in ["1", "3", "4", "5", "6"] {
        let baked = format!("baked{frame}.usda");
        usd_stages(&dir, &["bake", "sweep.usda", frame, &baked]);
        let e = render(&dir, &baked, &format!("baked{frame}.exr"), &[]);
        // The roulette pilot's note (`--rr-depth auto`) is about the render, not the stage.
        let notes = e.lines().filter(|l| l.starts_with("note:"));
        assert_eq!(
            notes.filter(|l| !l.contains("Russian roulette")).count(),
            0,
            "a static stage has no note: {e}"
        );
        for source in ["sweep.usda", "sweep.usdc"] {
            let out = format!("{source}.{frame}.exr");
            render(&dir, source, &out, &["--frame", frame]);
            assert!(
                pixels(&dir.join(&out)) == pixels(&dir.join(format!("baked{frame}.exr"))),
                "{source} --frame {frame} differs from usd-core's bake"
            );
        }
    }
    assert!(pixels(&dir.join("default.exr")) == pixels(&dir.join("baked1.exr")));
    assert!(pixels(&dir.join("baked1.exr")) != pixels(&dir.join("baked6.exr")));
}

#[test]
fn a_sequence_of_three_frames_writes_three_files() {
    let dir = temp_dir("usd-sequence");
    usd_stages(&dir, &["sweep", "sweep.usda"]);
    let e = render(
        &dir,
        "sweep.usda",
        "seq.####.exr",
        &["--frames", "2..6:2", "--preview", "seq.%03d.png"],
    );
    let files: Vec<PathBuf> = ["seq.0002.exr", "seq.0004.exr", "seq.0006.exr"]
        .iter()
        .map(|f| dir.join(f))
        .collect();
    for f in &files {
        assert!(f.is_file(), "{} missing: {e}", f.display());
    }
    for p in ["seq.002.png", "seq.004.png", "seq.006.png"] {
        assert!(dir.join(p).is_file(), "{p} missing");
    }
    let count = std::fs::read_dir(&dir).unwrap().count();
    assert_eq!(count, 1 + 3 + 3, "only the stage and the sequence");
    // Each frame equals the single-frame render of its time code.
    render(&dir, "sweep.usda", "single4.exr", &["--frame", "4"]);
    assert!(pixels(&files[1]) == pixels(&dir.join("single4.exr")));
    assert!(pixels(&files[0]) != pixels(&files[2]));
    // A pattern is required, and --frame and --frames exclude each other.
    let o = spectral_render(&["sweep.usda", "--frames", "1..3", "-o", "x.exr"], &dir);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("placeholder"), "{}", stderr(&o));
    let o = spectral_render(&["sweep.usda", "--frames", "1..3", "--frame", "2"], &dir);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn meter_and_lights_take_a_frame() {
    let dir = temp_dir("usd-meter-frame");
    usd_stages(&dir, &["sweep", "sweep.usda"]);
    let lux = |frame: &str| {
        let o = spectral_render(&["lights", "sweep.usda", "--json", "--frame", frame], &dir);
        assert!(o.status.success(), "{}", stderr(&o));
        stdout(&o)
    };
    // Intensity 1 at frame 1, 2 at frame 2: the report follows the frame.
    assert_ne!(lux("1"), lux("2"));
    let meter = |frame: &str| {
        let o = spectral_render(
            &[
                "meter",
                "sweep.usda",
                "--at",
                "0,0.01,0",
                "--normal",
                "0,1,0",
                "--frame",
                frame,
                "--spp",
                "256",
                "--json",
            ],
            &dir,
        );
        assert!(o.status.success(), "{}", stderr(&o));
        stdout(&o)
    };
    assert_ne!(meter("1"), meter("2"));
}

/// A static ground (two meshes), a light moving between frames 1 and 3, a still light and a
/// camera rising: time range 1..3, 24 frames and 48 time codes per second.
const MOVING_LIGHT: &str = r#"#usda 1.0
(
    startTimeCode = 1
    endTimeCode = 3
    framesPerSecond = 24
    timeCodesPerSecond = 48
    metersPerUnit = 1
    upAxis = "Y"
)
def Xform "World" {
    def Mesh "ground" {
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        point3f[] points = [(-2, 0, 2), (2, 0, 2), (2, 0, -2), (-2, 0, -2)]
    }
    def Mesh "wall" {
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        point3f[] points = [(-2, 0, -1), (2, 0, -1), (2, 2, -1), (-2, 2, -1)]
    }
    def SphereLight "moving" {
        float inputs:radius = 0.1
        float inputs:intensity = 50
        double3 xformOp:translate.timeSamples = { 1: (-1, 1, 0), 3: (1, 1, 0) }
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
    def SphereLight "still" {
        float inputs:radius = 0.2
        float inputs:intensity = 5
        double3 xformOp:translate = (0, 1.5, 1)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
    def Camera "camera" {
        float focalLength = 20
        float horizontalAperture = 36
        float verticalAperture = 36
        double3 xformOp:translate.timeSamples = { 1: (0, 1, 4), 3: (0, 1.5, 4) }
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
}
"#;

/// `--frames` keeps the geometry of a stage whose meshes do not move and rebuilds only the
/// light that changed, saying so per frame; every frame equals its own `--frame` render bit
/// for bit and carries its time code and the stage's rates in the EXR.
#[test]
fn a_sequence_rebuilds_only_what_changed_and_equals_single_frames() {
    let dir = temp_dir("usd-rebuild");
    write(&dir, "moving.usda", MOVING_LIGHT);
    let e = render(&dir, "moving.usda", "seq.#.exr", &["--frames", "1..4"]);
    for line in [
        "frame 1: built",
        "frame 2: camera, 1 light changed; geometry reused",
        "frame 3: camera, 1 light changed; geometry reused",
        "frame 4: nothing changed; geometry and light table reused",
    ] {
        assert!(e.contains(line), "no '{line}' in: {e}");
    }
    for frame in ["1", "2", "3", "4"] {
        let single = format!("single{frame}.exr");
        render(&dir, "moving.usda", &single, &["--frame", frame]);
        let seq = dir.join(format!("seq.{frame}.exr"));
        assert!(
            pixels(&seq) == pixels(&dir.join(&single)),
            "frame {frame} of the sequence differs from its --frame render"
        );
        let attributes = spectral_render::output::exr::read(&seq).unwrap().attributes;
        assert_eq!(attributes["spectralRender:timeCode"], frame);
        assert_eq!(attributes["spectralRender:usdFramesPerSecond"], "24");
        assert_eq!(attributes["spectralRender:timeCodesPerSecond"], "48");
        assert_eq!(attributes["framesPerSecond"], "24/1");
    }
    assert!(pixels(&dir.join("single1.exr")) != pixels(&dir.join("single2.exr")));
    // Without --frame: the stage's startTimeCode.
    render(&dir, "moving.usda", "default.exr", &[]);
    let attributes = spectral_render::output::exr::read(&dir.join("default.exr"))
        .unwrap()
        .attributes;
    assert_eq!(attributes["spectralRender:timeCode"], "1");
}
