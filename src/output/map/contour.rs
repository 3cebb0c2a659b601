//! Isolines of a grid of values: "nice" levels (1, 2 or 5 × 10ᵏ steps, as plotting programs
//! and DIALux/Radiance isolux plots choose them) and marching squares (Lorensen & Cline 1987
//! in 2D; Maple 2003, "Geometric design and space planning using the marching squares and
//! marching cube algorithms") with linear interpolation along cell edges and saddles resolved
//! by the cell's mean value.

/// A step of 1, 2 or 5 × 10ᵏ that splits `span` into about `count` intervals.
pub fn nice_step(span: f64, count: usize) -> f64 {
    let raw = span / count.max(1) as f64;
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let nice = if f < 1.5 {
        1.0
    } else if f < 3.0 {
        2.0
    } else if f < 7.0 {
        5.0
    } else {
        10.0
    };
    nice * mag
}

/// A colour scale [lo, hi] widened to whole steps around [min, max], with its step; it does
/// not go below 0 for non-negative data.
pub fn scale(min: f64, max: f64) -> (f64, f64, f64) {
    let (mut a, mut b) = (min, max);
    // A flat (or non-finite) range gets a symmetric pad.
    let flat = (b - a).is_nan() || b - a <= 1e-9 * a.abs().max(b.abs());
    if flat {
        let pad = (0.1 * a.abs()).max(1.0);
        a -= pad;
        b += pad;
    }
    let step = nice_step(b - a, 6);
    let lo = (a / step).floor() * step;
    let lo = if min >= 0.0 { lo.max(0.0) } else { lo };
    (lo, (b / step).ceil() * step, step)
}

/// Multiples of `step` strictly between `min` and `max`: the isoline levels.
pub fn levels(min: f64, max: f64, step: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let mut k = (min / step).floor() + 1.0;
    while k * step < max && out.len() < 64 {
        if k * step > min {
            out.push(k * step);
        }
        k += 1.0;
    }
    out
}

/// A segment of an isoline in grid coordinates (x = column, y = row of `values`).
pub type Segment = ([f64; 2], [f64; 2]);

/// Marching squares over `values` (`nx` columns × `ny` rows, row-major) at `level`.
pub fn isoline(values: &[f64], nx: usize, ny: usize, level: f64) -> Vec<Segment> {
    let mut out = Vec::new();
    for y in 0..ny.saturating_sub(1) {
        for x in 0..nx.saturating_sub(1) {
            let v = |dx: usize, dy: usize| values[(y + dy) * nx + x + dx];
            // Corners counter-clockwise from (x, y): a, b, c, d.
            let corners = [
                ([x as f64, y as f64], v(0, 0)),
                ([x as f64 + 1.0, y as f64], v(1, 0)),
                ([x as f64 + 1.0, y as f64 + 1.0], v(1, 1)),
                ([x as f64, y as f64 + 1.0], v(0, 1)),
            ];
            cell_segments(&corners, level, &mut out);
        }
    }
    out
}

/// The isoline pieces in one cell; edge k joins corner k and corner k+1.
fn cell_segments(corners: &[([f64; 2], f64); 4], level: f64, out: &mut Vec<Segment>) {
    let above = |v: f64| v >= level;
    let crossing = |k: usize| {
        let ((p0, v0), (p1, v1)) = (corners[k], corners[(k + 1) % 4]);
        if above(v0) == above(v1) {
            return None;
        }
        let t = (level - v0) / (v1 - v0);
        Some([p0[0] + t * (p1[0] - p0[0]), p0[1] + t * (p1[1] - p0[1])])
    };
    let edges: Vec<(usize, [f64; 2])> =
        (0..4).filter_map(|k| crossing(k).map(|p| (k, p))).collect();
    match edges.len() {
        2 => out.push((edges[0].1, edges[1].1)),
        4 => {
            // A saddle: cut off the two corners on the other side of the cell's mean.
            let centre = corners.iter().map(|c| c.1).sum::<f64>() / 4.0;
            for k in 0..4 {
                if above(corners[k].1) != above(centre) {
                    let before = edges[(k + 3) % 4].1;
                    out.push((before, edges[k].1));
                }
            }
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_steps_and_levels() {
        assert_eq!(nice_step(600.0, 6), 100.0);
        assert_eq!(nice_step(13.0, 6), 2.0);
        assert_eq!(nice_step(0.27, 6), 0.05);
        let (lo, hi, step) = scale(123.0, 487.0);
        assert_eq!((lo, hi, step), (100.0, 500.0, 50.0));
        assert_eq!(levels(123.0, 487.0, 100.0), [200.0, 300.0, 400.0]);
        assert_eq!(scale(0.0, 0.0), (0.0, 1.0, 0.5));
    }

    #[test]
    fn a_ramp_gives_a_straight_isoline() {
        // values = x on a 4 × 3 grid: the isoline of 1.5 is the vertical line x = 1.5.
        let values: Vec<f64> = (0..12).map(|i| (i % 4) as f64).collect();
        let segs = isoline(&values, 4, 3, 1.5);
        assert_eq!(segs.len(), 2);
        for (a, b) in segs {
            assert!((a[0] - 1.5).abs() < 1e-12 && (b[0] - 1.5).abs() < 1e-12);
        }
    }

    #[test]
    fn a_peak_is_encircled() {
        // A 3 × 3 grid with a peak in the middle: the isoline is a closed diamond of 4 pieces.
        let values = [0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0];
        let segs = isoline(&values, 3, 3, 1.0);
        assert_eq!(segs.len(), 4);
        // Opposite corners high: a saddle, resolved into two pieces.
        let saddle = [1.0, 0.0, 0.0, 1.0];
        assert_eq!(isoline(&saddle, 2, 2, 0.5).len(), 2);
    }
}
