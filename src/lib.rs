//! spectral-render: a spectral, physically based renderer for USD stages whose images and
//! light-meter readings are in absolute photometric units. See `ARCHITECTURE.md`.
//!
//! A stage is read into a [`scene::Scene`], rendered into absolute XYZ and Rec.709 RGB, and the
//! result is in cd/m². Here a grey card lit by a uniform dome of 100 nits is seen head-on; a
//! Lambertian card of albedo 0.18 under a uniform dome of luminance L has luminance 0.18·L:
//!
//! ```
//! use spectral_render::{render, scene};
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
//! std::fs::write(&path, stage).unwrap();
//!
//! let scene = scene::load(&path, Some((8, 8))).unwrap();
//! let options = render::RenderOptions { spp: Some(64), ..Default::default() };
//! let image = render::render(&scene, &options).unwrap();
//!
//! // Unbound meshes get a 0.18 grey Lambertian: luminance 0.18 × 100 cd/m².
//! let mean_y: f32 = image.xyz.iter().map(|p| p[1]).sum::<f32>() / image.xyz.len() as f32;
//! assert!((mean_y - 18.0).abs() < 0.5, "{mean_y}");
//! # std::fs::remove_file(&path).ok();
//! ```

pub mod accel;
pub mod bxdf;
pub mod cli;
pub mod error;
pub mod geometry;
pub mod imageio;
pub mod integrator;
pub mod light;
pub mod material;
pub mod math;
pub mod output;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod sensor;
pub mod spectral;
pub mod texture;

pub use error::{Error, Result};
