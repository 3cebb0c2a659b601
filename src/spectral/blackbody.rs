//! Planck's law. Constants: CODATA 2018 exact SI values (h, c, k_B).

/// Spectral radiance of a blackbody at `lambda_nm` and `kelvin`, in W·m⁻²·sr⁻¹·nm⁻¹:
/// L = 2hc² / (λ⁵ (exp(hc/(λ k T)) − 1)) (Planck 1901; PBR 4ed §4.4.1 eq. 4.17).
pub fn planck(lambda_nm: f32, kelvin: f32) -> f32 {
    planck_f64(lambda_nm as f64, kelvin as f64) as f32
}

/// [`planck`] in double precision (for tables such as the Planckian locus).
pub fn planck_f64(lambda_nm: f64, kelvin: f64) -> f64 {
    if kelvin <= 0.0 {
        return 0.0;
    }
    const H: f64 = 6.626_070_15e-34;
    const C: f64 = 299_792_458.0;
    const KB: f64 = 1.380_649e-23;
    let l = lambda_nm * 1e-9;
    let le = 2.0 * H * C * C / (l.powi(5) * (H * C / (l * KB * kelvin)).exp_m1());
    le * 1e-9
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_follows_wien() {
        // Wien's displacement constant b = 2.897771955e-3 m·K (CODATA 2018).
        let t = 5000.0;
        let peak = 2.897_771_955e-3 / t * 1e9;
        assert!(planck(peak as f32, t as f32) > planck(peak as f32 - 5.0, t as f32));
        assert!(planck(peak as f32, t as f32) > planck(peak as f32 + 5.0, t as f32));
    }

    #[test]
    fn matches_a_reference_value() {
        // 2hc²/λ⁵/(exp(hc/λkT)-1) at 500 nm and 6500 K, evaluated in f64 Python: 4.60972e13 W/m³/sr.
        let v = planck(500.0, 6500.0) as f64 * 1e9;
        assert!((v / 4.60972e13 - 1.0).abs() < 1e-4, "{v}");
    }
}
