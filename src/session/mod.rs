//! Progressive sessions: the one driver of images ([`ImageSession`], `image.rs`) and of light
//! meters ([`MeterSession`], `meter.rs`). Both are built from a scene and options naming an
//! [`Integrator`](crate::integrator::Integrator), own their worker threads (`pool.rs`), and
//! advance one *pass* per [`Progressive::step`], which returns the pass's [`PassStats`].
//! Sample counts, time budgets, relative-error targets, progress bars, snapshots and early
//! stops are all loops over `step()` ([`run`] with an [`Observer`]).
//!
//! Passes never change the answer: an image depends only on the seed and the sample count
//! (the film continues an open chunk across passes, `sensor::film`), and readings only on the
//! seed and each reading's sample count (blocks of fixed boundaries), whatever the pass sizes
//! and the number of threads.

pub mod adaptive;
pub mod auto;
pub mod checkpoint;
pub mod crop;
pub mod depth_cut;
pub mod emission_layers;
pub mod image;
pub mod layers;
pub mod memory;
pub mod meter;
pub mod part;
mod pool;
pub mod roulette;

pub use auto::{AutoReport, PilotFigures};
pub use depth_cut::DepthCut;
pub use image::{render, ImageSession, RenderOptions, RenderOutput, DEFAULT_SPP};
pub use meter::{measure, Cap, MeterOptions, MeterRun, MeterSession, Reading, Stop};

/// What one pass did and where the session stands.
#[derive(Clone, Debug, PartialEq)]
pub struct PassStats {
    /// Passes so far (1 after the first).
    pub pass: u32,
    /// Samples so far: per pixel for an image, over all readings for meters.
    pub samples: u64,
    /// The sample count the session is heading for, when it is known in advance (`--spp`).
    pub target: Option<u64>,
    /// Wall-clock seconds since the session started.
    pub wall_time_s: f64,
    /// Samples whose estimate was NaN or infinite and were dropped so far (should be 0).
    pub dropped: u64,
    /// The estimated variance of each estimate: per pixel of the image's luminance Y in
    /// (cd/m²)² (camera exposure applied), or per reading in its unit squared; infinite where
    /// fewer than 2 samples were taken.
    pub variance: Vec<f64>,
}

/// Something that advances in passes.
pub trait Progressive {
    /// Renders or measures one more pass and returns its statistics; `None` once the target
    /// (sample count, time budget, relative error) is reached and nothing was done.
    fn step(&mut self) -> Option<PassStats>;
}

/// Whether a loop over passes goes on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    Continue,
    Stop,
}

/// Sees every pass of [`run`]: a progress bar, a snapshot writer, an interrupt check.
pub trait Observer {
    fn pass(&mut self, stats: &PassStats) -> Control;
}

impl<F: FnMut(&PassStats) -> Control> Observer for F {
    fn pass(&mut self, stats: &PassStats) -> Control {
        self(stats)
    }
}

/// Steps `session` until it is finished or `observer` stops it; the number of passes run.
pub fn run(session: &mut dyn Progressive, observer: &mut dyn Observer) -> u32 {
    let mut passes = 0;
    while let Some(stats) = session.step() {
        passes += 1;
        if observer.pass(&stats) == Control::Stop {
            break;
        }
    }
    passes
}

/// An observer that watches nothing.
pub fn quiet(_: &PassStats) -> Control {
    Control::Continue
}
