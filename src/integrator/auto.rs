//! The static half of `--integrator auto`: from the scene analysis (`scene::analysis`), the
//! integrators worth a pilot, with the reasons. The pilot that measures them and picks one is
//! `session::auto`.
//!
//! | the scene | candidates |
//! |---|---|
//! | no lights | path (the answer is 0 whatever the integrator) |
//! | partially opaque surfaces | path (bdpt and vcm treat them as opaque) |
//! | caustics of point-like lights on diffuse surfaces, seen through specular surfaces (SDS) on ≥ 10 % of the view, or reaching a meter | vcm (only merging samples them) |
//! | caustics of point-like lights on diffuse surfaces, seen directly (L S+ D), or through specular surfaces on < 10 % of the view | vcm, bdpt |
//! | otherwise (no specular chains, large lights behind them, or near-specular receivers) | path, bdpt |
//!
//! Path tracing finds a caustic on a diffuse surface only by a BSDF-sampled ray hitting the
//! light after the specular surfaces: never behind a point light, and behind a point-like lamp
//! of some size (under
//! [`POINT_LIKE_SHARE`](crate::scene::analysis::lights::POINT_LIKE_SHARE) of the hemisphere) with a probability of the
//! order of the lamp's solid angle, each hit then carrying the caustic over that probability.
//! Its variance there is in these rare, enormous samples, which a pilot of a few samples per
//! pixel mostly does not draw: it then measures path's variance without them, far below its
//! expectation, and picks path. So path is no candidate there (`SceneFeatures::hard_caustics`).
//! Measured on `scenes/caustic.usda` (a 3 cm lamp, 0.018 % of the hemisphere; 96×72, 32 spp,
//! 8 seeds, one thread, without the lamp's glints through the ball): path's mean MSE × CPU
//! time is 136× vcm's and bdpt's 8.2×, yet path's 2-spp pilot won at all 8 seeds (docs/design.md,
//! "The pilot against the best fixed integrator"). On a near-specular receiver the narrow lobe
//! aims at the light and path tracing is the efficient one (`scenes/prism.usda`).
//! Likewise bdpt cannot connect to a specular vertex, so an SDS path from a point-like light
//! is out of its reach, as is light reaching a meter (a point) through glass; only vcm's
//! merges sample them. Where such paths cover only a small part of the view, the rest of the
//! image (caustics seen directly, diffuse light) decides, and bdpt joins the pilot
//! ([`SDS_DECIDES`]).

use super::vcm::VcmParams;
use super::{Integrator, MisHeuristic};
use crate::scene::SceneFeatures;

/// What the integrator will estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    Image,
    Meters,
}

/// The integrators a pilot compares, in the static analysis's order of preference, and why:
/// the first is kept unless the pilot finds a later one more efficient
/// (`session::auto::shown_ahead`).
#[derive(Clone, Debug, PartialEq)]
pub struct Candidates {
    pub integrators: Vec<Integrator>,
    pub reasons: Vec<String>,
    /// Whether a later candidate must be *shown* more efficient, its pilot's 95 % interval
    /// above the preference, rather than estimated so: where the first is the robust one and
    /// choosing a later one wrongly costs far more than keeping the first wrongly (vcm before
    /// bdpt for point-like caustics, [`point_like_caustics`]). Otherwise the candidates come in
    /// order of simplicity, a wrong choice either way costs alike (path against bdpt: 2.8× on
    /// `scenes/gap.usda` one way, 2.3× on `scenes/prism.usda` the other), and the pilot's
    /// point estimate decides.
    pub proof: bool,
}

/// The candidates for `target` in a scene with features `f`; bdpt and vcm get `mis`.
pub fn candidates(f: &SceneFeatures, target: Target, mis: MisHeuristic) -> Candidates {
    let path = Integrator::Path;
    let bdpt = Integrator::Bdpt { mis };
    let vcm = Integrator::Vcm(VcmParams {
        mis,
        ..VcmParams::default()
    });
    let proof = f.hard_caustics && !f.lights.is_empty() && !f.opacity.on;
    let (integrators, reason) = if f.lights.is_empty() {
        (
            vec![path],
            "no lights: the answer is 0 whatever the integrator".to_string(),
        )
    } else if f.opacity.on {
        (
            vec![path],
            "partially opaque surfaces: only path renders them (bdpt and vcm treat them as \
             opaque)"
                .to_string(),
        )
    } else if f.hard_caustics {
        point_like_caustics(f, target, bdpt, vcm)
    } else if f.caustics.on && f.delta_lights.on {
        (
            vec![path, bdpt],
            "caustics of point-like lights fall on near-specular surfaces only, whose narrow \
             lobes aim BSDF sampling at the light: path or bdpt by the pilot"
                .to_string(),
        )
    } else if f.specular.on {
        (
            vec![path, bdpt],
            "specular chains, but no point-like light behind them: BSDF sampling finds their \
             light; path or bdpt by the pilot"
                .to_string(),
        )
    } else {
        (
            vec![path, bdpt],
            "no specular chains: path, or bdpt where the pilot finds light arriving by \
             indirect routes more efficiently"
                .to_string(),
        )
    };
    Candidates {
        integrators,
        reasons: vec![reason],
        proof,
    }
}

