//! The hostile inputs of issue 13, one regression test each, through the command line: each
//! ends in exit 1 with one line `error: FILE: PRIM: reason` (or in a named warning), quickly
//! and in little memory, where it once panicked, aborted, overflowed the stack, hung, read
//! forever or rendered NaN. (The reader's own cases are in `src/scene/usd/tests/robust.rs`.)

mod common;

use common::{spectral_render, stderr, temp_dir, write};
use std::path::Path;
use std::time::Instant;

const HEADER: &str = "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n";

const FLOOR: &str = "def Mesh \"Floor\" {
    point3f[] points = [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)]
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 3, 2, 1]
}
";

const BULB: &str = "def SphereLight \"Bulb\" {
    float inputs:intensity = 1000
    float inputs:radius = 0.05
    double3 xformOp:translate = (0, 1, 0)
    uniform token[] xformOpOrder = [\"xformOp:translate\"]
}
";

const CAMERA: &str = "def Camera \"Cam\" {
    double3 xformOp:translate = (0, 0.5, 3)
    uniform token[] xformOpOrder = [\"xformOp:translate\"]
}
";

/// Runs `spectral-render STAGE --resolution 8x8 --spp 1` under a 1.5 GB address-space limit
/// on `text` written as `name` in `dir`: (exit code, stderr).
fn render_in(dir: &Path, name: &str, text: &str) -> (Option<i32>, String) {
    let stage = write(dir, name, text);
    let exe = env!("CARGO_BIN_EXE_spectral-render");
    let out = std::process::Command::new("bash")
        .arg("-c")
        .arg("ulimit -v 1500000; exec \"$@\"")
        .arg("bash")
        .arg(exe)
        .arg(&stage)
        .args(["--resolution", "8x8", "--spp", "1", "-o"])
        .arg(dir.join("out.exr"))
        .current_dir(dir)
        .output()
        .unwrap();
    (out.status.code(), stderr(&out))
}

/// The stage `body` (after the header) must be refused within a second with one error line
/// naming the file and containing every one of `parts`.
fn refused(name: &str, body: &str, parts: &[&str]) {
    let dir = temp_dir(name);
    refused_in(&dir, name, body, parts);
}

fn refused_in(dir: &Path, name: &str, body: &str, parts: &[&str]) {
    let start = Instant::now();
    let (code, err) = render_in(dir, &format!("{name}.usda"), &format!("{HEADER}{body}"));
    let seconds = start.elapsed().as_secs_f64();
    assert_eq!(code, Some(1), "{name}: {err}");
    assert_eq!(err.lines().count(), 1, "{name}: {err}");
    assert!(
        err.starts_with(&format!("error: {}", dir.join(name).display())),
        "{name}: {err}"
    );
    for part in parts {
        assert!(err.contains(part), "{name}: no {part:?} in {err}");
    }
    assert!(seconds < 1.0, "{name}: took {seconds:.2} s");
}

/// The stage renders (exit 0, finite) and its summary names every one of `parts`.
fn warned(name: &str, body: &str, parts: &[&str]) {
    let dir = temp_dir(name);
    let (code, err) = render_in(&dir, &format!("{name}.usda"), &format!("{HEADER}{body}"));
    assert_eq!(code, Some(0), "{name}: {err}");
    assert!(!err.contains("non-finite"), "{name}: {err}");
    for part in parts {
        assert!(err.contains(part), "{name}: no {part:?} in {err}");
    }
}

#[test]
fn far_points_and_huge_units_are_refused_before_the_bvh() {
    let far = FLOOR.replace("(1, 0, 1)", "(1e19, 0, -1e19)");
    refused(
        "far",
        &format!("{far}{BULB}{CAMERA}"),
        &["/Floor", "point 2", "beyond ±1e9 m"],
    );
    let header = HEADER.replace("metersPerUnit = 1", "metersPerUnit = 1e19");
    let dir = temp_dir("mpu");
    let (code, err) = render_in(&dir, "mpu.usda", &format!("{header}{FLOOR}{BULB}{CAMERA}"));
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("/Floor") && err.contains("beyond ±1e9 m"),
        "{err}"
    );
}

#[test]
fn composition_that_recursed_is_refused() {
    let cycle = "def Xform \"A\" ( inherits = </B> ) {}\nclass \"B\" ( inherits = </C> ) {}\nclass \"C\" ( inherits = </B> ) {}\n";
    refused("cycle", &format!("{cycle}{BULB}"), &["cycle through </B>"]);
    for n in [2_000, 10_000] {
        let nested = format!(
            "{}{BULB}{}",
            (0..n)
                .map(|i| format!("def Xform \"P{i}\" {{\n"))
                .collect::<String>(),
            "}\n".repeat(n)
        );
        refused(
            &format!("nested{n}"),
            &nested,
            &["nested more than 320 levels"],
        );
    }
}

