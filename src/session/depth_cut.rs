//! What a run's depth cap cut (`integrator::cut`): the fraction of the image's mean luminance,
//! or of a reading, carried by paths longer than the cap, with its 95 % interval. A run
//! reports one whenever a path reached the cap — the user's `max_depth`, or the safety cap
//! `SAFETY_DEPTH` of an unlimited run.

use crate::math::ratio::RatioSums;

/// The cut of a depth cap that was reached.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthCut {
    /// The cap (scattering events).
    pub max_depth: u32,
    /// The user's cap; false for the safety cap of an unlimited run.
    pub user: bool,
    /// Paths (for bidirectional integrators: subpaths) that reached it.
    pub capped: u64,
    /// The estimated fraction of the uncapped answer that the cap cut: cut / (capped + cut).
    pub fraction: f64,
    /// The 95 % half-width of `fraction`.
    pub ci95: f64,
    /// Some continuations reached their own limit (the cap plus `SAFETY_DEPTH`), so the
    /// fraction is a lower bound.
    pub lower_bound: bool,
}

impl DepthCut {
    /// The report from the paired sums `sums` (cut, capped + cut), or None when no path
    /// reached the cap; `max_depth` as the options give it (None: the safety cap).
    pub(crate) fn new(
        max_depth: Option<u32>,
        sums: &RatioSums,
        capped: u64,
        limited: u64,
    ) -> Option<DepthCut> {
        (capped > 0).then(|| DepthCut {
            max_depth: crate::integrator::cut::depth_cap(max_depth),
            user: max_depth.is_some(),
            capped,
            fraction: sums.ratio(),
            ci95: sums.ci95(),
            lower_bound: limited > 0,
        })
    }
}
