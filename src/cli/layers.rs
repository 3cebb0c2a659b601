//! The render command's layer flags: `--spectral` (`--spectral-bins`, `--spectral-range`),
//! turned into `session::layers::LayerOptions`.

use super::common::at_least;
use crate::error::{Error, Result};
use crate::integrator::Integrator;
use crate::sensor::spectral_film::{SpectralBins, DEFAULT_BINS};
use crate::session::layers::LayerOptions;
use crate::spectral::{LAMBDA_MAX, LAMBDA_MIN};

/// Extra EXR layers.
#[derive(clap::Args, Debug, Clone)]
pub struct LayerArgs {
    /// Also write the spectral radiance, in the layout of Fichet et al. 2021 (JCGT 10(3)):
    /// channels S0.<nm>nm, bin-averaged W·m⁻²·sr⁻¹·nm⁻¹ × 2^exposure (path integrator).
    #[arg(long)]
    pub spectral: bool,
    /// Number of equal spectral bins (default 32; implies --spectral).
    #[arg(long = "spectral-bins", value_name = "N", allow_negative_numbers = true,
          value_parser = at_least::<usize>(1))]
    pub spectral_bins: Option<usize>,
    /// The spectral bins' range in nm (default 360,830; implies --spectral).
    #[arg(long = "spectral-range", value_name = "A,B", value_parser = parse_range,
          allow_hyphen_values = true)]
    pub spectral_range: Option<(f32, f32)>,
    /// Extra layers (comma-separated): variance (variance.Y, of the pixel's mean luminance);
    /// position, normal, depth (P.X/Y/Z, N.X/Y/Z, Z of the first hit in camera space; any
    /// one writes the three).
    #[arg(long = "aov", value_name = "LIST", value_delimiter = ',',
          value_parser = ["variance", "position", "normal", "depth"])]
    pub aov: Vec<String>,
}

fn parse_range(s: &str) -> std::result::Result<(f32, f32), String> {
    let (a, b) = s
        .split_once(',')
        .ok_or("expected A,B in nm, e.g. 380,780")?;
    let nm = |v: &str| {
        v.trim()
            .parse::<f32>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or(format!("'{}' is not a wavelength in nm", v.trim()))
    };
    Ok((nm(a)?, nm(b)?))
}

impl LayerArgs {
    /// The layers asked for, checked against the integrator.
    pub fn options(&self, integrator: &Integrator) -> Result<LayerOptions> {
        let spectral =
            self.spectral || self.spectral_bins.is_some() || self.spectral_range.is_some();
        let bins = if spectral {
            let (a, b) = self.spectral_range.unwrap_or((LAMBDA_MIN, LAMBDA_MAX));
            let n = self.spectral_bins.unwrap_or(DEFAULT_BINS);
            Some(SpectralBins::new(a, b, n).map_err(Error::option)?)
        } else {
            None
        };
        let layers = LayerOptions {
            spectral: bins,
            variance: self.aov.iter().any(|a| a == "variance"),
            first_hit: self.aov.iter().any(|a| a != "variance"),
        };
        layers.check(integrator)?;
        Ok(layers)
    }

    /// The integrator to run: `auto` becomes `path` when a layer needs every contribution
    /// in the sample's own pixel (auto might choose an integrator that splats), said on
    /// stderr.
    pub fn integrator(&self, integrator: Integrator) -> Integrator {
        let binned = self.spectral || self.spectral_bins.is_some() || self.spectral_range.is_some();
        match integrator {
            Integrator::Auto { .. } if binned => {
                eprintln!(
                    "note: --spectral renders with --integrator path (auto could choose an \
                     integrator that splats light paths, which are not binned)"
                );
                Integrator::Path
            }
            other => other,
        }
    }

    /// Refuses layers with --part, --crop, --checkpoint and --resume: their raw state (`.part`,
    /// checkpoint files) carries the image's film only.
    pub fn check_state(&self, layers: &LayerOptions, part: bool, checkpoints: bool) -> Result<()> {
        if layers.spectral.is_some() && (part || checkpoints) {
            return Err(Error::option(
                "--spectral does not go with --part, --crop, --checkpoint or --resume: their saved \
                 state holds the image's film, not the spectral bins",
            ));
        }
        Ok(())
    }
}
