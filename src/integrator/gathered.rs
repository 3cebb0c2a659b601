//! The light a camera path gathers: the image's radiance and, when the scene has emission
//! layers (`light::emission_layers`: `--illuminants`, `--light-groups`), each layer's. The
//! path tracer evaluates every layer's emission wherever it evaluates the scene's (emitters
//! hit, escaped rays, next-event estimation) and weights it by the same throughput and MIS
//! weight, so a layer is exactly the render of the scene with that emission from the same
//! samples. Without layers the slices are empty and nothing extra runs.

use crate::light::emission_layers::EmissionLayer;
use crate::spectral::SampledSpectrum;

pub(crate) struct Gathered<'a> {
    /// The image's radiance.
    pub l: SampledSpectrum,
    /// The layers' definitions and their sums, index for index.
    pub layers: &'a [EmissionLayer],
    pub sums: &'a mut [SampledSpectrum],
}

impl Gathered<'_> {
    /// The image's radiance alone (meters, continuations past the depth cap).
    pub fn plain() -> Gathered<'static> {
        Gathered {
            l: SampledSpectrum::ZERO,
            layers: &[],
            sums: &mut [],
        }
    }
}
