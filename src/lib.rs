//! spectral-render: a spectral, physically based renderer for USD stages whose images and
//! light-meter readings are in absolute photometric units. See `ARCHITECTURE.md` for the
//! layers and `docs/design.md` for the units, the `spectral:` vocabulary and the decisions.
//!
//! A stage is read into a [`scene::Scene`]; a [`session`] renders it progressively into
//! absolute XYZ and Rec.709 RGB (cd/m²), or measures light meters (lx, cd/m²) with confidence
//! intervals, with any [`Integrator`]. Here a grey card lit by a uniform dome of 100 nits is
//! seen head-on; a Lambertian card of albedo 0.18 under a uniform dome of luminance L has
//! luminance 0.18·L and receives the illuminance π·L:
//!
//! ```
//! use spectral_render::session::{self, ImageSession, MeterOptions, Progressive, RenderOptions, Stop};
//! use spectral_render::{scene, Integrator, Meter};
//! use glam::Vec3;
//!
//! let stage = r#"#usda 1.0
//! (
//!     metersPerUnit = 1
//!     upAxis = "Y"
//! )
//! def DomeLight "Sky"
//! {
//!     float inputs:intensity = 100
//! }
//! def Mesh "Card"
//! {
//!     int[] faceVertexCounts = [4]
//!     int[] faceVertexIndices = [0, 1, 2, 3]
//!     point3f[] points = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
//! }
//! def Camera "Camera"
//! {
//!     float focalLength = 100
//!     double3 xformOp:translate = (0, 0, 2)
//!     uniform token[] xformOpOrder = ["xformOp:translate"]
//! }
//! "#;
//! let path = std::env::temp_dir().join(format!("spectral-render-doc-{}.usda", std::process::id()));
//! std::fs::write(&path, stage)?;
//! let scene = scene::load(&path, Some((8, 8)))?;
//!
//! // An image, pass by pass, until 64 samples per pixel.
//! let options = RenderOptions { spp: Some(64), ..Default::default() };
//! let mut image = ImageSession::new(&scene, &options)?;
//! while let Some(pass) = image.step() {
//!     assert!(pass.samples <= 64 && pass.dropped == 0);
//! }
//! let out = image.output();
//! // Unbound meshes get a 0.18 grey Lambertian: luminance 0.18 × 100 cd/m².
//! let mean_y: f32 = out.xyz.iter().map(|p| p[1]).sum::<f32>() / out.xyz.len() as f32;
//! assert!((mean_y - 18.0).abs() < 0.5, "{mean_y}");
//!
//! // A meter on the card's front, facing the sky: E = π · 100 lx, by BDPT.
//! let meter = Meter::illuminance(Vec3::new(0.0, 0.0, 0.001), Vec3::Z)?;
//! let options = MeterOptions {
//!     stop: Stop::Samples(4096),
//!     integrator: Integrator::from_name("bdpt").unwrap(),
//!     ..Default::default()
//! };
//! let reading = session::measure(&scene, &[meter], &options)?.readings[0];
//! assert!((reading.value - 100.0 * std::f64::consts::PI).abs() < 3.0 * reading.ci95);
//! # std::fs::remove_file(&path).ok();
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]

pub mod cli;
pub mod converge;
pub mod desc;
pub mod error;
pub mod output;
pub mod scene;
pub mod session;
pub mod spectral;

// Internal modules: `pub(crate)` for a library user, `pub` (and hidden from the docs) under the
// `testing` feature, for the project's own tests, benches and examples. Written out rather than
// through a macro so that rustfmt reaches them.
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod accel;
#[cfg(not(feature = "testing"))]
pub(crate) mod accel;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod bxdf;
#[cfg(not(feature = "testing"))]
pub(crate) mod bxdf;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod geometry;
#[cfg(not(feature = "testing"))]
pub(crate) mod geometry;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod imageio;
#[cfg(not(feature = "testing"))]
pub(crate) mod imageio;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod integrator;
#[cfg(not(feature = "testing"))]
pub(crate) mod integrator;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod light;
#[cfg(not(feature = "testing"))]
pub(crate) mod light;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod material;
#[cfg(not(feature = "testing"))]
pub(crate) mod material;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod math;
#[cfg(not(feature = "testing"))]
pub(crate) mod math;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod sampling;
#[cfg(not(feature = "testing"))]
pub(crate) mod sampling;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod sensor;
#[cfg(not(feature = "testing"))]
pub(crate) mod sensor;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod texture;
#[cfg(not(feature = "testing"))]
pub(crate) mod texture;

#[cfg(any(test, feature = "testing"))]
#[doc(hidden)]
pub mod testing;

pub use error::{Error, ErrorKind, Result};
pub use integrator::{Capabilities, Integrator, MisHeuristic};
pub use light::report;
pub use sampling::SamplerKind;
pub use sensor::meter::{Meter, MeterKind};
