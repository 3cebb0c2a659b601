//! A spectrum tabulated at 1 nm over the simulated range, the storage for every measured
//! curve (CIE observer, illuminants, reflectances, metal n and k).

use super::{LAMBDA_MAX, LAMBDA_MIN, N_LAMBDA};
use glam::{BVec4A, UVec4, Vec4};

/// Number of 1 nm samples in [`LAMBDA_MIN`, `LAMBDA_MAX`].
pub const DENSE_LEN: usize = (LAMBDA_MAX - LAMBDA_MIN) as usize + 1;

/// Where four wavelengths fall in a 1 nm table ([`DenseSpectrum::eval_lanes`], and the CIE
/// observer's rows in `xyz.rs`): each lane's lower node and weight, and whether it lies in the
/// range. A lane outside it (or NaN) reads node 0 and is zeroed by the caller.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LaneLookup {
    /// The lanes in [LAMBDA_MIN, LAMBDA_MAX] (false for NaN).
    pub inside: BVec4A,
    /// The lower node, at most `DENSE_LEN − 2`.
    pub index: [usize; N_LAMBDA],
    /// The upper node's weight, in [0, 1].
    pub t: Vec4,
}

impl LaneLookup {
    #[inline]
    pub fn new(lambda: [f32; N_LAMBDA]) -> LaneLookup {
        let x = Vec4::from_array(lambda) - Vec4::splat(LAMBDA_MIN);
        let last = Vec4::splat((DENSE_LEN - 1) as f32);
        // `contains`: false for NaN; such lanes are read at index 0 and give 0.
        let inside = x.cmpge(Vec4::ZERO) & x.cmple(last);
        let x = Vec4::select(inside, x, Vec4::ZERO);
        let i = x.as_uvec4().min(UVec4::splat(DENSE_LEN as u32 - 2));
        LaneLookup {
            inside,
            index: i.to_array().map(|k| k as usize),
            t: x - i.as_vec4(),
        }
    }
}

/// Values at every integer nm from 360 to 830, linearly interpolated in between and
/// zero outside.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseSpectrum {
    pub values: Box<[f32; DENSE_LEN]>,
}

impl DenseSpectrum {
    pub fn constant(v: f32) -> DenseSpectrum {
        DenseSpectrum {
            values: Box::new([v; DENSE_LEN]),
        }
    }

    /// Builds from a closure evaluated at every integer nm.
    pub fn from_fn(f: impl Fn(f32) -> f32) -> DenseSpectrum {
        let mut values = Box::new([0.0; DENSE_LEN]);
        for (i, v) in values.iter_mut().enumerate() {
            *v = f(LAMBDA_MIN + i as f32);
        }
        DenseSpectrum { values }
    }

    /// Resamples (nm, value) pairs sorted by wavelength by linear interpolation; outside the
    /// given range the end values are held (as colour-science's default extrapolator does).
    /// Returns None for an empty or unsorted table.
    pub fn from_samples(samples: &[(f32, f32)]) -> Option<DenseSpectrum> {
        if samples.is_empty() || samples.windows(2).any(|w| w[1].0 <= w[0].0) {
            return None;
        }
        if samples.iter().any(|s| !s.0.is_finite() || !s.1.is_finite()) {
            return None;
        }
        Some(DenseSpectrum::from_fn(|lambda| {
            interpolate(samples, lambda)
        }))
    }

    /// The value at `lambda` nm.
    #[inline]
    pub fn eval(&self, lambda: f32) -> f32 {
        let x = lambda - LAMBDA_MIN;
        let last = (DENSE_LEN - 1) as f32;
        // Branch-free: the lookup at x clamped into the table (NaN converts to 0), kept
        // inside it. For x ∈ [0, DENSE_LEN − 1] the i32 conversion truncates as a usize one
        // would, with a third of its instructions (no 64-bit saturation).
        let xc = x.clamp(0.0, last);
        let i = (xc as i32 as usize).min(DENSE_LEN - 2);
        let t = xc - i as f32;
        let v = self.values[i] * (1.0 - t) + self.values[i + 1] * t;
        if (0.0..=last).contains(&x) {
            v
        } else {
            0.0
        }
    }

    /// [`eval`](Self::eval) at a sample's four wavelengths, the same values bit for bit
    /// (tested): the range test, the index, the weight and the interpolation four lanes at a
    /// time, the two table reads per lane.
    #[inline]
    pub fn eval_lanes(&self, lambda: [f32; N_LAMBDA]) -> [f32; N_LAMBDA] {
        let at = LaneLookup::new(lambda);
        let lo = Vec4::from_array(at.index.map(|k| self.values[k]));
        let hi = Vec4::from_array(at.index.map(|k| self.values[k + 1]));
        let v = lo * (Vec4::ONE - at.t) + hi * at.t;
        Vec4::select(at.inside, v, Vec4::ZERO).to_array()
    }

