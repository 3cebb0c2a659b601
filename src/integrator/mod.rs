//! Light-transport integrators. All are spectral with the same hero-wavelength machinery.
//!
//! - `path`: unidirectional path tracing with NEE and MIS;
//! - `light_tracer`: light (particle) tracing, splatting to the film;
//! - `bdpt`: bidirectional path tracing, every (s, t) technique with MIS;
//! - `bidir/`: what the bidirectional ones share (vertices, walks, MIS recurrences);
//! - `meter`, `meter_bidir`: light-meter estimators (path tracing; light tracing and BDPT
//!   with the meter as sensor).

pub mod bdpt;
pub mod bidir;
pub mod light_tracer;
pub mod meter;
pub mod meter_bidir;
pub mod path;

pub use bdpt::BdptIntegrator;
pub use bidir::MisHeuristic;
pub use light_tracer::LightTracer;
pub use path::PathIntegrator;

/// Which integrator renders the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegratorKind {
    Path,
    Light,
    Bdpt,
}

impl IntegratorKind {
    pub fn name(&self) -> &'static str {
        match self {
            IntegratorKind::Path => "path",
            IntegratorKind::Light => "light",
            IntegratorKind::Bdpt => "bdpt",
        }
    }

    /// Light tracing and BDPT splat to the film and trace light subpaths.
    pub fn is_bidirectional(&self) -> bool {
        matches!(self, IntegratorKind::Light | IntegratorKind::Bdpt)
    }
}
