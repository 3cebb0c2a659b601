//! Scenes: the USD reader (`usd/`, the only module naming openusd) producing the plain
//! description (`crate::desc`), the builder (`build.rs`) and the immutable render scene with
//! its ray queries (`render_scene.rs`), and texture footprints at hits (`texcoord.rs`).

#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod build;
#[cfg(not(feature = "testing"))]
pub(crate) mod build;
mod limits;
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

pub use build::build;
pub use render_scene::{Hit, Scene, SurfaceHit};

use crate::error::Result;
use std::path::Path;

pub use usd::{OpenStage, ReadTime};

/// Reads a stage and builds the render scene; `resolution` overrides RenderSettings.
pub fn load(path: &Path, resolution: Option<(u32, u32)>) -> Result<Scene> {
    load_at(path, resolution, ReadTime::default())
}

/// [`load`] at a time code: every attribute is evaluated at `time`.
pub fn load_at(path: &Path, resolution: Option<(u32, u32)>, time: ReadTime) -> Result<Scene> {
    build(&usd::open(path)?.read(time)?, resolution)
}

/// Opens a stage once to read it at several times ([`OpenStage::read`], then [`build`]).
pub fn open(path: &Path) -> Result<OpenStage> {
    usd::open(path)
}
