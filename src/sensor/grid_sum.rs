//! Sums whose value does not depend on the order or grouping of their terms, so that a film
//! rendered in any passes, on any threads, or as separate parts merged later holds the same
//! bits (`session::part`). Each term (one sample's own-pixel XYZ, one splat) is rounded once
//! to a fixed grid of 2^−e and summed as an `i128`: integer addition is associative, f64
//! addition is not (a render's f64 sum in sample order cannot be rebuilt from the sums of
//! two halves).
//!
//! The grid follows the camera exposure: e = [`GRID_BITS`] + log₂(exposure scale) rounded,
//! so a term is resolved to 2^−50 ≈ 8.9e−16 of the output's white (RGB 1) whatever the
//! exposure: a pixel whose mean is 10⁻⁸ of white is still exact to its f32 in practice (the
//! rounding is at most 2^−51 per sample). A term is clamped at ±2^[`TERM_BITS`] grid units
//! (2^50 ≈ 1.1e15 × white in one sample) and a sum saturates at ±2^127; both are counted
//! ([`Film::clamped`](super::film::Film::clamped)) and reported, never silent.

/// Bits of a term below the output's white (RGB 1).
pub const GRID_BITS: i32 = 50;
/// A term's magnitude is clamped at 2^TERM_BITS grid units.
pub const TERM_BITS: i32 = 100;

/// The fixed grid 2^−exponent the film's sums are held on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    pub exponent: i32,
}

/// An XYZ sum on a [`Grid`].
pub type Fixed3 = [i128; 3];

impl Grid {
    /// The grid for an image scaled by `scale` (the camera exposure) on output.
    pub fn for_scale(scale: f64) -> Grid {
        let stops = if scale.is_finite() && scale > 0.0 {
            scale.log2().round().clamp(-400.0, 400.0) as i32
        } else {
            0
        };
        Grid {
            exponent: GRID_BITS + stops,
        }
    }

    /// `x` rounded to the grid (to nearest, ties away from zero); true when it was clamped
    /// (beyond ±2^[`TERM_BITS`] units, or not finite).
    #[inline]
    pub fn term(self, x: f64) -> (i128, bool) {
        let s = scale_by_power_of_two(x, self.exponent);
        if s.abs() < I64_RANGE {
            return (i128::from(round_to_i64(s)), false);
        }
        let limit = 2f64.powi(TERM_BITS);
        let v = s.round();
        if v.is_nan() {
            return (0, true);
        }
        let clamped = v.clamp(-limit, limit);
        (clamped as i128, clamped != v)
    }

    /// The f64 nearest to `v` grid units.
    pub fn value(self, v: i128) -> f64 {
        scale_by_power_of_two(v as f64, -self.exponent)
    }

    /// Adds `t` to `acc` per channel; true when a sum saturated.
    pub fn add3(acc: &mut Fixed3, t: &Fixed3) -> bool {
        let mut saturated = false;
        for (a, v) in acc.iter_mut().zip(t) {
            let (s, over) = a.overflowing_add(*v);
            *a = if over { a.saturating_add(*v) } else { s };
            saturated |= over;
        }
        saturated
    }

    /// An XYZ triple on the grid, and how many channels were clamped.
    pub fn triple(self, xyz: [f64; 3]) -> (Fixed3, u64) {
        let mut clamped = 0;
        let t = xyz.map(|c| {
            let (v, c) = self.term(c);
            clamped += u64::from(c);
            v
        });
        (t, clamped)
    }
}

/// 2^63: below it in magnitude a term takes the i64 path ([`round_to_i64`]), one machine
/// conversion instead of `round` and the i128 conversion's library calls (`__fixdfti`).
const I64_RANGE: f64 = 9_223_372_036_854_775_808.0;

/// `s.round() as i64` (to nearest, ties away from zero) for |s| < 2^63, without `round`'s
/// call: truncate, then step away from zero when the dropped fraction is at least ½. The
/// fraction s − trunc(s) is exact (below 2^52 it is a multiple of s's ulp and smaller than
/// s; from 2^52 on s is whole and it is 0). Equal to the general path for every such s
/// (tested).
#[inline]
fn round_to_i64(s: f64) -> i64 {
    let t = s as i64;
    let frac = s - t as f64;
    t + i64::from(frac >= 0.5) - i64::from(frac <= -0.5)
}

