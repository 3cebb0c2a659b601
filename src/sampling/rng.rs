//! Deterministic sampling: every sample's random numbers depend only on
//! (seed, pixel or path index, sample index), so the image does not depend on the number of
//! threads or the order of work (as pbrt-v4's IndependentSampler).
//!
//! A sampler is either independent (every number from PCG32) or a stream of the
//! low-discrepancy sequence (`zsobol.rs`) that keeps PCG32 beside it for its forks and for
//! decisions outside the dimension layout (`dimensions.rs`).
//!
//! Generator: PCG32 (O'Neill 2014, "PCG: A Family of Simple Fast Space-Efficient Statistically
//! Good Algorithms for Random Number Generation", XSH-RR output, multiplier 6364136223846793005),
//! seeded through SplitMix64 mixing (Steele et al. 2014).

use super::zsobol::Stream;

/// A per-sample random number stream; `'a` is the run's sequence (`ZSobol`), whose table of
/// seed hashes a low-discrepancy stream reads.
#[derive(Clone, Debug)]
pub struct Sampler<'a> {
    state: u64,
    inc: u64,
    /// The (seed, index, sample) of a PCG32 state not derived yet: a low-discrepancy sampler
    /// derives it at its first draw outside the sequence (a fork, a detached or free draw),
    /// which most of the path tracer's samples never make. None once derived, and always
    /// for the independent sampler.
    pending: Option<[u64; 3]>,
    /// The low-discrepancy stream, if this sample draws from one.
    lds: Option<Stream<'a>>,
}

const PCG_MULT: u64 = 6_364_136_223_846_793_005;

