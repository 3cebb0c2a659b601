//! Scenes: the USD reader (`usd/`, the only module naming openusd) producing the plain
//! description (`crate::desc`), the builder (`build.rs`) and the immutable render scene with
//! its ray queries (`render_scene.rs`, counted per thread by `ray_count.rs`), texture
//! footprints at hits (`texcoord.rs`), and what the stage calls for (`analysis/`).

pub mod analysis;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod build;
#[cfg(not(feature = "testing"))]
pub(crate) mod build;
mod limits;
pub mod machinery;
pub mod ray_count;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod render_scene;
#[cfg(not(feature = "testing"))]
pub(crate) mod render_scene;
mod texcoord;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod usd;
#[cfg(not(feature = "testing"))]
pub(crate) mod usd;

pub use analysis::{Feature, SceneFeatures};
pub use build::{build, build_with};
pub use machinery::Machinery;
pub use render_scene::{Hit, Scene, SurfaceHit};

use crate::error::Result;
use std::path::Path;

/// Reads a stage and builds the render scene; `resolution` overrides RenderSettings.
pub fn load(path: &Path, resolution: Option<(u32, u32)>) -> Result<Scene> {
    load_with(path, resolution, Machinery::default())
}

/// [`load`] with the pieces of `machinery` forced on where the scene does not need them.
pub fn load_with(
    path: &Path,
    resolution: Option<(u32, u32)>,
    machinery: Machinery,
) -> Result<Scene> {
    let desc = usd::load(path)?;
    build_with(&desc, resolution, machinery)
}
