//! What a configuration's curve says: the fitted slope of log error against log time, the
//! measured time to reach each target error, and the efficiency against the best.
//!
//! - **Slope**: ordinary least squares of ln(error) on ln(time) over the snapshots of the last
//!   two decades of time ([`FIT_DECADES`]) with at least 2 samples, where start-up costs no
//!   longer bend the curve. An unbiased Monte Carlo estimator's RMSE falls as t^(−1/2); a
//!   consistent one (VCM) falls more slowly while its bias shrinks.
//! - **Time to a target**: the measured time of the earliest snapshot after which every
//!   snapshot's error stays at or below the target — never interpolated or extrapolated, so a
//!   target not reached within the budget has no time. (For a single meter reading, whose
//!   error crosses a target by luck now and then, "stays" is what makes the time robust.)
//! - **Efficiency**: 1 / (error² × time) at the last snapshot (constant along a −1/2 slope),
//!   and its ratio to the best configuration's.

use super::Row;
use serde::Serialize;

/// The target errors of the report (10 %, 5 %, 2 %, 1 %).
pub const TARGETS: [f64; 4] = [0.10, 0.05, 0.02, 0.01];

/// Decades of time, back from the last snapshot, that the slope is fitted over.
pub const FIT_DECADES: f64 = 2.0;

/// A least-squares line through (ln x, ln y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fit {
    pub slope: f64,
    /// Standard error of the slope (from the residuals; 0 with two points).
    pub stderr: f64,
    /// ln y at ln x = 0.
    pub intercept: f64,
    pub points: usize,
}

/// The least-squares fit of ln y on ln x over the points with x > 0 and y > 0 (at least two
/// distinct x needed).
pub fn log_log_fit(points: &[(f64, f64)]) -> Option<Fit> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return None;
    }
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let rss: f64 = pts
        .iter()
        .map(|p| (p.1 - intercept - slope * p.0).powi(2))
        .sum();
    let stderr = if pts.len() > 2 {
        (rss / (n - 2.0) / sxx).sqrt()
    } else {
        0.0
    };
    Some(Fit {
        slope,
        stderr,
        intercept,
        points: pts.len(),
    })
}

/// One snapshot as the fits see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    pub samples: u64,
    pub time_s: f64,
    pub error: f64,
}

/// The slope of error against time over the last [`FIT_DECADES`] decades (see the module
/// docs); `points` in snapshot order.
pub fn time_slope(points: &[Point]) -> Option<Fit> {
    let t_last = points.iter().map(|p| p.time_s).fold(0.0, f64::max);
    let from = t_last * 10f64.powf(-FIT_DECADES);
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.samples >= 2 && p.time_s >= from)
        .map(|p| (p.time_s, p.error))
        .collect();
    log_log_fit(&pts)
}

/// The measured time from which on the error stays at or below `target`; None when the last
/// snapshot is above it. `points` in snapshot order.
pub fn time_to(points: &[Point], target: f64) -> Option<f64> {
    let mut since = None;
    for p in points {
        if p.error <= target {
            since.get_or_insert(p.time_s);
        } else {
            since = None;
        }
    }
    since
}

/// 1 / (error² × time) at the last snapshot; None without a positive error and time.
pub fn efficiency(points: &[Point]) -> Option<f64> {
    let last = points.last()?;
    (last.error > 0.0 && last.time_s > 0.0).then(|| 1.0 / (last.error.powi(2) * last.time_s))
}

/// What one configuration's rows say (one per configuration, source and meter).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    pub config: String,
    pub source: String,
    pub meter: Option<usize>,
    /// The last snapshot's samples, time and error.
    pub samples: u64,
    pub time_s: f64,
    pub error: f64,
    /// Samples (per pixel or per reading) per second of integrator time, at the last snapshot.
    pub samples_per_s: f64,
    /// Fitted slope of ln error on ln time, with its standard error.
    pub slope: Option<f64>,
    pub slope_stderr: Option<f64>,
    /// Measured time to each of [`TARGETS`] (None: not reached).
    pub time_to: Vec<Option<f64>>,
    pub efficiency: Option<f64>,
    /// Efficiency over the best configuration's of the same image or meter (1 for the best).
    pub efficiency_ratio: Option<f64>,
    /// The last snapshot's remaining bias estimate and its 95 % upper bound (images with a
    /// known reference noise).
    pub bias: Option<f64>,
    pub bias_bound: Option<f64>,
}

