//! Piecewise-constant 1D and 2D distributions (PBR 4ed §A.4.1 and §A.4.2).

/// Sampling an index (or a continuous value) proportionally to non-negative weights.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    func: Vec<f32>,
    cdf: Vec<f32>,
    integral: f32,
}

impl Distribution1D {
    /// Weights must be finite and non-negative; if all are zero, sampling is uniform.
    pub fn new(weights: &[f32]) -> Distribution1D {
        let func: Vec<f32> = weights
            .iter()
            .map(|w| if w.is_finite() { w.max(0.0) } else { 0.0 })
            .collect();
        let n = func.len();
        let mut cdf = vec![0.0f32; n + 1];
        let mut acc = 0.0f64;
        for i in 0..n {
            acc += func[i] as f64 / n as f64;
            cdf[i + 1] = acc as f32;
        }
        let integral = acc as f32;
        if integral > 0.0 {
            for c in cdf.iter_mut().skip(1) {
                *c /= integral;
            }
        } else {
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f32 / n.max(1) as f32;
            }
        }
        cdf[n] = 1.0;
        Distribution1D {
            func,
            cdf,
            integral,
        }
    }

    pub fn len(&self) -> usize {
        self.func.len()
    }

    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// Mean of the weights (the integral over [0,1] of the step function).
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Samples a discrete index; returns (index, probability, remapped u in [0,1)).
    #[inline]
    pub fn sample_discrete(&self, u: f32) -> (usize, f32, f32) {
        let i = self.find_interval(u);
        let width = self.cdf[i + 1] - self.cdf[i];
        let remapped = if width > 0.0 {
            ((u - self.cdf[i]) / width).clamp(0.0, 1.0 - f32::EPSILON)
        } else {
            0.0
        };
        (i, self.discrete_pmf(i), remapped)
    }

    /// Probability of index `i` under [`Self::sample_discrete`].
    #[inline]
    pub fn discrete_pmf(&self, i: usize) -> f32 {
        self.cdf[i + 1] - self.cdf[i]
    }

    /// Samples a continuous value in [0,1) with density func(x)/integral (PBR 4ed §A.4.1);
    /// returns (x, pdf, index).
    #[inline]
    pub fn sample_continuous(&self, u: f32) -> (f32, f32, usize) {
        let i = self.find_interval(u);
        let width = self.cdf[i + 1] - self.cdf[i];
        let du = if width > 0.0 {
            (u - self.cdf[i]) / width
        } else {
            0.0
        };
        let n = self.func.len() as f32;
        let x = ((i as f32 + du) / n).min(1.0 - f32::EPSILON);
        (x, self.pdf_continuous_index(i), i)
    }

    /// Density at cell `i` of the continuous distribution.
    #[inline]
    pub fn pdf_continuous_index(&self, i: usize) -> f32 {
        if self.integral > 0.0 {
            self.func[i] / self.integral
        } else {
            1.0
        }
    }

    /// Largest i with cdf[i] <= u, clamped to a valid cell.
    #[inline]
    fn find_interval(&self, u: f32) -> usize {
        let n = self.func.len();
        let i = self.cdf.partition_point(|&c| c <= u);
        let i = i.saturating_sub(1).min(n - 1);
        // Skip zero-width cells so a zero-weight entry is never chosen. The cell's width is
        // tested alone first (`cdf` has n + 1 entries, so `cdf[i + 1]` exists for i ≤ n − 1):
        // it is almost never zero, where the loop's `i + 1 < n`, which LLVM tests first, is as
        // random as the choice itself: a branch mispredicted on every other call of a
        // two-entry table (design.md §8, ninth pass).
        if self.cdf[i + 1] == self.cdf[i] {
            return self.skip_zero_widths(i);
        }
        i
    }

    /// The first cell from `i` on that has a non-zero width, or the last cell.
    fn skip_zero_widths(&self, mut i: usize) -> usize {
        let n = self.func.len();
        while i + 1 < n && self.cdf[i + 1] == self.cdf[i] {
            i += 1;
        }
        i
    }
}

