//! The light subpaths of one VCM iteration, kept whole (Georgiev et al. 2012 §5; SmallVCM
//! keeps its light vertices the same way): every non-specular light vertex for merging
//! ([`MergeVertex`], over a hash grid), and each subpath's origin and what rebuilding its
//! vertices needs, so that camera sample j connects to and splats light subpath j of the
//! iteration (n_VC = 1) instead of tracing a subpath of its own: one light subpath per camera
//! sample serves both connections and merges.
//!
//! BSDFs are not kept (a [`crate::bxdf::Bsdf`] is a few hundred bytes): a subpath's vertices
//! are rebuilt from their surface hits with the same wavelengths ([`bsdf_at`]), the same
//! vertices bit for bit, at a fraction of the cost of tracing the subpath again (no rays, no
//! sampling). Per light vertex the store holds a [`MergeVertex`] twice (its batch's and the
//! grid's contiguous copy), its surface hit and dVC ([`VertexHit`]) and ≤ 8 bytes of grid;
//! per subpath its origin. Buffers are reused from iteration to iteration.

use super::hashgrid::HashGrid;
use super::mis::SubpathMis;
use super::subpath::LightSubpath;
use super::vertex::{bsdf_at, LightOrigin, PathVertex};
use super::MergeVertex;
use crate::scene::{Scene, SurfaceHit};
use crate::spectral::SampledWavelengths;
use crate::texture::TextureFilter;
use rayon::prelude::*;

/// What a stored light vertex needs besides its [`MergeVertex`] to be rebuilt as the
/// [`PathVertex`] it was: its surface hit (for the BSDF) and dVC.
#[derive(Clone, Copy, Debug)]
pub struct VertexHit {
    pub hit: SurfaceHit,
    pub dvc: f32,
}

/// One stored light subpath.
#[derive(Clone, Copy, Debug)]
struct StoredSubpath {
    origin: Option<LightOrigin>,
    /// One past its last vertex in its batch.
    end: u32,
    /// The subpath terminated its secondary wavelengths (dispersion).
    hero_only: bool,
}

/// Light subpaths traced by one parallel task, whole.
#[derive(Clone, Debug, Default)]
struct SubpathBatch {
    paths: Vec<StoredSubpath>,
    vertices: Vec<MergeVertex>,
    hits: Vec<VertexHit>,
}

impl SubpathBatch {
    fn clear(&mut self) {
        self.paths.clear();
        self.vertices.clear();
        self.hits.clear();
    }

    fn push(&mut self, path: &LightSubpath, hero_only: bool) {
        debug_assert_eq!(path.vertices.len(), path.hits.len());
        for (v, hit) in path.vertices.iter().zip(&path.hits) {
            self.vertices.push(MergeVertex::new(v, hero_only));
            self.hits.push(VertexHit {
                hit: *hit,
                dvc: v.mis.dvc,
            });
        }
        self.paths.push(StoredSubpath {
            origin: path.origin,
            end: self.vertices.len() as u32,
            hero_only,
        });
    }

    fn bytes(&self) -> usize {
        self.paths.capacity() * std::mem::size_of::<StoredSubpath>()
            + self.vertices.capacity() * std::mem::size_of::<MergeVertex>()
            + self.hits.capacity() * std::mem::size_of::<VertexHit>()
    }
}

/// The light vertices of one iteration with their hash grid, and the subpaths they came from,
/// reused from iteration to iteration.
#[derive(Clone, Debug, Default)]
pub struct LightVertexStore {
    /// Every stored vertex, in subpath order (the grid indexes this).
    pub vertices: Vec<MergeVertex>,
    pub(super) grid: HashGrid,
    batches: Vec<SubpathBatch>,
    /// Subpaths per batch (all but the last batch hold this many).
    batch_size: u64,
    /// The largest number of bytes the store has held.
    pub peak_bytes: usize,
}

impl LightVertexStore {
    /// Traces light subpaths 0 … n − 1 with `trace(j, buffer)` (which fills the buffer and
    /// returns whether the subpath terminated its secondary wavelengths), in parallel batches
    /// of `batch_size` in a fixed order, keeps them, and rebuilds the grid for `radius`.
    pub fn fill<F>(&mut self, n: u64, batch_size: u64, radius: f32, trace: F)
    where
        F: Fn(u64, &mut LightSubpath) -> bool + Sync,
    {
        let batch_size = batch_size.max(1);
        let count = n.div_ceil(batch_size) as usize;
        self.batches.resize_with(count, SubpathBatch::default);
        self.batch_size = batch_size;
        self.batches.par_iter_mut().enumerate().for_each_init(
            LightSubpath::default,
            |path, (c, batch)| {
                batch.clear();
                let first = c as u64 * batch_size;
                for j in first..(first + batch_size).min(n) {
                    let hero_only = trace(j, path);
                    batch.push(path, hero_only);
                }
            },
        );
        self.vertices.clear();
        for b in &self.batches {
            self.vertices.extend_from_slice(&b.vertices);
        }
        self.grid.build(self.vertices.iter().map(|v| v.p), radius);
        self.peak_bytes = self.peak_bytes.max(self.bytes());
    }

    /// Bytes held now (vertices, subpaths and grid).
    pub fn bytes(&self) -> usize {
        self.vertices.capacity() * std::mem::size_of::<MergeVertex>()
            + self.batches.iter().map(SubpathBatch::bytes).sum::<usize>()
            + self.grid.bytes()
    }

    /// Bytes per stored light vertex: its merge vertex (in its batch and in the grid's
    /// array), its [`VertexHit`] and its grid index.
    pub const BYTES_PER_VERTEX: usize = 2 * std::mem::size_of::<MergeVertex>()
        + std::mem::size_of::<VertexHit>()
        + std::mem::size_of::<u32>();

    /// Light subpaths stored.
    #[cfg(test)]
    pub fn subpaths(&self) -> u64 {
        self.batches.iter().map(|b| b.paths.len() as u64).sum()
    }

    /// Rebuilds stored light subpath `j` into `out` as it was traced: its origin and its
    /// vertices with their BSDFs for `lambda` (the iteration's wavelengths, whose secondary
    /// wavelengths the caller has terminated if the subpath did: see the return value).
    /// Returns whether the subpath terminated its secondary wavelengths; `out` is left empty
    /// for a `j` not stored.
    pub fn subpath(
        &self,
        j: u64,
        scene: &Scene,
        filter: TextureFilter,
        lambda: &mut SampledWavelengths,
        out: &mut LightSubpath,
    ) -> bool {
        out.clear();
        let (c, i) = (j / self.batch_size.max(1), j % self.batch_size.max(1));
        let Some(b) = self.batches.get(c as usize) else {
            return false;
        };
        let Some(path) = b.paths.get(i as usize) else {
            return false;
        };
        let start = if i == 0 {
            0
        } else {
            b.paths[i as usize - 1].end
        };
        if path.hero_only {
            lambda.terminate_secondary();
        }
        out.origin = path.origin;
        for k in start as usize..path.end as usize {
            let (m, h) = (&b.vertices[k], &b.hits[k]);
            let mis = SubpathMis {
                dvcm: m.dvcm,
                dvc: h.dvc,
                dvm: m.dvm,
            };
            let bsdf = bsdf_at(scene, &h.hit, filter, lambda);
            out.vertices
                .push(PathVertex::new(&h.hit, m.wo, bsdf, m.beta, mis, m.depth));
            out.hits.push(h.hit);
        }
        path.hero_only
    }
}
