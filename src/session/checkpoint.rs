//! Checkpoints of an image session (`--checkpoint FILE`, `--resume FILE`): the film's raw
//! state (`sensor::film_state`), the strategy images' sums, the samples per pixel done, the
//! samples dropped and the time spent, under the *identity* of the run — what decides the
//! image for a given sample count: the stage's content hash, the resolution, the seed, the
//! sample target, the maximum depth, the integrator with its settings, texture filtering,
//! strategy images, the wavelengths per sample and the renderer's version. An image depends on those and the sample
//! count only (`session::image`), so a session resumed from a checkpoint ends bit for bit
//! where the uninterrupted one does. A checkpoint of another run is refused naming the first
//! difference.
//!
//! File layout (`raw_bytes`): the magic line [`MAGIC`], the format version, the identity as
//! (key, value) strings, samples, dropped, seconds, the film state, a strategy flag and the
//! strategy sums, the sums of what the depth cap cut (`integrator::cut::BatchedRatio`: per
//! batch samples, cut and total, then the capped paths and limited continuations), and an
//! FNV-1a hash of everything before it (a damaged file is refused).

use crate::desc::ContentHash;
use crate::error::Reason;
use crate::integrator::bidir::strategies::StrategySums;
use crate::integrator::cut::{BatchedRatio, BATCHES};
use crate::integrator::roulette::{RrStart, DEFAULT_RR_DEPTH};
use crate::integrator::split::Split;
use crate::scene::Scene;
use crate::sensor::film_state::FilmState;
use crate::sensor::raw_bytes::{ByteReader, ByteWriter};

use super::RenderOptions;

/// The first bytes of a checkpoint file.
pub const MAGIC: &[u8] = b"spectral-render checkpoint\n";
/// The version of the layout.
const FORMAT: u64 = 3;

/// An image session's state under its run's identity.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    /// (what, value) pairs that decide the image (see the module docs).
    pub identity: Vec<(String, String)>,
    /// Samples per pixel done.
    pub samples: u64,
    /// Samples dropped as non-finite so far.
    pub dropped: u64,
    /// Wall-clock seconds spent so far.
    pub wall_time_s: f64,
    pub film: FilmState,
    pub strategies: Option<StrategySums>,
    /// What the depth cap cut so far, for the resumed run's report.
    pub depth_cut: BatchedRatio,
}

/// What decides the image of `scene` under `opts` for a given sample count.
pub fn identity(scene: &Scene, opts: &RenderOptions) -> Vec<(String, String)> {
    let spp = match (opts.spp, opts.time_budget) {
        (Some(n), _) => n.to_string(),
        (None, Some(_)) => "a time budget".into(),
        (None, None) => super::DEFAULT_SPP.to_string(),
    };
    let pairs = [
        ("stage content", format!("{:016x}", scene.content_hash)),
        (
            "resolution",
            format!("{}x{}", scene.camera.width, scene.camera.height),
        ),
        ("seed", opts.seed.to_string()),
        ("spp", spp),
        (
            "max depth",
            opts.max_depth
                .map_or("unlimited".to_string(), |d| d.to_string()),
        ),
        ("integrator", format!("{:?}", opts.integrator)),
        ("texture filtering", opts.filter_textures.to_string()),
        ("strategy images", opts.strategies.to_string()),
        ("wavelengths", opts.wavelengths.to_string()),
        (
            "sampler",
            super::image::sampler_kind(opts).name().to_string(),
        ),
        ("version", env!("CARGO_PKG_VERSION").to_string()),
    ];
    let mut id: Vec<(String, String)> =
        pairs.into_iter().map(|(k, v)| (k.to_string(), v)).collect();
    // Named only when not the default, so that checkpoints and parts written before the option
    // existed (all at the default) still resume and merge.
    if opts.rr_depth != RrStart::At(DEFAULT_RR_DEPTH) {
        id.push(("rr depth".into(), opts.rr_depth.to_string()));
    }
    if opts.split != Split::At(1) {
        id.push(("split".into(), opts.split.to_string()));
    }
    id
}

impl Checkpoint {
    /// Refuses a checkpoint whose identity differs from `expected`, naming the first
    /// difference.
    pub fn check_identity(&self, expected: &[(String, String)]) -> Reason<()> {
        for (key, want) in expected {
            let have = self.identity.iter().find(|(k, _)| k == key).map(|(_, v)| v);
            if have != Some(want) {
                return Err(format!(
                    "the checkpoint is of another run: {key} {} there, {want} here",
                    have.map_or("missing", String::as_str)
                ));
            }
        }
        Ok(())
    }

    pub fn encode(&self) -> Vec<u8> {
        let mut w = ByteWriter::default();
        w.bytes.extend_from_slice(MAGIC);
        w.u64(FORMAT);
        w.u64(self.identity.len() as u64);
        for (k, v) in &self.identity {
            w.bytes(k.as_bytes());
            w.bytes(v.as_bytes());
        }
        w.u64(self.samples);
        w.u64(self.dropped);
        w.f64(self.wall_time_s);
        self.film.encode(&mut w);
        match &self.strategies {
            None => w.u64(0),
            Some(s) => {
                w.u64(1);
                w.u64(s.samples_per_pixel);
                for images in [&s.weighted, &s.unweighted] {
                    w.u64(images.len() as u64);
                    images.iter().for_each(|i| w.triples(i));
                }
            }
        }
        let b = &self.depth_cut.batches;
        w.u64s(&b.map(|x| x.0));
        w.f64s(&b.map(|x| x.1));
        w.f64s(&b.map(|x| x.2));
        w.u64(self.depth_cut.capped);
        w.u64(self.depth_cut.limited);
        let mut hash = ContentHash::default();
        hash.add(&w.bytes);
        w.u64(hash.0);
        w.bytes
    }

