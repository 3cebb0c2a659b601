//! Ray acceleration structures. Only `bvh.rs` and `sah.rs` name obvhs.

pub mod bvh;
mod sah;
mod stack;
mod store;
