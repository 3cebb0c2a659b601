//! Where an image's path tracer starts Russian roulette: `--rr-depth auto` (the default)
//! resolved by the pilot of `integrator::roulette_pilot` before the first sample, a given
//! start kept as it is. The other integrators keep their own rule.
//!
//! The pilot depends on the stage, the resolution, the depth cap and the seed only (its
//! textures are looked up at their finest level, whatever the render's filtering), so a
//! resumed checkpoint, every part of a split render and their merge resolve it alike.

use crate::integrator::roulette::{RrStart, DEFAULT_RR_DEPTH};
use crate::integrator::roulette_pilot;
use crate::integrator::Integrator;
use crate::scene::Scene;
use crate::texture::TextureFilter;

/// The roulette an image's path tracer runs with.
#[derive(Clone, Debug, PartialEq)]
pub struct Roulette {
    /// The first scattering event after which roulette may end a path.
    pub start: u32,
    /// What the pilot chose and why, for the log; None for a start the user gave.
    pub report: Option<String>,
}

/// The roulette of an image of `scene` by `integrator` capped at `cap` scattering events,
/// with `rr` and `seed`; None when the integrator is not the path tracer. The pilot runs on
/// the current rayon pool.
pub fn resolve(
    scene: &Scene,
    integrator: &Integrator,
    rr: RrStart,
    cap: u32,
    seed: u64,
) -> Option<Roulette> {
    if *integrator != Integrator::Path {
        return None;
    }
    let RrStart::At(start) = rr else {
        let choice = roulette_pilot::choose(scene, cap, TextureFilter::Finest, seed);
        return Some(match choice {
            Some(c) => Roulette {
                start: c.start,
                report: Some(c.describe(DEFAULT_RR_DEPTH)),
            },
            None => Roulette {
                start: DEFAULT_RR_DEPTH,
                report: Some(format!(
                    "Russian roulette from bounce {DEFAULT_RR_DEPTH} (the roulette pilot found \
                     no light to choose by)"
                )),
            },
        });
    };
    Some(Roulette {
        start,
        report: None,
    })
}
