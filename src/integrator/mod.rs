//! Light-transport integrators. All are spectral with the same hero-wavelength machinery.
//!
//! - [`Integrator`]: which algorithm, with its settings, its name and what it can do
//!   ([`Capabilities`]); the CLI and both drivers of `session` consult only this type;
//! - [`Estimator`]: one run of an integrator on a scene, one sample at a time, for images
//!   and for light meters (`estimator.rs`);
//! - `path`: unidirectional path tracing with NEE and MIS; `roulette`: its Russian roulette
//!   (`--rr-depth`); `meter`: its light-meter estimators;
//! - `light_tracer`: light (particle) tracing, splatting to the film;
//! - `bdpt`: bidirectional path tracing, every (s, t) technique with MIS;
//! - `vcm`: vertex connection and merging, BDPT plus merges with the iteration's light
//!   vertices;
//! - `bidir/`: what the bidirectional ones share (vertices, walks, MIS recurrences, the
//!   light vertex store and its hash grid);
//! - `auto`: the candidates of `--integrator auto` from the scene analysis (its pilot, which
//!   runs sessions, is `session::auto`).
//!
//! Adding an integrator: an arm of [`Integrator`] (its name, capabilities and estimator, all
//! in this file) and its own module implementing [`Estimator`].

pub mod auto;
pub mod bdpt;
pub mod bidir;
pub mod cut;
pub mod estimator;
pub(crate) mod gathered;
pub mod light_tracer;
pub mod meter;
pub mod path;
pub(crate) mod radiance_memo;
pub mod roulette;
pub mod roulette_pilot;
pub mod split;
pub mod vcm;

pub use bidir::{MisHeuristic, Workspace};
pub use estimator::{Estimator, Iteration, Settings};

use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::sensor::meter::MeterKind;
use vcm::{VcmMode, VcmParams};

/// A light-transport algorithm with its settings.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Integrator {
    /// Path tracing with next-event estimation and MIS (`path.rs`).
    #[default]
    Path,
    /// Light (particle) tracing: light subpaths connected to the sensor (`light_tracer.rs`).
    Light,
    /// Bidirectional path tracing, all (s, t) techniques combined by MIS (`bdpt.rs`).
    Bdpt { mis: MisHeuristic },
    /// Vertex connection and merging (`vcm.rs`): BDPT plus merges, consistent.
    Vcm(VcmParams),
    /// One of path, bdpt and vcm, chosen per scene: the analysis narrows the candidates
    /// (`auto.rs`), a short pilot measures their efficiency (`session::auto`). Resolved
    /// before a session runs; it has no estimator of its own.
    Auto { mis: MisHeuristic },
}

/// What an integrator can and cannot do. Every check and warning about an integrator's
/// limits reads this table ([`Integrator::check_meter`], [`Integrator::check_strategies`],
/// [`Integrator::warnings`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Capabilities {
    /// Illuminance meters (a point sensor with a cosine response).
    pub illuminance_meters: bool,
    /// Luminance meters: a delta in position and direction, which no light-subpath
    /// connection (t = 1) can reach.
    pub luminance_meters: bool,
    /// Partially opaque surfaces (UsdPreviewSurface `opacity`) rendered as such; otherwise
    /// they are treated as opaque.
    pub partial_opacity: bool,
    /// Infinite lights (dome, distant) seen directly by the camera; light tracing cannot
    /// connect a point of theirs to the lens (pbrt-v4 and SmallVCM neither).
    pub infinite_lights_seen_directly: bool,
    /// The per-(s, t) strategy images of `--strategies`.
    pub strategy_images: bool,
    /// Contributions land on other pixels than the sample's own (light subpaths splat).
    pub splats: bool,
    /// The estimate's expectation is the answer at any sample count; otherwise it is
    /// consistent (VCM's merges: the bias vanishes as the iterations shrink the radius).
    pub unbiased: bool,
    /// The MIS heuristic is a setting (`--mis`).
    pub mis_heuristic: bool,
}

impl Integrator {
    /// Every integrator, with default settings, in the order the CLI lists them.
    pub const ALL: [Integrator; 5] = [
        Integrator::Path,
        Integrator::Light,
        Integrator::Bdpt {
            mis: MisHeuristic::Power,
        },
        Integrator::Vcm(VcmParams {
            mis: MisHeuristic::Power,
            mode: VcmMode::Vcm,
            radius: None,
            alpha: vcm::DEFAULT_ALPHA,
            meter_light_paths: vcm::DEFAULT_METER_LIGHT_PATHS,
            wavelengths: vcm::VcmWavelengths::PerIteration,
            merges: vcm::DEFAULT_MERGE_RULE,
        }),
        Integrator::Auto {
            mis: MisHeuristic::Power,
        },
    ];

    /// The estimator draws its camera path's numbers at fixed dimensions
    /// (`sampling::dimensions`), so the low-discrepancy sampler may feed it (`--sampler`):
    /// the path tracer, and BDPT's and VCM's camera subpaths, whose light subpaths, splats
    /// and continuations draw from the sample's independent stream
    /// (`Sampler::detached`, `Sampler::fork`). Light tracing draws only numbers whose count
    /// varies and keeps the independent sampler.
    pub fn low_discrepancy(&self) -> bool {
        matches!(
            self,
            Integrator::Path | Integrator::Bdpt { .. } | Integrator::Vcm(_)
        )
    }

