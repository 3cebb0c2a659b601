//! A pixel's two replicates kept apart, for films whose pixels take different numbers of even
//! and odd samples (adaptive sampling, `session::adaptive`).
//!
//! The even and the odd samples of a pixel are two independent estimates of it, with means a
//! and b over n_even and n_odd samples. When the counts are equal, the pixel is the mean of
//! all its samples, (a + b)/2 (the film's own sum over n). When they differ, the film's sum
//! over n would weight the replicates by their counts, and adaptive sampling chooses each
//! replicate's count from the other replicate's pilot: weights that depend on the samples
//! would bias the pixel. So the pixel is (a + b)/2 with the fixed weights ½, and the variance
//! of that mean is estimated by (a − b)²/4.

use super::grid_sum::{Fixed3, Grid};

/// The odd samples' own-pixel sums and counts per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Replicates {
    odd: Vec<Fixed3>,
    odd_samples: Vec<u64>,
}

impl Replicates {
    pub fn new(pixels: usize) -> Replicates {
        Replicates {
            odd: vec![[0; 3]; pixels],
            odd_samples: vec![0; pixels],
        }
    }

    /// Adds the odd samples' sum `odd` and their count `n` to pixel `i`; true when a sum
    /// saturated.
    pub fn add(&mut self, i: usize, odd: &Fixed3, n: u64) -> bool {
        self.odd_samples[i] += n;
        Grid::add3(&mut self.odd[i], odd)
    }

    /// The odd samples of pixel `i` so far.
    pub fn odd_samples(&self, i: usize) -> u64 {
        self.odd_samples[i]
    }

    /// Pixel `i`'s (a + b)/2 from `sums` over all its `n` samples, where its replicates'
    /// counts differ and neither is empty; None where they are equal (the plain mean is the
    /// same estimate) or one is empty.
    pub fn mean(&self, i: usize, sums: &Fixed3, n: u64, g: Grid) -> Option<[f64; 3]> {
        let n_odd = self.odd_samples[i];
        let n_even = n - n_odd;
        if n_odd == n_even || n_odd == 0 || n_even == 0 {
            return None;
        }
        let (ne, no) = (n_even as f64, n_odd as f64);
        Some(std::array::from_fn(|c| {
            let odd = g.value(self.odd[i][c]);
            let even = g.value(sums[c].saturating_sub(self.odd[i][c]));
            0.5 * (even / ne + odd / no)
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::grid_sum::GRID_BITS;

    const UNIT: Grid = Grid {
        exponent: GRID_BITS,
    };

    fn fixed(v: [f64; 3]) -> Fixed3 {
        v.map(|c| UNIT.term(c).0)
    }

    #[test]
    fn unequal_replicates_are_averaged_with_weights_one_half() {
        let mut r = Replicates::new(1);
        // Even: 3 samples summing to (3, 6, 9): mean (1, 2, 3). Odd: 1 sample (5, 5, 5).
        r.add(0, &fixed([5.0; 3]), 1);
        let all = fixed([8.0, 11.0, 14.0]);
        assert_eq!(r.mean(0, &all, 4, UNIT), Some([3.0, 3.5, 4.0]));
        // Equal counts: the film's own mean.
        let mut e = Replicates::new(1);
        e.add(0, &fixed([5.0; 3]), 2);
        assert_eq!(e.mean(0, &all, 4, UNIT), None);
        assert_eq!(Replicates::new(1).mean(0, &all, 4, UNIT), None);
        assert_eq!(r.odd_samples(0), 1);
    }
}
