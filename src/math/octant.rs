//! Sine and cosine of an angle of at most π/4 in magnitude (an octant on either side of an
//! axis), inline and without range reduction: the concentric disk map (`sampling/warp.rs`)
//! needs only these, and a library `sincosf` call costs about 40 instructions and a call, a
//! few times a path (docs/design.md §8, "Samples/s against the build issue 18 was measured
//! on").
//!
//! The polynomials are Cephes `sinf`/`cosf`'s for |x| ≤ π/4 (Moshier 1989, "Methods and Programs
//! for Mathematical Functions", §6.4; Cephes Math Library 2.2, `sinf.c`, freely distributable):
//! sin x = x + x³ (s₁ + x² (s₂ + x² s₃)), cos x = 1 − x²/2 + x⁴ (c₁ + x² (c₂ + x² c₃)). Over the
//! octant both are within 2·10⁻⁷ of the f64 functions in absolute value and their squares sum
//! to 1 within 5·10⁻⁷ (tested below against f64).

/// (sin θ, cos θ) for |θ| ≤ π/4 (outside it the error grows: callers keep to the octant).
#[inline]
pub fn sin_cos_octant(theta: f32) -> (f32, f32) {
    let z = theta * theta;
    let s = theta + theta * z * ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1);
    let c = 1.0 - 0.5 * z + z * z * ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2);
    (s, c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_4;

    /// Every 2⁻²⁰ of the octant and its ends, against the f64 functions.
    #[test]
    fn agrees_with_f64_over_the_octant() {
        let n = 1 << 20;
        let (mut worst_s, mut worst_c, mut worst_norm) = (0f64, 0f64, 0f64);
        for i in -n..=n {
            let theta = (FRAC_PI_4 * f64::from(i) / f64::from(n)) as f32;
            let (s, c) = sin_cos_octant(theta);
            let t = f64::from(theta);
            worst_s = worst_s.max((f64::from(s) - t.sin()).abs());
            worst_c = worst_c.max((f64::from(c) - t.cos()).abs());
            let norm = f64::from(s).powi(2) + f64::from(c).powi(2);
            worst_norm = worst_norm.max((norm - 1.0).abs());
        }
        assert!(worst_s < 2e-7, "sin: {worst_s:e}");
        assert!(worst_c < 2e-7, "cos: {worst_c:e}");
        assert!(worst_norm < 5e-7, "sin² + cos²: {worst_norm:e}");
    }

    /// Odd and even exactly, and exact at 0.
    #[test]
    fn symmetric_and_exact_at_zero() {
        assert_eq!(sin_cos_octant(0.0), (0.0, 1.0));
        for theta in [1e-30f32, 1e-8, 0.1, 0.5, 0.785] {
            let (s, c) = sin_cos_octant(theta);
            assert_eq!(sin_cos_octant(-theta), (-s, c));
        }
    }
}