#[test]
fn corrupt_crate_files_are_refused() {
    let good = std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/usdc/cornell-box.usdc"),
    )
    .unwrap();
    let dir = temp_dir("usdc");
    // The TOKENS section's uncompressed size (a 9e17-byte allocation), and a truncation.
    let mut huge = good.clone();
    let toc = u64::from_le_bytes(good[16..24].try_into().unwrap()) as usize;
    let tokens = u64::from_le_bytes(good[toc + 24..toc + 32].try_into().unwrap()) as usize;
    huge[tokens + 8..tokens + 16].copy_from_slice(&(9u64 << 56).to_le_bytes());
    for (name, bytes) in [
        ("huge.usdc", huge),
        ("short.usdc", good[..good.len() / 2].to_vec()),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = spectral_render(&[path.to_str().unwrap(), "--resolution", "8x8"], &dir);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.starts_with(&format!("error: {}", path.display())),
            "{err}"
        );
    }
}

#[test]
fn ies_paths_must_be_regular_files() {
    let lamp = "def SphereLight \"Lamp\" (prepend apiSchemas = [\"ShapingAPI\"]) {\n    float inputs:radius = 0.05\n    asset inputs:shaping:ies:file = @/dev/zero@\n}\n";
    refused(
        "devzero",
        &format!("{FLOOR}{lamp}{CAMERA}"),
        &["/Lamp", "/dev/zero", "not a regular file"],
    );
}

#[test]
fn images_are_sized_from_their_header() {
    let dir = temp_dir("bigpng");
    // A 200 kB PNG declaring 8192 × 8192 RGBA pixels (268 MB of samples, 1 GB as texels).
    write_png_header(&dir.join("big.png"), 8192, 8192, 200_000);
    // A 2 kB one declaring 4096 × 4096: more than its bytes can hold.
    write_png_header(&dir.join("dense.png"), 4096, 4096, 2_000);
    for (png, reason) in [
        ("big.png", "the image is 8192×8192 pixels; at most 33554432"),
        ("dense.png", "truncated or corrupt"),
    ] {
        let body = format!("{}{CAMERA}", textured_floor(png));
        refused_in(&dir, &format!("stage-{png}"), &body, &[png, reason]);
    }
    let dome = "def DomeLight \"Sky\" {\n    asset inputs:texture:file = @big.png@\n}\n";
    refused_in(
        &dir,
        "dome",
        &format!("{FLOOR}{dome}{CAMERA}"),
        &["/Sky", "big.png", "8192×8192"],
    );
}

/// A PNG with a valid IHDR (8-bit RGBA, `width` × `height`) and `len` bytes of IDAT filler.
fn write_png_header(path: &Path, width: u32, height: u32, len: usize) {
    fn chunk(out: &mut Vec<u8>, kind: &[u8], data: &[u8]) {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let start = out.len();
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
        let crc = crc32(&out[start..]);
        out.extend_from_slice(&crc.to_be_bytes());
    }
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
    chunk(&mut png, b"IHDR", &ihdr);
    chunk(&mut png, b"IDAT", &vec![0x5a; len]);
    chunk(&mut png, b"IEND", &[]);
    std::fs::write(path, png).unwrap();
}

/// CRC-32 (ISO-HDLC, as PNG chunks use).
fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &byte in data {
        crc ^= u32::from(byte);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// The floor with a UsdPreviewSurface whose diffuse colour reads `file`, and the bulb.
fn textured_floor(file: &str) -> String {
    format!(
        "def Mesh \"Floor\" (prepend apiSchemas = [\"MaterialBindingAPI\"]) {{
    point3f[] points = [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)]
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 3, 2, 1]
    rel material:binding = </M>
}}
def Material \"M\" {{
    token outputs:surface.connect = </M/S.outputs:surface>
    def Shader \"S\" {{
        uniform token info:id = \"UsdPreviewSurface\"
        color3f inputs:diffuseColor.connect = </M/T.outputs:rgb>
        token outputs:surface
    }}
    def Shader \"T\" {{
        uniform token info:id = \"UsdUVTexture\"
        asset inputs:file = @{file}@
        float3 outputs:rgb
    }}
}}
{BULB}"
    )
}

