//! Running mean and variance of a reading's per-sample estimates, in f64.
//!
//! Samples are added one at a time with Welford's update (Welford 1962, "Note on a method for
//! calculating corrected sums of squares and products", Technometrics 4(3)) and blocks of
//! samples are combined with the pairwise formula of Chan, Golub & LeVeque 1979 ("Updating
//! formulae and a pairwise algorithm for computing sample variances", eq. 2.1b). Blocks are
//! always merged in sample order, so the result does not depend on the number of threads.

/// Count, mean and sum of squared deviations (M₂) of a set of samples.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    pub n: u64,
    pub mean: f64,
    pub m2: f64,
}

pub use crate::math::Z95;

impl Stats {
    /// Adds one sample (Welford).
    #[inline]
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    /// Appends the samples summarised by `other` (Chan et al.).
    pub fn merge(&mut self, other: &Stats) {
        if other.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = *other;
            return;
        }
        let (na, nb) = (self.n as f64, other.n as f64);
        let n = na + nb;
        let d = other.mean - self.mean;
        self.mean += d * (nb / n);
        self.m2 += other.m2 + d * d * (na * nb / n);
        self.n += other.n;
    }

    /// Unbiased sample variance s² (infinite with fewer than two samples).
    pub fn variance(&self) -> f64 {
        if self.n < 2 {
            return f64::INFINITY;
        }
        (self.m2 / (self.n - 1) as f64).max(0.0)
    }

    /// Half-width of the 95% confidence interval of the mean, 1.96·s/√n: the normal
    /// approximation of the sample mean (central limit theorem), with s the sample standard
    /// deviation.
    pub fn ci95(&self) -> f64 {
        Z95 * (self.variance() / self.n as f64).sqrt()
    }

    /// ci95 / |mean|: 0 when every sample was exactly 0, infinite for a zero mean otherwise.
    pub fn relative_ci95(&self) -> f64 {
        let h = self.ci95();
        if self.mean != 0.0 {
            h / self.mean.abs()
        } else if self.m2 == 0.0 && self.n >= 2 {
            0.0
        } else {
            f64::INFINITY
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn naive(xs: &[f64]) -> (f64, f64) {
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, var)
    }

    #[test]
    fn welford_and_merging_match_the_two_pass_formula() {
        let xs: Vec<f64> = (0..1000)
            .map(|i| 1e6 + ((i * 7919) % 1013) as f64 * 0.37)
            .collect();
        let (mean, var) = naive(&xs);
        let mut all = Stats::default();
        xs.iter().for_each(|&x| all.push(x));
        let mut merged = Stats::default();
        for chunk in xs.chunks(77) {
            let mut s = Stats::default();
            chunk.iter().for_each(|&x| s.push(x));
            merged.merge(&s);
        }
        for s in [all, merged] {
            assert_eq!(s.n, 1000);
            assert!((s.mean - mean).abs() < 1e-9 * mean);
            assert!((s.variance() / var - 1.0).abs() < 1e-9);
        }
        assert!((all.ci95() - Z95 * (var / 1000.0).sqrt()).abs() < 1e-9);
    }

    #[test]
    fn degenerate_cases() {
        let mut s = Stats::default();
        assert_eq!(s.relative_ci95(), f64::INFINITY);
        s.push(0.0);
        s.push(0.0);
        assert_eq!(s.relative_ci95(), 0.0);
        let mut one = Stats::default();
        one.push(3.0);
        assert!(one.ci95().is_infinite());
    }
}
