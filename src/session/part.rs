//! Partial renders and their exact merge (`--part K/N`, `spectral-render merge`).
//!
//! Part K of N renders samples [K·spp/N, (K+1)·spp/N) of every pixel, with the random numbers
//! the whole render gives them (the sampler is keyed by seed, pixel and sample index), and
//! saves its film's raw state in the checkpoint format (`session::checkpoint`) under the
//! render's identity plus [`PART_KEY`]. The film sums every term on a fixed grid as integers
//! (`sensor::grid_sum`), so the parts' films added in any grouping are the single render's
//! film bit for bit, for every integrator: the own-pixel sums, the splats of light tracing
//! and BDPT, and VCM, whose iterations are one sample per pixel, so a part is a range of
//! iterations. [`merge`] checks that the parts belong together and are complete.

use super::checkpoint::{self, Checkpoint};
use super::RenderOptions;
use crate::error::Reason;
use crate::integrator::cut::BatchedRatio;
use crate::integrator::{Integrator, MisHeuristic};
use crate::scene::Scene;
use crate::sensor::film::Film;

/// The identity key naming a part, `K/N`.
pub const PART_KEY: &str = "part";
/// The identity key of the stage file as the user named it (informative: parts of the same
/// stage content rendered from another path still merge).
pub const STAGE_FILE_KEY: &str = "stage file";

/// Part `index` of `count` (0 ≤ index < count).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Part {
    pub index: u64,
    pub count: u64,
}

impl Part {
    /// `K/N` with 0 ≤ K < N.
    pub fn parse(s: &str) -> Reason<Part> {
        let (k, n) = s
            .split_once('/')
            .ok_or_else(|| format!("'{s}' is not K/N (e.g. 0/4)"))?;
        let num = |v: &str| {
            v.trim()
                .parse::<u64>()
                .map_err(|_| format!("'{s}': '{v}' is not a whole number of at least 0"))
        };
        let (index, count) = (num(k)?, num(n)?);
        if count == 0 || index >= count {
            return Err(format!("'{s}': K must be in 0..N and N at least 1"));
        }
        Ok(Part { index, count })
    }

    /// The samples [first, end) of every pixel this part renders of a render of `spp`.
    pub fn samples(&self, spp: u64) -> (u64, u64) {
        let at = |k: u64| (u128::from(k) * u128::from(spp) / u128::from(self.count)) as u64;
        (at(self.index), at(self.index + 1))
    }

    pub fn label(&self) -> String {
        format!("{}/{}", self.index, self.count)
    }
}

/// The identity keys of the integrator's name and MIS heuristic (for the merged EXR's
/// metadata).
pub const INTEGRATOR_NAME_KEY: &str = "integrator name";
pub const MIS_KEY: &str = "mis";

/// A part's identity: the render's (`checkpoint::identity`), the integrator's name and MIS
/// heuristic, the stage file and the part.
pub fn identity(
    scene: &Scene,
    opts: &RenderOptions,
    stage_file: &str,
    part: Part,
) -> Vec<(String, String)> {
    let mut id = checkpoint::identity(scene, opts);
    id.push((INTEGRATOR_NAME_KEY.into(), opts.integrator.name().into()));
    let mis = match opts.integrator {
        Integrator::Bdpt { mis } | Integrator::Auto { mis } => Some(mis),
        Integrator::Vcm(p) => Some(p.mis),
        Integrator::Path | Integrator::Light => None,
    };
    id.push((MIS_KEY.into(), mis.map_or("none", |m| m.name()).into()));
    id.push((STAGE_FILE_KEY.into(), stage_file.into()));
    id.push((PART_KEY.into(), part.label()));
    id
}

/// The integrator a part's identity names (its name and MIS heuristic; other settings at
/// their defaults: what the EXR's metadata records).
pub fn integrator(identity: &[(String, String)]) -> Option<Integrator> {
    let integrator = Integrator::from_name(value(identity, INTEGRATOR_NAME_KEY)?)?;
    let mis = value(identity, MIS_KEY)?;
    Some(
        match [MisHeuristic::Power, MisHeuristic::Balance]
            .into_iter()
            .find(|m| m.name() == mis)
        {
            Some(m) => integrator.with_mis(m),
            None => integrator,
        },
    )
}

/// The value of `key` in an identity.
pub fn value<'a>(identity: &'a [(String, String)], key: &str) -> Option<&'a str> {
    identity
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
}

