//! The run's choice of sampler (`--sampler`) and the sampler of each (pixel, sample).

use super::rng::Sampler;
use super::zsobol::{morton, ZSobol};

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

    /// The samplers of pixel (x, y), whose pixel index and Morton code are found once for
    /// all its samples (design.md §8, "The per-sample cost, seventh pass").
    #[inline]
    pub fn pixel(&self, x: u32, y: u32) -> PixelSampler<'_> {
        PixelSampler {
            samplers: self,
            pixel: u64::from(y) * self.width + u64::from(x),
            morton: if self.zsobol.is_some() {
                morton(x, y)
            } else {
                0
            },
        }
    }
}

/// The samplers of one pixel ([`PixelSamplers::pixel`]).
#[derive(Clone, Copy, Debug)]
pub struct PixelSampler<'a> {
    samplers: &'a PixelSamplers,
    /// The pixel's index in the image (y · width + x).
    pixel: u64,
    /// The pixel's Morton code (zsobol only).
    morton: u64,
}

impl<'a> PixelSampler<'a> {
    /// The sampler of sample `s` of this pixel: keyed by (seed, pixel, sample) only.
    #[inline]
    pub fn sampler(&self, s: u64) -> Sampler<'a> {
        let p = self.samplers;
        match &p.zsobol {
            Some(z) => Sampler::low_discrepancy(p.seed, self.pixel, s, z.stream_at(self.morton, s)),
            None => Sampler::new(p.seed, self.pixel, s),
        }
    }
}
