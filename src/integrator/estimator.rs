//! The one interface every integrator offers the drivers of `session`: one sample at a time,
//! of a pixel or of a light meter, with the sample's wavelengths and random numbers chosen by
//! the driver, and buffers from the caller's per-thread [`Workspace`].
//!
//! A sample's contributions go to `ws.record` ([`super::bidir::SampleRecord`]): the sample's
//! own pixel (`camera`) and, for integrators that trace light subpaths, splats to any pixel.
//! They stay spectral until the sample ends, so that a secondary-wavelength termination on
//! any subpath (dispersion) applies to everything the sample contributed; the driver converts
//! them with the final wavelengths.

use super::Workspace;
use crate::sampling::Sampler;
use crate::sensor::meter::MeterSensor;
use crate::spectral::{SampledSpectrum, SampledWavelengths};
use crate::texture::TextureFilter;

/// What every integrator is built with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Maximum scattering events (pbrt's maxdepth).
    pub max_depth: u32,
    /// The path tracer's first bounce of Russian roulette (`roulette.rs`, `--rr-depth`); the
    /// bidirectional integrators' subpaths keep their own rule.
    pub rr_depth: u32,
    /// The continuations the path tracer's image paths split into at their first vertex
    /// (`split.rs`, `--split`); the other integrators and meters take none.
    pub split: u32,
    /// Texture footprints: the camera's for images, the finest level for meters.
    pub filter: TextureFilter,
    /// The run measures light meters rather than an image.
    pub meters: bool,
}

/// What an iteration is: the samples it covers share work prepared before any of them
/// (VCM's light vertices and their hash grid).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Iteration {
    /// The seed of the run.
    pub seed: u64,
    /// The iteration's index, from 0: the sample index of images, the round of meters.
    pub index: u64,
}

/// One integrator run on one scene (`Integrator::estimator`).
pub trait Estimator: Sync + Send {
    /// Samples per pixel (or per meter reading) of one iteration, for estimators whose
    /// samples share work prepared per iteration ([`Estimator::begin_iteration`]); None when
    /// every sample stands alone (path tracing, light tracing, BDPT).
    fn iteration_samples(&self) -> Option<u64> {
        None
    }

    /// Prepares iteration `it` before any of its samples is taken; runs on the session's
    /// worker threads (it may use rayon). Only called when [`Estimator::iteration_samples`]
    /// is Some.
    fn begin_iteration(&mut self, _it: Iteration) {}

    /// What a user should know about this run's settings and resources (VCM's radius and
    /// store), one line; None when there is nothing to say.
    fn report(&self) -> Option<String> {
        None
    }

    /// True when [`Estimator::image_sample`] replaces the wavelengths it is given by its own
    /// before using them (VCM: its iteration's tuple, or its stored light subpath's): the
    /// driver then still draws the sample's wavelength number, so that the sampler's stream
    /// is the same, but does not turn it into wavelengths.
    fn own_image_wavelengths(&self) -> bool {
        false
    }

    /// False when [`Estimator::image_sample`] never reads its `u_lens` (a pinhole camera's
    /// path tracer): the driver then need not compute the lens sample
    /// (`Sampler::get_2d_if`).
    fn reads_lens(&self) -> bool {
        true
    }

    /// One sample of the pixel at raster position `film`, through lens sample `u_lens`:
    /// contributions into `ws.record`, which the caller has cleared. `lambda` may have its
    /// secondary wavelengths terminated on return.
    fn image_sample(
        &self,
        film: [f32; 2],
        u_lens: [f32; 2],
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    );

    /// One sample of `meter`'s quantity (irradiance or radiance per lane), not yet divided by
    /// the wavelength pdfs, relative to the final `lambda`.
    fn meter_sample(
        &self,
        meter: &MeterSensor,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        ws: &mut Workspace,
    ) -> SampledSpectrum;
}
