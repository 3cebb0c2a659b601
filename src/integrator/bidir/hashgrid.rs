//! A hash grid over points for fixed-radius queries: the light vertices an iteration of VCM
//! stores, looked up around every camera vertex (Georgiev et al. 2012 §5; SmallVCM's
//! `HashGrid`, written anew). Every point carries a key (the hero-wavelength bin of its light
//! subpath, `vcm.rs`; 0 when all share one), hashed with its cell: a query finds only the
//! points of its own key.
//!
//! Cells are cubes of side 2r, so a ball of radius r around a query point overlaps at most
//! the 2 × 2 × 2 block of cells nearest to it. Cells are hashed into a table of a power of two
//! slots, at least as many as points (Teschner et al. 2003, "Optimized spatial hashing for
//! collision detection of deformable objects", with their three primes); points are sorted by
//! slot with a counting sort, so a slot's points are contiguous. Hash collisions only add
//! candidates: every candidate is tested against the radius, by the grid itself on a copy of
//! the positions in slot order (a query reads a candidate's index, key and position from
//! three contiguous arrays, not the caller's record; on a surface the 2 × 2 × 2 block holds
//! about 5 candidates for each inside the ball, (4r)² / π r²). The buffers are kept and
//! reused by the next build.

use glam::Vec3;

#[derive(Clone, Debug, Default)]
pub struct HashGrid {
    /// Point indices sorted by slot, with their keys and positions.
    indices: Vec<u32>,
    keys: Vec<u32>,
    points: Vec<Vec3>,
    /// `slot_end[k]`: one past the last entry of slot k in `indices` (slot k starts at
    /// `slot_end[k − 1]`, or 0).
    slot_end: Vec<u32>,
    origin: Vec3,
    inv_cell: f32,
    radius2: f32,
}

impl HashGrid {
    /// Rebuilds the grid over `points` (position, key) for queries of radius `radius` (> 0,
    /// finite).
    pub fn build(
        &mut self,
        points: impl ExactSizeIterator<Item = (Vec3, u32)> + Clone,
        radius: f32,
    ) {
        let n = points.len();
        let slots = n.max(1).next_power_of_two();
        let lo = points
            .clone()
            .fold(Vec3::splat(f32::INFINITY), |a, (p, _)| a.min(p));
        self.origin = if lo.is_finite() { lo } else { Vec3::ZERO };
        self.inv_cell = 1.0 / (2.0 * radius);
        self.radius2 = radius * radius;
        self.slot_end.clear();
        self.slot_end.resize(slots, 0);
        for (p, key) in points.clone() {
            let k = self.slot_of(self.cell_of(p), key);
            self.slot_end[k] += 1;
        }
        let mut start = 0u32;
        for c in self.slot_end.iter_mut() {
            start += *c;
            *c = start;
        }
        self.indices.clear();
        self.indices.resize(n, 0);
        self.keys.clear();
        self.keys.resize(n, 0);
        self.points.clear();
        self.points.resize(n, Vec3::ZERO);
        // Filling from the back leaves the cursor at each slot's start.
        let mut cursor = self.slot_end.clone();
        for (i, (p, key)) in points.enumerate() {
            let k = self.slot_of(self.cell_of(p), key);
            cursor[k] -= 1;
            self.indices[cursor[k] as usize] = i as u32;
            self.keys[cursor[k] as usize] = key;
            self.points[cursor[k] as usize] = p;
        }
    }

    /// Calls `visit(i)` for every point index i of key `key` whose point lies within the
    /// radius of `q` ([`Self::within`]), in a fixed order.
    pub fn query(&self, q: Vec3, key: u32, mut visit: impl FnMut(u32)) {
        if self.indices.is_empty() {
            return;
        }
        let c = (q - self.origin) * self.inv_cell;
        let base = c.floor();
        let frac = c - base;
        // The 2 × 2 × 2 block: the cell of q and its neighbour on the side q is nearer to.
        let step = |f: f32| if f < 0.5 { -1 } else { 1 };
        let b = [base.x as i64, base.y as i64, base.z as i64];
        let d = [step(frac.x), step(frac.y), step(frac.z)];
        let mut seen = [usize::MAX; 8];
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
            let range = if k == 0 {
                0
            } else {
                self.slot_end[k - 1] as usize
            }..self.slot_end[k] as usize;
            let entries = self.indices[range.clone()]
                .iter()
                .zip(&self.keys[range.clone()]);
            for ((&i, &pk), &p) in entries.zip(&self.points[range]) {
                if pk == key && self.within(q, p) {
                    visit(i);
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
        (self.indices.capacity() + self.keys.capacity() + self.slot_end.capacity())
            * std::mem::size_of::<u32>()
            + self.points.capacity() * std::mem::size_of::<Vec3>()
    }

    fn cell_of(&self, p: Vec3) -> [i64; 3] {
        let c = ((p - self.origin) * self.inv_cell).floor();
        // Saturating casts: a point far outside the others lands in some cell, never UB.
        [c.x as i64, c.y as i64, c.z as i64]
    }

    /// The slot of cell `c` for points of key `key` (Teschner et al.'s hash, the key mixed in
    /// with a fourth large prime).
    fn slot_of(&self, c: [i64; 3], key: u32) -> usize {
        let h = (c[0].wrapping_mul(73_856_093))
            ^ (c[1].wrapping_mul(19_349_663))
            ^ (c[2].wrapping_mul(83_492_791))
            ^ (i64::from(key).wrapping_mul(2_654_435_761));
        (h as u64 as usize) & (self.slot_end.len() - 1)
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
            grid.build(points.iter().enumerate().map(|(i, p)| (*p, key(i))), radius);
            for _ in 0..200 {
                let q = rng.vec3(-1.2, 1.2);
                for k in 0..4 {
                    let mut found: Vec<u32> = Vec::new();
                    grid.query(q, k, |i| found.push(i));
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
    fn an_empty_grid_and_far_points_are_safe() {
        let mut grid = HashGrid::default();
        grid.build(std::iter::empty::<(Vec3, u32)>(), 0.1);
        grid.query(Vec3::ZERO, 0, |_| panic!("no points"));
        let far = [Vec3::splat(1e30), Vec3::splat(-1e30), Vec3::ZERO];
        grid.build(far.iter().map(|p| (*p, 0)), 1e-6);
        let mut found = Vec::new();
        grid.query(Vec3::ZERO, 0, |i| found.push(i));
        assert_eq!(found, [2]);
    }
}
