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
//! grid's contiguous copy), its surface hit and dVC ([`VertexHit`]) and ≤ 20 bytes of grid;
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

/// What tracing a light subpath into the store reports besides its vertices.
#[derive(Clone, Copy, Debug)]
pub struct Traced {
    /// The wavelengths the subpath was traced with.
    pub lambda: SampledWavelengths,
    /// The trace terminated their secondary wavelengths (dispersion).
    pub hero_only: bool,
    /// The key a merge must match to use its vertices (its hero-wavelength bin; 0 when the
    /// iteration shares one tuple).
    pub key: u32,
}

/// One stored light subpath.
#[derive(Clone, Copy, Debug)]
struct StoredSubpath {
    origin: Option<LightOrigin>,
    /// One past its last vertex in its batch.
    end: u32,
    traced: Traced,
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

    fn push(&mut self, path: &LightSubpath, traced: Traced) {
        debug_assert_eq!(path.vertices.len(), path.hits.len());
        let hero_only = traced.hero_only;
        for (v, hit) in path.vertices.iter().zip(&path.hits) {
            self.vertices
                .push(MergeVertex::new(v, hit.tri.mesh, hero_only));
            self.hits.push(VertexHit {
                hit: *hit,
                dvc: v.mis.dvc,
            });
        }
        self.paths.push(StoredSubpath {
            origin: path.origin,
            end: self.vertices.len() as u32,
            traced,
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
    /// Every stored vertex, in subpath order (the grid indexes this), and its key.
    pub vertices: Vec<MergeVertex>,
    keys: Vec<u32>,
    pub(super) grid: HashGrid,
    batches: Vec<SubpathBatch>,
    /// Subpaths per batch (all but the last batch hold this many).
    batch_size: u64,
    /// The largest number of bytes the store has held.
    pub peak_bytes: usize,
}

impl LightVertexStore {
    /// Bytes per stored light vertex: its merge vertex (in its batch and in the grid's
    /// array), its [`VertexHit`], its key (in the store and the grid), its grid index and
    /// the grid's copy of its position.
    pub const BYTES_PER_VERTEX: usize = 2 * std::mem::size_of::<MergeVertex>()
        + std::mem::size_of::<VertexHit>()
        + 3 * std::mem::size_of::<u32>()
        + std::mem::size_of::<glam::Vec3>();

    /// Traces light subpaths 0 … n − 1 with `trace(j, buffer)` (which fills the buffer), in
    /// parallel batches of `batch_size` in a fixed order, keeps them, and rebuilds the grid
    /// for `radius`.
    pub fn fill<F>(&mut self, n: u64, batch_size: u64, radius: f32, trace: F)
    where
        F: Fn(u64, &mut LightSubpath) -> Traced + Sync,
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
                    let traced = trace(j, path);
                    batch.push(path, traced);
                }
            },
        );
        self.vertices.clear();
        self.keys.clear();
        for b in &self.batches {
            self.vertices.extend_from_slice(&b.vertices);
            let mut start = 0;
            for path in &b.paths {
                let count = (path.end - start) as usize;
                self.keys
                    .extend(std::iter::repeat_n(path.traced.key, count));
                start = path.end;
            }
        }
        let points = self.vertices.iter().zip(&self.keys).map(|(v, k)| (v.p, *k));
        self.grid.build(points, radius);
        self.peak_bytes = self.peak_bytes.max(self.bytes());
    }

    /// Bytes held now (vertices, subpaths and grid).
    pub fn bytes(&self) -> usize {
        self.vertices.capacity() * std::mem::size_of::<MergeVertex>()
            + self.keys.capacity() * std::mem::size_of::<u32>()
            + self.batches.iter().map(SubpathBatch::bytes).sum::<usize>()
            + self.grid.bytes()
    }

    /// Light subpaths stored.
    #[cfg(test)]
    pub fn subpaths(&self) -> u64 {
        self.batches.iter().map(|b| b.paths.len() as u64).sum()
    }

    /// What tracing stored light subpath `j` reported (its wavelengths and key); None for a
    /// `j` not stored.
    pub fn traced(&self, j: u64) -> Option<Traced> {
        let (b, i) = self.locate(j)?;
        Some(self.batches[b].paths[i].traced)
    }

    /// Rebuilds stored light subpath `j` into `out` as it was traced: its origin and its
    /// vertices with their BSDFs for `lambda` (its wavelengths, [`Self::traced`], terminated
    /// as the trace left them); `out` is left empty for a `j` not stored.
    pub fn subpath(
        &self,
        j: u64,
        scene: &Scene,
        filter: TextureFilter,
        lambda: &mut SampledWavelengths,
        out: &mut LightSubpath,
    ) {
        out.clear();
        let Some((b, i)) = self.locate(j) else {
            return;
        };
        let batch = &self.batches[b];
        let start = if i == 0 { 0 } else { batch.paths[i - 1].end };
        let path = &batch.paths[i];
        out.origin = path.origin;
        for k in start as usize..path.end as usize {
            let (m, h) = (&batch.vertices[k], &batch.hits[k]);
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
    }

    /// (batch, index in it) of stored subpath `j`.
    fn locate(&self, j: u64) -> Option<(usize, usize)> {
        let size = self.batch_size.max(1);
        let (b, i) = ((j / size) as usize, (j % size) as usize);
        (i < self.batches.get(b)?.paths.len()).then_some((b, i))
    }
}