    pub fn decode(bytes: &[u8]) -> Reason<Checkpoint> {
        let body = bytes
            .strip_prefix(MAGIC)
            .ok_or("not a spectral-render checkpoint")?;
        let Some(split) = bytes.len().checked_sub(8).filter(|&s| s >= MAGIC.len()) else {
            return Err("the checkpoint is truncated".into());
        };
        let mut hash = ContentHash::default();
        hash.add(&bytes[..split]);
        let stored = ByteReader::new(&bytes[split..]).u64()?;
        if hash.0 != stored {
            return Err("the checkpoint is damaged (its hash does not match)".into());
        }
        let mut r = ByteReader::new(&body[..body.len() - 8]);
        let format = r.u64()?;
        if format != FORMAT {
            return Err(format!(
                "checkpoint format {format}; this renderer reads format {FORMAT}"
            ));
        }
        let c = Checkpoint {
            identity: read_identity(&mut r)?,
            samples: r.u64()?,
            dropped: r.u64()?,
            wall_time_s: r.f64()?,
            film: FilmState::decode(&mut r)?,
            strategies: read_strategies(&mut r)?,
            depth_cut: read_depth_cut(&mut r)?,
        };
        if r.remaining() != 0 {
            return Err("the checkpoint has trailing data".into());
        }
        Ok(c)
    }
}

fn read_identity(r: &mut ByteReader) -> Reason<Vec<(String, String)>> {
    let n = r.u64()?;
    let mut pairs = Vec::new();
    for _ in 0..n {
        let text = |b: &[u8]| String::from_utf8(b.to_vec()).map_err(|e| e.to_string());
        let k = text(r.bytes()?)?;
        let v = text(r.bytes()?)?;
        pairs.push((k, v));
    }
    Ok(pairs)
}

fn read_depth_cut(r: &mut ByteReader) -> Reason<BatchedRatio> {
    let (n, c, t) = (r.u64s()?, r.f64s()?, r.f64s()?);
    if [n.len(), c.len(), t.len()] != [BATCHES; 3] {
        return Err("the checkpoint's depth-cut sums have the wrong size".into());
    }
    Ok(BatchedRatio {
        batches: std::array::from_fn(|i| (n[i], c[i], t[i])),
        capped: r.u64()?,
        limited: r.u64()?,
    })
}

fn read_strategies(r: &mut ByteReader) -> Reason<Option<StrategySums>> {
    if r.u64()? == 0 {
        return Ok(None);
    }
    let samples_per_pixel = r.u64()?;
    let mut images = || -> Reason<Vec<Vec<[f64; 3]>>> {
        let n = r.u64()?;
        let mut v = Vec::new();
        for _ in 0..n {
            v.push(r.triples()?);
        }
        Ok(v)
    };
    Ok(Some(StrategySums {
        weighted: images()?,
        unweighted: images()?,
        samples_per_pixel,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checkpoint() -> Checkpoint {
        Checkpoint {
            identity: vec![("seed".into(), "3".into()), ("spp".into(), "8".into())],
            samples: 4,
            dropped: 0,
            wall_time_s: 1.25,
            film: FilmState {
                width: 1,
                height: 1,
                grid_exponent: 50,
                sums: vec![[1, 2, -3]],
                samples: vec![4],
                odd_y: vec![1.0],
                splat: vec![[5; 3]],
                odd_splat_y: vec![0.25],
                light_paths: 4,
                clamped: 0,
            },
            strategies: Some(StrategySums {
                weighted: vec![vec![[1.0; 3]]],
                unweighted: vec![vec![[2.0; 3]]],
                samples_per_pixel: 4,
            }),
            depth_cut: BatchedRatio {
                batches: std::array::from_fn(|i| (i as u64, 0.5 * i as f64, 2.0 * i as f64)),
                capped: 7,
                limited: 1,
            },
        }
    }

    #[test]
    fn round_trip_and_identity() {
        let c = checkpoint();
        let bytes = c.encode();
        assert_eq!(Checkpoint::decode(&bytes), Ok(c.clone()));
        assert!(c.check_identity(&c.identity).is_ok());
        let other = vec![("seed".to_string(), "4".to_string())];
        let e = c.check_identity(&other).unwrap_err();
        assert!(e.contains("seed 3 there, 4 here"), "{e}");
    }

    #[test]
    fn damaged_files_are_refused() {
        let bytes = checkpoint().encode();
        let mut flipped = bytes.clone();
        flipped[MAGIC.len() + 20] ^= 1;
        assert!(Checkpoint::decode(&flipped)
            .unwrap_err()
            .contains("damaged"));
        assert!(Checkpoint::decode(&bytes[..bytes.len() / 2]).is_err());
        assert!(Checkpoint::decode(b"hello").is_err());
        assert!(Checkpoint::decode(MAGIC).is_err());
    }
}
