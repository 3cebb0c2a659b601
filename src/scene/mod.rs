//! Scenes: the USD reader (`usd.rs`, the only module naming openusd), the plain description
//! (`desc.rs`) and the builder (`build.rs`) that turns it into the immutable render scene.

pub mod desc;
pub mod usd;
