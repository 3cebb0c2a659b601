//! `spectral-render falsecolor` on synthetic luminance ramps: each legend value's tick, label
//! and colour sit on the bar where that luminance's colour is, and the ramp's pixel of that
//! luminance has the same colour (linear and logarithmic scales); bad options are one-line
//! errors.

mod common;
use common::*;
use spectral_render::output::exr::{self, ExrMetadata};
use spectral_render::output::falsecolor::FalseColor;
use std::path::Path;

const W: usize = 201;
const H: usize = 16;

/// An EXR whose XYZ.Y is `lum(x)` in every row.
fn ramp(dir: &Path, lum: impl Fn(usize) -> f32) -> std::path::PathBuf {
    let xyz: Vec<[f32; 3]> = (0..W * H)
        .map(|i| {
            let y = lum(i % W);
            [0.95 * y, y, 1.09 * y]
        })
        .collect();
    let path = dir.join("ramp.exr");
    let meta = ExrMetadata::default();
    exr::write(&path, W, H, &xyz, &xyz, [0.3127, 0.329], &meta).unwrap();
    path
}

/// Checks the legend and the ramp of the PNG at `png` drawn with `f`; `column(v)` is the
/// ramp's column of luminance v.
fn check(png: &Path, f: &FalseColor, column: impl Fn(f64) -> usize) {
    let img = image::open(png).unwrap().into_rgb8();
    let l = f.layout(W, H);
    assert_eq!(img.dimensions(), (l.width as u32, l.height as u32));
    let at = |x: i64, y: i64| img.get_pixel(x as u32, y as u32).0;
    let n = f.divisions;
    for (k, v) in f.ticks().iter().enumerate() {
        let t = k as f64 / n as f64;
        let row = f.bar_row(&l, t);
        // The bar's colour at the tick is the colour of the tick's luminance (within the
        // bar's and the ramp's half-pixel steps)...
        let close = |a: [u8; 3], b: [u8; 3]| (0..3).all(|c| (a[c] as i32 - b[c] as i32).abs() <= 2);
        let bar = at(l.bar_x + 4, row);
        let want = f.colour(*v);
        assert!(
            close(bar, want),
            "tick {k} ({v} cd/m²): bar {bar:?}, colour {want:?}"
        );
        // ...which the ramp shows where its luminance is v.
        let x = column(*v);
        let pixel = at(l.image_x + x as i64, l.top + H as i64 / 2);
        assert!(
            close(pixel, want),
            "tick {k} ({v}): ramp {pixel:?} at column {x}, {want:?}"
        );
        // The tick mark and its label are beside that row.
        assert_eq!(at(l.bar_x + 24 + 2, row), [20, 20, 20], "tick mark {k}");
        let label_ink =
            (row - 7..row + 7).any(|y| (l.bar_x + 32..l.image_x).any(|x| at(x, y) == [20, 20, 20]));
        assert!(label_ink, "label {k}");
    }
}

#[test]
fn legend_values_sit_where_the_ramp_has_them() {
    let dir = temp_dir("falsecolor");
    // Linear: 5 cd/m² per column, 0 to 1000.
    let exr = ramp(&dir, |x| 5.0 * x as f32);
    let o = spectral_render(
        &[
            "falsecolor",
            exr.to_str().unwrap(),
            "-o",
            "lin.png",
            "--scale",
            "1000",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let f = FalseColor {
        scale: 1000.0,
        decades: None,
        divisions: 8,
        contours: false,
    };
    check(&dir.join("lin.png"), &f, |v| (v / 5.0).round() as usize);

    // Log over 4 decades: 0.1 to 1000 cd/m², one decade per 50 columns.
    let exr = ramp(&dir, |x| 10f32.powf(x as f32 / 50.0 - 1.0));
    let o = spectral_render(
        &[
            "falsecolor",
            exr.to_str().unwrap(),
            "-o",
            "log.png",
            "--scale",
            "1000",
            "--log",
            "4",
            "--divisions",
            "4",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let f = FalseColor {
        scale: 1000.0,
        decades: Some(4.0),
        divisions: 4,
        contours: false,
    };
    check(&dir.join("log.png"), &f, |v| {
        ((v.log10() + 1.0) * 50.0).round() as usize
    });
}

#[test]
fn contours_and_bad_options() {
    let dir = temp_dir("falsecolor-contours");
    let exr = ramp(&dir, |x| 5.0 * x as f32);
    let o = spectral_render(
        &[
            "falsecolor",
            exr.to_str().unwrap(),
            "-o",
            "c.png",
            "--contours",
            "4",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    // Default scale: the maximum, 1000, is already round.
    assert!(stderr(&o).contains("0 to 1000 cd/m²"), "{}", stderr(&o));
    for bad in [
        &["--scale", "0"][..],
        &["--log", "-1"],
        &["--contours", "0"],
    ] {
        let mut args = vec!["falsecolor", exr.to_str().unwrap(), "-o", "x.png"];
        args.extend_from_slice(bad);
        let o = spectral_render(&args, &dir);
        assert_eq!(o.status.code(), Some(1), "{bad:?}");
        assert_eq!(stderr(&o).lines().count(), 1, "{}", stderr(&o));
        assert!(!dir.join("x.png").exists());
    }
    let o = spectral_render(&["falsecolor", "missing.exr", "-o", "x.png"], &dir);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("missing.exr"), "{}", stderr(&o));
}
