//! A hash grid over points for fixed-radius queries: the light vertices an iteration of VCM
//! stores, looked up around every camera vertex (Georgiev et al. 2012 §5; SmallVCM's
//! `HashGrid`, written anew). Every point carries a key (the hero-wavelength bin of its light
//! subpath, `vcm.rs`; 0 when all share one), hashed with its cell: a query finds only the
//! points of its own key.
//!
//! Cells are cubes of side 2r, so a ball of radius r around a query point overlaps at most
//! the 2 × 2 × 2 block of cells nearest to it. Cells are hashed into a table of a power of two
//! slots, at least as many as points (Teschner et al. 2003, "Optimized spatial hashing for
//! collision detection of deformable objects", with their three primes), in aligned blocks of
//! 2 × 2 × 2 cells to 8 adjacent slots, so that a query's cells are few runs of memory
//! ([`HashGrid::slot_of`]); points are sorted by
//! slot with a counting sort, so a slot's points are contiguous. Hash collisions only add
//! candidates: every candidate is tested against the radius, by the grid itself on its own
//! copy of the points in slot order, position and key side by side in 16 bytes (on a surface
//! the 2 × 2 × 2 block holds about 5 candidates for each inside the ball, (4r)² / π r²).
//! Queries report a candidate by its position in that order ([`HashGrid::order`] maps it back
//! to the point's index), so that the caller can keep its own records in slot order too and
//! read a cell's records contiguously. A query first asks a coarse bitmap of the points
//! (`reach.rs`) whether any point can lie within r of it at all, and stops there if not.
//!
//! The build is parallel (rayon) and deterministic: the bounds, the points' slots and the
//! gather into slot order are computed in parallel, each element independently; only the
//! counting sort's histogram and placement, a few integer operations per point, run serially,
//! in point order. The order within a slot is by decreasing point index whatever the thread
//! count. The buffers are kept and reused by the next build.

use super::reach::Reach;
use glam::Vec3;
use rayon::prelude::*;

/// A point and its key, as the grid stores them in slot order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GridPoint {
    pub p: Vec3,
    pub key: u32,
}

#[derive(Clone, Debug, Default)]
pub struct HashGrid {
    /// The points in slot order.
    points: Vec<GridPoint>,
    /// `order[i]`: the index of the i-th point in slot order.
    order: Vec<u32>,
    /// The slot of every point, by point index (a build's scratch).
    slot: Vec<u32>,
    /// `slot_end[k]`: one past the last entry of slot k in `points` (slot k starts at
    /// `slot_end[k − 1]`, or 0).
    slot_end: Vec<u32>,
    /// The counting sort's cursors (a build's scratch).
    cursor: Vec<u32>,
    origin: Vec3,
    /// Where a query can find a point at all (`reach.rs`): [`HashGrid::query`]'s early exit.
    reach: Reach,
    inv_cell: f32,
    radius2: f32,
}

/// Points per parallel task of a build.
const BUILD_CHUNK: usize = 4096;
/// Adjacent slots of the 2 × 2 × 2 cells of one hashed block ([`HashGrid::slot_of`]).
const BLOCK_SLOTS: usize = 8;

impl HashGrid {
    /// Rebuilds the grid over the `n` points `point(0)` … `point(n − 1)` (position, key) for
    /// queries of radius `radius` (> 0, finite).
    pub fn build(&mut self, n: usize, point: impl Fn(usize) -> GridPoint + Sync, radius: f32) {
        // Whole blocks of 8 slots, at least as many slots as points.
        let slots = n.max(1).next_power_of_two().max(BLOCK_SLOTS);
        let (lo, hi) = (0..n)
            .into_par_iter()
            .with_min_len(BUILD_CHUNK)
            .map(|i| {
                let p = point(i).p;
                (p, p)
            })
            .reduce(
                || (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            );
        self.origin = if lo.is_finite() { lo } else { Vec3::ZERO };
        self.inv_cell = 1.0 / (2.0 * radius);
        self.radius2 = radius * radius;
        self.slot_end.clear();
        self.slot_end.resize(slots, 0);
        let mut slot = std::mem::take(&mut self.slot);
        slot.clear();
        slot.resize(n, 0);
        let grid = &*self;
        slot.par_iter_mut()
            .with_min_len(BUILD_CHUNK)
            .enumerate()
            .for_each(|(i, s)| {
                let q = point(i);
                *s = grid.slot_of(grid.cell_of(q.p), q.key) as u32;
            });
        self.slot = slot;
        for &k in &self.slot {
            self.slot_end[k as usize] += 1;
        }
        let mut start = 0u32;
        for c in self.slot_end.iter_mut() {
            start += *c;
            *c = start;
        }
        // Filling from the back leaves the cursor at each slot's start.
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.slot_end);
        self.order.clear();
        self.order.resize(n, 0);
        for (i, &k) in self.slot.iter().enumerate() {
            let c = &mut self.cursor[k as usize];
            *c -= 1;
            self.order[*c as usize] = i as u32;
        }
        self.points.clear();
        self.points.resize(n, GridPoint::default());
        self.points
            .par_iter_mut()
            .with_min_len(BUILD_CHUNK)
            .zip(self.order.par_iter())
            .for_each(|(q, &i)| *q = point(i as usize));
        self.reach
            .build(self.points.iter().map(|g| g.p), lo, hi, radius);
    }

