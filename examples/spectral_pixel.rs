//! Plots one pixel of a spectral EXR (`--spectral`: Fichet et al. 2021's `S0.<λ>nm` channels)
//! against the CIE 1931 colour-matching functions, each curve scaled to the spectrum's peak, and
//! prints the pixel's XYZ recomputed from its bins beside the EXR's `XYZ` channels:
//!
//! ```text
//! spectral-render scenes/colorchecker.usda --resolution 120x80 --spp 1024 --spectral \
//!     --integrator path -o cc.exr
//! cargo run --release --example spectral_pixel -- cc.exr 20 14 docs/images/spectral-pixel.png
//! ```

use spectral_render::output::exr;
use spectral_render::output::plot::{self, Curve};
use spectral_render::spectral::data;
use std::path::Path;

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.len() != 4 {
        eprintln!("usage: spectral_pixel IN.exr X Y OUT.png");
        std::process::exit(2);
    }
    let (x, y) = match (a[1].parse::<usize>(), a[2].parse::<usize>()) {
        (Ok(x), Ok(y)) => (x, y),
        _ => {
            eprintln!("error: X and Y are pixel indices");
            std::process::exit(2);
        }
    };
    if let Err(e) = run(Path::new(&a[0]), (x, y), Path::new(&a[3])) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

/// The wavelength of a channel `S0.512,500000nm` (None for other channels).
fn wavelength(name: &str) -> Option<f64> {
    let nm = name.strip_prefix("S0.")?.strip_suffix("nm")?;
    nm.replace(',', ".").parse().ok()
}

fn run(input: &Path, (x, y): (usize, usize), out: &Path) -> Result<(), String> {
    let img = exr::read(input).map_err(|e| e.to_string())?;
    if x >= img.width || y >= img.height {
        return Err(format!(
            "({x}, {y}) is outside the {}×{} image",
            img.width, img.height
        ));
    }
    let i = y * img.width + x;
    let mut bins: Vec<(f64, f64)> = img
        .channels
        .iter()
        .filter_map(|(k, v)| wavelength(k).map(|nm| (nm, f64::from(v[i]))))
        .collect();
    if bins.is_empty() {
        return Err(format!(
            "{} has no S0.<λ>nm channels (render with --spectral)",
            input.display()
        ));
    }
    bins.sort_by(|a, b| a.0.total_cmp(&b.0));
    let width = if bins.len() > 1 {
        bins[1].0 - bins[0].0
    } else {
        1.0
    };
    let cmf = data::cie_xyz();
    // XYZ = 683 ∫ L x̄ dλ over the bins (the EXR's XYZ is in cd/m² for Y, §2 of the design).
    let xyz: Vec<f64> = (0..3)
        .map(|c| {
            683.0
                * bins
                    .iter()
                    .map(|(nm, l)| l * f64::from(cmf[c].eval(*nm as f32)) * width)
                    .sum::<f64>()
        })
        .collect();
    let stored: Vec<f32> = ["XYZ.X", "XYZ.Y", "XYZ.Z"]
        .iter()
        .map(|k| img.channels.get(*k).map_or(f32::NAN, |v| v[i]))
        .collect();
    println!("pixel ({x}, {y}): XYZ from the bins {xyz:.4?}, the EXR's {stored:.4?}");
    let peak = bins.iter().fold(0.0f64, |m, b| m.max(b.1));
    let mut series = vec![Curve {
        label: format!("pixel ({x}, {y}), W/(m² sr nm)"),
        points: bins.clone(),
        dashed: false,
    }];
    for (c, name) in ["x-bar", "y-bar", "z-bar"].iter().enumerate() {
        let top = (360..=830)
            .map(|nm| cmf[c].eval(nm as f32))
            .fold(0.0f32, f32::max);
        let pts = (360..=830)
            .step_by(2)
            .map(|nm| {
                (
                    f64::from(nm),
                    f64::from(cmf[c].eval(nm as f32) / top) * peak,
                )
            })
            .collect();
        series.push(Curve {
            label: format!("CIE 1931 {name} (scaled)"),
            points: pts,
            dashed: true,
        });
    }
    let title = format!("{}: one pixel's spectral radiance", input.display());
    plot::lines(
        out,
        &title,
        ("wavelength (nm)", "spectral radiance"),
        &series,
    )
    .map_err(|e| e.to_string())?;
    println!("wrote {}", out.display());
    Ok(())
}
