//! Partial renders and their exact merge (`--part K/N`, `spectral-render merge`).
//!
//! Part K of N renders samples [K·spp/N, (K+1)·spp/N) of every pixel, with the random numbers
//! the whole render gives them (the sampler is keyed by seed, pixel and sample index), and
//! saves its film's raw state in the checkpoint format (`session::checkpoint`) under the
//! render's identity plus [`PART_KEY`]. The film sums every term on a fixed grid as integers
//! (`sensor::grid_sum`), so the parts' films added in any grouping are the single render's
//! film bit for bit, for every integrator: the own-pixel sums, the splats of light tracing
//! and BDPT, and VCM, whose iterations are one sample per pixel, so a part is a range of
//! iterations. [`check`] checks that the parts belong together and are complete, and [`add`]
//! adds them one by one.

use super::checkpoint::{self, Checkpoint};
use super::crop::Crop;
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
/// The identity key of a part's window (`--crop`, `session::crop`), `x0,y0,x1,y1` in pixels;
/// absent for the whole image.
pub const CROP_KEY: &str = "crop";
/// The identity key of the render's own window (the stage's `dataWindowNDC`,
/// `session::crop::stage_window`), `x0,y0,x1,y1` in pixels; absent for the whole image. The
/// parts' windows tile it, and the merged image is its window.
pub const WINDOW_KEY: &str = "window";

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
    crop: Option<Crop>,
) -> Vec<(String, String)> {
    let mut id = checkpoint::identity(scene, opts);
    // A stage whose window cannot be resolved renders nothing, so no part names it.
    if let Ok(Some(w)) = super::crop::stage_window(scene) {
        id.push((WINDOW_KEY.into(), w.label()));
    }
    id.push((INTEGRATOR_NAME_KEY.into(), opts.integrator.name().into()));
    let mis = match opts.integrator {
        Integrator::Bdpt { mis } | Integrator::Auto { mis } => Some(mis),
        Integrator::Vcm(p) => Some(p.mis),
        Integrator::Path | Integrator::Light => None,
    };
    id.push((MIS_KEY.into(), mis.map_or("none", |m| m.name()).into()));
    id.push((STAGE_FILE_KEY.into(), stage_file.into()));
    id.push((PART_KEY.into(), part.label()));
    if let Some(c) = crop {
        id.push((CROP_KEY.into(), c.label()));
    }
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
    /// The render's window (the stage's `dataWindowNDC`), when not the whole image.
    pub window: Option<Crop>,
}

/// A part as merge sees it: its sample part, its window (None: the whole image) and its
/// index among the parts given.
#[derive(Clone, Copy)]
struct Labelled {
    part: Part,
    crop: Option<Crop>,
    at: usize,
}

impl Labelled {
    fn label(&self) -> String {
        match self.crop {
            Some(c) => format!("{} (crop {})", self.part.label(), c.label()),
            None => self.part.label(),
        }
    }
}

/// Adds a checked part to the merge so far (the first part starts it).
pub fn add(merged: &mut Option<Merged>, c: &Checkpoint) -> Result<(), String> {
    match merged {
        None => {
            *merged = Some(Merged {
                film: Film::from_state(c.film.clone())?,
                identity: render_identity(c),
                samples: value(&c.identity, "spp")
                    .and_then(|s| s.parse().ok())
                    .ok_or("the parts' render has no sample count")?,
                dropped: c.dropped,
                wall_time_s: c.wall_time_s,
                depth_cut: c.depth_cut,
                window: value(&c.identity, WINDOW_KEY).and_then(Crop::from_label),
            })
        }
        Some(m) => {
            m.film.merge(&c.film)?;
            m.dropped += c.dropped;
            m.wall_time_s += c.wall_time_s;
            m.depth_cut.merge(&c.depth_cut);
        }
    }
    Ok(())
}

/// The render's identity of a part: its own without the part, the crop and the stage file.
fn render_identity(c: &Checkpoint) -> Vec<(String, String)> {
    c.identity
        .iter()
        .filter(|(k, _)| k != PART_KEY && k != STAGE_FILE_KEY && k != CROP_KEY)
        .cloned()
        .collect()
}

