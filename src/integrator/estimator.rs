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
    /// Texture footprints: the camera's for images, the finest level for meters.
    pub filter: TextureFilter,
}

/// One integrator run on one scene (`Integrator::estimator`).
pub trait Estimator: Sync {
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
