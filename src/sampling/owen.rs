//! Hash-based Owen scrambling (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4),
//! §3–4): a nested uniform scramble of a 32-bit fraction, and the same permutation applied to
//! a sample index to shuffle a sequence.
//!
//! Owen's scrambling flips each digit of a fraction with a random bit that depends on the
//! digits before it (more significant). Laine and Karras (2011) observed that a hash in which
//! every output bit depends only on the input bits below it does exactly that to the
//! bit-reversed value; Burley's §3 gives such a hash with constants found by search. We use
//! its structure with those four multipliers (each even, so bit j of x·c depends only on the
//! bits of x below j) and the seed added first (the carry only moves upwards).

/// Burley 2020's Laine–Karras-style permutation: bit j of the result is bit j of `x` flipped by
/// a function of `seed` and the bits of `x` below j.
#[inline]
fn lk_permutation(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Nested uniform (Owen) scramble of the 32-bit fraction `x`: bit j, counted from the most
/// significant, flipped by a function of `seed` and the bits above it. The definition, kept
/// for the tests: the sampler has the reversed bits at hand and calls [`scramble_reversed`].
#[cfg(test)]
#[inline]
pub fn scramble(x: u32, seed: u32) -> u32 {
    scramble_reversed(x.reverse_bits(), seed)
}

/// `scramble` of the fraction whose bits, reversed, are `x_reversed`: for callers that have
/// the reversed bits at hand (a van der Corput point is its index reversed, `sobol.rs`), one
/// reversal fewer.
#[inline]
pub fn scramble_reversed(x_reversed: u32, seed: u32) -> u32 {
    lk_permutation(x_reversed, seed).reverse_bits()
}

/// The index permutation of Burley 2020 §4 ("shuffling"): the same nested scramble on the
/// index, so bit j of the result is bit j of `index` flipped by a function of the bits above
/// it. Every aligned block of 2^k indices maps onto an aligned block of 2^k indices, so a
/// shuffled (0, 2)-sequence keeps its nets. The sampler shuffles with [`scramble_reversed`] of
/// the index's reversed bits (`zsobol.rs`); this is the definition the tests check it by.
#[cfg(test)]
#[inline]
pub fn shuffle(index: u32, seed: u32) -> u32 {
    scramble(index, seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scrambling_is_a_permutation_that_keeps_aligned_blocks() {
        // On 12 bits: a bijection, and for every k the image of each aligned block of 2^k
        // indices is an aligned block (its values agree above bit k).
        for seed in [0u32, 1, 0xdead_beef] {
            let img: Vec<u32> = (0..4096u32).map(|i| shuffle(i, seed) & 0xfff).collect();
            let mut sorted = img.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), 4096);
            for k in 0..12 {
                for block in img.chunks(1 << k) {
                    assert!(block.iter().all(|&v| v >> k == block[0] >> k), "k {k}");
                }
            }
        }
    }

    #[test]
    fn scrambled_fractions_are_uniform_over_seeds() {
        // A fixed point scrambled with many seeds covers [0, 1) evenly: 16 bins, χ² with 15
        // degrees of freedom below its 99.9 % quantile 37.7.
        for x in [0u32, 0x8000_0000, 0x1234_5678] {
            let mut bins = [0u32; 16];
            let n = 16_000u32;
            for s in 0..n {
                let seed = crate::sampling::rng::mix64(u64::from(s)) as u32;
                bins[(scramble(x, seed) >> 28) as usize] += 1;
            }
            let e = f64::from(n) / 16.0;
            let chi2: f64 = bins.iter().map(|&c| (f64::from(c) - e).powi(2) / e).sum();
            assert!(chi2 < 37.7, "x {x:#x}: χ² {chi2}");
        }
    }
}
