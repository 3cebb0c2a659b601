//! The first two dimensions of Sobol's sequence (Sobol' 1967), in base 2 with 32-bit
//! fractions: all the sampler needs, because every pair of dimensions it hands out is a
//! (0, 2)-sequence of its own, decorrelated from the others by hash-based shuffling and Owen
//! scrambling (Burley 2020 §4; pbrt-v4's `ZSobolSampler` does the same). Higher Sobol'
//! dimensions (Joe and Kuo's direction numbers) are therefore not carried.
//!
//! Dimension 0 is the van der Corput sequence: its generator matrix is the identity, so the
//! point of index i is i with its bits reversed. Dimension 1 has the primitive polynomial
//! x + 1 and initial direction number m₁ = 1; the recurrence m_k = m_{k−1} ⊕ 2 m_{k−1}
//! (Bratley and Fox 1988, eq. 2) makes its generator matrix Pascal's triangle mod 2.
//! Both matrices are computed here; there is no table of data: dimension 1 by a five-step
//! transform of the index's bits ([`dim1_reversed`]), with no branch.

/// Column k of dimension 1's generator matrix as a 32-bit fraction (the k-th direction number
/// v_{k+1} = m_{k+1} / 2^{k+1}, most significant bit first).
#[cfg(test)]
const DIM1: [u32; 32] = dim1_columns();

#[cfg(test)]
const fn dim1_columns() -> [u32; 32] {
    let mut cols = [0u32; 32];
    let mut m: u32 = 1;
    let mut k = 0;
    while k < 32 {
        cols[k] = m << (31 - k);
        m ^= m << 1;
        k += 1;
    }
    cols
}

/// Point `index` of Sobol' dimension 0 as a 32-bit fraction (the definition, for the tests:
/// the sampler scrambles the index itself, which is this point's bits reversed).
#[cfg(test)]
#[inline]
pub fn dim0(index: u32) -> u32 {
    index.reverse_bits()
}

/// Point `index` of Sobol' dimension 1 as a 32-bit fraction (for the tests: the sampler
/// scrambles [`dim1_reversed`]).
#[cfg(test)]
#[inline]
pub fn dim1(index: u32) -> u32 {
    dim1_reversed(index).reverse_bits()
}

/// `dim1` with its bits reversed (least significant = 1/2), without a branch or a table.
/// Column k of the generator matrix holds the binomial coefficients C(k, p) mod 2 in the
/// reversed bit p, and C(k, p) is odd iff the bits of p are a subset of those of k (Lucas's
/// theorem), so reversed bit p is the XOR of the index's bits k ⊇ p: the superset-sum
/// (Möbius) transform over GF(2), five shift–mask–XOR steps (one per bit of p). Equal to the
/// column-by-column product for every index (tested against it).
#[inline]
pub fn dim1_reversed(mut index: u32) -> u32 {
    index ^= (index >> 1) & 0x5555_5555;
    index ^= (index >> 2) & 0x3333_3333;
    index ^= (index >> 4) & 0x0f0f_0f0f;
    index ^= (index >> 8) & 0x00ff_00ff;
    index ^= (index >> 16) & 0x0000_ffff;
    index
}

/// `dim1` as the product of the index's bits with the generator matrix, column by column:
/// the definition, kept as the tests' reference.
#[cfg(test)]
fn dim1_by_columns(mut index: u32) -> u32 {
    let mut v = 0;
    while index != 0 {
        v ^= DIM1[index.trailing_zeros() as usize];
        index &= index - 1;
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(x: u32) -> f64 {
        f64::from(x) / 4_294_967_296.0
    }

    #[test]
    fn the_transform_is_the_matrix_product() {
        // Every single bit (the columns), then indices spread over the whole range.
        for k in 0..32 {
            assert_eq!(dim1(1 << k), DIM1[k as usize], "column {k}");
        }
        let mut x = 0x1234_5678u32;
        for i in 0..200_000u32 {
            x = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            assert_eq!(dim1(x), dim1_by_columns(x), "{x:#x}");
            assert_eq!(dim1(i), dim1_by_columns(i), "{i}");
        }
        assert_eq!(dim1(u32::MAX), dim1_by_columns(u32::MAX));
    }

    #[test]
    fn first_points_are_sobols() {
        // The second coordinate in index (not Gray-code) order: direction numbers 1/2, 3/4,
        // 5/8, XORed by the index's bits.
        let want = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875];
        for (i, w) in want.iter().enumerate() {
            assert_eq!(f(dim1(i as u32)), *w, "point {i}");
        }
        let vdc = [0.0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875];
        for (i, w) in vdc.iter().enumerate() {
            assert_eq!(f(dim0(i as u32)), *w, "point {i}");
        }
    }

    #[test]
    fn the_two_dimensions_form_a_0_m_2_net_in_every_aligned_block() {
        // Every aligned block of 2^m points has one point in each elementary interval of
        // area 2^-m: the (0, 2)-sequence property.
        for m in 0..=10u32 {
            for block in [0u32, 1, 5] {
                for a in 0..=m {
                    let b = m - a;
                    let mut seen = vec![false; 1 << m];
                    for i in 0..(1u32 << m) {
                        let idx = (block << m) | i;
                        let (x, y) = (dim0(idx) as u64, dim1(idx) as u64);
                        let cell = ((x >> (32 - a)) << b | (y >> (32 - b))) as usize;
                        let cell = if m == 0 { 0 } else { cell };
                        assert!(!seen[cell], "m {m} a {a} block {block}");
                        seen[cell] = true;
                    }
                }
            }
        }
    }
}