#[test]
fn emission_that_overflows_f32_is_refused_at_load() {
    let too_bright = "exceeds 1e16 cd/m²";
    let overflows = "is not a finite non-negative number";
    let cases = [
        (
            "intensity",
            BULB.replace("intensity = 1000", "intensity = 1e38"),
            too_bright,
        ),
        (
            "colour",
            BULB.replace(
                "float inputs:radius",
                "color3f inputs:color = (1e38, 1, 1)\n    float inputs:radius",
            ),
            too_bright,
        ),
        (
            "flux",
            BULB.replace(
                "float inputs:intensity = 1000",
                "float spectral:luminousFlux = 1e38",
            ),
            overflows,
        ),
        (
            "flux",
            BULB.replace(
                "float inputs:intensity = 1000",
                "float spectral:luminousFlux = 1e30",
            ),
            too_bright,
        ),
        (
            "exposure",
            BULB.replace(
                "float inputs:radius",
                "float inputs:exposure = 120\n    float inputs:radius",
            ),
            overflows,
        ),
    ];
    for (name, bulb, reason) in cases {
        refused(name, &format!("{FLOOR}{bulb}{CAMERA}"), &["/Bulb", reason]);
    }
    let emissive = format!(
        "{}{CAMERA}",
        textured_floor("x.png")
            .replace(
                "color3f inputs:diffuseColor.connect = </M/T.outputs:rgb>",
                "color3f inputs:emissiveColor = (1e38, 1e38, 1e38)"
            )
            .replace(BULB, "")
    );
    refused("emissive", &emissive, &["/Floor", "exceeds 1e16 cd/m²"]);
}

#[test]
fn an_ies_multiplier_of_1e38_is_refused() {
    let dir = temp_dir("ies1e38");
    let ies =
        "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1e38 3 1 1 2 0 0 0\n1 1 10\n0 45 90\n0\n1000 700 0\n";
    write(&dir, "lamp.ies", ies);
    let lamp = "def SphereLight \"Lamp\" (prepend apiSchemas = [\"ShapingAPI\"]) {\n    float inputs:radius = 0.05\n    asset inputs:shaping:ies:file = @lamp.ies@\n}\n";
    refused_in(
        &dir,
        "ies",
        &format!("{FLOOR}{lamp}{CAMERA}"),
        &["/Lamp", "lamp.ies:7", "overflows"],
    );
    let moderate = ies.replace("1e38", "1e30");
    write(&dir, "lamp.ies", &moderate);
    refused_in(
        &dir,
        "ies",
        &format!("{FLOOR}{lamp}{CAMERA}"),
        &["/Lamp", "exceeds 1e16 cd/m²"],
    );
}

#[test]
fn dome_texels_must_be_finite_and_bounded() {
    let dir = temp_dir("dome");
    for (name, value) in [("inf", f32::INFINITY), ("nan", f32::NAN), ("big", 1e38)] {
        let file = dir.join(format!("{name}.exr"));
        exr::prelude::write_rgb_file(&file, 4, 2, |x, y| {
            if (x, y) == (1, 1) {
                (value, value, value)
            } else {
                (1.0, 1.0, 1.0)
            }
        })
        .unwrap();
        let dome =
            format!("def DomeLight \"Sky\" {{\n    asset inputs:texture:file = @{name}.exr@\n}}\n");
        let reason = if name == "big" {
            "exceeds 1e16 cd/m²"
        } else {
            "non-finite texels"
        };
        refused_in(
            &dir,
            name,
            &format!("{FLOOR}{dome}{CAMERA}"),
            &["/Sky", reason],
        );
    }
}

