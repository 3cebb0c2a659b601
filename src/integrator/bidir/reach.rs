//! Where a fixed-radius query can find a point at all: a coarse bitmap over the points'
//! bounding box, for the hash grid's queries (`hashgrid.rs`) to skip, in one test, the camera
//! vertices no stored light vertex lies near.
//!
//! Why: under VCM's default merge rule (`merge_rule.rs`) only the light vertices that follow a
//! near-specular one are gridded, a few per iteration on a stage like `scenes/caustic.usda`
//! (about 16 at 96 × 72), spread over the room by the glass ball's reflection, while every
//! non-specular camera vertex queries. The grid's table has as many slots as points, so each
//! query hashed its 2 × 2 × 2 cells into a table they almost all shared and scanned the hash
//! collisions' candidates, to find nothing: about 1,200 instructions per query, 9 % of the
//! render (docs/design.md "### VCM", "The cost per sample, session 29").
//!
//! The bitmap divides the box grown by 2r on every side into at most 32 cells per axis, each
//! at least 4r wide, and marks the cells that the cube of half-side 2r around some point
//! overlaps (at most 2 per axis). A point within r of a query point q differs from it by at
//! most r along every axis, so q lies in that cube and its cell is marked: an unmarked cell
//! has no point within r. The margin is twice the radius so that the rounding of the bounds
//! and of the distance test cannot matter (the cell index is a monotone function of the
//! coordinate). Exact: a query that passes scans as before, so the grid finds the same
//! points in the same order, and the images stay bit for bit the same.

use glam::Vec3;

/// Cells per axis of the bitmap at most (32³ bits: 4 KB).
const MAX_CELLS: usize = 32;

#[derive(Clone, Debug, Default)]
pub struct Reach {
    /// The points' bounding box grown by 2r.
    lo: Vec3,
    hi: Vec3,
    /// Cells per unit length along each axis.
    inv: Vec3,
    dims: [usize; 3],
    /// One bit per cell, x fastest.
    bits: Vec<u64>,
}

impl Reach {
    /// Rebuilds the bitmap over `points` (bounding box `lo`–`hi`) for radius `radius` (> 0).
    pub fn build(
        &mut self,
        points: impl ExactSizeIterator<Item = Vec3>,
        lo: Vec3,
        hi: Vec3,
        radius: f32,
    ) {
        let margin = Vec3::splat(2.0 * radius);
        self.lo = lo - margin;
        self.hi = hi + margin;
        let extent = self.hi - self.lo;
        let cells = |e: f32| ((e / (2.0 * margin.x)) as usize).clamp(1, MAX_CELLS);
        self.dims = [cells(extent.x), cells(extent.y), cells(extent.z)];
        let dims = Vec3::new(
            self.dims[0] as f32,
            self.dims[1] as f32,
            self.dims[2] as f32,
        );
        let inv = dims / extent;
        // An infinite or empty extent maps every coordinate to cell 0.
        self.inv = Vec3::select(inv.is_finite_mask(), inv, Vec3::ZERO);
        let total = self.dims.iter().product::<usize>();
        self.bits.clear();
        // Many points mark nearly every cell: then every query passes, unmarked.
        let all = points.len() >= total;
        self.bits
            .resize(total.div_ceil(64), if all { u64::MAX } else { 0 });
        if all {
            return;
        }
        for p in points {
            let (a, b) = (self.cell(p - margin), self.cell(p + margin));
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        let i = self.index([x, y, z]);
                        self.bits[i / 64] |= 1 << (i % 64);
                    }
                }
            }
        }
    }

    /// False when no point of the build lies within the radius of `q`.
    #[inline]
    pub fn may_reach(&self, q: Vec3) -> bool {
        if q.cmplt(self.lo).any() || q.cmpgt(self.hi).any() || self.bits.is_empty() {
            return false;
        }
        let i = self.index(self.cell(q));
        self.bits[i / 64] & (1 << (i % 64)) != 0
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.bits.capacity() * std::mem::size_of::<u64>()
    }

    /// The cell of `p`, clamped to the bitmap (a NaN coordinate maps to 0).
    #[inline]
    fn cell(&self, p: Vec3) -> [usize; 3] {
        let c = (p - self.lo) * self.inv;
        let axis = |v: f32, n: usize| (v.max(0.0) as usize).min(n - 1);
        [
            axis(c.x, self.dims[0]),
            axis(c.y, self.dims[1]),
            axis(c.z, self.dims[2]),
        ]
    }

    #[inline]
    fn index(&self, c: [usize; 3]) -> usize {
        c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::rng::Rng;

    fn bounds(points: &[Vec3]) -> (Vec3, Vec3) {
        points.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
    }

    #[test]
    fn no_point_within_the_radius_of_a_rejected_query() {
        let mut rng = Rng::new(5);
        for (n, radius) in [(1usize, 0.01f32), (16, 0.003), (300, 0.02), (5000, 0.001)] {
            // Clustered points (a caustic) and a few far ones (a reflection's).
            let mut points: Vec<Vec3> = (0..n).map(|_| rng.vec3(0.2, 0.25)).collect();
            points.extend((0..3).map(|_| rng.vec3(-2.0, 2.0)));
            let (lo, hi) = bounds(&points);
            let mut reach = Reach::default();
            reach.build(points.iter().copied(), lo, hi, radius);
            let (mut rejected, mut queries) = (0, 0);
            for _ in 0..20_000 {
                // Queries near the points as well as anywhere.
                let q = if queries % 2 == 0 {
                    points[queries % points.len()] + rng.vec3(-2.0 * radius, 2.0 * radius)
                } else {
                    rng.vec3(-2.5, 2.5)
                };
                queries += 1;
                let near = points
                    .iter()
                    .any(|&p| (p - q).length_squared() <= radius * radius);
                if !reach.may_reach(q) {
                    assert!(!near, "{q} rejected with a point within {radius}");
                    rejected += 1;
                }
            }
            // It rejects most queries far from every point.
            assert!(rejected > queries / 4, "{n}: {rejected} of {queries}");
        }
    }

    #[test]
    fn odd_inputs_are_safe() {
        let mut reach = Reach::default();
        assert!(!reach.may_reach(Vec3::ZERO));
        let far = [Vec3::splat(1e30), Vec3::splat(-1e30)];
        let (lo, hi) = bounds(&far);
        reach.build(far.iter().copied(), lo, hi, 1e-6);
        assert!(reach.may_reach(Vec3::splat(1e30)));
        // A NaN query is no error (the grid then finds nothing within the radius).
        let _ = reach.may_reach(Vec3::splat(f32::NAN));
        let one = [Vec3::ONE];
        reach.build(one.iter().copied(), Vec3::ONE, Vec3::ONE, 0.5);
        assert!(reach.may_reach(Vec3::splat(1.4)));
        assert!(!reach.may_reach(Vec3::splat(3.5)));
    }
}
