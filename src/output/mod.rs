//! Writing results: EXR images (only `exr.rs` names the exr crate), PNG previews and
//! illuminance maps.

pub mod atomic;
pub mod exr;
pub mod map;
pub mod png;
