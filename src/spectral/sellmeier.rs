//! Dispersive index of refraction from the Sellmeier equation.
//!
//! W. Sellmeier, "Zur Erklärung der abnormen Farbenfolge im Spectrum einiger Substanzen",
//! Annalen der Physik und Chemie 219 (1871) 272–282, in the three-term form used by glass
//! catalogues (SCHOTT Technical Information TIE-29, "Refractive Index and Dispersion"):
//!
//! ```text
//! n²(λ) = 1 + Σᵢ Bᵢ λ² / (λ² − Cᵢ),   λ in µm, Cᵢ in µm²
//! ```
//!
//! Coefficients for named glasses live in `spectra/glass/` (see [`super::data::glass`]).

/// Three-term Sellmeier coefficients: `b` dimensionless, `c` in µm².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sellmeier {
    pub b: [f32; 3],
    pub c: [f32; 3],
}

impl Sellmeier {
    /// A non-dispersive medium of index `n` (B = (n² − 1, 0, 0), C = 0).
    pub fn constant(n: f32) -> Sellmeier {
        Sellmeier {
            b: [n * n - 1.0, 0.0, 0.0],
            c: [0.0; 3],
        }
    }

    /// The index of refraction at `lambda_nm` (nm).
    #[inline]
    pub fn ior(&self, lambda_nm: f32) -> f32 {
        let l2 = {
            let l = lambda_nm * 1e-3;
            l * l
        };
        let mut n2 = 1.0;
        for i in 0..3 {
            if self.b[i] != 0.0 {
                n2 += self.b[i] * l2 / (l2 - self.c[i]);
            }
        }
        n2.max(0.0).sqrt()
    }

    /// Whether the index varies with wavelength: any term with both Bᵢ ≠ 0 and Cᵢ ≠ 0
    /// (a term with Cᵢ = 0 only adds the constant Bᵢ to n²).
    pub fn is_dispersive(&self) -> bool {
        self.b
            .iter()
            .zip(&self.c)
            .any(|(&b, &c)| b != 0.0 && c != 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_medium_is_not_dispersive() {
        let s = Sellmeier::constant(1.5);
        assert!(!s.is_dispersive());
        assert!((s.ior(400.0) - 1.5).abs() < 1e-6);
        assert!((s.ior(800.0) - 1.5).abs() < 1e-6);
        assert_eq!(Sellmeier::constant(1.0).ior(500.0), 1.0);
    }

    #[test]
    fn schott_n_bk7_matches_the_datasheet() {
        // SCHOTT N-BK7 datasheet: n_d (587.5618 nm) = 1.51680, n_F (486.1327) = 1.52238,
        // n_C (656.2725) = 1.51432.
        let bk7 = Sellmeier {
            b: [1.039_612_12, 0.231_792_344, 1.010_469_45].map(|v: f64| v as f32),
            c: [0.006_000_698_67, 0.020_017_914_4, 103.560_653].map(|v: f64| v as f32),
        };
        assert!(bk7.is_dispersive());
        for (l, n) in [
            (587.5618, 1.51680),
            (486.1327, 1.52238),
            (656.2725, 1.51432),
        ] {
            assert!((bk7.ior(l) - n).abs() < 2e-5, "n({l}) = {}", bk7.ior(l));
        }
        assert!(bk7.ior(400.0) > bk7.ior(700.0));
    }
}
