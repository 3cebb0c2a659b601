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
    assert_eq!(input.rgba(uv), [6.5, 3.0, 1.5, 0.5]);
    assert_eq!(input.float(uv), 0.5);
    assert_eq!(input.rgb(uv), [0.5; 3]);
    let rgb = TextureInput {
        channel: TextureChannel::Rgb,
        ..input.clone()
    };
    assert_eq!(rgb.rgb(uv), [6.5, 3.0, 1.5]);
    assert_eq!(rgb.float(uv), 6.5);
    assert_eq!(input.rgba(Vec2::new(f32::NAN, 0.0)), [7.0; 4]);
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
    let at = input.float(Vec2::new(0.75, 0.25));
    // (0.75, 0.25) ↦ (0.375, 0.25) ↦ (−0.25, 0.375) ↦ (0.25, 0.375).
    let expected = at_clamped(0.25, 0.375);
    assert!((at - expected).abs() < 1e-5, "{at} vs {expected}");
    assert_eq!(input.rgba(Vec2::new(f32::NAN, 0.0)), [7.0; 4]);
}

fn at_clamped(u: f32, v: f32) -> f32 {
    at(&two_by_two(), u, v, Wrap::Clamp)
}
