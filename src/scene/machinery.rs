//! Machinery the scene builder leaves out when the scene does not need it, decided once at
//! build rather than tested per sample — and the switch that forces each piece back on, for
//! the tests and the benchmark (`tools/bench_pruning.sh`) that show it changes only time:
//!
//! | piece | left out when | forced on, the image is |
//! |---|---|---|
//! | UsdPreviewSurface lobes | their weight is exactly 0 (`material::preview::PreviewLobes`) | the same up to float round-off |
//! | the light-selection table | the scene has one light (`light::LightSampler::Single`) | bit-identical |
//! | the per-vertex dispersion check | no material is dispersive (`Scene::dispersive`) | bit-identical |

/// Which pieces of machinery to keep even where the scene does not need them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Machinery {
    /// Every lobe of every UsdPreviewSurface.
    pub all_lobes: bool,
    /// A light-selection table for a single light.
    pub light_table: bool,
    /// The dispersion check at every vertex without a dispersive material.
    pub dispersion_checks: bool,
}

impl Machinery {
    /// Everything forced on.
    pub const ALL: Machinery = Machinery {
        all_lobes: true,
        light_table: true,
        dispersion_checks: true,
    };

    /// The names [`Machinery::parse`] takes.
    pub const NAMES: [&'static str; 4] = ["all", "lobes", "light-table", "dispersion"];

    /// A comma-separated list of [`Machinery::NAMES`].
    pub fn parse(list: &str) -> Result<Machinery, String> {
        let mut m = Machinery::default();
        for name in list.split(',').map(str::trim) {
            match name {
                "all" => m = Machinery::ALL,
                "lobes" => m.all_lobes = true,
                "light-table" => m.light_table = true,
                "dispersion" => m.dispersion_checks = true,
                _ => {
                    return Err(format!(
                        "unknown machinery '{name}' (available: {})",
                        Machinery::NAMES.join(", ")
                    ))
                }
            }
        }
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse() {
        assert_eq!(Machinery::parse("all"), Ok(Machinery::ALL));
        let m = Machinery::parse("lobes, dispersion").unwrap();
        assert!(m.all_lobes && m.dispersion_checks && !m.light_table);
        assert!(Machinery::parse("bvh").unwrap_err().contains("light-table"));
    }
}