/// A piecewise-constant 2D distribution on [0,1)² (marginal in v, conditionals in u).
#[derive(Clone, Debug, Default)]
pub struct Distribution2D {
    conditionals: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// `weights` is row-major with `nu` columns and `nv` rows.
    pub fn new(weights: &[f32], nu: usize, nv: usize) -> Distribution2D {
        let conditionals: Vec<Distribution1D> = (0..nv)
            .map(|v| Distribution1D::new(&weights[v * nu..(v + 1) * nu]))
            .collect();
        let marginal = Distribution1D::new(
            &conditionals
                .iter()
                .map(|c| c.integral())
                .collect::<Vec<_>>(),
        );
        Distribution2D {
            conditionals,
            marginal,
        }
    }

    /// Returns ((u, v), pdf) with pdf relative to the unit square.
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> ([f32; 2], f32) {
        let (v, pdf_v, iv) = self.marginal.sample_continuous(u[1]);
        let (uu, pdf_u, _) = self.conditionals[iv].sample_continuous(u[0]);
        ([uu, v], pdf_u * pdf_v)
    }

    #[inline]
    pub fn pdf(&self, p: [f32; 2]) -> f32 {
        let nv = self.conditionals.len();
        let nu = self.conditionals[0].len();
        let iv = ((p[1] * nv as f32) as usize).min(nv - 1);
        let iu = ((p[0] * nu as f32) as usize).min(nu - 1);
        let m = self.marginal.integral();
        if m > 0.0 {
            self.conditionals[iv].func[iu] / m
        } else {
            1.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    #[test]
    fn discrete_frequencies_follow_weights() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, 4.0]);
        let mut counts = [0usize; 4];
        let mut s = Sampler::new(1, 0, 0);
        let n = 80_000;
        for _ in 0..n {
            counts[d.sample_discrete(s.get_1d()).0] += 1;
        }
        assert_eq!(counts[1], 0);
        for (i, &w) in [1.0f64, 0.0, 3.0, 4.0].iter().enumerate() {
            let p = w / 8.0;
            let sigma = (p * (1.0 - p) / n as f64).sqrt();
            assert!((counts[i] as f64 / n as f64 - p).abs() <= 5.0 * sigma + 1e-12);
            assert!((d.discrete_pmf(i) as f64 - p).abs() < 1e-6);
        }
    }

    /// `find_interval` as it was written before its two tests were swapped.
    fn interval_reference(d: &Distribution1D, u: f32) -> usize {
        let n = d.func.len();
        let mut i = d
            .cdf
            .partition_point(|&c| c <= u)
            .saturating_sub(1)
            .min(n - 1);
        while i + 1 < n && d.cdf[i + 1] == d.cdf[i] {
            i += 1;
        }
        i
    }

    #[test]
    fn interval_is_the_references_with_zero_widths_anywhere() {
        let tables: [&[f32]; 7] = [
            &[1.0, 1.0],
            &[1.0, 0.0],
            &[0.0, 1.0],
            &[0.0, 0.0, 2.0, 0.0, 0.0],
            &[3.0],
            &[0.0, 0.0, 0.0],
            &[1.0, 0.0, 3.0, 4.0, 0.0],
        ];
        let mut s = Sampler::new(7, 0, 0);
        for w in tables {
            let d = Distribution1D::new(w);
            let mut us = vec![
                0.0,
                1.0,
                -0.0,
                -1.0,
                2.0,
                f32::NAN,
                1.0 - f32::EPSILON / 2.0,
            ];
            for &c in &d.cdf {
                us.extend([c, c.next_down(), c.next_up()]);
            }
            us.extend((0..1000).map(|_| s.get_1d()));
            for u in us {
                assert_eq!(
                    d.find_interval(u),
                    interval_reference(&d, u),
                    "{w:?} at {u}"
                );
            }
        }
    }

    #[test]
    fn continuous_pdf_integrates_to_one() {
        let d = Distribution2D::new(&[1.0, 2.0, 0.0, 5.0, 1.0, 1.0], 3, 2);
        let n = 300;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                sum += d.pdf([(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32]) as f64;
            }
        }
        assert!((sum / (n * n) as f64 - 1.0).abs() < 1e-3);
        let ([u, v], pdf) = d.sample([0.3, 0.7]);
        assert!((pdf - d.pdf([u, v])).abs() < 1e-4);
    }
}
