//! Light-transport integrators. All are spectral with the same hero-wavelength machinery.

pub mod meter;
pub mod path;

pub use path::PathIntegrator;

/// Which integrator renders the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegratorKind {
    Path,
}

impl IntegratorKind {
    pub fn name(&self) -> &'static str {
        match self {
            IntegratorKind::Path => "path",
        }
    }
}
