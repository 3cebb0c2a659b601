//! Shared machinery of the bidirectional integrators (light tracing, BDPT and VCM, which adds
//! merging on top of the same vertices, walks and MIS quantities).
//!
//! | file | concept |
//! |---|---|
//! | `mis.rs` | heuristics and SmallVCM's recurrent partial weights dVCM/dVC/dVM (Georgiev 2012) |
//! | `vertex.rs` | [`PathVertex`] (y_i, z_i) and [`LightOrigin`] (y_0); shading-normal correction |
//! | `subpath.rs` | [`Walk`] (loop-carried state), [`trace_light_subpath`], [`BidirContext`] |
//! | `connect.rs` | the techniques: s = 0, t = 1, s = 1 and general connections |
//! | `splat.rs` | t = 1: the light subpath connected to the sensor |
//! | `store.rs` | the iteration's light subpaths ([`store::LightVertexStore`]): merge vertices and whole subpaths for connections |
//! | `merge.rs` | vertex merging: the merge technique over the stored light vertices |
//! | `merge_rule.rs` | where merging is available ([`MergeRule`]: everywhere, or after near-specular vertices) and its MIS |
//! | `hashgrid.rs` | the fixed-radius hash grid over them |
//! | `reach.rs` | a coarse bitmap of where the grid's queries can find a point at all |
//! | `record.rs` | a sample's contributions → tile sums and splats |
//! | `strategies.rs` | the per-(s, t) decomposition written by `--strategies` |
//!
//! Naming (as SmallVCM's header): y_i light vertices, z_i camera vertices, i = depth (segments
//! from the subpath's origin); a path made of s light and t camera vertices is technique
//! (s, t) with s + t − 2 scattering events. `wo` points back along a vertex's own subpath,
//! `wi` towards the next or the connected vertex. Pdfs carry `_w` (solid angle) or `_a` (area);
//! "forward" is a subpath's own sampling direction, "reverse" the opposite one.
//!
//! Memory: a per-thread [`Workspace`] holds the light subpath and the sample record; both are
//! cleared and reused from sample to sample, so nothing is allocated per bounce.

pub mod connect;
pub mod hashgrid;
pub mod merge;
pub mod merge_rule;
pub mod mis;
pub mod origin_view;
pub mod reach;
pub mod record;
pub mod splat;
pub mod store;
pub mod strategies;
pub mod subpath;
pub mod vertex;

pub use connect::Contribution;
pub use merge::{MergeParams, MergeVertex};
pub use merge_rule::MergeRule;
pub use mis::{Mis, MisHeuristic};
pub use record::{SampleRecord, TileAccumulator};
pub use splat::splat_light_subpath;
pub use store::LightVertexStore;
pub use subpath::{trace_light_subpath, BidirContext, CappedSubpath, LightSubpath, Walk};
pub use vertex::PathVertex;

/// Per-thread buffers of a bidirectional integrator, reused for every sample.
#[derive(Clone, Debug, Default)]
pub struct Workspace {
    pub light: LightSubpath,
    pub record: SampleRecord,
}

impl Workspace {
    /// Buffers for paths up to `max_depth` scattering events; `strategy_count` > 0 also
    /// records the per-strategy decomposition.
    pub fn new(max_depth: u32, strategy_count: usize) -> Workspace {
        let mut light = LightSubpath::default();
        light.vertices.reserve((max_depth as usize + 1).min(64));
        light.hits.reserve((max_depth as usize + 1).min(64));
        Workspace {
            light,
            record: SampleRecord::new(strategy_count),
        }
    }
}