/// Checks that `parts` are parts of one render (same identity but the part and crop), each
/// rendered whole, and that for every sample part the windows cover each pixel of the
/// render's window (the whole image, or [`WINDOW_KEY`]'s) exactly once: none missing, none
/// twice, none outside. Only the films' sizes are read, so the parts may be given with
/// their films' data left out (merge then reads them one at a time). Returns the merge order
/// (by part, then window). An error names the index of the part at fault, when there is one.
pub fn check(parts: &[Checkpoint]) -> Result<Vec<usize>, (Option<usize>, String)> {
    let mut labelled = label(parts)?;
    let Some(&first) = labelled.first() else {
        return Err((None, "no parts given".into()));
    };
    let expected = render_identity(&parts[first.at]);
    for l in &labelled {
        if l.part.count != first.part.count {
            return Err((
                Some(l.at),
                format!(
                    "part {} of a split into {}, not {} as the first part's",
                    l.part.label(),
                    l.part.count,
                    first.part.count
                ),
            ));
        }
        let mut c = parts[l.at].clone();
        c.identity = render_identity(&parts[l.at]);
        c.check_identity(&expected).map_err(|e| {
            (
                Some(l.at),
                e.replace("the checkpoint is of another run", "another render")
                    .replace(" here", " in the first part"),
            )
        })?;
    }
    labelled.sort_by_key(|l| (l.part.index, l.crop.map(|c| (c.y0, c.x0))));
    let window = match value(&expected, WINDOW_KEY) {
        None => None,
        Some(s) => {
            Some(Crop::from_label(s).ok_or((Some(first.at), format!("bad render window '{s}'")))?)
        }
    };
    check_cover(parts, &labelled, first.part.count, window)?;
    let spp: u64 = value(&expected, "spp")
        .and_then(|s| s.parse().ok())
        .ok_or((
            Some(first.at),
            "the parts' render has no sample count".to_string(),
        ))?;
    for l in &labelled {
        let (a, b) = l.part.samples(spp);
        if parts[l.at].samples != b - a {
            return Err((
                Some(l.at),
                format!(
                    "part {} holds {} of its {} samples per pixel (interrupted?)",
                    l.label(),
                    parts[l.at].samples,
                    b - a
                ),
            ));
        }
    }
    Ok(labelled.iter().map(|l| l.at).collect())
}

/// Each part's sample part and window, read from its identity.
fn label(parts: &[Checkpoint]) -> Result<Vec<Labelled>, (Option<usize>, String)> {
    let mut labelled = Vec::new();
    for (i, c) in parts.iter().enumerate() {
        let part = value(&c.identity, PART_KEY)
            .ok_or("not a part of a render (no --part; a checkpoint?)".to_string())
            .and_then(Part::parse)
            .map_err(|e| (Some(i), e))?;
        let crop = match value(&c.identity, CROP_KEY) {
            None => None,
            Some(s) => Some(Crop::from_label(s).ok_or((Some(i), format!("bad crop '{s}'")))?),
        };
        labelled.push(Labelled { part, crop, at: i });
    }
    Ok(labelled)
}

/// For every sample part 0..count, the parts' windows (`labelled`, sorted by part) cover
/// every pixel of the render's `window` (None: the whole film) exactly once.
fn check_cover(
    parts: &[Checkpoint],
    labelled: &[Labelled],
    count: u64,
    window: Option<Crop>,
) -> Result<(), (Option<usize>, String)> {
    let film = &parts[labelled[0].at].film;
    let (w, h) = (film.width, film.height);
    let target = window.unwrap_or(Crop::whole(w, h));
    if target.x1 > w || target.y1 > h {
        return Err((None, "the render's window is outside its film".into()));
    }
    let inside =
        |c: &Crop| c.x0 >= target.x0 && c.y0 >= target.y0 && c.x1 <= target.x1 && c.y1 <= target.y1;
    let mut covered = vec![0u8; w * h];
    for k in 0..count {
        covered.fill(0);
        let of_k: Vec<&Labelled> = labelled.iter().filter(|l| l.part.index == k).collect();
        if of_k.is_empty() {
            return Err((None, format!("missing part {k}/{count}")));
        }
        for (j, l) in of_k.iter().enumerate() {
            if of_k[..j].iter().any(|o| o.crop == l.crop) {
                return Err((Some(l.at), format!("part {} given twice", l.label())));
            }
            let c = l.crop.unwrap_or(target);
            if !inside(&c) {
                return Err((
                    Some(l.at),
                    format!(
                        "part {}: crop outside the render's window {}",
                        l.label(),
                        target.label()
                    ),
                ));
            }
            for y in c.y0..c.y1 {
                for x in c.x0..c.x1 {
                    if covered[y * w + x] > 0 {
                        return Err((
                            Some(l.at),
                            format!(
                                "part {} overlaps another part's pixels at ({x}, {y})",
                                l.label()
                            ),
                        ));
                    }
                    covered[y * w + x] = 1;
                }
            }
        }
        for y in target.y0..target.y1 {
            if let Some(x) = (target.x0..target.x1).find(|&x| covered[y * w + x] == 0) {
                return Err((
                    None,
                    format!("missing pixels of part {k}/{count}: no crop covers ({x}, {y})"),
                ));
            }
        }
    }
    Ok(())
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
