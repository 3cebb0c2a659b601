//! Writing results: EXR images (only `exr.rs` names the exr crate), PNG previews,
//! illuminance maps and JSON documents (only `json.rs` names serde_json).

internal_modules!(atomic, json);
pub mod exr;
pub mod map;
pub mod png;
