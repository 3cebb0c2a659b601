//! Writing results: EXR images (only `exr.rs` names the exr crate) and PNG previews.

pub mod atomic;
pub mod exr;
pub mod png;
