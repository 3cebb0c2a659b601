//! Scenes: the USD reader (`usd/`, the only module naming openusd) producing the plain
//! description (`crate::desc`), the builder (`build.rs`) and the immutable render scene with
//! its ray queries (`render_scene.rs`, over the primitives of `prim.rs`, counted per thread by `ray_count.rs`), texture
//! footprints at hits (`texcoord.rs`), and what the stage calls for (`analysis/`).

pub mod analysis;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod build;
#[cfg(not(feature = "testing"))]
pub(crate) mod build;
pub mod emission_layers;
mod limits;
pub mod machinery;
mod prim;
pub mod ray_count;
mod rebuild;
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
pub use rebuild::{Rebuilder, Rebuilt};
pub use render_scene::{Hit, Scene, SurfaceHit};

use crate::error::Result;
use std::path::Path;

pub use usd::{OpenStage, ReadTime};

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
    load_at(path, resolution, machinery, ReadTime::default())
}

/// [`load_with`] at a time code: every attribute is evaluated at `time`.
pub fn load_at(
    path: &Path,
    resolution: Option<(u32, u32)>,
    machinery: Machinery,
    time: ReadTime,
) -> Result<Scene> {
    build_with(&usd::open(path)?.read(time)?, resolution, machinery)
}

/// Opens a stage once to read it at several times ([`OpenStage::read`], then [`build_with`]).
pub fn open(path: &Path) -> Result<OpenStage> {
    usd::open(path)
}
