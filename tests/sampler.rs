//! The low-discrepancy sampler (`--sampler zsobol`, `sampling/zsobol.rs`):
//!
//! - stratification: in each replicate (the even, the odd samples) of a pixel, the first 2^k
//!   samples are a (0, k, 2)-net in every 1D and 2D projection the path tracer draws — the
//!   camera's dimensions and those of bounces beyond any table (padding by hashing);
//! - determinism: a sample's numbers depend on (seed, pixel, sample) only; path-traced images
//!   are bit-identical for 1 and 2 threads, and the low-discrepancy sequence changes them;
//! - no correlation between pixels: the error image of a known integral has no positive
//!   correlation at any of a set of lags, and its 8 × 8 block means vary no more than white
//!   noise's would (blue noise: much less);
//! - the z-tests between integrators with both samplers are in `tests/bidir.rs`.

mod common;

use common::*;
use spectral_render::sampling::dimensions::{self, BSDF, LIGHT, ROULETTE};
use spectral_render::sampling::{PixelSamplers, Sampler, SamplerKind};
use spectral_render::session::{self, RenderOptions};
use spectral_render::{scene, Integrator};

/// The cell of `u` among 2^bits equal intervals of [0, 1).
fn cell(u: f32, bits: u32) -> usize {
    ((u as f64) * (1u64 << bits) as f64) as usize
}

/// True when `points` (2^k of them) are a (0, k, 2)-net: one point in each elementary
/// interval 2^-a × 2^-(k−a), for every a.
fn is_net_2d(points: &[[f32; 2]], k: u32) -> bool {
    (0..=k).all(|a| {
        let mut seen = vec![false; 1 << k];
        points.iter().all(|p| {
            let c = (cell(p[0], a) << (k - a)) | cell(p[1], k - a);
            !std::mem::replace(&mut seen[c], true)
        })
    })
}

/// True when `values` (2^k of them) have one value in each interval of length 2^-k.
fn is_net_1d(values: &[f32], k: u32) -> bool {
    let mut seen = vec![false; 1 << k];
    values
        .iter()
        .all(|&v| !std::mem::replace(&mut seen[cell(v, k)], true))
}

/// The draws of one sample as the renderer makes them: wavelength, film, lens, then at
/// bounces 0, 1 and 40 the light's selection and point, the BSDF's lobe and direction and
/// the roulette test.
fn draws(sampler: &mut Sampler) -> (Vec<f32>, Vec<[f32; 2]>) {
    let (mut d1, mut d2) = (Vec::new(), Vec::new());
    sampler.set_dimension(dimensions::WAVELENGTH);
    d1.push(sampler.get_1d());
    sampler.set_dimension(dimensions::FILM);
    d2.push(sampler.get_2d());
    sampler.set_dimension(dimensions::LENS);
    d2.push(sampler.get_2d());
    for b in [0, 1, 40] {
        sampler.set_dimension(dimensions::bounce(b, LIGHT));
        d1.push(sampler.get_1d());
        d2.push(sampler.get_2d());
        sampler.set_dimension(dimensions::bounce(b, BSDF));
        d1.push(sampler.get_1d());
        d2.push(sampler.get_2d());
        sampler.set_dimension(dimensions::bounce(b, ROULETTE));
        d1.push(sampler.get_1d());
    }
    (d1, d2)
}

#[test]
fn each_replicate_of_a_pixel_is_a_0_k_2_net_in_every_projection() {
    let kmax = 9;
    for (seed, spp, width) in [(0u64, 1024u64, 64u64), (7, 4096, 1000), (3, 1 << 20, 5)] {
        let samplers = PixelSamplers::new(SamplerKind::ZSobol, seed, width, Some(spp));
        for (x, y) in [(0u32, 0u32), (3, 1), (width as u32 - 1, 17)] {
            for r in 0..2u64 {
                let all: Vec<_> = (0..1u64 << kmax)
                    .map(|j| draws(&mut samplers.pixel(x, y).sampler(2 * j + r)))
                    .collect();
                for k in 0..=kmax {
                    let n = 1 << k;
                    for d in 0..all[0].0.len() {
                        let v: Vec<f32> = all[..n].iter().map(|s| s.0[d]).collect();
                        assert!(
                            is_net_1d(&v, k),
                            "seed {seed} pixel {x},{y} rep {r} k {k} 1D {d}"
                        );
                    }
                    for d in 0..all[0].1.len() {
                        let p: Vec<[f32; 2]> = all[..n].iter().map(|s| s.1[d]).collect();
                        assert!(
                            is_net_2d(&p, k),
                            "seed {seed} pixel {x},{y} rep {r} k {k} 2D {d}"
                        );
                    }
                }
            }
        }
    }
}

