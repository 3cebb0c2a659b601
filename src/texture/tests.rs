use super::*;

/// A 2×2 image, top row (1, 2), bottom row (3, 4) in every channel.
fn two_by_two() -> ImageTexture {
    let t = |v: f32| [v, v, v, 1.0];
    ImageTexture::from_texels(2, 2, vec![t(1.0), t(2.0), t(3.0), t(4.0)]).unwrap()
}

fn at(img: &ImageTexture, u: f32, v: f32, wrap: Wrap) -> f32 {
    img.bilinear(Vec2::new(u, v), [wrap; 2])[0]
}

#[test]
fn texel_centres_and_v_flip() {
    let img = two_by_two();
    // st (0, 0) is the bottom-left: the bottom row of the file holds 3 and 4.
    assert_eq!(at(&img, 0.25, 0.25, Wrap::Clamp), 3.0);
    assert_eq!(at(&img, 0.75, 0.25, Wrap::Clamp), 4.0);
    assert_eq!(at(&img, 0.25, 0.75, Wrap::Clamp), 1.0);
    assert_eq!(at(&img, 0.75, 0.75, Wrap::Clamp), 2.0);
    // Halfway between all four centres.
    assert!((at(&img, 0.5, 0.5, Wrap::Clamp) - 2.5).abs() < 1e-6);
}

#[test]
fn wrap_modes_at_the_edges() {
    let img = two_by_two();
    // u = 0 lies halfway between texel −1 and texel 0 of the bottom row.
    assert!((at(&img, 0.0, 0.25, Wrap::Clamp) - 3.0).abs() < 1e-6);
    assert!((at(&img, 0.0, 0.25, Wrap::Repeat) - 3.5).abs() < 1e-6);
    assert!((at(&img, 0.0, 0.25, Wrap::Mirror) - 3.0).abs() < 1e-6);
    assert!((at(&img, 0.0, 0.25, Wrap::Black) - 1.5).abs() < 1e-6);
    // Beyond the image: repeat is periodic, mirror reflects, black is 0.
    assert_eq!(at(&img, 1.25, 0.25, Wrap::Repeat), 3.0);
    assert_eq!(at(&img, -0.75, 0.25, Wrap::Repeat), 3.0);
    assert_eq!(at(&img, 1.25, 0.25, Wrap::Mirror), 4.0);
    assert_eq!(at(&img, 1.75, 0.25, Wrap::Mirror), 3.0);
    assert_eq!(at(&img, 5.0, 0.25, Wrap::Black), 0.0);
    assert_eq!(at(&img, 5.0, 0.25, Wrap::Clamp), 4.0);
    // Different modes per axis: v beyond the top, repeat in u, clamp in v.
    let t = img.bilinear(Vec2::new(0.25, 3.0), [Wrap::Repeat, Wrap::Clamp]);
    assert_eq!(t[0], 1.0);
}

#[test]
fn scale_bias_channels_and_fallback() {
    let img = Arc::new(two_by_two());
    let input = TextureInput {
        image: img,
        wrap: [Wrap::Clamp; 2],
        scale: [2.0, 1.0, 0.5, 1.0],
        bias: [0.5, 0.0, 0.0, -0.5],
        fallback: [7.0; 4],
        channel: TextureChannel::A,
        transform: None,
    };
    let uv = Vec2::new(0.25, 0.25);
    assert_eq!(input.rgba(uv.into()), [6.5, 3.0, 1.5, 0.5]);
    assert_eq!(input.float(uv.into()), 0.5);
    assert_eq!(input.rgb(uv.into()), [0.5; 3]);
    let rgb = TextureInput {
        channel: TextureChannel::Rgb,
        ..input.clone()
    };
    assert_eq!(rgb.rgb(uv.into()), [6.5, 3.0, 1.5]);
    assert_eq!(rgb.float(uv.into()), 6.5);
    assert_eq!(input.rgba(Vec2::new(f32::NAN, 0.0).into()), [7.0; 4]);
}

#[test]
fn huge_and_negative_coordinates_stay_finite() {
    let img = two_by_two();
    for wrap in [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror, Wrap::Black] {
        for u in [-1e9_f32, -3.3, 0.0, 1.0, 7.7, 1e9, f32::MAX] {
            let v = at(&img, u, u * 0.5, wrap);
            assert!(v.is_finite(), "{wrap:?} at {u}");
        }
    }
}

