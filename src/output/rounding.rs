//! Figures rounded to their confidence, for people (`546 ± 3 lx`, not `546.1083122715354`):
//! the 95 % half-width keeps one significant digit, two when that digit is 1 (the rule of the
//! Particle Data Group's Review, "Introduction: rounding", and of ISO/IEC Guide 98-3 §7.2.6,
//! which allows two), and the value is rounded to the same decimal place. JSON and CSV keep
//! every digit.

/// `value ± ci95` with both rounded to the confidence's place. A zero or non-finite
/// confidence leaves the value at six significant digits and no ±.
pub fn with_confidence(value: f64, ci95: f64) -> String {
    if !(ci95.is_finite() && ci95 > 0.0 && value.is_finite()) {
        return significant(value, 6);
    }
    let exponent = ci95.log10().floor() as i32;
    let leading = (ci95 / 10f64.powi(exponent)).floor();
    // One significant digit, two when it is a 1 (so 0.14 stays 0.14, not 0.1).
    let place = if leading < 2.0 {
        exponent - 1
    } else {
        exponent
    };
    let decimals = (-place).max(0) as usize;
    format!(
        "{:.decimals$} ± {:.decimals$}",
        round_to(value, place),
        round_to(ci95, place)
    )
}

/// `v` rounded to a multiple of 10^place.
fn round_to(v: f64, place: i32) -> f64 {
    let unit = 10f64.powi(place);
    (v / unit).round() * unit
}

/// `v` with `digits` significant digits, without exponent within 1e-6..1e9.
pub fn significant(v: f64, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let magnitude = v.abs().log10().floor() as i32;
    if !(-6..9).contains(&magnitude) {
        return format!("{v:.*e}", (digits - 1).max(0) as usize);
    }
    let decimals = (digits - 1 - magnitude).max(0) as usize;
    format!("{v:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounds_to_the_confidence() {
        assert_eq!(with_confidence(546.1083122715354, 3.2), "546 ± 3");
        assert_eq!(with_confidence(546.1083122715354, 1.4), "546.1 ± 1.4");
        assert_eq!(with_confidence(0.012345, 0.00061), "0.0123 ± 0.0006");
        assert_eq!(with_confidence(12345.6, 870.0), "12300 ± 900");
        assert_eq!(with_confidence(2.71, 0.96), "2.7 ± 1.0");
        assert_eq!(with_confidence(2.5, 0.0), "2.50000");
        assert_eq!(with_confidence(2.5, f64::NAN), "2.50000");
    }

    #[test]
    fn significant_digits() {
        assert_eq!(significant(546.108, 3), "546");
        assert_eq!(significant(0.000123456, 3), "0.000123");
        assert_eq!(significant(1.5e12, 3), "1.50e12");
        assert_eq!(significant(0.0, 3), "0");
    }
}
