//! The render command's layer flags: `--spectral` (`--spectral-bins`, `--spectral-range`),
//! `--aov`, turned into `session::layers::LayerOptions`; `--illuminants`, `--light-groups`
//! and `--illuminant`, applied to the scene (`scene::emission_layers`).

use super::common::at_least;
use crate::error::{Error, Result};
use crate::integrator::Integrator;
use crate::light::emission_layers::illuminant_name;
use crate::scene::Scene;
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
    /// one writes the three); albedo (albedo.R/G/B: the first hit's directional-hemispherical
    /// reflectance, pbrt-v4's GBufferFilm albedo).
    #[arg(long = "aov", value_name = "LIST", value_delimiter = ',',
          value_parser = ["variance", "position", "normal", "depth", "albedo"])]
    pub aov: Vec<String>,
    /// One-pass renders under other illuminants (comma-separated names of
    /// spectra/illuminants, e.g. D65,A,F11,LED-B3): per illuminant a layer <name>.R/G/B and
    /// <name>.XYZ.X/Y/Z with every light's spectrum replaced by it at the same luminance
    /// (path integrator; no textured emission).
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = parse_illuminant)]
    pub illuminants: Vec<String>,
    /// A layer per light group (spectral:lightGroup on a light, else one per light prim):
    /// <group>.R/G/B and <group>.XYZ.X/Y/Z, which sum to the image (path integrator).
    #[arg(long = "light-groups")]
    pub light_groups: bool,
    /// Replace every light's spectrum by this illuminant at the same luminance (the render
    /// an --illuminants layer equals).
    #[arg(long, value_name = "NAME", value_parser = parse_illuminant)]
    pub illuminant: Option<String>,
}

/// An illuminant's full name (`A` → `CIE-A`).
fn parse_illuminant(s: &str) -> std::result::Result<String, String> {
    illuminant_name(s.trim()).map(str::to_string)
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
            first_hit: self
                .aov
                .iter()
                .any(|a| ["position", "normal", "depth"].contains(&a.as_str())),
            albedo: self.aov.iter().any(|a| a == "albedo"),
        };
        layers.check(integrator)?;
        self.check_emission(integrator)?;
        Ok(layers)
    }

    /// The integrator to run: `auto` becomes `path` when a layer needs every contribution
    /// in the sample's own pixel (auto might choose an integrator that splats), said on
    /// stderr.
    pub fn integrator(&self, integrator: Integrator) -> Integrator {
        let binned = self.spectral
            || self.spectral_bins.is_some()
            || self.spectral_range.is_some()
            || self.emission_layers();
        match integrator {
            Integrator::Auto { .. } if binned => {
                eprintln!(
                    "note: --spectral, --illuminants and --light-groups render with \
                     --integrator path (auto could choose an integrator that splats light \
                     paths, which these layers do not hold)"
                );
                Integrator::Path
            }
            other => other,
        }
    }

    /// Refuses layers with --part, --crop, --checkpoint and --resume: their raw state (`.part`,
    /// checkpoint files) carries the image's film only.
    pub fn check_state(&self, layers: &LayerOptions, part: bool, checkpoints: bool) -> Result<()> {
        if self.emission_layers() && (part || checkpoints) {
            return Err(Error::option(
                "--illuminants and --light-groups do not go with --part, --crop, --checkpoint \
                 or --resume: their saved state holds the image's film, not the layers' films",
            ));
        }
        if layers.spectral.is_some() && (part || checkpoints) {
            return Err(Error::option(
                "--spectral does not go with --part, --crop, --checkpoint or --resume: their saved \
                 state holds the image's film, not the spectral bins",
            ));
        }
        Ok(())
    }
}

impl LayerArgs {
    /// Whether `--illuminants` or `--light-groups` asks for emission layers.
    pub fn emission_layers(&self) -> bool {
        !self.illuminants.is_empty() || self.light_groups
    }

    /// Checks the emission layers' integrator (path only) before the stage is read.
    fn check_emission(&self, integrator: &Integrator) -> Result<()> {
        if self.emission_layers() && *integrator != Integrator::Path {
            return Err(Error::option(format!(
                "--illuminants and --light-groups weight each camera path by the layers' \
                 emission: integrator {} is not supported (use --integrator path)",
                integrator.name()
            )));
        }
        Ok(())
    }

    /// Applies `--illuminant`, `--illuminants` and `--light-groups` to `scene`.
    pub fn apply(&self, scene: &mut Scene) -> Result<()> {
        if let Some(name) = &self.illuminant {
            scene.replace_emission(name)?;
        }
        scene.add_illuminant_layers(&self.illuminants)?;
        if self.light_groups {
            scene.add_light_group_layers()?;
        }
        Ok(())
    }
}