    /// The name the CLI and the EXR metadata use.
    pub fn name(&self) -> &'static str {
        match self {
            Integrator::Path => "path",
            Integrator::Light => "light",
            Integrator::Bdpt { .. } => "bdpt",
            Integrator::Vcm(_) => "vcm",
            Integrator::Auto { .. } => "auto",
        }
    }

    /// One line of help for the CLI.
    pub fn help(&self) -> &'static str {
        match self {
            Integrator::Path => "path tracing with next-event estimation and MIS",
            Integrator::Light => "light tracing (light subpaths connected to the sensor)",
            Integrator::Bdpt { .. } => "bidirectional path tracing, all (s, t) with MIS",
            Integrator::Vcm(_) => "vertex connection and merging: BDPT plus merges (consistent)",
            Integrator::Auto { .. } => {
                "path, bdpt or vcm, chosen from the scene analysis and a short pilot (the default)"
            }
        }
    }

    /// The integrator named `name` with default settings.
    pub fn from_name(name: &str) -> Option<Integrator> {
        Integrator::ALL.into_iter().find(|i| i.name() == name)
    }

    /// The same integrator with MIS heuristic `mis` where it has one.
    pub fn with_mis(self, mis: MisHeuristic) -> Integrator {
        match self {
            Integrator::Bdpt { .. } => Integrator::Bdpt { mis },
            Integrator::Vcm(p) => Integrator::Vcm(VcmParams { mis, ..p }),
            Integrator::Auto { .. } => Integrator::Auto { mis },
            other => other,
        }
    }

    pub fn capabilities(&self) -> Capabilities {
        let bidirectional = Capabilities {
            illuminance_meters: true,
            luminance_meters: true,
            partial_opacity: false,
            infinite_lights_seen_directly: true,
            strategy_images: false,
            splats: true,
            mis_heuristic: false,
            unbiased: true,
        };
        match self {
            Integrator::Path => Capabilities {
                partial_opacity: true,
                splats: false,
                ..bidirectional
            },
            Integrator::Light => Capabilities {
                luminance_meters: false,
                infinite_lights_seen_directly: false,
                ..bidirectional
            },
            Integrator::Bdpt { .. } => Capabilities {
                strategy_images: true,
                mis_heuristic: true,
                ..bidirectional
            },
            Integrator::Vcm(p) => Capabilities {
                mis_heuristic: true,
                unbiased: p.mode == VcmMode::Vc,
                ..bidirectional
            },
            // What the chosen one can do: partial opacity makes the choice path
            // (`auto.rs`), and vcm may be chosen.
            Integrator::Auto { .. } => Capabilities {
                partial_opacity: true,
                splats: false,
                mis_heuristic: true,
                unbiased: false,
                ..bidirectional
            },
        }
    }

    /// Refuses a meter kind the integrator cannot estimate.
    pub fn check_meter(&self, kind: MeterKind) -> Result<()> {
        let caps = self.capabilities();
        let ok = match kind {
            MeterKind::Illuminance => caps.illuminance_meters,
            MeterKind::Luminance => caps.luminance_meters,
        };
        if ok {
            return Ok(());
        }
        let others = Integrator::names_with(|c| match kind {
            MeterKind::Illuminance => c.illuminance_meters,
            MeterKind::Luminance => c.luminance_meters,
        });
        Err(Error::option(match kind {
            MeterKind::Luminance => format!(
                "a luminance meter is a delta sensor (one point, one direction) that {} can \
                 never connect to; use --integrator {others}",
                self.long_name()
            ),
            MeterKind::Illuminance => format!(
                "--integrator {} cannot estimate illuminance; use --integrator {others}",
                self.name()
            ),
        }))
    }

    /// The number of strategy images for `max_depth` (None: unlimited), or why there are
    /// none.
    pub fn check_strategies(&self, max_depth: Option<u32>) -> Result<usize> {
        if !self.capabilities().strategy_images {
            let others = Integrator::names_with(|c| c.strategy_images);
            return Err(Error::option(format!(
                "strategy images need --integrator {others}"
            )));
        }
        match max_depth {
            Some(d) if d <= bidir::strategies::MAX_DEPTH => Ok(bidir::strategies::count(d)),
            Some(_) => Err(Error::option(format!(
                "strategy images need --max-depth {} or less",
                bidir::strategies::MAX_DEPTH
            ))),
            None => Err(Error::option(format!(
                "strategy images need --max-depth {} or less (one image per technique and \
                 depth; the default depth is unlimited)",
                bidir::strategies::MAX_DEPTH
            ))),
        }
    }

    /// What this integrator will not render in `scene` as the scene describes it, one line
    /// each (`images`: for an image rather than meters).
    pub fn warnings(&self, scene: &Scene, images: bool) -> Vec<String> {
        let caps = self.capabilities();
        let mut out = Vec::new();
        if !caps.partial_opacity && !scene.all_opaque {
            out.push(format!(
                "--integrator {} treats partially opaque surfaces (UsdPreviewSurface opacity) \
                 as opaque; use --integrator {} for cutouts",
                self.name(),
                Integrator::names_with(|c| c.partial_opacity)
            ));
        }
        if images && !caps.infinite_lights_seen_directly && !scene.infinite_lights.is_empty() {
            out.push(format!(
                "--integrator {} does not show dome or distant lights seen directly (only what \
                 they light); use --integrator {} to see them",
                self.name(),
                Integrator::names_with(|c| c.infinite_lights_seen_directly)
            ));
        }
        // Light subpaths carry light through occluders only by bouncing around them; a
        // shadowless light is a next-event notion, which only path tracing has alone.
        if !matches!(self, Integrator::Path) && !scene.shadowless.is_empty() {
            let names: Vec<&str> = scene
                .shadowless
                .iter()
                .map(|&i| scene.lights[i as usize].prim_path())
                .collect();
            out.push(format!(
                "--integrator {} renders the shadows of {} (inputs:shadow:enable = 0 is \
                 honoured by --integrator path only)",
                self.name(),
                names.join(", ")
            ));
        }
        out
    }

    /// A run of this integrator on `scene`; `Auto` has none (the sessions resolve it to a
    /// concrete integrator first, `session::auto`).
    pub fn estimator<'a>(
        &self,
        scene: &'a Scene,
        settings: Settings,
    ) -> Result<Box<dyn Estimator + 'a>> {
        Ok(match *self {
            Integrator::Path => Box::new(path::PathEstimator::new(scene, settings)),
            Integrator::Light => Box::new(light_tracer::LightEstimator::new(scene, settings)),
            Integrator::Bdpt { mis } => Box::new(bdpt::BdptEstimator::new(scene, settings, mis)),
            // `vc` is BDPT, the same estimator.
            Integrator::Vcm(p) if p.mode == VcmMode::Vc => {
                Box::new(bdpt::BdptEstimator::new(scene, settings, p.mis))
            }
            Integrator::Vcm(p) => Box::new(vcm::VcmEstimator::new(scene, settings, p)),
            Integrator::Auto { .. } => {
                return Err(Error::option(
                    "--integrator auto has no estimator of its own: it is resolved to path, \
                     bdpt or vcm before a run (session::auto)",
                ))
            }
        })
    }

    fn long_name(&self) -> &'static str {
        match self {
            Integrator::Path => "path tracing",
            Integrator::Light => "light tracing",
            Integrator::Bdpt { .. } => "bidirectional path tracing",
            Integrator::Vcm(_) => "vertex connection and merging",
            Integrator::Auto { .. } => "the integrator auto chooses",
        }
    }

    /// The names of the concrete integrators (not `auto`) that have capability `has`, as
    /// "a or b".
    pub fn names_with(has: impl Fn(&Capabilities) -> bool) -> String {
        let names: Vec<&str> = Integrator::ALL
            .iter()
            .filter(|i| !matches!(i, Integrator::Auto { .. }) && has(&i.capabilities()))
            .map(|i| i.name())
            .collect();
        names.join(" or ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for i in Integrator::ALL {
            assert_eq!(Integrator::from_name(i.name()), Some(i));
        }
        assert_eq!(Integrator::from_name("magic"), None);
        assert!(matches!(
            Integrator::from_name("auto"),
            Some(Integrator::Auto { .. })
        ));
    }

    #[test]
    fn light_tracing_refuses_luminance_meters_only() {
        let lt = Integrator::Light;
        assert!(lt.check_meter(MeterKind::Illuminance).is_ok());
        let e = lt
            .check_meter(MeterKind::Luminance)
            .unwrap_err()
            .to_string();
        assert!(e.contains("use --integrator path or bdpt"), "{e}");
        for i in [Integrator::Path, Integrator::ALL[2], Integrator::ALL[3]] {
            assert!(i.check_meter(MeterKind::Luminance).is_ok());
        }
    }

    #[test]
    fn strategy_images_are_bdpt_only() {
        assert!(Integrator::Path.check_strategies(Some(5)).is_err());
        let bdpt = Integrator::ALL[2];
        assert_eq!(bdpt.check_strategies(Some(2)).unwrap(), 9);
        assert!(bdpt
            .check_strategies(Some(bidir::strategies::MAX_DEPTH + 1))
            .is_err());
        assert!(bdpt.check_strategies(None).is_err());
    }

    #[test]
    fn mis_is_a_setting_of_bdpt_only() {
        let b = Integrator::ALL[2].with_mis(MisHeuristic::Balance);
        assert_eq!(
            b,
            Integrator::Bdpt {
                mis: MisHeuristic::Balance
            }
        );
        assert_eq!(
            Integrator::Path.with_mis(MisHeuristic::Balance),
            Integrator::Path
        );
        assert!(b.capabilities().mis_heuristic && !Integrator::Light.capabilities().mis_heuristic);
    }
}