#[test]
fn rejects_bad_texels() {
    assert!(ImageTexture::from_texels(2, 1, vec![[0.0; 4]]).is_none());
    assert!(ImageTexture::from_texels(1, 1, vec![[f32::NAN; 4]]).is_none());
    assert!(ImageTexture::from_texels(0, 0, vec![]).is_none());
}

#[test]
fn the_st_transform_applies_before_the_lookup() {
    let img = Arc::new(two_by_two());
    let input = TextureInput {
        image: img,
        wrap: [Wrap::Clamp; 2],
        scale: [1.0; 4],
        bias: [0.0; 4],
        fallback: [7.0; 4],
        channel: TextureChannel::R,
        // UsdTransform2d: scale (0.5, 1), then rotation 90° counter-clockwise, then
        // translation (0.5, 0).
        transform: Some(Affine2::from_scale_angle_translation(
            Vec2::new(0.5, 1.0),
            std::f32::consts::FRAC_PI_2,
            Vec2::new(0.5, 0.0),
        )),
    };
    let at = input.float(Vec2::new(0.75, 0.25).into());
    // (0.75, 0.25) ↦ (0.375, 0.25) ↦ (−0.25, 0.375) ↦ (0.25, 0.375).
    let expected = at_clamped(0.25, 0.375);
    assert!((at - expected).abs() < 1e-5, "{at} vs {expected}");
    assert_eq!(input.rgba(Vec2::new(f32::NAN, 0.0).into()), [7.0; 4]);
}

fn at_clamped(u: f32, v: f32) -> f32 {
    at(&two_by_two(), u, v, Wrap::Clamp)
}

// ---- MIP pyramid and trilinear filtering ----------------------------------------------------

/// A `w`×`h` image of reproducible pseudo-random texels (integers 0..=255 / 8, exact in f32).
fn noise(w: usize, h: usize, seed: u64) -> ImageTexture {
    let mut s = seed;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 33) % 256) as f32 / 8.0
    };
    let texels = (0..w * h)
        .map(|_| [next(), next(), next(), next()])
        .collect();
    ImageTexture::from_texels(w, h, texels).unwrap()
}

#[test]
fn power_of_two_levels_are_block_means() {
    let img = noise(32, 16, 3);
    assert_eq!(img.levels(), 6);
    for k in 0..img.levels() {
        let (w, h) = img.level_size(k);
        assert_eq!((w, h), ((32 >> k).max(1), (16 >> k).max(1)));
        // The block of level 0 under texel (x, y): 2^k × 2^k, but only as tall as the image
        // once the height reached 1.
        let (bw, bh) = (32 / w, 16 / h);
        for y in 0..h {
            for x in 0..w {
                let mut mean = [0.0f64; 4];
                for j in 0..bh {
                    for i in 0..bw {
                        let t = img.level_texel(0, x * bw + i, y * bh + j);
                        for c in 0..4 {
                            mean[c] += f64::from(t[c]) / (bw * bh) as f64;
                        }
                    }
                }
                let t = img.level_texel(k, x, y);
                for c in 0..4 {
                    assert!(
                        (f64::from(t[c]) - mean[c]).abs() < 1e-5 * mean[c].max(1.0),
                        "level {k} ({x}, {y}) channel {c}: {} vs {}",
                        t[c],
                        mean[c]
                    );
                }
            }
        }
    }
}

