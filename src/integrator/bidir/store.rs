//! The light subpaths of one VCM iteration, kept whole (Georgiev et al. 2012 §5; SmallVCM
//! keeps its light vertices the same way): every non-specular light vertex for merging
//! ([`MergeVertex`], over a hash grid), and each subpath's origin and what rebuilding its
//! vertices needs, so that camera sample j connects to and splats light subpath j of the
//! iteration (n_VC = 1) instead of tracing a subpath of its own: one light subpath per camera
//! sample serves both connections and merges.
//!
//! BSDFs are not kept (a [`crate::bxdf::Bsdf`] is a few hundred bytes): a subpath's vertices
//! are rebuilt from their surface hits with the same wavelengths ([`cached_bsdf_at`]), the
//! same vertices bit for bit, at a fraction of the cost of tracing the subpath again (no rays,
//! no sampling; the materials' spectra at the iteration's wavelengths come from the thread's
//! cache, `material::spectra`). Per light vertex the store holds a [`MergeVertex`] (its
//! batch's), its surface hit, dVC and merge flags ([`VertexHit`]) and its key; per vertex
//! merging is available at (all of them, unless `merge_rule.rs` says otherwise) also its index
//! in a list of those, a copy of its [`MergeVertex`] in the grid's slot order (so that a merge
//! reads the records of a cell's candidates contiguously) and the grid's 24 bytes (its
//! position and key in slot order, its index, its slot); per subpath its origin. The
//! subpaths are traced, and the grid built and the copy gathered, in parallel and in a fixed
//! order: the same store for any thread count. Buffers are reused from iteration to
//! iteration.

use super::hashgrid::{GridPoint, HashGrid};
use super::mis::SubpathMis;
use super::subpath::LightSubpath;
use super::vertex::{cached_bsdf_at, LightOrigin, PathVertex};
use super::MergeVertex;
use crate::scene::{Scene, SurfaceHit};
use crate::spectral::SampledWavelengths;
use crate::texture::TextureFilter;
use rayon::prelude::*;

/// Vertices per parallel task of the gather into slot order.
const STORE_GATHER_CHUNK: usize = 4096;

/// What a stored light vertex needs besides its [`MergeVertex`] to be rebuilt as the
/// [`PathVertex`] it was: its surface hit (for the BSDF), dVC and its merge flags
/// (`merge_rule.rs`).
#[derive(Clone, Copy, Debug)]
pub struct VertexHit {
    pub hit: SurfaceHit,
    pub dvc: f32,
    pub merges: bool,
    pub near_specular: bool,
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
    /// Each vertex's key (its subpath's).
    keys: Vec<u32>,
    /// The vertices merging is available at (`PathVertex::merges`, `merge_rule.rs`), by
    /// index in `vertices`: the grid holds these only.
    mergeable: Vec<u32>,
}

impl SubpathBatch {
    fn clear(&mut self) {
        self.paths.clear();
        self.vertices.clear();
        self.hits.clear();
        self.keys.clear();
        self.mergeable.clear();
    }

    fn push(&mut self, path: &LightSubpath, traced: Traced) {
        debug_assert_eq!(path.vertices.len(), path.hits.len());
        let hero_only = traced.hero_only;
        for (v, hit) in path.vertices.iter().zip(&path.hits) {
            if v.merges {
                self.mergeable.push(self.vertices.len() as u32);
            }
            self.vertices
                .push(MergeVertex::new(v, hit.tri.mesh, hero_only));
            self.hits.push(VertexHit {
                hit: *hit,
                dvc: v.mis.dvc,
                merges: v.merges,
                near_specular: v.near_specular,
            });
            self.keys.push(traced.key);
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
            + self.keys.capacity() * std::mem::size_of::<u32>()
            + self.mergeable.capacity() * std::mem::size_of::<u32>()
    }
}

/// The light vertices of one iteration with their hash grid, and the subpaths they came from,
/// reused from iteration to iteration.
#[derive(Clone, Debug, Default)]
pub struct LightVertexStore {
    /// Every stored vertex merging is available at, in the grid's slot order (position s of a
    /// grid query).
    pub vertices: Vec<MergeVertex>,
    pub(super) grid: HashGrid,
    batches: Vec<SubpathBatch>,
    /// `batch_start[b]`: the index of batch b's first mergeable vertex in subpath order.
    batch_start: Vec<usize>,
    /// Subpaths per batch (all but the last batch hold this many).
    batch_size: u64,
    /// The largest number of bytes the store has held.
    pub peak_bytes: usize,
}

impl LightVertexStore {
    /// Bytes per stored light vertex merging is available at: its merge vertex (in its batch
    /// and in slot order), its [`VertexHit`], its key and mergeable index, and the grid's
    /// position and key, index and slot of it (a vertex that does not merge has no grid
    /// entry, no copy and no mergeable index: 104 bytes fewer).
    pub const BYTES_PER_VERTEX: usize = 2 * std::mem::size_of::<MergeVertex>()
        + std::mem::size_of::<VertexHit>()
        + 4 * std::mem::size_of::<u32>()
        + std::mem::size_of::<GridPoint>();

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
        self.batch_start.clear();
        let mut n = 0;
        for b in &self.batches {
            self.batch_start.push(n);
            n += b.mergeable.len();
        }
        let (batches, starts) = (&self.batches, &self.batch_start);
        // Mergeable vertex i in subpath order: (its batch, its index there).
        let at = |i: usize| {
            let b = starts.partition_point(|&s| s <= i) - 1;
            (&batches[b], batches[b].mergeable[i - starts[b]] as usize)
        };
        self.grid.build(
            n,
            |i| {
                let (b, k) = at(i);
                GridPoint {
                    p: b.vertices[k].p,
                    key: b.keys[k],
                }
            },
            radius,
        );
        let order = self.grid.order();
        self.vertices.resize(n, MergeVertex::default());
        self.vertices
            .par_iter_mut()
            .with_min_len(STORE_GATHER_CHUNK)
            .zip(order.par_iter())
            .for_each(|(v, &i)| {
                let (b, k) = at(i as usize);
                *v = b.vertices[k];
            });
        self.peak_bytes = self.peak_bytes.max(self.bytes());
    }

    /// Bytes held now (vertices, subpaths and grid).
    pub fn bytes(&self) -> usize {
        self.vertices.capacity() * std::mem::size_of::<MergeVertex>()
            + self.batch_start.capacity() * std::mem::size_of::<usize>()
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
        out.spectra.begin(&scene.materials, lambda);
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
            let bsdf = cached_bsdf_at(scene, &h.hit, filter, lambda, &mut out.spectra);
            let mut v = PathVertex::new(&h.hit, m.wo, bsdf, m.beta, mis, m.depth);
            v.merges = h.merges;
            v.near_specular = h.near_specular;
            out.vertices.push(v);
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