/// The share of the view seen through specular surfaces from which SDS caustics decide the
/// candidates: vcm alone. Below it, the rest of the image decides and bdpt joins the pilot.
/// Measured (equal time, `tools/equal_time.sh`, 160×120, depth 10): on
/// `scenes/caustic-mirror.usda` (45 % of the view in the mirror) vcm's MSE × time is 26×
/// lower than bdpt's, and a 2-spp pilot (whose few samples miss bdpt's SDS fireflies) picked
/// bdpt; on `scenes/caustic.usda` (4 % of the view through the ball) bdpt and vcm trade
/// places from seed to seed (vcm's MSE × time over bdpt's between 0.2 and 3.8 in five 20-s
/// runs), so neither is excluded. 10 % lies between; a rule of thumb, not a derived bound.
pub const SDS_DECIDES: f32 = 0.10;

/// Why path is no candidate for caustics of point-like lights (the module's header), and why
/// vcm comes first.
const BIDIRECTIONAL: &str = "light subpaths find them, while path tracing reaches them only \
     by rare hits on the light, whose variance a short pilot cannot see; vcm, unless the \
     pilot shows bdpt more efficient";

/// Caustics of point-like lights: vcm where only merging samples them, else vcm first and
/// bdpt if the pilot shows it ahead. vcm's MIS combination holds every one of bdpt's
/// strategies and adds merging (Georgiev et al. 2012, "Light transport simulation with
/// vertex connection and merging", §4), and a balance-heuristic combination is never much
/// worse than any one of its strategies (Veach 1997, Theorem 9.2): choosing vcm where bdpt
/// is better costs about their cost ratio (1.5 / 1.1, `session::auto::cost_per_ray`), while
/// choosing bdpt where vcm is better is unbounded (its SDS fireflies through the ball on
/// `scenes/caustic.usda`: bdpt's MSE × CPU time without the lamp's glints was 26.6× vcm's,
/// 95 % interval 1.4–73, over 16 seeds). A pilot of a few samples per pixel cannot tell them
/// apart reliably there (it chose bdpt at 6 of 16 seeds), so the burden of proof is on bdpt.
fn point_like_caustics(
    f: &SceneFeatures,
    target: Target,
    bdpt: Integrator,
    vcm: Integrator,
) -> (Vec<Integrator>, String) {
    match target {
        Target::Meters => (
            vec![vcm],
            "caustics of point-like lights: light reaching a meter through specular surfaces \
             is sampled only by vcm's merges"
                .to_string(),
        ),
        Target::Image if f.sds.on && f.seen_specular >= SDS_DECIDES => (
            vec![vcm],
            format!(
                "caustics of point-like lights seen through specular surfaces (SDS) on {:.0} % \
                 of the view: only vcm's merges sample them",
                100.0 * f.seen_specular
            ),
        ),
        Target::Image if f.sds.on => (
            vec![vcm, bdpt],
            format!(
                "caustics of point-like lights seen through specular surfaces (SDS) on only \
                 {:.0} % of the view, caustics seen directly elsewhere: {BIDIRECTIONAL}",
                100.0 * f.seen_specular
            ),
        ),
        Target::Image => (
            vec![vcm, bdpt],
            format!("caustics of point-like lights seen directly (L S+ D): {BIDIRECTIONAL}"),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::analysis::lights::LightInfo;
    use crate::scene::Feature;

    fn on() -> Feature {
        Feature {
            on: true,
            ..Default::default()
        }
    }

    fn lit() -> SceneFeatures {
        SceneFeatures {
            lights: vec![LightInfo {
                prim: "/L".into(),
                kind: "sphere",
                share: 1e-4,
                point_like: true,
                infinite: false,
                textured: false,
                shaped: false,
            }],
            ..Default::default()
        }
    }

    fn names(c: &Candidates) -> Vec<&'static str> {
        c.integrators.iter().map(|i| i.name()).collect()
    }

    #[test]
    fn the_table() {
        let mis = MisHeuristic::Power;
        let image = |f: &SceneFeatures| names(&candidates(f, Target::Image, mis));
        assert_eq!(image(&SceneFeatures::default()), ["path"]);
        let mut f = lit();
        assert_eq!(image(&f), ["path", "bdpt"]);
        f.specular = on();
        assert_eq!(image(&f), ["path", "bdpt"]);
        f.caustics = on();
        assert_eq!(image(&f), ["path", "bdpt"]);
        f.delta_lights = on();
        assert_eq!(image(&f), ["path", "bdpt"]);
        assert!(!candidates(&f, Target::Image, mis).proof);
        f.hard_caustics = true;
        assert_eq!(image(&f), ["vcm", "bdpt"]);
        assert!(candidates(&f, Target::Image, mis).proof);
        assert_eq!(names(&candidates(&f, Target::Meters, mis)), ["vcm"]);
        f.sds = on();
        f.seen_specular = 0.04;
        assert_eq!(image(&f), ["vcm", "bdpt"]);
        // Behind a point light path never finds the caustic.
        let mut point = f.clone();
        point.lights[0].share = 0.0;
        assert_eq!(image(&point), ["vcm", "bdpt"]);
        point.sds = Feature::default();
        assert_eq!(image(&point), ["vcm", "bdpt"]);
        f.seen_specular = SDS_DECIDES;
        assert_eq!(image(&f), ["vcm"]);
        f.opacity = on();
        assert_eq!(image(&f), ["path"]);
    }
}
