//! The low-discrepancy sampler: Owen-scrambled Sobol' points in pbrt-v4's Morton ("Z") order
//! over the image (`ZSobolSampler`, after Ahmed and Wonka 2020, "Screen-space blue-noise
//! diffusion of Monte Carlo sampling error via hierarchical ordering of pixels"), with Burley
//! 2020's hash-based shuffling and scrambling.
//!
//! Sample s of pixel (x, y) belongs to replicate r = s mod 2 as its sample j = ⌊s/2⌋. In each
//! replicate the sample's global index is (Morton(x, y) · 2^L) + (j mod 2^L), with 2^L the
//! samples per pixel of the replicate rounded up to a power of two: a pixel's samples are one
//! aligned block of the sequence, and a 2 × 2 quad of pixels the next block up, so the error
//! of neighbouring pixels is spread as blue noise. Each request for a dimension (1D) or pair
//! of dimensions (2D) d takes the first one or two Sobol' dimensions (`sobol.rs`) at the index
//! shuffled with a seed of (run seed, r, d, higher index bits), and Owen-scrambles the values
//! with seeds of their own (`owen.rs`): every dimension is uniform on its own, dimensions of
//! one sample are independent, and the first 2^k samples of a replicate of a pixel are a
//! (0, k, 2)-net in every 1D and 2D projection. Dimensions are unbounded (padding by hashing).
//!
//! **Why two replicates.** The even and the odd samples of a pixel are independent
//! randomisations, so the film's even/odd variance estimate (`sensor/film.rs`), on which
//! `auto`'s pilot, `converge`'s bias estimate and the z-tests between integrators rest, stays
//! unbiased (Owen 1997: independent replicates of a scrambled net). One net over all the
//! samples would make the halves anti-correlated and overstate the variance.
//!
//! Samples beyond 2^L per replicate (a `--time` run, whose sample count is unknown, takes
//! L = 16) start a new epoch, hashed into the seeds: another independent scramble.

use super::owen;
use super::rng::mix64;
use super::sobol;

/// The largest log2 of samples per pixel and replicate that a run's blocks take.
pub const MAX_LOG2: u32 = 20;
/// log2 of the block of a run whose sample count is unknown (a time budget).
pub const UNKNOWN_SPP_LOG2: u32 = 16;

/// The dimensions whose seed hashes a run keeps for each of its first keys (`ZSobol::seeds`):
/// the camera's five and 17 bounces of the path tracer's layout (`dimensions.rs`).
pub const TABLED_DIMENSIONS: usize = 128;

/// A run's parameters of the sequence: its seed and the block size.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ZSobol {
    seed: u64,
    log2: u32,
    /// The stream keys of replicates 0 and 1 in epoch 0 with no index bits above 32 (`key`):
    /// every sample's of a run of at most 2^L samples per replicate on an image whose Morton
    /// codes fit in 32 − L bits, found once per run instead of per sample.
    first_keys: [u64; 2],
    /// For each first key, the seed hash of each of the first [`TABLED_DIMENSIONS`]
    /// dimensions and that hash hashed again (the second dimension's scramble of a 2D draw):
    /// the same numbers as `seed_hash`, found once per run rather than at every draw
    /// (design.md §8, "The per-sample cost, seventh pass").
    seeds: [Box<[[u64; 2]]>; 2],
}

impl ZSobol {
    /// The sequence for a run of `spp` samples per pixel (None: unknown).
    pub fn new(seed: u64, spp: Option<u64>) -> ZSobol {
        let log2 = match spp {
            Some(n) => (n.div_ceil(2).max(1).next_power_of_two().trailing_zeros()).min(MAX_LOG2),
            None => UNKNOWN_SPP_LOG2,
        };
        let first_keys = [0, 1].map(|r| key(seed, r, 0, 0));
        let seeds = first_keys.map(|k| {
            (0..TABLED_DIMENSIONS as u32)
                .map(|d| {
                    let h = seed_hash(k, d);
                    [h, mix64(h)]
                })
                .collect()
        });
        ZSobol {
            seed,
            log2,
            first_keys,
            seeds,
        }
    }

