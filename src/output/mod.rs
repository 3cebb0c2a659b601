//! Writing results: EXR images (only `exr.rs` names the exr crate), PNG previews,
//! illuminance maps, JSON documents (only `json.rs` names serde_json), and the files of a
//! convergence report (`reference.rs`, `report.rs`, `plot.rs`, the only module naming
//! plotters).

#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod atomic;
#[cfg(not(feature = "testing"))]
pub(crate) mod atomic;
pub mod exr;
pub mod falsecolor;
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod json;
#[cfg(not(feature = "testing"))]
pub(crate) mod json;
pub mod layers;
pub mod map;
pub mod ocio;
pub mod plot;
pub mod png;
pub mod preview;
pub mod reference;
pub mod report;
pub mod rounding;
pub mod target;
