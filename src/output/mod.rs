//! Writing results: EXR images (only `exr.rs` names the exr crate), PNG previews,
//! illuminance maps and JSON documents (only `json.rs` names serde_json).

#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod atomic;
#[cfg(not(feature = "testing"))]
pub(crate) mod atomic;
pub mod exr;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod json;
#[cfg(not(feature = "testing"))]
pub(crate) mod json;
pub mod map;
pub mod png;
pub mod target;
