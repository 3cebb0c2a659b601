//! The ratio estimator of survey sampling: R = Σc / Σt over n paired observations (c, t),
//! and its standard error se² = n/(n − 1) · Σ (c − R t)² / (Σ t)² (Cochran, *Sampling
//! Techniques*, 3rd ed. 1977, §6.3–6.4, eq. 6.9 with s²(c − R t) = Σ (c − R t)² / (n − 1)
//! and no finite-population correction).
//!
//! Used where a figure is a ratio of two sums whose terms are noisy together: the fraction of
//! the light a depth cap cut (`integrator::cut`, per sample or per batch of samples), and the
//! ratio of two integrators' pilot variances over the same pixel blocks (`session::auto`).

use super::Z95;

/// Paired sums of observations (c, t) for the ratio R = Σc / Σt and its standard error,
/// accumulated in one pass (Σ (c − R t)² = Σc² − 2R Σct + R² Σt²), so that sums from threads
/// or batches merge.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RatioSums {
    pub n: u64,
    pub c: f64,
    pub t: f64,
    pub cc: f64,
    pub ct: f64,
    pub tt: f64,
}

impl RatioSums {
    #[inline]
    pub fn push(&mut self, c: f64, t: f64) {
        self.n += 1;
        self.c += c;
        self.t += t;
        self.cc += c * c;
        self.ct += c * t;
        self.tt += t * t;
    }

    pub fn merge(&mut self, o: &RatioSums) {
        self.n += o.n;
        self.c += o.c;
        self.t += o.t;
        self.cc += o.cc;
        self.ct += o.ct;
        self.tt += o.tt;
    }

    /// R = Σc / Σt (0 when nothing was measured).
    pub fn ratio(&self) -> f64 {
        if self.t != 0.0 {
            self.c / self.t
        } else {
            0.0
        }
    }

    /// The standard error of R, √(n/(n − 1) · Σ (c − R t)²) / |Σt| (Cochran 1977, eq. 6.9);
    /// infinite with fewer than two observations or Σt = 0.
    pub fn standard_error(&self) -> f64 {
        if self.n < 2 || self.t == 0.0 {
            return f64::INFINITY;
        }
        let r = self.ratio();
        let n = self.n as f64;
        let residuals = (self.cc - 2.0 * r * self.ct + r * r * self.tt).max(0.0);
        (n / (n - 1.0) * residuals).sqrt() / self.t.abs()
    }

    /// The 95 % half-width of R in the normal approximation, [`Z95`] × the standard error.
    pub fn ci95(&self) -> f64 {
        Z95 * self.standard_error()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_standard_error_is_the_two_pass_one() {
        let pairs = [(1.0, 2.0), (2.5, 3.0), (0.5, 1.5), (4.0, 5.0), (1.0, 1.0)];
        let mut s = RatioSums::default();
        pairs.iter().for_each(|&(c, t)| s.push(c, t));
        let (sc, st): (f64, f64) = pairs.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
        let r = sc / st;
        let squares: f64 = pairs.iter().map(|(c, t)| (c - r * t).powi(2)).sum();
        let se = (5.0 / 4.0 * squares).sqrt() / st;
        assert!((s.ratio() - r).abs() < 1e-15);
        assert!(
            (s.standard_error() / se - 1.0).abs() < 1e-12,
            "{}",
            s.standard_error()
        );
        // Merging halves gives the whole.
        let (mut a, mut b) = (RatioSums::default(), RatioSums::default());
        pairs[..2].iter().for_each(|&(c, t)| a.push(c, t));
        pairs[2..].iter().for_each(|&(c, t)| b.push(c, t));
        a.merge(&b);
        assert!((a.standard_error() / se - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_interval_covers_a_known_fraction() {
        // c = 0.3 t + noise: R → 0.3; the interval shrinks as 1/√n. A fixed sequence of
        // equidistributed noise (the golden-ratio sequence) keeps the test deterministic.
        let mut r = RatioSums::default();
        for k in 0..10_000 {
            let u = (k as f64 * 0.618_033_988_749_895).fract();
            let v = (k as f64 * 0.754_877_666_246_693).fract();
            let t = 1.0 + u;
            r.push(0.3 * t + 0.2 * (v - 0.5), t);
        }
        let (ratio, h) = (r.ratio(), r.ci95());
        assert!((ratio - 0.3).abs() < h, "{ratio} ± {h}");
        assert!(h > 0.0 && h < 0.01, "{h}");
    }

    #[test]
    fn too_few_observations_give_an_infinite_error() {
        assert!(RatioSums::default().ci95().is_infinite());
        let mut one = RatioSums::default();
        one.push(1.0, 2.0);
        assert!(one.standard_error().is_infinite());
        let mut zero = RatioSums::default();
        zero.push(1.0, 0.0);
        zero.push(-1.0, 0.0);
        assert!(zero.standard_error().is_infinite());
    }
}
