//! The false-colour scale of illuminance maps: viridis, a perceptually uniform, monotonically
//! brightening colormap that stays readable in grey and for colour-blind viewers.
//!
//! Source: `_viridis_data` of matplotlib (`lib/matplotlib/_cm_listed.py`, originally the
//! BIDS `mpl-colormaps` package by Nathaniel J. Smith, Stefan van der Walt and Eric Firing,
//! released under CC0). The table below keeps entries 0, 16, 32, …, 240 and 255 of the 256
//! (sRGB values in [0, 1]); between them it is interpolated linearly, which stays within one
//! 8-bit code value of the full table.

/// (position in [0, 1] = index/255, sRGB).
const VIRIDIS: [(f32, [f32; 3]); 17] = [
    (0.0 / 255.0, [0.267004, 0.004874, 0.329415]),
    (16.0 / 255.0, [0.282327, 0.094955, 0.417331]),
    (32.0 / 255.0, [0.278826, 0.175490, 0.483397]),
    (48.0 / 255.0, [0.258965, 0.251537, 0.524736]),
    (64.0 / 255.0, [0.229739, 0.322361, 0.545706]),
    (80.0 / 255.0, [0.199430, 0.387607, 0.554642]),
    (96.0 / 255.0, [0.172719, 0.448791, 0.557885]),
    (112.0 / 255.0, [0.149039, 0.508051, 0.557250]),
    (128.0 / 255.0, [0.127568, 0.566949, 0.550556]),
    (144.0 / 255.0, [0.120638, 0.625828, 0.533488]),
    (160.0 / 255.0, [0.157851, 0.683765, 0.501686]),
    (176.0 / 255.0, [0.246070, 0.738910, 0.452024]),
    (192.0 / 255.0, [0.369214, 0.788888, 0.382914]),
    (208.0 / 255.0, [0.515992, 0.831158, 0.294279]),
    (224.0 / 255.0, [0.678489, 0.863742, 0.189503]),
    (240.0 / 255.0, [0.845561, 0.887322, 0.099702]),
    (1.0, [0.993248, 0.906157, 0.143936]),
];

/// The 8-bit sRGB colour at `t` (clamped to [0, 1]; NaN gives the low end).
pub fn viridis(t: f32) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let k = VIRIDIS
        .windows(2)
        .position(|w| t <= w[1].0)
        .unwrap_or(VIRIDIS.len() - 2);
    let ((t0, c0), (t1, c1)) = (VIRIDIS[k], VIRIDIS[k + 1]);
    let f = (t - t0) / (t1 - t0);
    std::array::from_fn(|i| ((c0[i] + f * (c1[i] - c0[i])) * 255.0).round() as u8)
}

/// Relative luminance of an 8-bit sRGB colour, roughly (for picking black or white ink).
pub fn is_light(c: [u8; 3]) -> bool {
    0.2126 * c[0] as f32 + 0.7152 * c[1] as f32 + 0.0722 * c[2] as f32 > 110.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_and_middle_match_matplotlib() {
        // #440154, #21918c and #fde725 are viridis(0), viridis(0.5), viridis(1).
        assert_eq!(viridis(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(viridis(1.0), [0xfd, 0xe7, 0x25]);
        let mid = viridis(0.5);
        let want: [i32; 3] = [0x21, 0x91, 0x8c];
        assert!(
            (0..3).all(|i| (mid[i] as i32 - want[i]).abs() <= 1),
            "{mid:?}"
        );
    }

    #[test]
    fn brightness_increases_monotonically() {
        let lum = |c: [u8; 3]| 0.2126 * c[0] as f32 + 0.7152 * c[1] as f32 + 0.0722 * c[2] as f32;
        let ls: Vec<f32> = (0..=100).map(|i| lum(viridis(i as f32 / 100.0))).collect();
        assert!(ls.windows(2).all(|w| w[1] >= w[0] - 0.5), "{ls:?}");
    }
}
