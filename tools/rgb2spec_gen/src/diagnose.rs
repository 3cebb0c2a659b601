//! `--diagnose <table.bin>`: measures the round-trip error of trilinear lookups in a table
//! against the renderer's colorimetry (no optimisation).

use crate::refine::{self, Colorimetry};
use crate::Table;

/// Trilinear lookup exactly as `src/spectral/uplift.rs` does it (nm-convention coefficients).
pub fn fetch(t: &Table, rgb: [f32; 3]) -> [f32; 3] {
    let res = t.res;
    let l = (1..3).fold(0, |m, j| if rgb[j] >= rgb[m] { j } else { m });
    let z = rgb[l];
    let k = (res - 1) as f32 / z;
    let (x, y) = (rgb[(l + 1) % 3] * k, rgb[(l + 2) % 3] * k);
    let xi = (x as usize).min(res - 2);
    let yi = (y as usize).min(res - 2);
    let zi = t
        .scale
        .partition_point(|&s| s <= z)
        .saturating_sub(1)
        .min(res - 2);
    let (dx, dy) = (x - xi as f32, y - yi as f32);
    let dz = (z - t.scale[zi]) / (t.scale[zi + 1] - t.scale[zi]);
    let at = |xo: usize, yo: usize, zo: usize, c: usize| {
        t.data[((((l * res + zi + zo) * res + yi + yo) * res + xi + xo) * 3) + c]
    };
    let lerp = |a: f32, b: f32, w: f32| a + w * (b - a);
    [0, 1, 2].map(|c| {
        let plane = |zo| {
            lerp(
                lerp(at(0, 0, zo, c), at(1, 0, zo, c), dx),
                lerp(at(0, 1, zo, c), at(1, 1, zo, c), dx),
                dy,
            )
        };
        lerp(plane(0), plane(1), dz)
    })
}

fn report(name: &str, t: &Table, cm: &Colorimetry, colours: &[[f32; 3]]) {
    let (mut worst_rel, mut worst_abs, mut fails, mut at) = (0.0f64, 0.0f64, 0, [0.0; 3]);
    let mut at_abs = [0.0; 3];
    for &rgb in colours {
        let c = fetch(t, rgb).map(f64::from);
        let out = cm.rgb_of(refine::to_normalised(c));
        let mut ok = true;
        for i in 0..3 {
            let e = (out[i] - rgb[i] as f64).abs();
            ok &= e <= (1e-3 * rgb[i] as f64).max(1e-4);
            if rgb[i] > 0.1 && e / rgb[i] as f64 > worst_rel {
                worst_rel = e / rgb[i] as f64;
                at = rgb;
            }
            if e > worst_abs {
                worst_abs = e;
                at_abs = rgb;
            }
        }
        fails += usize::from(!ok);
    }
    println!("{name:>28}: max rel {worst_rel:.2e} (at {at:?}), max abs {worst_abs:.2e} (at {at_abs:?}), {fails}/{} outside 1e-3 rel / 1e-4 abs", colours.len());
}

/// Distribution of the node errors (nodes with z ≥ 0.05 and not near white).
fn node_errors(t: &Table, cm: &Colorimetry) {
    let mut e: Vec<f64> = (0..t.data.len() / 3)
        .filter_map(|n| {
            let rgb = t.node_rgb(n);
            let z = rgb.iter().copied().fold(0.0, f64::max);
            if z < 0.05 || rgb.iter().all(|&v| v > 0.5) {
                return None;
            }
            let c = [0, 1, 2].map(|k| t.data[3 * n + k] as f64);
            Some(cm.error(refine::to_normalised(c), rgb))
        })
        .collect();
    e.sort_by(f64::total_cmp);
    let q = |p: f64| e[((e.len() - 1) as f64 * p) as usize];
    println!(
        "node errors (z >= 0.05, not near white, {} nodes): median {:.2e}, 90% {:.2e}, 99% {:.2e}, max {:.2e}",
        e.len(),
        q(0.5),
        q(0.9),
        q(0.99),
        q(1.0)
    );
}

pub fn run(t: &Table, cm: &Colorimetry) {
    node_errors(t, cm);
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let random: Vec<[f32; 3]> = (0..20000).map(|_| [next(), next(), next()]).collect();
    report("random in [0,1]^3", t, cm, &random);
    let bright: Vec<[f32; 3]> = random
        .iter()
        .filter(|c| c.iter().cloned().fold(0.0, f32::max) > 0.5)
        .copied()
        .collect();
    report("random, max > 0.5", t, cm, &bright);
    // Along z only: x, y on nodes (pure primaries and secondaries of varying brightness).
    let mut z_only = Vec::new();
    for i in 1..1000 {
        let z = i as f32 / 1000.0;
        z_only.extend([
            [z, 0.0, 0.0],
            [0.0, z, 0.0],
            [0.0, 0.0, z],
            [z, z, 0.0],
            [0.0, z, z],
            [z, 0.0, z],
        ]);
    }
    report("primaries/secondaries (z)", t, cm, &z_only);
    // Along x only at z = 1 (on a node).
    let mut x_only = Vec::new();
    for i in 0..1000 {
        let x = i as f32 / 1000.0;
        x_only.extend([[1.0, x, 0.0], [x, 1.0, 0.0], [0.0, x, 1.0], [1.0, x, 0.5]]);
    }
    report("z = 1, x varying", t, cm, &x_only);
    let mut white = Vec::new();
    for i in 0..=1000 {
        let v = 0.9 + 0.1 * i as f32 / 1000.0;
        white.extend([
            [v, 1.0, 1.0],
            [1.0, v, 1.0],
            [1.0, 1.0, v],
            [v, v, 1.0],
            [0.95, v, 1.0],
        ]);
    }
    report("near white", t, cm, &white);
}
