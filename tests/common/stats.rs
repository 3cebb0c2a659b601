//! Statistics for the tests' tolerances: sample mean, variance and standard error, and the
//! two-sided p-value of Student's t.

/// Mean and unbiased sample variance (divided by n − 1, or by 1 for a single value).
pub fn mean_and_var<T: Into<f64>>(values: impl IntoIterator<Item = T>) -> (f64, f64) {
    let v: Vec<f64> = values.into_iter().map(Into::into).collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var)
}

/// Mean and standard error of the mean of a channel over a set of pixels (or of any values).
pub fn mean_and_sem<T: Into<f64>>(values: impl IntoIterator<Item = T>) -> (f64, f64) {
    let v: Vec<f64> = values.into_iter().map(Into::into).collect();
    let n = v.len() as f64;
    let (mean, var) = mean_and_var(v);
    (mean, (var / n).sqrt())
}

/// ln Γ(x): the χ² harness's (Lanczos, g = 7).
pub use spectral_render::testing::chi2::ln_gamma;

/// Regularised incomplete beta I_x(a, b) by its continued fraction (modified Lentz).
pub fn inc_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    if x > (a + 1.0) / (a + b + 2.0) {
        return 1.0 - inc_beta(b, a, 1.0 - x);
    }
    let front =
        (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln()).exp() / a;
    let tiny = 1e-300;
    let (mut c, mut d) = (1.0, 1.0 - (a + b) * x / (a + 1.0));
    d = 1.0 / if d.abs() < tiny { tiny } else { d };
    let mut f = d;
    for m in 1..400 {
        let m = m as f64;
        for num in [
            m * (b - m) * x / ((a + 2.0 * m - 1.0) * (a + 2.0 * m)),
            -(a + m) * (a + b + m) * x / ((a + 2.0 * m) * (a + 2.0 * m + 1.0)),
        ] {
            d = 1.0 + num * d;
            d = 1.0 / if d.abs() < tiny { tiny } else { d };
            c = 1.0 + num / c;
            if c.abs() < tiny {
                c = tiny;
            }
            f *= c * d;
        }
        if (c * d - 1.0).abs() < 1e-14 {
            break;
        }
    }
    front * f
}

/// Two-sided p-value of a statistic z under Student's t with `df` degrees of freedom
/// (the normal distribution as df → ∞).
pub fn two_sided_p(z: f64, df: f64) -> f64 {
    inc_beta(0.5 * df, 0.5, df / (df + z * z))
}