impl<'a> Sampler<'a> {
    /// The stream for one (seed, index, sample) triple; `index` is typically the pixel index.
    pub fn new(seed: u64, index: u64, sample: u64) -> Sampler<'a> {
        let key = mix64(seed ^ mix64(index.wrapping_add(mix64(sample))));
        let inc = (mix64(key ^ 0x9e37_79b9_7f4a_7c15) << 1) | 1;
        let mut s = Sampler {
            state: 0,
            inc,
            pending: None,
            lds: None,
        };
        s.next_u32();
        s.state = s.state.wrapping_add(key);
        s.next_u32();
        s
    }

    /// The sampler of sample `sample` of pixel `index` that draws from the low-discrepancy
    /// `stream`; its forks and [`get_1d_free`](Self::get_1d_free) are those of
    /// `Sampler::new(seed, index, sample)`, whose state it derives at the first of them.
    #[inline]
    pub fn low_discrepancy(seed: u64, index: u64, sample: u64, stream: Stream<'a>) -> Sampler<'a> {
        Sampler {
            state: 0,
            inc: 0,
            pending: Some([seed, index, sample]),
            lds: Some(stream),
        }
    }

    /// Derives the PCG32 state if it is still pending (`low_discrepancy`).
    #[inline]
    fn seed_pcg(&mut self) {
        if let Some([seed, index, sample]) = self.pending.take() {
            let s = Sampler::new(seed, index, sample);
            (self.state, self.inc) = (s.state, s.inc);
        }
    }

    /// Makes `d` the next dimension a low-discrepancy sampler draws (`dimensions.rs`); the
    /// independent sampler draws in order and ignores it.
    #[inline]
    pub fn set_dimension(&mut self, d: u32) {
        if let Some(q) = &mut self.lds {
            q.set_dimension(d);
        }
    }

    /// PCG32's next output; private, as a pending state (`low_discrepancy`) must be derived
    /// first (`seed_pcg`).
    #[inline]
    fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform number in [0, 1): the next dimension.
    #[inline]
    pub fn get_1d(&mut self) -> f32 {
        match &mut self.lds {
            Some(q) => unit(q.next_1d()),
            None => unit(self.next_u32()),
        }
    }

    /// A uniform point in [0, 1)²: the next two dimensions.
    #[inline(always)]
    pub fn get_2d(&mut self) -> [f32; 2] {
        match &mut self.lds {
            Some(q) => q.next_2d().map(unit),
            None => [unit(self.next_u32()), unit(self.next_u32())],
        }
    }

    /// [`get_2d`](Self::get_2d) for a caller that reads the point only when `read` (the lens
    /// sample of a pinhole camera). Unread, a low-discrepancy stream steps past the two
    /// dimensions without computing them (its dimensions are addressed, so every later number
    /// is the same) and the point is the square's centre; the independent sampler draws them
    /// either way, as its later numbers follow in order.
    #[inline(always)]
    pub fn get_2d_if(&mut self, read: bool) -> [f32; 2] {
        match &mut self.lds {
            Some(q) if !read => {
                q.skip(2);
                [0.5, 0.5]
            }
            _ => self.get_2d(),
        }
    }

    /// A uniform number in [0, 1) from PCG32 whatever the sampler, for decisions a path
    /// takes a variable number of times (stochastic opacity), which have no place in the
    /// dimension layout. For the independent sampler it is [`get_1d`](Self::get_1d).
    /// Switches to continuation `c` of the 2^`bits` that a path splits into at its first
    /// vertex (`integrator::path`): the low-discrepancy stream takes the continuation's points
    /// (`Stream::continuation`) at the current dimension; the independent sampler, and the
    /// free draws of both, go on with their own numbers, so that the continuations, drawn
    /// one after another, are independent.
    #[inline]
    pub fn enter_continuation(&mut self, c: u32, bits: u32) {
        if let Some(q) = &mut self.lds {
            *q = q.continuation(c, bits);
        }
    }

    #[inline]
    pub fn get_1d_free(&mut self) -> f32 {
        self.seed_pcg();
        unit(self.next_u32())
    }

    /// Runs `f` with the low-discrepancy stream set aside: every number `f` draws comes from
    /// PCG32, as [`get_1d_free`](Self::get_1d_free), and the sequence's dimensions are left
    /// as they were. For the parts of a sample whose count of draws varies outside the
    /// dimension layout (a bidirectional sample's light subpath and its splats). For the
    /// independent sampler it is `f(self)`: the same numbers in the same order.
    #[inline]
    pub fn detached<R>(&mut self, f: impl FnOnce(&mut Sampler<'a>) -> R) -> R {
        self.seed_pcg();
        let lds = self.lds.take();
        let r = f(self);
        self.lds = lds;
        r
    }

    /// A stream of its own, derived from this one's current state and `stream` without
    /// advancing this one: what this sampler draws next does not change.
    pub fn fork(&self, stream: u64) -> Sampler<'a> {
        if self.pending.is_some() {
            let mut seeded = self.clone();
            seeded.seed_pcg();
            return seeded.fork(stream);
        }
        let key = mix64(self.state ^ mix64(stream ^ self.inc));
        let inc = (mix64(key ^ stream) << 1) | 1;
        let mut s = Sampler {
            state: key,
            inc,
            pending: None,
            lds: None,
        };
        s.next_u32();
        s
    }
}

