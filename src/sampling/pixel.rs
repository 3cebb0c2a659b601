//! The run's choice of sampler (`--sampler`) and the sampler of each (pixel, sample).

use super::rng::Sampler;
use super::zsobol::ZSobol;

/// Which numbers the samples of an image draw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SamplerKind {
    /// Owen-scrambled Sobol' points in Morton order over the image (`zsobol.rs`), for the
    /// estimators that keep the dimension layout (`Integrator::low_discrepancy`: path, and
    /// BDPT's and VCM's camera subpaths); light tracing draws independent numbers.
    #[default]
    ZSobol,
    /// Independent uniform numbers (PCG32) for every sample.
    Independent,
}

impl SamplerKind {
    pub const ALL: [SamplerKind; 2] = [SamplerKind::ZSobol, SamplerKind::Independent];

    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::ZSobol => "zsobol",
            SamplerKind::Independent => "independent",
        }
    }

    pub fn from_name(name: &str) -> Option<SamplerKind> {
        SamplerKind::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// The samplers of one image run: the seed, the image width (pixel indices) and the
/// sequence, if any.
#[derive(Clone, Debug)]
pub struct PixelSamplers {
    seed: u64,
    width: u64,
    zsobol: Option<ZSobol>,
}

impl PixelSamplers {
    /// `kind` for a run of `spp` samples per pixel (None: unknown) on an image `width` wide.
    pub fn new(kind: SamplerKind, seed: u64, width: u64, spp: Option<u64>) -> PixelSamplers {
        PixelSamplers {
            seed,
            width,
            zsobol: (kind == SamplerKind::ZSobol).then(|| ZSobol::new(seed, spp)),
        }
    }

    /// The sampler of sample `s` of pixel (x, y): keyed by (seed, pixel, sample) only.
    #[inline]
    pub fn sampler(&self, x: u32, y: u32, s: u64) -> Sampler<'_> {
        let pixel = u64::from(y) * self.width + u64::from(x);
        match &self.zsobol {
            Some(z) => Sampler::low_discrepancy(self.seed, pixel, s, z.stream(x, y, s)),
            None => Sampler::new(self.seed, pixel, s),
        }
    }
}
