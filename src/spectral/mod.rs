//! Spectral quantities: sampled wavelengths and spectra, tabulated data, CIE observer,
//! RGB uplift, photometry and colour difference (CIEDE2000).
//!
//! Conventions: wavelengths in nm over [`LAMBDA_MIN`, `LAMBDA_MAX`] (docs/design.md §2); radiance
//! spectra in W·m⁻²·sr⁻¹·nm⁻¹, so that luminance = K_m ∫ L(λ) ȳ(λ) dλ in cd/m².

pub mod blackbody;
pub mod color;
pub mod data;
pub mod dense;
pub mod difference;
pub mod photometry;
pub mod sampled;
pub mod sellmeier;
pub mod spectrum;
pub mod uplift;
pub mod wavelengths;
pub mod working_space;
pub mod xyz;

pub use dense::DenseSpectrum;
pub use sampled::SampledSpectrum;
pub use spectrum::Spectrum;
pub use wavelengths::SampledWavelengths;

/// Shortest wavelength simulated, nm (docs/design.md §2).
pub const LAMBDA_MIN: f32 = 360.0;
/// Longest wavelength simulated, nm (docs/design.md §2).
pub const LAMBDA_MAX: f32 = 830.0;
/// Wavelengths carried per path: a hero plus three rotations.
pub const N_LAMBDA: usize = 4;
/// Maximum luminous efficacy K_m in lm/W, the value colour-science uses (CIE 015:2018).
pub const K_M: f32 = 683.0;