#[test]
fn degenerate_light_and_camera_parameters_are_refused() {
    let sun = "def DistantLight \"Sun\" {\n    matrix4d xformOp:transform = ( (0, 0, 0, 0), (0, 0, 0, 0), (0, 0, 0, 0), (0, 0, 0, 1) )\n    uniform token[] xformOpOrder = [\"xformOp:transform\"]\n}\n";
    refused(
        "sun",
        &format!("{FLOOR}{sun}{CAMERA}"),
        &["/Sun", "degenerate transform"],
    );
    let exposure = CAMERA.replace("double3", "float exposure = 128\n    double3");
    refused(
        "exposure",
        &format!("{FLOOR}{BULB}{exposure}"),
        &["/Cam", "exposure 128 is outside ±64 stops"],
    );
    let nan_camera = CAMERA.replace("(0, 0.5, 3)", "(0, nan, 3)");
    refused(
        "nancam",
        &format!("{FLOOR}{BULB}{nan_camera}"),
        &["/Cam", "not finite"],
    );
    let nan_light = BULB.replace(
        "double3 xformOp:translate = (0, 1, 0)\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]",
        "float3 xformOp:rotateXYZ = (nan, 0, 0)\n    uniform token[] xformOpOrder = [\"xformOp:rotateXYZ\"]",
    );
    refused(
        "nanlight",
        &format!("{FLOOR}{nan_light}{CAMERA}"),
        &["/Bulb", "not finite"],
    );
    let lens = CAMERA.replace(
        "double3",
        "float fStop = 2\n    float focusDistance = 0\n    double3",
    );
    refused(
        "lens",
        &format!("{FLOOR}{BULB}{lens}"),
        &["/Cam", "needs focusDistance > 0"],
    );
}

#[test]
fn invalid_scene_content_is_refused() {
    let subset = FLOOR.replacen(
        "}\n",
        "    def GeomSubset \"S\" {\n        uniform token elementType = \"face\"\n        int[] indices = [3]\n    }\n}\n",
        1,
    );
    refused(
        "subset",
        &format!("{subset}{BULB}{CAMERA}"),
        &["/Floor/S", "face 3 is out of range"],
    );
    let reference = "def Xform \"A\" ( references = </Missing> ) {}\n";
    refused(
        "reference",
        &format!("{FLOOR}{BULB}{CAMERA}{reference}"),
        &["/A", "</Missing>"],
    );
    let short = FLOOR.replace("(1, 0, 1)", "(1, 0)");
    refused(
        "tuple",
        &format!("{short}{BULB}{CAMERA}"),
        &["line 7", "a tuple of 2 values"],
    );
    let rough = textured_floor("x.png").replace(
        "color3f inputs:diffuseColor.connect = </M/T.outputs:rgb>",
        "float inputs:roughness = -0.5",
    );
    refused(
        "roughness",
        &format!("{rough}{CAMERA}"),
        &["/M/S", "inputs:roughness = -0.5 is negative"],
    );
}

#[test]
fn silent_defaults_are_named() {
    let typo = BULB.replace("inputs:intensity", "inputs:intensty");
    warned(
        "typo",
        &format!("{FLOOR}{typo}{CAMERA}"),
        &[
            "/Bulb: unknown input 'inputs:intensty'",
            "did you mean inputs:intensity?",
        ],
    );
    warned(
        "dark",
        &format!("{FLOOR}{CAMERA}"),
        &["the stage has no lights"],
    );
    let settings = "def RenderSettings \"R\" {\n    float pixelAspectRatio = 2\n    float4 dataWindowNDC = (0.25, 0, 1, 1)\n}\n";
    warned(
        "settings",
        &format!("{FLOOR}{BULB}{CAMERA}{settings}"),
        &[
            "/R: pixelAspectRatio is not supported",
            "data window 2,0,8,8 (6×8 pixels) from </R>'s dataWindowNDC",
        ],
    );
}

#[test]
fn a_distant_light_narrower_than_f32_is_not_a_sun_of_its_luminance() {
    // Without normalize, intensity is luminance: a cone of 1e-30° gives E = L π sin²θ ≈ 0,
    // as 1e-6° does, not the L lux of a delta light (angle 0).
    let dir = temp_dir("narrow");
    let mut lux = Vec::new();
    for angle in ["1e-30", "1e-6", "0"] {
        let sun = format!("def DistantLight \"Sun\" {{\n    float inputs:angle = {angle}\n    float inputs:intensity = 50000\n    float xformOp:rotateX = -90\n    uniform token[] xformOpOrder = [\"xformOp:rotateX\"]\n}}\n");
        let stage = write(&dir, "sun.usda", &format!("{HEADER}{FLOOR}{sun}"));
        let out = spectral_render(
            &[
                "meter",
                stage.to_str().unwrap(),
                "--at",
                "0,0.1,0",
                "--normal",
                "0,1,0",
                "--json",
            ],
            &dir,
        );
        let json = common::stdout(&out);
        let value = json
            .split("\"value\":")
            .nth(1)
            .unwrap()
            .split(',')
            .next()
            .unwrap();
        lux.push(value.parse::<f64>().unwrap());
    }
    assert!(lux[0] < 1e-6 && lux[1] < 1e-6, "{lux:?}");
    assert!((lux[2] / 50000.0 - 1.0).abs() < 0.01, "{lux:?}");
}