#[test]
fn non_power_of_two_sizes_halve_down_to_one_and_keep_the_mean() {
    type Sizes = Vec<(usize, usize)>;
    let cases: [((usize, usize), Sizes); 4] = [
        ((5, 3), vec![(5, 3), (2, 1), (1, 1)]),
        ((1, 1), vec![(1, 1)]),
        ((7, 1), vec![(7, 1), (3, 1), (1, 1)]),
        (
            (300, 200),
            vec![
                (300, 200),
                (150, 100),
                (75, 50),
                (37, 25),
                (18, 12),
                (9, 6),
                (4, 3),
                (2, 1),
            ],
        ),
    ];
    for ((w, h), sizes) in cases {
        let img = noise(w, h, 11);
        let mut expected = sizes.clone();
        if expected.last() != Some(&(1, 1)) {
            expected.push((1, 1));
        }
        let got: Vec<_> = (0..img.levels()).map(|k| img.level_size(k)).collect();
        assert_eq!(got, expected, "{w}×{h}");
        assert_eq!(img.levels(), 1 + (w.max(h) as f64).log2().floor() as usize);
        // Every level holds the image's mean (box filters preserve area averages).
        let mean = |k: usize| {
            let (lw, lh) = img.level_size(k);
            let mut m = 0.0f64;
            for y in 0..lh {
                for x in 0..lw {
                    m += f64::from(img.level_texel(k, x, y)[1]) / (lw * lh) as f64;
                }
            }
            m
        };
        for k in 1..img.levels() {
            assert!(
                (mean(k) - mean(0)).abs() < 1e-4 * mean(0),
                "{w}×{h} level {k}"
            );
        }
        // Memory: at most a third more than the image while both sides halve.
        let total: usize = got.iter().map(|(a, b)| a * b).sum();
        if w == 300 {
            assert!(total * 3 <= 4 * w * h, "{total}");
        }
    }
}

#[test]
fn zero_footprint_is_the_bilinear_lookup_exactly() {
    let img = noise(13, 9, 5);
    for wrap in [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror, Wrap::Black] {
        for (u, v) in [(0.0, 0.0), (0.31, 0.77), (-1.2, 3.4), (0.999, 0.5)] {
            let uv = Vec2::new(u, v);
            assert_eq!(
                img.trilinear(uv, 0.0, [wrap; 2]),
                img.bilinear(uv, [wrap; 2])
            );
            // Widths below a texel stay at level 0, as do NaN widths.
            assert_eq!(
                img.trilinear(uv, 0.5 / 13.0, [wrap; 2]),
                img.bilinear(uv, [wrap; 2])
            );
            assert_eq!(
                img.trilinear(uv, f32::NAN, [wrap; 2]),
                img.bilinear(uv, [wrap; 2])
            );
        }
    }
}

#[test]
fn trilinear_interpolates_between_levels_and_saturates_at_the_mean() {
    // Horizontal stripes of 0 and 1, one texel each, 8×8: level 1 and coarser are all 0.5.
    let texels = (0..64)
        .map(|i| if (i / 8) % 2 == 0 { [0.0; 4] } else { [1.0; 4] })
        .collect();
    let img = ImageTexture::from_texels(8, 8, texels).unwrap();
    let uv = Vec2::new(0.5 / 8.0, 1.0 - 0.5 / 8.0); // the centre of texel (0, 0) = 0
    let at = |width: f32| img.trilinear(uv, width, [Wrap::Repeat; 2])[0];
    assert_eq!(at(0.0), 0.0);
    // width = 1 texel: level 0; 2 texels: level 1; 1.5: log2(1.5) of the way.
    assert_eq!(at(1.0 / 8.0), 0.0);
    assert!((at(2.0 / 8.0) - 0.5).abs() < 1e-6);
    let t = 1.5f32.log2();
    assert!((at(1.5 / 8.0) - 0.5 * t).abs() < 1e-6);
    for width in [1.0, 10.0, 1e8, f32::INFINITY] {
        assert!((at(width) - 0.5).abs() < 1e-6, "{width}");
    }
}

#[test]
fn a_constant_texture_is_the_same_at_every_footprint() {
    let c = [0.25, 0.5, 0.75, 1.0];
    let img = Arc::new(ImageTexture::from_texels(6, 10, vec![c; 60]).unwrap());
    for wrap in [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror] {
        let input = TextureInput {
            image: img.clone(),
            wrap: [wrap; 2],
            scale: [1.0; 4],
            bias: [0.0; 4],
            fallback: [7.0; 4],
            channel: TextureChannel::Rgb,
            transform: None,
        };
        for d in [0.0, 1e-4, 0.05, 0.3, 1.0, 50.0, 1e8] {
            let tc = TexCoord {
                uv: Vec2::new(0.37, 0.61),
                duvdx: Vec2::new(d, 0.3 * d),
                duvdy: Vec2::new(-0.2 * d, d),
            };
            assert_eq!(input.rgba(tc), c, "{wrap:?} {d}");
        }
    }
}
