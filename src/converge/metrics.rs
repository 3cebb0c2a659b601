//! Image error against a reference, per snapshot.
//!
//! - **relMSE** as pbrt-v4 defines it (`ImageMetrics`, `imgtool diff --metric relmse` and
//!   `--mse-reference-image`): the mean over pixels and RGB channels of
//!   (x − r)² / (r² + 0.01), r the reference; **relRMSE** = √relMSE.
//! - **masked**: the same over the pixels whose first hit is not an emitter (`mask.rs`), so
//!   that lamps seen directly, whose relative error says little about the lighting, do not
//!   dominate.
//! - **noise-corrected**: a reference rendered with finite samples has its own variance v_r;
//!   for x independent of r, E[(x − r)²] = E[(x − t)²] + v_r (t the true value), so
//!   subtracting mean(v_r / (r² + 0.01)) estimates the error against the truth. The correction
//!   can come out negative when x is closer than the reference's noise; relRMSE is then 0.
//! - **bias**: on luminance Y over the unmasked pixels, E[(x − r)²] = b² + v_x + v_r, with v_x
//!   the snapshot's own variance of the mean (the film's even/odd halves, `sensor::film`) and
//!   v_r the reference's; mean((x − r)² − v_x − v_r)/(r² + 0.01) estimates the relative squared
//!   bias that remains (about 0 for an unbiased integrator, > 0 for a consistent one such as
//!   VCM early on). Reported as √max(b², 0), only when both variances are known (VCM's
//!   even and odd iterations are independent replicates: `integrator::vcm::iteration_u`).

/// pbrt-v4's offset in the relMSE denominator (`ImageMetrics`: (x − r)² / (r² + 0.01)).
pub const REL_MSE_OFFSET: f64 = 0.01;

/// A reference image: linear Rec.709 RGB and luminance Y per pixel (same absolute scale as
/// the snapshots), and the per-pixel variance of its mean when it is known.
#[derive(Clone, Debug)]
pub struct Reference {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<[f32; 3]>,
    pub y: Vec<f32>,
    pub variance: Option<ReferenceVariance>,
}

/// Per-pixel variance of a reference's mean: of R, G, B and of Y.
#[derive(Clone, Debug)]
pub struct ReferenceVariance {
    pub rgb: Vec<[f32; 3]>,
    pub y: Vec<f32>,
}

/// The errors of one snapshot (fractions, not percent).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImageErrors {
    pub rel_mse: f64,
    pub rel_rmse: f64,
    /// None when every pixel is masked.
    pub rel_rmse_masked: Option<f64>,
    /// relMSE minus the reference's noise (may be negative); None without its variance.
    pub rel_mse_corrected: Option<f64>,
    pub rel_rmse_corrected: Option<f64>,
    pub rel_rmse_masked_corrected: Option<f64>,
    /// The relative bias on Y that remains (see the module docs).
    pub bias_masked: Option<f64>,
    /// Its 95 % upper bound: √max(b² + 1.96 · se(b²), 0), se from the pixels' spread.
    pub bias_masked_bound: Option<f64>,
}

impl ImageErrors {
    /// The error a configuration is judged by (targets, slopes): the masked relRMSE, noise
    /// corrected when the reference's variance is known; unmasked when everything is masked.
    pub fn primary(&self) -> f64 {
        self.rel_rmse_masked_corrected
            .or(self.rel_rmse_masked)
            .or(self.rel_rmse_corrected)
            .unwrap_or(self.rel_rmse)
    }
}

/// Sums over pixels for one mean.
#[derive(Clone, Copy, Default)]
struct Sum {
    err: f64,
    noise: f64,
    n: u64,
    /// Σ of the squared per-pixel terms (err − noise), for the standard error.
    sq: f64,
}

impl Sum {
    fn mean(&self) -> Option<f64> {
        (self.n > 0).then(|| self.err / self.n as f64)
    }

    fn corrected(&self) -> Option<f64> {
        (self.n > 0).then(|| (self.err - self.noise) / self.n as f64)
    }

    /// The standard error of [`Sum::corrected`] (terms pushed with `sq`).
    fn corrected_se(&self) -> Option<f64> {
        let n = self.n as f64;
        let m = self.corrected()?;
        (self.n > 1).then(|| ((self.sq / n - m * m).max(0.0) / (n - 1.0)).sqrt())
    }
}

