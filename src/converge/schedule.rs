//! When snapshots are taken: at log-spaced sample counts, [`PER_DECADE`] per decade
//! (1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 15, 18, 22, 26, 32, …), so that a log-log plot has evenly
//! spaced points whatever the speed of the integrator. Counts are fixed in advance (not
//! chosen by the clock), so the snapshots of a seed are the same images on every run.

/// Snapshots per decade of samples.
pub const PER_DECADE: u32 = 12;

/// The snapshot sample counts, multiples of `unit` (1 for images; a meter's block size, so
/// that readings keep their block boundaries), increasing without end.
pub fn checkpoints(unit: u64) -> impl Iterator<Item = u64> {
    let unit = unit.max(1);
    let mut last = 0;
    (0u32..)
        .map(move |k| {
            let n = 10f64.powf(f64::from(k) / f64::from(PER_DECADE)).round() as u64;
            n.saturating_mul(unit)
        })
        .take_while(|&n| n < u64::MAX / 2)
        .filter(move |&n| {
            let new = n > last;
            last = last.max(n);
            new
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twelve_per_decade_without_repeats() {
        let c: Vec<u64> = checkpoints(1).take_while(|&n| n <= 100).collect();
        assert_eq!(
            c,
            [1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 15, 18, 22, 26, 32, 38, 46, 56, 68, 83, 100]
        );
        let per_decade = checkpoints(1)
            .filter(|&n| (1000..10_000).contains(&n))
            .count();
        assert_eq!(per_decade, 12);
        assert!(checkpoints(256).take(5).all(|n| n % 256 == 0));
    }
}
