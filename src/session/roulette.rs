//! Where an image's path tracer starts Russian roulette and how many continuations its paths
//! split into at their first vertex: `--rr-depth auto` and `--split auto` (the defaults)
//! resolved together by the pilot of `integrator::roulette_pilot` before the first sample, a
//! given start or split kept as it is. The other integrators keep their own rule.
//!
//! The pilot depends on the stage, the resolution, the depth cap and the seed only (its
//! textures are looked up at their finest level, whatever the render's filtering), so a
//! resumed checkpoint, every part of a split render and their merge resolve it alike.

use crate::integrator::roulette::RrStart;
use crate::integrator::roulette_pilot::{self, Fixed};
use crate::integrator::split::Split;
use crate::integrator::Integrator;
use crate::scene::Scene;
use crate::texture::TextureFilter;

/// The roulette and splitting an image's path tracer runs with.
#[derive(Clone, Debug, PartialEq)]
pub struct Roulette {
    /// The first scattering event after which roulette may end a path.
    pub start: u32,
    /// The continuations a path splits into at its first vertex (`integrator::split`).
    pub split: u32,
    /// What the pilot chose and why, for the log; None when the user gave both.
    pub report: Option<String>,
}

/// The roulette and splitting of an image of `scene` by `integrator` capped at `cap`
/// scattering events, with `rr`, `split` and `seed`; None when the integrator is not the path
/// tracer. The pilot runs on the current rayon pool when either is `auto`.
pub fn resolve(
    scene: &Scene,
    integrator: &Integrator,
    (rr, split): (RrStart, Split),
    cap: u32,
    seed: u64,
) -> Option<Roulette> {
    if *integrator != Integrator::Path {
        return None;
    }
    let fixed = Fixed {
        start: match rr {
            RrStart::At(s) => Some(s),
            RrStart::Auto => None,
        },
        split: match split {
            Split::At(n) => Some(n),
            Split::Auto => None,
        },
    };
    if let (Some(start), Some(split)) = (fixed.start, fixed.split) {
        return Some(Roulette {
            start,
            split,
            report: None,
        });
    }
    let (start, split) = fixed.reference();
    Some(
        match roulette_pilot::choose(scene, cap, TextureFilter::Finest, seed, fixed) {
            Some(c) => Roulette {
                start: c.start,
                split: c.split,
                report: Some(c.describe()),
            },
            None => Roulette {
                start,
                split,
                report: Some(format!(
                    "Russian roulette from bounce {start}, {} (the pilot found no light to \
                     choose by)",
                    match split {
                        1 => "paths not split".to_string(),
                        n => format!("paths split in {n}"),
                    }
                )),
            },
        },
    )
}