/// The errors of the image `rgb` (luminance `y`, own per-pixel variance of Y `own_var_y`
/// when known) against `reference`; `masked[i]` excludes pixel i from the masked metrics.
pub fn image_errors(
    rgb: &[[f32; 3]],
    y: &[f32],
    own_var_y: Option<&[f64]>,
    reference: &Reference,
    masked: &[bool],
) -> ImageErrors {
    let (mut all, mut kept) = (Sum::default(), Sum::default());
    let mut bias = Sum::default();
    let var = reference.variance.as_ref();
    for (i, (px, pr)) in rgb.iter().zip(&reference.rgb).enumerate() {
        for (c, (&x, &r)) in px.iter().zip(pr).enumerate() {
            let r = f64::from(r);
            let d = f64::from(x) - r;
            let den = r * r + REL_MSE_OFFSET;
            let e = d * d / den;
            let v = var.map_or(0.0, |v| f64::from(v.rgb[i][c]) / den);
            all.err += e;
            all.noise += v;
            all.n += 1;
            if !masked[i] {
                kept.err += e;
                kept.noise += v;
                kept.n += 1;
            }
        }
        if let (Some(v), Some(own), false) = (var, own_var_y, masked[i]) {
            let r = f64::from(reference.y[i]);
            let d = f64::from(y[i]) - r;
            let (e, v) = (
                d * d / (r * r + REL_MSE_OFFSET),
                (own[i] + f64::from(v.y[i])) / (r * r + REL_MSE_OFFSET),
            );
            bias.err += e;
            bias.noise += v;
            bias.sq += (e - v) * (e - v);
            bias.n += 1;
        }
    }
    let rel_mse = all.mean().unwrap_or(0.0);
    let root = |m: f64| m.max(0.0).sqrt();
    let known = var.is_some();
    let own_finite = own_var_y.is_some_and(|v| v.iter().all(|x| x.is_finite()));
    ImageErrors {
        rel_mse,
        rel_rmse: rel_mse.sqrt(),
        rel_rmse_masked: kept.mean().map(f64::sqrt),
        rel_mse_corrected: known.then(|| all.corrected()).flatten(),
        rel_rmse_corrected: known.then(|| all.corrected().map(root)).flatten(),
        rel_rmse_masked_corrected: known.then(|| kept.corrected().map(root)).flatten(),
        bias_masked: own_finite.then(|| bias.corrected().map(root)).flatten(),
        bias_masked_bound: own_finite
            .then(|| Some(root(bias.corrected()? + 1.96 * bias.corrected_se()?)))
            .flatten(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reference(rgb: Vec<[f32; 3]>) -> Reference {
        let y = rgb.iter().map(|p| p[1]).collect();
        Reference {
            width: rgb.len(),
            height: 1,
            rgb,
            y,
            variance: None,
        }
    }

    #[test]
    fn rel_mse_by_hand() {
        // Pixel 0: r = (1, 0, 2), x = (1.5, 0.1, 2); pixel 1: r = (0.1, 0.1, 0.1), x = 0.
        // Terms: 0.25/1.01, 0.01/0.01, 0, 3 × 0.01/0.02 → sum 0.247525 + 1 + 1.5 = 2.747525.
        let r = reference(vec![[1.0, 0.0, 2.0], [0.1, 0.1, 0.1]]);
        let x = vec![[1.5, 0.1, 2.0], [0.0, 0.0, 0.0]];
        let y: Vec<f32> = x.iter().map(|p| p[1]).collect();
        let e = image_errors(&x, &y, None, &r, &[false, false]);
        let want = (0.25f64 / 1.01 + 1.0 + 1.5) / 6.0;
        assert!((e.rel_mse - want).abs() < 1e-6, "{}", e.rel_mse);
        assert!((e.rel_rmse - want.sqrt()).abs() < 1e-6);
        // Masking pixel 1 leaves pixel 0's three terms.
        let m = image_errors(&x, &y, None, &r, &[false, true]);
        let want0 = (0.25f64 / 1.01 + 1.0) / 3.0;
        assert!((m.rel_rmse_masked.unwrap() - want0.sqrt()).abs() < 1e-6);
        assert_eq!(m.rel_rmse_masked_corrected, None);
        assert!((m.primary() - want0.sqrt()).abs() < 1e-6);
        assert_eq!(
            image_errors(&x, &y, None, &r, &[true, true]).rel_rmse_masked,
            None
        );
    }

    #[test]
    fn noise_correction_subtracts_the_reference_variance() {
        // x = r exactly, reference variance 0.0202 per channel at r = 0.1: relMSE 0,
        // corrected −0.0202/0.02 = −1.01 → relRMSE 0.
        let mut r = reference(vec![[0.1; 3]]);
        r.variance = Some(ReferenceVariance {
            rgb: vec![[0.0202; 3]],
            y: vec![0.0202],
        });
        let e = image_errors(&[[0.1; 3]], &[0.1], Some(&[0.0]), &r, &[false]);
        assert!((e.rel_mse_corrected.unwrap() + 1.01).abs() < 1e-6);
        assert_eq!(e.rel_rmse_corrected, Some(0.0));
        assert_eq!(e.bias_masked, Some(0.0));
    }
}