    /// The stream of sample `s` of pixel (x, y) (the tests' form of `stream_at`).
    #[cfg(test)]
    pub fn stream(&self, x: u32, y: u32, s: u64) -> Stream<'_> {
        self.stream_at(morton(x, y), s)
    }

    /// The stream of sample `s` of the pixel whose Morton code is `m` ([`morton`]), for a
    /// caller that draws several samples of one pixel.
    #[inline]
    pub fn stream_at(&self, m: u64, s: u64) -> Stream<'_> {
        self.stream_in(m, s, 0, 0)
    }

    /// Sample `s` of the pixel of Morton index `m`, in its continuation `c` of 2^`bits`
    /// (`Stream::continuation`): in its replicate, index j · 2^bits + c of blocks 2^bits
    /// times larger, so that the pixel's continuations are one aligned block of the sequence
    /// as its samples are. `bits` 0 (and `c` 0) is the sample's own stream.
    #[inline]
    fn stream_in(&self, m: u64, s: u64, c: u64, bits: u32) -> Stream<'_> {
        let (r, j) = (s & 1, ((s >> 1) << bits) | c);
        let l = self.log2 + bits;
        let epoch = j >> l;
        let high = m >> (32 - l);
        let low = ((m << l) | (j & ((1 << l) - 1))) as u32;
        let (key, seeds) = if epoch | high == 0 {
            (self.first_keys[r as usize], &self.seeds[r as usize][..])
        } else {
            (key(self.seed, r, epoch, high), &[][..])
        };
        Stream {
            key,
            seeds,
            index_reversed: low.reverse_bits(),
            dim: 0,
            origin: (self, m, s),
        }
    }
}

fn key(seed: u64, r: u64, epoch: u64, high: u64) -> u64 {
    mix64(seed ^ mix64(r ^ mix64(epoch ^ mix64(high))))
}

/// The seed hash of dimension `d` of the stream keyed `key`: its shuffle's seed in the low 32
/// bits, its first scramble's in the high 32.
#[inline]
fn seed_hash(key: u64, d: u32) -> u64 {
    mix64(key ^ u64::from(d).wrapping_mul(0x9e37_79b9_7f4a_7c15))
}

/// One sample's draws from the sequence: dimension `dim` next. The index is kept with its
/// bits reversed, as the shuffle takes it (`owen::scramble_reversed`), so each draw costs a
/// seed hash, the shuffle and one scramble per dimension, with three bit reversals for a 2D
/// draw — the same bits as `scramble(dim0(shuffle(index)))` and `scramble(dim1(..))`, by
/// dim0(i) = reverse(i) and dim1(i) = reverse(dim1_reversed(i)) (tested). The seed hashes of
/// the first dimensions come from the run's table when the key is a first key.
#[derive(Clone, Copy, Debug)]
pub struct Stream<'a> {
    key: u64,
    /// [`ZSobol::seeds`] of this key (empty for any other key).
    seeds: &'a [[u64; 2]],
    index_reversed: u32,
    dim: u32,
    /// The sequence, the pixel's Morton index and the sample this stream belongs to, for
    /// its continuations.
    origin: (&'a ZSobol, u64, u64),
}

impl<'a> Stream<'a> {
    /// The seed hash of dimension `d` (`seed_hash`).
    #[inline]
    fn seeds(&self, d: u32) -> u64 {
        match self.seeds.get(d as usize) {
            Some(s) => s[0],
            None => seed_hash(self.key, d),
        }
    }

    /// The seed hash of dimension `d` and its hash, the seeds of a 2D draw.
    #[inline]
    fn seed_pair(&self, d: u32) -> [u64; 2] {
        match self.seeds.get(d as usize) {
            Some(&s) => s,
            None => {
                let h = seed_hash(self.key, d);
                [h, mix64(h)]
            }
        }
    }

    /// The index shuffled with the seed hash `h` (Burley 2020 §4): `owen::shuffle`.
    #[inline]
    fn shuffled(&self, h: u64) -> u32 {
        owen::scramble_reversed(self.index_reversed, h as u32)
    }

    /// The next dimension as a 32-bit fraction: Sobol' dimension 0 at the shuffled index,
    /// scrambled (dim0(i) reversed is i).
    #[inline(always)]
    pub fn next_1d(&mut self) -> u32 {
        let h = self.seeds(self.dim);
        self.dim += 1;
        let i = self.shuffled(h);
        owen::scramble_reversed(i, (h >> 32) as u32)
    }

    /// The next two dimensions, a point of one (0, 2)-sequence, as 32-bit fractions.
    #[inline(always)]
    pub fn next_2d(&mut self) -> [u32; 2] {
        let [h, h2] = self.seed_pair(self.dim);
        self.dim += 2;
        let i = self.shuffled(h);
        [
            owen::scramble_reversed(i, (h >> 32) as u32),
            owen::scramble_reversed(sobol::dim1_reversed(i), h2 as u32),
        ]
    }

    /// Makes `d` the next dimension drawn.
    #[inline]
    pub fn set_dimension(&mut self, d: u32) {
        self.dim = d;
    }

