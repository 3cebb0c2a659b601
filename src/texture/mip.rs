//! The MIP pyramid of an image (PBR 4ed §10.4.3, pbrt-v4 `MIPMap`).
//!
//! Level k + 1 has ⌊w_k / 2⌋ × ⌊h_k / 2⌋ texels (at least 1 per axis), down to 1 × 1, so an
//! image has 1 + ⌊log2 max(w, h)⌋ levels. Each texel of level k + 1 is the exact box average
//! of level k over the texel's area: output texel i of an axis of n → m texels covers source
//! [i·n/m, (i + 1)·n/m] and weights each source texel by its overlap (separably, x then y).
//! For a power-of-two image this is pbrt's 2 × 2 box, and level k's texel is the mean of its
//! 2^k × 2^k block; for other sizes it replaces pbrt-v4's resampling up to a power of two
//! (a windowed-sinc filter that can ring) by a box over 2 or 3 texels, which needs no texel
//! outside the image, so the wrap mode matters only at lookup (every level is read with the
//! input's wrap mode). Memory: ≤ 1/3 more than the image while both sides halve; an image
//! much longer than it is high keeps halving its long side after the short one reached 1
//! (up to ×2 for a 1-texel-high strip, as any pyramid that reaches 1 × 1).

use super::Level;

/// Level 0 and every coarser level.
pub(super) fn pyramid(base: Level) -> Vec<Level> {
    let mut levels = vec![base];
    loop {
        let last = &levels[levels.len() - 1];
        if last.width == 1 && last.height == 1 {
            return levels;
        }
        let next = downsample(last);
        levels.push(next);
    }
}

/// `l` box-filtered to ⌊size / 2⌋ per axis (at least 1).
fn downsample(l: &Level) -> Level {
    let (w, h) = ((l.width / 2).max(1), (l.height / 2).max(1));
    let (wx, wy) = (box_weights(l.width, w), box_weights(l.height, h));
    let mut rows = vec![[0.0f32; 4]; w * l.height];
    for y in 0..l.height {
        let src = &l.texels[y * l.width..(y + 1) * l.width];
        for (x, taps) in wx.iter().enumerate() {
            rows[y * w + x] = weighted(taps.iter().map(|&(j, wt)| (src[j], wt)));
        }
    }
    let mut texels = vec![[0.0f32; 4]; w * h];
    for (y, taps) in wy.iter().enumerate() {
        for x in 0..w {
            texels[y * w + x] = weighted(taps.iter().map(|&(j, wt)| (rows[j * w + x], wt)));
        }
    }
    Level {
        width: w,
        height: h,
        texels,
    }
}

/// Σ weight · texel.
#[inline]
fn weighted(taps: impl Iterator<Item = ([f32; 4], f32)>) -> [f32; 4] {
    let mut sum = [0.0f32; 4];
    for (t, wt) in taps {
        for c in 0..4 {
            sum[c] += wt * t[c];
        }
    }
    sum
}

/// For each of `m` output texels along an axis of `n` source texels: the source texels it
/// overlaps and their weights (overlap / output width, summing to 1). In units of 1/m of a
/// source texel the bounds are integers, so the weights are exact ratios.
fn box_weights(n: usize, m: usize) -> Vec<Vec<(usize, f32)>> {
    (0..m)
        .map(|i| {
            let (a, b) = (i * n, (i + 1) * n);
            (a / m..b.div_ceil(m).min(n))
                .filter_map(|j| {
                    let overlap = b.min((j + 1) * m).saturating_sub(a.max(j * m));
                    (overlap > 0).then(|| (j, (overlap as f64 / n as f64) as f32))
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_weights_cover_each_output_once() {
        assert_eq!(
            box_weights(4, 2),
            vec![vec![(0, 0.5), (1, 0.5)], vec![(2, 0.5), (3, 0.5)]]
        );
        // 5 → 2: each output covers 2.5 source texels.
        assert_eq!(
            box_weights(5, 2),
            vec![
                vec![(0, 0.4), (1, 0.4), (2, 0.2)],
                vec![(2, 0.2), (3, 0.4), (4, 0.4)]
            ]
        );
        assert_eq!(box_weights(1, 1), vec![vec![(0, 1.0)]]);
        for (n, m) in [(7, 3), (3, 1), (1000, 500), (999, 499)] {
            let w = box_weights(n, m);
            let mut per_source = vec![0.0f64; n];
            for taps in &w {
                let s: f64 = taps.iter().map(|t| f64::from(t.1)).sum();
                assert!((s - 1.0).abs() < 1e-6, "{n} → {m}: {s}");
                for &(j, wt) in taps {
                    per_source[j] += f64::from(wt);
                }
            }
            // Every source texel contributes m/n of an output in total: no area lost or doubled.
            for s in per_source {
                assert!((s - m as f64 / n as f64).abs() < 1e-6);
            }
        }
    }
}