/// x · 2^k, exactly (two steps, so that no intermediate factor overflows).
#[inline]
fn scale_by_power_of_two(x: f64, k: i32) -> f64 {
    let half = k / 2;
    x * power_of_two(half) * power_of_two(k - half)
}

/// 2^k, the value `2f64.powi(k)` gives: for a normal result (−1022 ≤ k ≤ 1023, which covers
/// every exponent `for_scale` makes) built from its IEEE 754 exponent field (biased by 1023,
/// mantissa 0, IEEE 754-2019 §3.4) without `powi`'s per-call loop of multiplications
/// (`__powidf2`, twice per film term).
#[inline]
fn power_of_two(k: i32) -> f64 {
    if (-1022..=1023).contains(&k) {
        f64::from_bits(((k + 1023) as u64) << 52)
    } else {
        2f64.powi(k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `term` as it was before its i64 path: round, clamp, convert.
    fn term_by_i128(g: Grid, x: f64) -> (i128, bool) {
        let limit = 2f64.powi(TERM_BITS);
        let v = scale_by_power_of_two(x, g.exponent).round();
        if v.is_nan() {
            return (0, true);
        }
        let clamped = v.clamp(-limit, limit);
        (clamped as i128, clamped != v)
    }

    #[test]
    fn the_i64_path_is_the_general_one() {
        let g = Grid { exponent: 0 };
        let mut special = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            4_503_599_627_370_495.5,
            -4_503_599_627_370_495.5,
            4_503_599_627_370_496.0,
            I64_RANGE,
            -I64_RANGE,
            I64_RANGE * 4.0,
            f64::MAX,
            f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        special.push(f64::from_bits(I64_RANGE.to_bits() - 1));
        special.push(-f64::from_bits(I64_RANGE.to_bits() - 1));
        let mut z = 1u64;
        for _ in 0..200_000 {
            z = crate::sampling::rng::mix64(z);
            // Magnitudes 2^-10 … 2^70, both signs, and halves.
            let e = (z >> 56) as i32 % 81 - 10;
            let m = (z >> 11) as f64 / (1u64 << 53) as f64;
            let x = (1.0 + m) * 2f64.powi(e) * if z & 1 == 0 { 1.0 } else { -1.0 };
            special.push(x);
            special.push((x * 2.0).round() / 2.0);
        }
        for x in special {
            assert_eq!(g.term(x), term_by_i128(g, x), "{x:e}");
        }
        let g = Grid::for_scale(1.0);
        assert_eq!(g.term(0.3), term_by_i128(g, 0.3));
    }

    #[test]
    fn powers_of_two_are_exact() {
        for k in -1100..=1100 {
            assert_eq!(power_of_two(k).to_bits(), 2f64.powi(k).to_bits(), "{k}");
        }
    }

    #[test]
    fn sums_do_not_depend_on_grouping() {
        let g = Grid::for_scale(1.0);
        let (big, small) = (2f64.powi(40), 2f64.powi(-20));
        let terms = [big, small, -big, small, 0.1, 1.0 / 3.0];
        let all = terms.iter().fold(0i128, |a, &x| a + g.term(x).0);
        let left = terms[..2].iter().fold(0i128, |a, &x| a + g.term(x).0);
        let right = terms[2..].iter().fold(0i128, |a, &x| a + g.term(x).0);
        assert_eq!(all, left + right);
        // The f64 sums of the same split differ: what the grid is for.
        let f = |t: &[f64]| t.iter().fold(0.0f64, |a, &x| a + x);
        assert_ne!(f(&terms), f(&terms[..2]) + f(&terms[2..]));
        // Both terms below big's f64 resolution count on the grid.
        assert!((g.value(all) - (2.0 * small + 0.1 + 1.0 / 3.0)).abs() < 1e-15);
    }

    #[test]
    fn the_grid_follows_the_exposure_and_clamps_are_counted() {
        assert_eq!(Grid::for_scale(1.0).exponent, GRID_BITS);
        assert_eq!(Grid::for_scale(2f64.powi(-8)).exponent, GRID_BITS - 8);
        let g = Grid::for_scale(1.0);
        assert_eq!(g.term(1.0), (1i128 << GRID_BITS, false));
        assert_eq!(g.value(1i128 << GRID_BITS), 1.0);
        assert!(g.term(1e300).1 && g.term(f64::NAN).1);
        let mut acc = [i128::MAX - 1, 0, 0];
        assert!(Grid::add3(&mut acc, &[5, 1, -1]));
        assert_eq!(acc, [i128::MAX, 1, -1]);
    }
}