/// The rows of each configuration (config, source, meter), in order of first appearance.
pub fn groups(rows: &[Row]) -> Vec<Vec<&Row>> {
    let mut out: Vec<Vec<&Row>> = Vec::new();
    for r in rows {
        let key = |x: &Row| (x.config.clone(), x.source.clone(), x.meter);
        match out.iter_mut().find(|g| key(g[0]) == key(r)) {
            Some(g) => g.push(r),
            None => out.push(vec![r]),
        }
    }
    out
}

/// The points of a group that have an error, in snapshot order.
pub fn points(group: &[&Row]) -> Vec<Point> {
    group
        .iter()
        .filter_map(|r| {
            r.error.map(|error| Point {
                samples: r.samples,
                time_s: r.time_s,
                error,
            })
        })
        .collect()
}

/// A summary per configuration; efficiency ratios against the best among them.
pub fn summarize(rows: &[Row]) -> Vec<Summary> {
    let mut out: Vec<Summary> = groups(rows)
        .iter()
        .filter_map(|g| {
            let pts = points(g);
            let last = pts.last()?;
            let fit = time_slope(&pts);
            Some(Summary {
                config: g[0].config.clone(),
                source: g[0].source.clone(),
                meter: g[0].meter,
                samples: last.samples,
                time_s: last.time_s,
                error: last.error,
                samples_per_s: last.samples as f64 / last.time_s.max(1e-12),
                slope: fit.map(|f| f.slope),
                slope_stderr: fit.map(|f| f.stderr),
                time_to: TARGETS.iter().map(|&t| time_to(&pts, t)).collect(),
                efficiency: efficiency(&pts),
                efficiency_ratio: None,
                bias: g.last().and_then(|r| r.bias_masked),
                bias_bound: g.last().and_then(|r| r.bias_masked_bound),
            })
        })
        .collect();
    // The best of the same quantity: the image, or the same meter.
    let best = |meter: Option<usize>, out: &[Summary]| {
        out.iter()
            .filter(|s| s.meter == meter)
            .filter_map(|s| s.efficiency)
            .fold(0.0, f64::max)
    };
    for i in 0..out.len() {
        let b = best(out[i].meter, &out);
        out[i].efficiency_ratio = out[i].efficiency.filter(|_| b > 0.0).map(|e| e / b);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_of_an_exact_power_law() {
        let pts: Vec<(f64, f64)> = (1..20)
            .map(|i| (i as f64, 3.0 * (i as f64).powf(-0.5)))
            .collect();
        let f = log_log_fit(&pts).unwrap();
        assert!((f.slope + 0.5).abs() < 1e-12 && f.stderr < 1e-12);
        assert!((f.intercept - 3f64.ln()).abs() < 1e-12);
        assert_eq!(log_log_fit(&[(1.0, 1.0)]), None);
        assert_eq!(log_log_fit(&[(1.0, 1.0), (1.0, 2.0)]), None);
    }

    #[test]
    fn time_to_a_target_is_the_time_it_stays_below() {
        let p = |t: f64, e: f64| Point {
            samples: 4,
            time_s: t,
            error: e,
        };
        let pts = [
            p(1.0, 0.2),
            p(2.0, 0.04),
            p(3.0, 0.06),
            p(4.0, 0.045),
            p(5.0, 0.03),
        ];
        assert_eq!(time_to(&pts, 0.05), Some(4.0));
        assert_eq!(time_to(&pts, 0.1), Some(2.0));
        assert_eq!(time_to(&pts, 0.01), None);
        assert_eq!(efficiency(&pts), Some(1.0 / (0.03f64.powi(2) * 5.0)));
    }

    #[test]
    fn the_slope_ignores_early_snapshots() {
        // Start-up costs before 0.05 s: the first points are off the line.
        let mut pts = vec![Point {
            samples: 1,
            time_s: 0.001,
            error: 5.0,
        }];
        pts.extend((0..30).map(|k| {
            let t = 0.01 * 10f64.powf(k as f64 / 10.0);
            Point {
                samples: 2 + k,
                time_s: t,
                error: 0.3 * t.powf(-0.5),
            }
        }));
        let f = time_slope(&pts).unwrap();
        assert!((f.slope + 0.5).abs() < 1e-9, "{f:?}");
    }
}
