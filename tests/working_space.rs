//! `--colorspace`: the ColorChecker rendered with each working space (same seed, so the same
//! XYZ), converted back to Rec.709 by colour-science from the EXR's own `chromaticities`
//! (`tools/check_working_space.py`), matches the Rec.709 render within 1e-4 (ACEScg, P3-D65;
//! XYZ is the identity); the `colorspace` attribute names the OCIO colour space, and the XYZ
//! channels do not change.

mod common;
use common::*;
use spectral_render::output::exr;
use std::path::Path;

fn render(dir: &Path, space: &str) -> exr::ExrImage {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let stage = root.join("scenes/colorchecker.usda");
    let out = format!("{space}.exr");
    let o = spectral_render(
        &[
            stage.to_str().unwrap(),
            "--spp",
            "2",
            "--resolution",
            "60x40",
            "--colorspace",
            space,
            "-o",
            &out,
        ],
        dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    exr::read(&dir.join(out)).unwrap()
}

fn rgb_json(img: &exr::ExrImage) -> String {
    let c = |n: &str| &img.channels[n];
    let (r, g, b) = (c("R"), c("G"), c("B"));
    let pixels: Vec<String> = (0..r.len())
        .map(|i| format!("[{:?}, {:?}, {:?}]", r[i], g[i], b[i]))
        .collect();
    let chroma = img.attributes["chromaticities"].replace(' ', ", ");
    format!(
        "{{\"chromaticities\": [{chroma}], \"rgb\": [{}]}}",
        pixels.join(", ")
    )
}

#[test]
fn working_spaces_convert_back_to_rec709_within_1e_4() {
    colour_science_venv();
    let dir = temp_dir("working-space");
    let rec709 = render(&dir, "lin_rec709");
    assert_eq!(rec709.attributes["colorspace"], "Linear Rec.709 (sRGB)");
    let mut others = Vec::new();
    for (space, ocio) in [
        ("acescg", "ACEScg"),
        ("lin_p3d65", "Linear P3-D65"),
        ("xyz", "CIE XYZ-D65 - Scene-referred"),
    ] {
        let img = render(&dir, space);
        assert_eq!(img.attributes["colorspace"], ocio);
        for c in ["XYZ.X", "XYZ.Y", "XYZ.Z"] {
            assert_eq!(img.channels[c], rec709.channels[c], "{space} {c}");
        }
        match space {
            // XYZ is the identity (OpenEXR's XYZ chromaticities); colour-science would
            // adapt its equal-energy white, which our D65-referred XYZ does not have.
            "xyz" => {
                assert_eq!(img.channels["R"], img.channels["XYZ.X"]);
                assert_eq!(img.channels["B"], img.channels["XYZ.Z"]);
                let c = &img.attributes["chromaticities"];
                assert_eq!(c, "1 0 0 1 0 0 0.33333334 0.33333334");
            }
            _ => others.push(format!("\"{space}\": {}", rgb_json(&img))),
        }
        if space == "acescg" {
            let c = &img.attributes["chromaticities"];
            assert_eq!(c, "0.713 0.293 0.165 0.83 0.128 0.044 0.32168 0.33767");
        }
    }
    let json = format!(
        "{{\"reference\": {}, \"others\": {{{}}}}}",
        rgb_json(&rec709),
        others.join(", ")
    );
    let path = write(&dir, "pixels.json", &json);
    let (passed, report) = colour_science_check("check_working_space.py", &path);
    println!("{report}");
    assert!(
        passed,
        "working spaces disagree with colour-science:\n{report}"
    );
}