    /// The index of every point in slot order: the position a query reports ↦ the point's
    /// index in the build.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Calls `visit(s)` for the position s in slot order ([`Self::order`]) of every point of
    /// key `key` that lies within the radius of `q` ([`Self::within`]), in a fixed order.
    pub fn query(&self, q: Vec3, key: u32, mut visit: impl FnMut(usize)) {
        if self.points.is_empty() || !self.reach.may_reach(q) {
            return;
        }
        let c = (q - self.origin) * self.inv_cell;
        let base = c.floor();
        let frac = c - base;
        // The 2 × 2 × 2 block: the cell of q and its neighbour on the side q is nearer to.
        let step = |f: f32| if f < 0.5 { -1 } else { 1 };
        let b = [base.x as i64, base.y as i64, base.z as i64];
        let d = [step(frac.x), step(frac.y), step(frac.z)];
        // First the slots' ranges, then their points: the 8 slot lookups are independent
        // loads that the processor overlaps, rather than each waiting behind the previous
        // slot's scan.
        let mut seen = [usize::MAX; 8];
        let mut ranges = [(0usize, 0usize); 8];
        let mut count = 0;
        for (n, corner) in (0..8).enumerate() {
            let cell = [
                b[0] + if corner & 1 != 0 { d[0] } else { 0 },
                b[1] + if corner & 2 != 0 { d[1] } else { 0 },
                b[2] + if corner & 4 != 0 { d[2] } else { 0 },
            ];
            let k = self.slot_of(cell, key);
            // Two cells of the block may hash to one slot: visit it once.
            if seen[..n].contains(&k) {
                continue;
            }
            seen[n] = k;
            let start = if k == 0 {
                0
            } else {
                self.slot_end[k - 1] as usize
            };
            ranges[count] = (start, self.slot_end[k] as usize);
            count += 1;
        }
        for &(start, end) in &ranges[..count] {
            for (s, g) in self.points[start..end].iter().enumerate() {
                if g.key == key && self.within(q, g.p) {
                    visit(start + s);
                }
            }
        }
    }

    /// True when `p` lies within the radius of `q`.
    #[inline]
    pub fn within(&self, q: Vec3, p: Vec3) -> bool {
        (p - q).length_squared() <= self.radius2
    }

    /// The query radius.
    pub fn radius(&self) -> f32 {
        self.radius2.sqrt()
    }

    /// Bytes held by the grid's buffers.
    pub fn bytes(&self) -> usize {
        (self.order.capacity()
            + self.slot.capacity()
            + self.slot_end.capacity()
            + self.cursor.capacity())
            * std::mem::size_of::<u32>()
            + self.points.capacity() * std::mem::size_of::<GridPoint>()
            + self.reach.bytes()
    }

    fn cell_of(&self, p: Vec3) -> [i64; 3] {
        let c = ((p - self.origin) * self.inv_cell).floor();
        // Saturating casts: a point far outside the others lands in some cell, never UB.
        [c.x as i64, c.y as i64, c.z as i64]
    }

