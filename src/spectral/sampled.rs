//! A spectral quantity at the [`N_LAMBDA`] wavelengths a path carries.

use super::N_LAMBDA;
use std::ops::{Add, AddAssign, Div, Index, IndexMut, Mul, MulAssign, Sub};

/// Four lanes, one per sampled wavelength. Plain `Copy` data for the hot path.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SampledSpectrum(pub [f32; N_LAMBDA]);

impl SampledSpectrum {
    pub const ZERO: SampledSpectrum = SampledSpectrum([0.0; N_LAMBDA]);
    pub const ONE: SampledSpectrum = SampledSpectrum([1.0; N_LAMBDA]);

    #[inline]
    pub fn splat(v: f32) -> SampledSpectrum {
        SampledSpectrum([v; N_LAMBDA])
    }

    #[inline]
    pub fn from_fn(f: impl Fn(usize) -> f32) -> SampledSpectrum {
        SampledSpectrum(std::array::from_fn(f))
    }

    #[inline]
    pub fn is_black(&self) -> bool {
        self.0.iter().all(|&v| v == 0.0)
    }

    #[inline]
    pub fn max_value(&self) -> f32 {
        self.0.iter().copied().fold(f32::MIN, f32::max)
    }

    #[inline]
    pub fn average(&self) -> f32 {
        self.0.iter().sum::<f32>() / N_LAMBDA as f32
    }

    /// Division that yields 0 where the divisor is 0 (pbrt's SafeDiv).
    #[inline]
    pub fn safe_div(self, d: SampledSpectrum) -> SampledSpectrum {
        SampledSpectrum::from_fn(|i| {
            if d.0[i] != 0.0 {
                self.0[i] / d.0[i]
            } else {
                0.0
            }
        })
    }

    /// True when every lane is finite.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }

    #[inline]
    pub fn map(self, f: impl Fn(f32) -> f32) -> SampledSpectrum {
        SampledSpectrum(self.0.map(f))
    }
}

impl Index<usize> for SampledSpectrum {
    type Output = f32;
    #[inline]
    fn index(&self, i: usize) -> &f32 {
        &self.0[i]
    }
}

impl IndexMut<usize> for SampledSpectrum {
    #[inline]
    fn index_mut(&mut self, i: usize) -> &mut f32 {
        &mut self.0[i]
    }
}

macro_rules! lanewise {
    ($trait:ident, $f:ident, $op:tt) => {
        impl $trait for SampledSpectrum {
            type Output = SampledSpectrum;
            #[inline]
            fn $f(self, o: SampledSpectrum) -> SampledSpectrum {
                SampledSpectrum::from_fn(|i| self.0[i] $op o.0[i])
            }
        }
        impl $trait<f32> for SampledSpectrum {
            type Output = SampledSpectrum;
            #[inline]
            fn $f(self, o: f32) -> SampledSpectrum {
                SampledSpectrum::from_fn(|i| self.0[i] $op o)
            }
        }
    };
}

lanewise!(Add, add, +);
lanewise!(Sub, sub, -);
lanewise!(Mul, mul, *);
lanewise!(Div, div, /);

impl Mul<SampledSpectrum> for f32 {
    type Output = SampledSpectrum;
    #[inline]
    fn mul(self, s: SampledSpectrum) -> SampledSpectrum {
        s * self
    }
}

impl AddAssign for SampledSpectrum {
    #[inline]
    fn add_assign(&mut self, o: SampledSpectrum) {
        *self = *self + o;
    }
}

impl MulAssign for SampledSpectrum {
    #[inline]
    fn mul_assign(&mut self, o: SampledSpectrum) {
        *self = *self * o;
    }
}

impl MulAssign<f32> for SampledSpectrum {
    #[inline]
    fn mul_assign(&mut self, o: f32) {
        *self = *self * o;
    }
}