/// A path split at its first vertex into 2^bits continuations (`--split`): the pixel's N
/// samples of a replicate give N · 2^bits continuations, and those are one (0, k, 2)-net in
/// every projection the continuations draw, as N · 2^bits samples' would be; continuation 0
/// of 1 is the sample's own stream.
#[test]
fn a_replicates_continuations_are_one_net() {
    let samplers = PixelSamplers::new(SamplerKind::ZSobol, 5, 300, Some(64));
    for (x, y) in [(0u32, 0u32), (7, 2), (299, 150)] {
        let pixel = samplers.pixel(x, y);
        let mut own = pixel.sampler(6);
        let mut first = pixel.sampler(6);
        first.enter_continuation(0, 0);
        assert_eq!(draws(&mut own), draws(&mut first));
        for bits in 1..=3u32 {
            for r in 0..2u64 {
                let all: Vec<_> = (0..32u64)
                    .flat_map(|j| (0..1u32 << bits).map(move |c| (j, c)))
                    .map(|(j, c)| {
                        let mut s = pixel.sampler(2 * j + r);
                        s.enter_continuation(c, bits);
                        draws(&mut s)
                    })
                    .collect();
                let k = 5 + bits;
                for d in 0..all[0].0.len() {
                    let v: Vec<f32> = all.iter().map(|s| s.0[d]).collect();
                    assert!(is_net_1d(&v, k), "pixel {x},{y} bits {bits} rep {r} 1D {d}");
                }
                for d in 0..all[0].1.len() {
                    let p: Vec<[f32; 2]> = all.iter().map(|s| s.1[d]).collect();
                    assert!(is_net_2d(&p, k), "pixel {x},{y} bits {bits} rep {r} 2D {d}");
                }
            }
        }
    }
}

#[test]
fn the_independent_sampler_is_not_a_net() {
    // The test above can fail: 16 independent 2D points are a (0, 4, 2)-net with
    // probability (16!/16^16)^5-ish, far below 1e-6.
    let samplers = PixelSamplers::new(SamplerKind::Independent, 0, 64, Some(1024));
    let p: Vec<[f32; 2]> = (0..16u64)
        .map(|j| draws(&mut samplers.pixel(1, 2).sampler(2 * j)).1[0])
        .collect();
    assert!(!is_net_2d(&p, 4));
}

#[test]
fn a_samples_numbers_depend_on_seed_pixel_and_sample_only() {
    let a = PixelSamplers::new(SamplerKind::ZSobol, 5, 64, Some(256));
    let b = PixelSamplers::new(SamplerKind::ZSobol, 5, 64, Some(256));
    for (x, y, s) in [(0, 0, 0), (9, 4, 17), (63, 63, 255)] {
        assert_eq!(
            draws(&mut a.pixel(x, y).sampler(s)),
            draws(&mut b.pixel(x, y).sampler(s))
        );
    }
    // Other seeds, pixels, samples and replicates give other numbers.
    let base = draws(&mut a.pixel(9, 4).sampler(16));
    let c = PixelSamplers::new(SamplerKind::ZSobol, 6, 64, Some(256));
    for other in [
        draws(&mut c.pixel(9, 4).sampler(16)),
        draws(&mut a.pixel(10, 4).sampler(16)),
        draws(&mut a.pixel(9, 4).sampler(18)),
        draws(&mut a.pixel(9, 4).sampler(17)),
    ] {
        assert_ne!(base, other);
    }
    // Out-of-order draws: a dimension's value does not depend on what was drawn before.
    let mut s = a.pixel(9, 4).sampler(16);
    s.set_dimension(dimensions::bounce(40, BSDF) + 1);
    let late = s.get_2d();
    assert_eq!(late, base.1[7]);
}