/// 24 random mantissa bits of `x` as a number in [0, 1): exactly representable and strictly
/// below 1.
#[inline]
fn unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// SplitMix64 finaliser (Steele, Lea, Flood 2014).
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let a: Vec<f32> = (0..8)
            .map(|_| 0.0)
            .scan(Sampler::new(1, 2, 3), |s, _| Some(s.get_1d()))
            .collect();
        let b: Vec<f32> = (0..8)
            .map(|_| 0.0)
            .scan(Sampler::new(1, 2, 3), |s, _| Some(s.get_1d()))
            .collect();
        let c: Vec<f32> = (0..8)
            .map(|_| 0.0)
            .scan(Sampler::new(1, 2, 4), |s, _| Some(s.get_1d()))
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn a_fork_is_reproducible_and_leaves_its_parent_alone() {
        let mut a = Sampler::new(1, 2, 3);
        a.get_1d();
        let (mut f, mut g) = (a.fork(7), a.fork(7));
        let (x, y) = (f.get_1d(), g.get_1d());
        assert_eq!(x, y);
        let parent: Vec<f32> = (0..4).map(|_| a.get_1d()).collect();
        let fork: Vec<f32> = (0..4).map(|_| f.get_1d()).collect();
        assert_ne!(parent, fork);
        assert_ne!(a.fork(8).get_1d(), a.fork(7).get_1d());
    }

    #[test]
    fn detached_draws_are_the_free_stream_and_leave_the_sequence_alone() {
        let z = super::super::zsobol::ZSobol::new(3, Some(16));
        let lds = || Sampler::low_discrepancy(3, 9, 5, z.stream(9, 0, 5));
        // The sequence's draws do not depend on what ran detached in between.
        let (mut a, mut b) = (lds(), lds());
        a.get_1d();
        b.get_1d();
        let inner: Vec<f32> = a.detached(|s| (0..5).map(|_| s.get_1d()).collect());
        assert_eq!(a.get_2d(), b.get_2d());
        // Detached draws are the PCG32 stream of (seed, index, sample), in order.
        let mut free = Sampler::new(3, 9, 5);
        let want: Vec<f32> = (0..5).map(|_| free.get_1d()).collect();
        assert_eq!(inner, want);
        // For the independent sampler detaching changes nothing.
        let (mut c, mut d) = (Sampler::new(3, 9, 5), Sampler::new(3, 9, 5));
        let x: Vec<f32> = (0..4).map(|_| c.detached(|s| s.get_1d())).collect();
        let y: Vec<f32> = (0..4).map(|_| d.get_1d()).collect();
        assert_eq!(x, y);
    }

    #[test]
    fn a_low_discrepancy_samplers_pcg_is_the_independent_ones() {
        let z = super::super::zsobol::ZSobol::new(3, Some(16));
        let lds = || Sampler::low_discrepancy(3, 9, 5, z.stream(9, 0, 5));
        // A fork before any free draw, and after one, are those of Sampler::new's stream.
        let (a, mut b, mut free) = (lds(), lds(), Sampler::new(3, 9, 5));
        assert_eq!(a.fork(7).get_1d(), free.fork(7).get_1d());
        b.get_2d();
        assert_eq!(b.get_1d_free(), free.get_1d_free());
        assert_eq!(b.fork(11).get_1d(), free.fork(11).get_1d());
        assert_eq!(b.get_1d_free(), free.get_1d_free());
    }

    /// An unread 2D draw leaves every later number as a read one would: the low-discrepancy
    /// sampler's next dimensions and PCG32, the independent sampler's stream.
    #[test]
    fn an_unread_2d_draw_leaves_the_later_numbers_alone() {
        fn check<'a>(make: impl Fn() -> Sampler<'a>) {
            let (mut read, mut unread) = (make(), make());
            read.get_1d();
            unread.get_1d();
            let point = read.get_2d();
            assert_eq!(unread.get_2d_if(true), point);
            let (mut read, mut unread) = (make(), make());
            read.get_2d();
            unread.get_2d_if(false);
            let later = |s: &mut Sampler| (s.get_1d(), s.get_2d(), s.get_1d_free());
            assert_eq!(later(&mut read), later(&mut unread));
        }
        let z = super::super::zsobol::ZSobol::new(3, Some(16));
        let independent = || Sampler::new(3, 9, 5);
        check(independent);
        check(|| Sampler::low_discrepancy(3, 9, 5, z.stream(9, 0, 5)));
        // The independent sampler draws the point either way.
        assert_eq!(independent().get_2d_if(false), independent().get_2d());
    }

    #[test]
    fn uniform_mean_and_range() {
        let mut s = Sampler::new(7, 0, 0);
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let u = s.get_1d();
            assert!((0.0..1.0).contains(&u));
            sum += u as f64;
        }
        // Mean of U(0,1) has standard error 1/sqrt(12 n) ≈ 6.5e-4; allow 5 sigma.
        assert!((sum / n as f64 - 0.5).abs() < 5.0 * (1.0 / (12.0 * n as f64)).sqrt());
    }
}
