//! Random numbers — independent or low-discrepancy (`--sampler`) — and the warps from the
//! unit square to directions and shapes.

pub mod bilinear;
pub mod dimensions;
pub mod distribution;
pub mod owen;
pub mod pixel;
pub mod rng;
pub mod sobol;
pub mod spherical_rect;
pub mod spherical_triangle;
pub mod warp;
pub mod zsobol;

pub use distribution::Distribution1D;
pub use pixel::{PixelSamplers, SamplerKind};
pub use rng::Sampler;

/// Power heuristic with β = 2 (Veach 1997, §9.2.4, eq. 9.13), for one sample from each of
/// two strategies: w = p_a² / (p_a² + p_b²).
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let (a, b) = (pdf_a * pdf_a, pdf_b * pdf_b);
    if a.is_infinite() {
        return 1.0;
    }
    if a + b == 0.0 {
        return 0.0;
    }
    a / (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0, 2.0), (0.1, 30.0), (5.0, 0.0)] {
            let s = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((s - 1.0).abs() < 1e-6);
        }
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
        assert_eq!(power_heuristic(f32::INFINITY, 1.0), 1.0);
    }
}