    /// ∫ self(λ) other(λ) dλ over the range by the trapezoidal rule on the 1 nm grid.
    pub fn inner_product(&self, other: &DenseSpectrum) -> f64 {
        let n = DENSE_LEN;
        let mut sum = 0.0f64;
        for i in 0..n {
            let w = if i == 0 || i == n - 1 { 0.5 } else { 1.0 };
            sum += w * self.values[i] as f64 * other.values[i] as f64;
        }
        sum
    }

    pub fn scaled(&self, s: f32) -> DenseSpectrum {
        DenseSpectrum::from_fn(|l| self.eval(l) * s)
    }

    pub fn max_value(&self) -> f32 {
        self.values.iter().copied().fold(0.0, f32::max)
    }
}

/// Linear interpolation in a sorted (x, y) table, holding the end values outside it.
pub fn interpolate(samples: &[(f32, f32)], x: f32) -> f32 {
    let first = samples[0];
    let last = samples[samples.len() - 1];
    if x <= first.0 {
        return first.1;
    }
    if x >= last.0 {
        return last.1;
    }
    let i = samples.partition_point(|s| s.0 <= x);
    let (a, b) = (samples[i - 1], samples[i]);
    let t = (x - a.0) / (b.0 - a.0);
    a.1 + t * (b.1 - a.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_are_the_scalar_evaluation_bit_for_bit() {
        // Every integer nm, its neighbouring floats, points in between, the ends, outside the
        // range, infinities and NaN, on a table with distinct values everywhere.
        let d = DenseSpectrum::from_fn(|l| (l * 0.013).sin() * 3.0 + l * 1e-3);
        let mut ls: Vec<f32> = vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -0.0, 1e30];
        for k in 0..DENSE_LEN + 2 {
            let l = LAMBDA_MIN - 1.0 + k as f32;
            ls.extend([l, l.next_up(), l.next_down(), l + 0.25, l + 0.5, l + 0.999]);
        }
        let mut x = 0x1234_5678u32;
        for _ in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            ls.push(LAMBDA_MIN - 5.0 + (LAMBDA_MAX - LAMBDA_MIN + 10.0) * (x as f32 / 4.3e9));
        }
        for w in ls.windows(N_LAMBDA) {
            let lanes: [f32; N_LAMBDA] = w.try_into().unwrap();
            let want = lanes.map(|l| d.eval(l).to_bits());
            assert_eq!(d.eval_lanes(lanes).map(f32::to_bits), want, "{lanes:?}");
        }
    }

    #[test]
    fn resampling_is_linear_and_holds_ends() {
        let s = DenseSpectrum::from_samples(&[(400.0, 1.0), (500.0, 3.0)]).unwrap();
        assert_eq!(s.eval(360.0), 1.0);
        assert!((s.eval(450.0) - 2.0).abs() < 1e-6);
        assert!((s.eval(450.5) - 2.01).abs() < 1e-5);
        assert_eq!(s.eval(830.0), 3.0);
        assert_eq!(s.eval(900.0), 0.0);
    }

    #[test]
    fn eval_interpolates_inside_and_is_zero_outside() {
        // The definition: linear between the 1 nm nodes, the nodes exactly, 0 outside and
        // for NaN.
        let s = DenseSpectrum::from_fn(|l| (l * 0.37).sin() + 2.0);
        for k in 0..=4700 {
            let l = LAMBDA_MIN + k as f32 * 0.1;
            let i = ((l - LAMBDA_MIN) as usize).min(DENSE_LEN - 2);
            let t = (l - LAMBDA_MIN) - i as f32;
            let expected = s.values[i] * (1.0 - t) + s.values[i + 1] * t;
            assert_eq!(s.eval(l).to_bits(), expected.to_bits(), "{l}");
        }
        assert_eq!(s.eval(LAMBDA_MAX), s.values[DENSE_LEN - 1]);
        for l in [
            LAMBDA_MIN - 1e-3,
            LAMBDA_MAX + 1e-3,
            -1e30,
            1e30,
            f32::NAN,
            f32::INFINITY,
        ] {
            assert_eq!(s.eval(l), 0.0, "{l}");
        }
    }

    #[test]
    fn rejects_unsorted_and_empty() {
        assert!(DenseSpectrum::from_samples(&[]).is_none());
        assert!(DenseSpectrum::from_samples(&[(500.0, 1.0), (400.0, 1.0)]).is_none());
        assert!(DenseSpectrum::from_samples(&[(500.0, f32::NAN)]).is_none());
    }
}