/// The error image of a known integral over a 64 × 64 image at 4 samples per pixel: the
/// integrand mixes the camera's dimensions and a bounce's, with discontinuities.
fn error_image(kind: SamplerKind, seed: u64) -> Vec<f64> {
    let n = 64u32;
    let samplers = PixelSamplers::new(kind, seed, u64::from(n), Some(4));
    let f = |s: &mut Sampler| {
        let (d1, d2) = draws(s);
        let a = f64::from(u8::from(d1[0] < 0.3));
        let b = f64::from(u8::from(d2[0][0] + d2[0][1] > 1.2));
        let c = f64::from(d2[3][0] * d2[3][1]);
        a + b + c
    };
    // E = 0.3 + 0.32 + 0.25.
    let exact = 0.3 + 0.5 * 0.8 * 0.8 + 0.25;
    (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            (0..4)
                .map(|s| f(&mut samplers.pixel(x, y).sampler(s)))
                .sum::<f64>()
                / 4.0
                - exact
        })
        .collect()
}

/// Correlation of the error image with itself shifted by (dx, dy).
fn lag_correlation(e: &[f64], n: usize, dx: usize, dy: usize) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for y in 0..n - dy {
        for x in 0..n - dx {
            num += e[y * n + x] * e[(y + dy) * n + x + dx];
        }
    }
    for v in e {
        den += v * v;
    }
    num / den * (n * n) as f64 / ((n - dx) * (n - dy)) as f64
}

/// Variance of the 8 × 8 block means over (pixel variance / 64): 1 for independent pixels.
fn block_variance_ratio(e: &[f64], n: usize) -> f64 {
    let pixel_var = e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64;
    let blocks: Vec<f64> = (0..(n / 8) * (n / 8))
        .map(|b| {
            let (bx, by) = (b % (n / 8) * 8, b / (n / 8) * 8);
            (0..64)
                .map(|i| e[(by + i / 8) * n + bx + i % 8])
                .sum::<f64>()
                / 64.0
        })
        .collect();
    let block_var = blocks.iter().map(|v| v * v).sum::<f64>() / blocks.len() as f64;
    block_var / (pixel_var / 64.0)
}

#[test]
fn pixels_errors_are_not_positively_correlated() {
    let n = 64;
    // Under independence a lag's correlation is about N(0, 1/4096): σ = 0.016, bound 4σ;
    // 64 block means give a variance ratio of χ²₆₄/64, below 1.7 with p > 0.999.
    let bound = 4.0 / n as f64;
    for kind in SamplerKind::ALL {
        for seed in [1, 2] {
            let e = error_image(kind, seed);
            for (dx, dy) in [
                (1, 0),
                (0, 1),
                (1, 1),
                (2, 0),
                (0, 2),
                (5, 3),
                (17, 9),
                (32, 0),
            ] {
                let r = lag_correlation(&e, n, dx, dy);
                assert!(
                    r < bound,
                    "{kind:?} seed {seed}: lag ({dx}, {dy}) correlation {r}"
                );
            }
            let ratio = block_variance_ratio(&e, n);
            eprintln!("{kind:?} seed {seed}: 8 × 8 block-mean variance / white noise's {ratio:.4}");
            assert!(ratio < 1.7, "{kind:?} seed {seed}: {ratio}");
            if kind == SamplerKind::ZSobol {
                // Morton order: an 8 × 8 block's samples are a net, its mean error tiny.
                assert!(ratio < 0.5, "{kind:?} seed {seed}: not blue: {ratio}");
            }
        }
    }
}

#[test]
fn path_traced_images_are_bit_identical_for_one_and_two_threads() {
    let scene = scene::load(&cbox_path(), Some((24, 18))).unwrap();
    let run = |threads, sampler| {
        let opts = RenderOptions {
            spp: Some(6),
            seed: 3,
            threads: Some(threads),
            integrator: Integrator::Path,
            sampler,
            ..Default::default()
        };
        session::render(&scene, &opts).unwrap().xyz
    };
    let zsobol = run(1, SamplerKind::ZSobol);
    assert_eq!(zsobol, run(2, SamplerKind::ZSobol));
    assert_ne!(zsobol, run(1, SamplerKind::Independent));
}
