//! Scenes: the USD reader (`usd.rs`, the only module naming openusd), the plain description
//! (`desc.rs`), the builder (`build.rs`) and the immutable render scene with its ray queries
//! (`render_scene.rs`), and texture footprints at hits (`texcoord.rs`).

pub mod build;
pub mod desc;
pub mod render_scene;
mod texcoord;
pub mod usd;

pub use build::build;
pub use render_scene::{Hit, Scene, SurfaceHit};

use crate::Result;
use std::path::Path;

/// Reads a stage and builds the render scene; `resolution` overrides RenderSettings.
pub fn load(path: &Path, resolution: Option<(u32, u32)>) -> Result<Scene> {
    let desc = usd::load(path)?;
    build(&desc, resolution)
}
