//! Ray acceleration structures. Only `bvh.rs` and `sah.rs` name obvhs; only `pages.rs` names
//! memmap2.

pub mod bvh;
mod pages;
mod sah;
mod stack;
