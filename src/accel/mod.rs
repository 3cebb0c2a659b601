//! Ray acceleration structures. Only `bvh.rs` names obvhs.

pub mod bvh;
mod stack;
