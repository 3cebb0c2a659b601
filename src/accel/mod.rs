//! Ray acceleration structures. Only `bvh.rs` names obvhs.

#[cfg(target_arch = "x86_64")]
mod avx;
pub mod bvh;
