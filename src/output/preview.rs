//! The PNG preview of a render: the working-space RGB scaled by 2^EV, through an OCIO display
//! transform (`output::ocio`), as 8-bit code values (`output::png`).
//!
//! `--preview-exposure auto` chooses EV so that the image's log-average luminance lands on
//! middle grey 0.18 (Reinhard et al. 2002, "Photographic Tone Reproduction for Digital
//! Images", eq. 1 and the key a = 0.18): EV = log2(0.18 / exp(mean ln Y)), the mean over the
//! pixels with Y > 0 (a black pixel has no logarithm; Reinhard's δ would make the answer
//! depend on an arbitrary floor). An image without a lit pixel gets EV 0.

use std::path::Path;

use super::ocio::DisplayTransform;
use super::png;
use crate::error::Result;

/// Middle grey, the key of Reinhard et al. 2002 §2.
pub const MIDDLE_GREY: f64 = 0.18;

/// The preview's exposure: stops, or chosen from the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exposure {
    Stops(f32),
    Auto,
}

impl Exposure {
    /// Parses `EV` or `auto`.
    pub fn parse(s: &str) -> std::result::Result<Exposure, String> {
        if s.trim() == "auto" {
            return Ok(Exposure::Auto);
        }
        match s.trim().parse::<f32>() {
            Ok(ev) if ev.is_finite() && ev.abs() <= 64.0 => Ok(Exposure::Stops(ev)),
            Ok(ev) => Err(format!("the exposure {ev} is not within ±64 stops")),
            Err(_) => Err(format!("'{s}' is neither a number of stops nor 'auto'")),
        }
    }

    /// The stops for an image of luminances `y` (cd/m²).
    pub fn stops(self, y: impl Iterator<Item = f32>) -> f32 {
        match self {
            Exposure::Stops(ev) => ev,
            Exposure::Auto => auto_exposure(y),
        }
    }
}

/// EV placing the log-average of the positive, finite luminances `y` at [`MIDDLE_GREY`].
pub fn auto_exposure(y: impl Iterator<Item = f32>) -> f32 {
    let (sum, n) = y
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((0.0f64, 0u64), |(s, n), v| (s + f64::from(v).ln(), n + 1));
    if n == 0 {
        return 0.0;
    }
    let log_average = (sum / n as f64).exp();
    (MIDDLE_GREY / log_average).log2() as f32
}

/// Writes the preview of `rgb` (working space, row-major) at `ev` stops through `transform`.
pub fn write(
    path: &Path,
    width: usize,
    height: usize,
    rgb: &[[f32; 3]],
    ev: f32,
    transform: &DisplayTransform,
) -> Result<()> {
    let scale = ev.exp2();
    let mut code: Vec<[f32; 3]> = rgb.iter().map(|p| p.map(|c| c * scale)).collect();
    transform.apply(&mut code);
    png::write_code_values(path, width, height, &code)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_puts_the_log_average_on_middle_grey() {
        // Log-average of 1 and 100 is 10: EV = log2(0.018).
        let ev = auto_exposure([1.0, 100.0, 0.0, f32::NAN].into_iter());
        assert!((ev - 0.018f32.log2()).abs() < 1e-6, "{ev}");
        assert_eq!(auto_exposure([0.0, -1.0].into_iter()), 0.0);
    }

    #[test]
    fn parses_stops_and_auto() {
        assert_eq!(Exposure::parse("auto"), Ok(Exposure::Auto));
        assert_eq!(Exposure::parse("-6.5"), Ok(Exposure::Stops(-6.5)));
        assert!(Exposure::parse("inf").is_err());
        assert!(Exposure::parse("bright").is_err());
    }
}
