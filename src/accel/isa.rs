//! The instruction set the BVH's queries run in, chosen once at run time.
//!
//! The queries are written once, for the baseline x86-64 target (SSE2). On a CPU with AVX the
//! same code is also compiled with AVX enabled: the compiler then emits the VEX encodings of
//! the same SSE operations, whose three operands spare the register copies and let the
//! per-ray splats stay in memory operands instead of being reloaded into registers around the
//! node test (docs/design.md §8, session 34). AVX alone, not FMA: every operation is the same
//! IEEE operation with the same rounding, so hits are bit for bit the baseline's (tested in
//! `bvh.rs`).

/// Whether the queries may run their AVX build. Made only by [`Isa::detect`] (or
/// [`Isa::baseline`]), so `avx` is true only on CPUs that have AVX.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Isa {
    avx: bool,
}

impl Isa {
    /// The best instruction set of this CPU.
    pub fn detect() -> Isa {
        #[cfg(target_arch = "x86_64")]
        let avx = std::arch::is_x86_feature_detected!("avx");
        #[cfg(not(target_arch = "x86_64"))]
        let avx = false;
        Isa { avx }
    }

    /// The baseline target's instruction set (for tests that compare the builds).
    #[cfg(test)]
    pub fn baseline() -> Isa {
        Isa { avx: false }
    }

    /// Runs `query` in the build of this instruction set.
    #[inline(always)]
    pub fn run<Q: Query>(self, query: Q) -> Q::Output {
        #[cfg(target_arch = "x86_64")]
        if self.avx {
            // SAFETY: `with_avx` requires AVX; `avx` is true only when `Isa::detect` found it
            // on this CPU (`is_x86_feature_detected!`).
            #[allow(unsafe_code)]
            return unsafe { with_avx(query) };
        }
        query.run::<false>()
    }
}

/// A query compiled into each instruction set's build: `run` and everything it calls down to
/// the hot loop must be `#[inline(always)]`, or it is compiled once, in the baseline build, and
/// called. (A closure is not enough: its body is a function of its own that the AVX build
/// called instead of inlining.)
pub(super) trait Query {
    type Output;
    /// `WIDE`: the node test of all eight children lane by lane, for the compiler to
    /// vectorise (`bvh.rs`' `slab_wide`), as the AVX build does; else two SSE halves.
    fn run<const WIDE: bool>(self) -> Self::Output;
}

/// `query.run()`, compiled with AVX enabled.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn with_avx<Q: Query>(query: Q) -> Q::Output {
    query.run::<true>()
}
