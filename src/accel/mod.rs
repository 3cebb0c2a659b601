//! Ray acceleration structures. Only `bvh.rs` names obvhs (its binary BVH builder);
//! `collapse.rs` makes the 8-wide tree from it, `leaf4.rs` holds the four-triangle leaves.

pub mod bvh;
mod collapse;
mod leaf4;
mod stack;