    /// The slot of cell `c` for points of key `key`: the 2 × 2 × 2 block of cells holding `c`
    /// (cell coordinates halved) is hashed to a run of [`BLOCK_SLOTS`] adjacent slots
    /// (Teschner et al.'s hash, the key mixed in with a fourth large prime), and the cell takes
    /// the slot of its place in the block. A query's 2 × 2 × 2 cells then fall in one block
    /// when the query point lies in a block's inner half along all three axes, and in 1.5³ ≈
    /// 3.4 blocks on average instead of 8 hashed slots: their bounds and points are that many
    /// contiguous runs in memory (docs/design.md "### VCM", cache misses of the merge pass).
    fn slot_of(&self, c: [i64; 3], key: u32) -> usize {
        let h = ((c[0] >> 1).wrapping_mul(73_856_093))
            ^ ((c[1] >> 1).wrapping_mul(19_349_663))
            ^ ((c[2] >> 1).wrapping_mul(83_492_791))
            ^ (i64::from(key).wrapping_mul(2_654_435_761));
        let within = ((c[0] & 1) | ((c[1] & 1) << 1) | ((c[2] & 1) << 2)) as usize;
        ((h as u64 as usize).wrapping_mul(BLOCK_SLOTS) | within) & (self.slot_end.len() - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::rng::Rng;

    #[test]
    fn queries_find_exactly_the_points_within_the_radius() {
        let mut rng = Rng::new(7);
        let points: Vec<Vec3> = (0..2000).map(|_| rng.vec3(-1.0, 1.0)).collect();
        let mut grid = HashGrid::default();
        let key = |i: usize| (i % 3) as u32;
        for radius in [0.05f32, 0.2, 3.0] {
            let point = |i: usize| GridPoint {
                p: points[i],
                key: key(i),
            };
            grid.build(points.len(), point, radius);
            for _ in 0..200 {
                let q = rng.vec3(-1.2, 1.2);
                for k in 0..4 {
                    let mut found: Vec<u32> = Vec::new();
                    grid.query(q, k, |s| found.push(grid.order()[s]));
                    found.sort_unstable();
                    let brute: Vec<u32> = (0..points.len() as u32)
                        .filter(|&i| {
                            key(i as usize) == k && (points[i as usize] - q).length() <= radius
                        })
                        .collect();
                    assert_eq!(found, brute, "radius {radius} at {q}, key {k}");
                }
            }
        }
    }

    #[test]
    fn the_cells_of_an_aligned_block_take_adjacent_slots() {
        let mut rng = Rng::new(3);
        let points: Vec<Vec3> = (0..5000).map(|_| rng.vec3(-1.0, 1.0)).collect();
        let mut grid = HashGrid::default();
        grid.build(
            points.len(),
            |i| GridPoint {
                p: points[i],
                key: 1,
            },
            0.01,
        );
        for _ in 0..100 {
            let c = rng.vec3(-100.0, 100.0);
            let base = [2 * c.x as i64, 2 * c.y as i64, 2 * c.z as i64];
            let slots: Vec<usize> = (0..8)
                .map(|k| {
                    let cell = [
                        base[0] + (k & 1),
                        base[1] + ((k >> 1) & 1),
                        base[2] + (k >> 2),
                    ];
                    grid.slot_of(cell, 1)
                })
                .collect();
            let first = slots[0];
            assert_eq!(first % BLOCK_SLOTS, 0, "{slots:?}");
            assert!(
                slots.iter().enumerate().all(|(k, &s)| s == first + k),
                "{slots:?}"
            );
        }
    }

    #[test]
    fn an_empty_grid_and_far_points_are_safe() {
        let mut grid = HashGrid::default();
        grid.build(0, |_| unreachable!("no points"), 0.1);
        grid.query(Vec3::ZERO, 0, |_| panic!("no points"));
        let far = [Vec3::splat(1e30), Vec3::splat(-1e30), Vec3::ZERO];
        grid.build(far.len(), |i| GridPoint { p: far[i], key: 0 }, 1e-6);
        let mut found = Vec::new();
        grid.query(Vec3::ZERO, 0, |s| found.push(grid.order()[s]));
        assert_eq!(found, [2]);
    }

    #[test]
    fn the_build_is_the_same_on_one_thread_and_on_several() {
        let mut rng = Rng::new(11);
        // Several build chunks, clustered so that slots hold many points.
        let points: Vec<Vec3> = (0..3 * BUILD_CHUNK + 17)
            .map(|_| rng.vec3(-0.3, 0.3))
            .collect();
        let point = |i: usize| GridPoint {
            p: points[i],
            key: (i % 2) as u32,
        };
        let build = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut grid = HashGrid::default();
            pool.install(|| grid.build(points.len(), point, 0.02));
            grid
        };
        let (one, four) = (build(1), build(4));
        assert_eq!(one.order, four.order);
        assert_eq!(one.points, four.points);
        assert_eq!(one.slot_end, four.slot_end);
        // Within a slot, by decreasing point index.
        let mut start = 0usize;
        for &end in &one.slot_end {
            let slot = &one.order[start..end as usize];
            assert!(slot.windows(2).all(|w| w[0] > w[1]), "{slot:?}");
            start = end as usize;
        }
    }
}
