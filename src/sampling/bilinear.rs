//! Sampling the unit square in proportion to a linear or bilinear function of four corner
//! values, by inversion (PBR 4ed §2.3 for the inversion method; the bilinear density as a
//! marginal in y and a conditional in x, §2.4.2's marginal–conditional recipe). Used to warp the
//! primary sample of solid-angle light sampling by the receiver's cos θ at the light's corners
//! (Hart et al. 2020, "Practical Product Sampling by Fitting and Composing Warps", EGSR, §4;
//! PBR 4ed §6.5.4).
//!
//! Corner order of the four weights: [w(0,0), w(1,0), w(0,1), w(1,1)] (x first).

/// x ∈ [0, 1] with density p(x) = 2((1 − x) a + x b)/(a + b), a, b ≥ 0 not both 0: the root
/// of the CDF (a x + (b − a) x²/2)/((a + b)/2) = u, written as u(a + b)/(a + √((1 − u)a² + u b²))
/// (the quadratic's root rationalised, exact also for a = b).
#[inline]
pub fn sample_linear(u: f32, a: f32, b: f32) -> f32 {
    if u == 0.0 && a == 0.0 {
        return 0.0;
    }
    let x = u * (a + b) / (a + ((1.0 - u) * a * a + u * b * b).sqrt());
    // The largest f32 below 1 (pbrt's `OneMinusEpsilon`): samples stay in [0, 1).
    x.min(1.0 - f32::EPSILON / 2.0)
}

/// A point of the unit square with density [`bilinear_pdf`]: y from the marginal (linear in y
/// with end values w00 + w10 and w01 + w11), then x from the conditional at that y (linear with
/// ends lerp(y, w00, w01) and lerp(y, w10, w11)).
#[inline]
pub fn sample_bilinear(u: [f32; 2], w: [f32; 4]) -> [f32; 2] {
    let y = sample_linear(u[1], w[0] + w[1], w[2] + w[3]);
    let a = (1.0 - y) * w[0] + y * w[2];
    let b = (1.0 - y) * w[1] + y * w[3];
    [sample_linear(u[0], a, b), y]
}

/// p(x, y) = 4 f(x, y) / (w00 + w10 + w01 + w11), f the bilinear interpolation of the corners
/// (its integral over the square is their mean).
#[inline]
pub fn bilinear_pdf(p: [f32; 2], w: [f32; 4]) -> f32 {
    let [x, y] = p;
    if !(0.0..=1.0).contains(&x) || !(0.0..=1.0).contains(&y) {
        return 0.0;
    }
    let sum = w[0] + w[1] + w[2] + w[3];
    if sum == 0.0 {
        return 0.0;
    }
    let f =
        (1.0 - x) * (1.0 - y) * w[0] + x * (1.0 - y) * w[1] + (1.0 - x) * y * w[2] + x * y * w[3];
    4.0 * f / sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::rng::Rng;

    /// The warp's density integrates to 1 (midpoint rule on a 200² grid: the bilinear density
    /// is integrated exactly by it), and a histogram of 2·10⁵ samples over 8 × 8 cells matches
    /// the cell integrals within 5 binomial standard deviations.
    #[test]
    fn bilinear_warp_matches_its_density() {
        let w = [0.01, 0.7, 0.3, 1.0];
        let n = 200;
        let mut integral = 0.0f64;
        for i in 0..n * n {
            let p = [
                ((i % n) as f32 + 0.5) / n as f32,
                ((i / n) as f32 + 0.5) / n as f32,
            ];
            integral += f64::from(bilinear_pdf(p, w)) / (n * n) as f64;
        }
        assert!((integral - 1.0).abs() < 1e-4, "{integral}");

        let (cells, count) = (8usize, 200_000usize);
        let mut hist = vec![0u32; cells * cells];
        let mut rng = Rng::new(7);
        for _ in 0..count {
            let p = sample_bilinear([rng.f32(), rng.f32()], w);
            assert!((0.0..1.0).contains(&p[0]) && (0.0..1.0).contains(&p[1]));
            let (i, j) = (
                (p[0] * cells as f32) as usize,
                (p[1] * cells as f32) as usize,
            );
            hist[j * cells + i] += 1;
        }
        for (k, &h) in hist.iter().enumerate() {
            let (i, j) = (k % cells, k / cells);
            let mut e = 0.0f64;
            for s in 0..16 {
                let x = (i as f32 + ((s % 4) as f32 + 0.5) / 4.0) / cells as f32;
                let y = (j as f32 + ((s / 4) as f32 + 0.5) / 4.0) / cells as f32;
                e += f64::from(bilinear_pdf([x, y], w)) / (16 * cells * cells) as f64;
            }
            let (mean, sd) = (e * count as f64, (e * (1.0 - e) * count as f64).sqrt());
            assert!(
                (f64::from(h) - mean).abs() < 5.0 * sd,
                "cell {k}: {h} vs {mean}"
            );
        }
    }

    #[test]
    fn linear_sampling_inverts_its_cdf() {
        for (a, b) in [(1.0, 1.0), (0.0, 2.0), (3.0, 0.5), (0.01, 1.0)] {
            for k in 0..=20 {
                let u = k as f32 / 20.0;
                let x = sample_linear(u, a, b);
                let cdf = (a * x + (b - a) * x * x / 2.0) / ((a + b) / 2.0);
                assert!(
                    (cdf - u).abs() < 1e-5,
                    "a {a} b {b} u {u}: x {x}, cdf {cdf}"
                );
                assert!((0.0..1.0).contains(&x));
            }
        }
    }
}