/// Parts merged: the whole render's film and what the parts report, summed.
pub struct Merged {
    pub film: Film,
    /// The first part's identity without its part (the render's).
    pub identity: Vec<(String, String)>,
    pub samples: u64,
    pub dropped: u64,
    /// The parts' wall-clock times added (the CPU time of the render, as a farm sees it).
    pub wall_time_s: f64,
    pub depth_cut: BatchedRatio,
}

/// Merges `parts` (in any order given; merged in part order) after checking that they are
/// parts of one render (same identity but the part), each rendered whole, none missing and
/// none twice. An error names the index of the part at fault, when there is one.
pub fn merge(parts: &[Checkpoint]) -> Result<Merged, (Option<usize>, String)> {
    let mut labelled = Vec::new();
    for (i, c) in parts.iter().enumerate() {
        let part = value(&c.identity, PART_KEY)
            .ok_or("not a part of a render (no --part; a checkpoint?)".to_string())
            .and_then(Part::parse)
            .map_err(|e| (Some(i), e))?;
        labelled.push((part, i));
    }
    let Some(&(first, i0)) = labelled.first() else {
        return Err((None, "no parts given".into()));
    };
    let render = |c: &Checkpoint| -> Vec<(String, String)> {
        c.identity
            .iter()
            .filter(|(k, _)| k != PART_KEY && k != STAGE_FILE_KEY)
            .cloned()
            .collect()
    };
    let expected = render(&parts[i0]);
    for &(part, i) in &labelled {
        if part.count != first.count {
            return Err((
                Some(i),
                format!(
                    "part {} of a split into {}, not {} as the first part's",
                    part.label(),
                    part.count,
                    first.count
                ),
            ));
        }
        let mut c = parts[i].clone();
        c.identity = render(&parts[i]);
        c.check_identity(&expected).map_err(|e| {
            (
                Some(i),
                e.replace("the checkpoint is of another run", "another render")
                    .replace(" here", " in the first part"),
            )
        })?;
    }
    labelled.sort_by_key(|&(p, _)| p.index);
    for w in labelled.windows(2) {
        if w[0].0 == w[1].0 {
            return Err((Some(w[1].1), format!("part {} given twice", w[1].0.label())));
        }
    }
    let missing: Vec<String> = (0..first.count)
        .filter(|k| !labelled.iter().any(|(p, _)| p.index == *k))
        .map(|k| format!("{k}/{}", first.count))
        .collect();
    if !missing.is_empty() {
        return Err((None, format!("missing part {}", missing.join(", "))));
    }
    let spp: u64 = value(&expected, "spp")
        .and_then(|s| s.parse().ok())
        .ok_or((
            Some(i0),
            "the parts' render has no sample count".to_string(),
        ))?;
    let mut merged: Option<Merged> = None;
    for &(part, i) in &labelled {
        let c = &parts[i];
        let (a, b) = part.samples(spp);
        if c.samples != b - a {
            return Err((
                Some(i),
                format!(
                    "part {} holds {} of its {} samples per pixel (interrupted?)",
                    part.label(),
                    c.samples,
                    b - a
                ),
            ));
        }
        let fail = |e: String| (Some(i), e);
        match &mut merged {
            None => {
                merged = Some(Merged {
                    film: Film::from_state(c.film.clone()).map_err(fail)?,
                    identity: expected.clone(),
                    samples: c.samples,
                    dropped: c.dropped,
                    wall_time_s: c.wall_time_s,
                    depth_cut: c.depth_cut,
                })
            }
            Some(m) => {
                m.film.merge(&c.film).map_err(fail)?;
                m.samples += c.samples;
                m.dropped += c.dropped;
                m.wall_time_s += c.wall_time_s;
                m.depth_cut.merge(&c.depth_cut);
            }
        }
    }
    Ok(merged.expect("at least one part"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_cover_the_samples_once() {
        for (spp, n) in [(64, 1), (10, 3), (7, 4), (3, 5)] {
            let mut next = 0;
            for k in 0..n {
                let (a, b) = Part { index: k, count: n }.samples(spp);
                assert_eq!(a, next);
                assert!(b >= a);
                next = b;
            }
            assert_eq!(next, spp);
        }
        assert_eq!(Part::parse("2/5"), Ok(Part { index: 2, count: 5 }));
        for bad in ["5/5", "1/0", "-1/3", "3", "a/b"] {
            assert!(Part::parse(bad).is_err(), "{bad}");
        }
    }
}