    /// This sample's continuation `c` of 2^`bits` (a path split at its first vertex,
    /// `integrator::path`), at the current dimension: the points of index j · 2^bits + c of its
    /// replicate, so that the 2^bits continuations of the pixel's N samples of a replicate
    /// are one (0, k, 2)-net of 2^bits · N points in every 1D and 2D projection, as N · 2^bits
    /// samples would be (design.md §8, "Splitting at the first vertex").
    #[inline]
    pub fn continuation(&self, c: u32, bits: u32) -> Stream<'a> {
        let (z, m, s) = self.origin;
        Stream {
            dim: self.dim,
            ..z.stream_in(m, s, u64::from(c), bits)
        }
    }

    /// Steps past the next `n` dimensions without drawing them.
    #[inline]
    pub fn skip(&mut self, n: u32) {
        self.dim += n;
    }
}

/// The Morton (Z-order) code of (x, y): their bits interleaved, x in the even bits.
pub fn morton(x: u32, y: u32) -> u64 {
    spread(x) | (spread(y) << 1)
}

/// The bits of `v` moved to the even positions of a u64.
fn spread(v: u32) -> u64 {
    let mut v = u64::from(v);
    v = (v | (v << 16)) & 0x0000_ffff_0000_ffff;
    v = (v | (v << 8)) & 0x00ff_00ff_00ff_00ff;
    v = (v | (v << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
    v = (v | (v << 2)) & 0x3333_3333_3333_3333;
    (v | (v << 1)) & 0x5555_5555_5555_5555
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_interleaves() {
        assert_eq!(morton(0, 0), 0);
        assert_eq!(morton(1, 0), 1);
        assert_eq!(morton(0, 1), 2);
        assert_eq!(morton(3, 3), 15);
        assert_eq!(morton(u32::MAX, 0), 0x5555_5555_5555_5555);
    }

    /// The draws as the definition writes them: shuffle, Sobol' point, scramble, with the
    /// seed hashed here (not read from the run's table).
    fn reference_2d(q: &Stream, d: u32) -> [u32; 2] {
        let h = seed_hash(q.key, d);
        let i = owen::shuffle(q.index_reversed.reverse_bits(), h as u32);
        [
            owen::scramble(sobol::dim0(i), (h >> 32) as u32),
            owen::scramble(sobol::dim1(i), mix64(h) as u32),
        ]
    }

    /// (x, y, sample) of first keys (epoch 0) and of an epoch-1 sample (`s` = 64 at 64 spp).
    const PIXEL_SAMPLES: [(u32, u32, u64); 5] = [
        (0, 0, 0),
        (3, 5, 17),
        (63, 1, 63),
        (1000, 77, 5),
        (2, 9, 64),
    ];

    #[test]
    fn draws_are_the_definitions_bits() {
        let z = ZSobol::new(7, Some(64));
        // First keys (tabled seeds), an epoch 1 sample and index bits above 32 (hashed), and
        // dimensions on both sides of the table's end.
        let t = TABLED_DIMENSIONS as u32;
        for (x, y, s) in PIXEL_SAMPLES.into_iter().chain([(1 << 14, 1 << 14, 3)]) {
            let mut q = z.stream(x, y, s);
            for d in [0u32, 1, 5, 12, 40, t - 2, t - 1, t, t + 7] {
                q.set_dimension(d);
                let want = reference_2d(&q, d);
                assert_eq!(q.next_2d(), want, "pixel ({x}, {y}) sample {s} dim {d}");
                q.set_dimension(d);
                assert_eq!(q.next_1d(), want[0], "pixel ({x}, {y}) sample {s} dim {d}");
            }
        }
    }

    #[test]
    fn the_first_keys_are_the_definitions() {
        let z = ZSobol::new(7, Some(64));
        for (x, y, s) in PIXEL_SAMPLES {
            let (r, j) = (s & 1, s >> 1);
            let m = morton(x, y);
            let want = key(7, r, j >> z.log2, m >> (32 - z.log2));
            assert_eq!(z.stream(x, y, s).key, want, "pixel ({x}, {y}) sample {s}");
        }
        // Index bits above 32: a key of its own.
        let big = z.stream(1 << 14, 1 << 14, 3);
        assert_eq!(big.key, key(7, 1, 0, morton(1 << 14, 1 << 14) >> 27));
        assert_ne!(big.key, z.first_keys[1]);
    }

    #[test]
    fn block_sizes() {
        assert_eq!(ZSobol::new(0, Some(1)).log2, 0);
        assert_eq!(ZSobol::new(0, Some(2)).log2, 0);
        assert_eq!(ZSobol::new(0, Some(64)).log2, 5);
        assert_eq!(ZSobol::new(0, Some(65)).log2, 6);
        assert_eq!(ZSobol::new(0, None).log2, UNKNOWN_SPP_LOG2);
        assert_eq!(ZSobol::new(0, Some(u64::MAX)).log2, MAX_LOG2);
    }
}
