//! OpenColorIO display transforms for the PNG preview: the only module naming the `ocio` crate
//! (a pure-Rust port of OpenColorIO 2.5; `tests/ocio.rs` measures it against PyOpenColorIO
//! on every display/view pair of the shipped config).
//!
//! The config is `--ocio CONFIG`, else the file `$OCIO` names, else the ACES CG config
//! (ACES 2.0) shipped in `assets/ocio/` and embedded in the binary. The display and view are
//! `--display` / `--view`, else the config's defaults (for the shipped config: `sRGB -
//! Display`, `ACES 2.0 - SDR 100 nits (Rec.709)`). The input is the EXR's working space,
//! looked up by its OCIO name (`WorkingSpace::ocio_name`) among the config's colour spaces
//! and aliases.

use std::path::Path;

use crate::error::{Error, Result};

/// The name of the shipped config (OpenColorIO's built-in `ocio://` name).
pub const DEFAULT_CONFIG_NAME: &str = "cg-config-v4.0.0_aces-v2.0_ocio-v2.5";

/// The shipped config's text (see `assets/ocio/README.md` for its source and licence).
const DEFAULT_CONFIG: &str =
    include_str!("../../assets/ocio/cg-config-v4.0.0_aces-v2.0_ocio-v2.5.ocio");

/// The largest config file read (the shipped one is 33 kB); a larger one is refused.
const MAX_CONFIG_BYTES: u64 = 16 << 20;

/// An OCIO config and where it came from.
pub struct OcioConfig {
    config: ocio::Config,
    /// The file, or the shipped config's name, for messages.
    pub source: String,
}

/// A display transform chosen from a config: one processor, applied on the CPU.
pub struct DisplayTransform {
    cpu: ocio::CpuProcessor,
    pub input: String,
    pub display: String,
    pub view: String,
}

impl OcioConfig {
    /// The shipped ACES CG config.
    pub fn shipped() -> OcioConfig {
        let config = ocio::Config::create_from_str(DEFAULT_CONFIG)
            .expect("the shipped OCIO config parses (tested)");
        OcioConfig {
            config,
            source: DEFAULT_CONFIG_NAME.into(),
        }
    }

    /// The config in `path` (an `.ocio` file).
    pub fn from_file(path: &Path) -> Result<OcioConfig> {
        let fail = |reason: String| Error::io(path, format!("OCIO config: {reason}"));
        let meta = std::fs::metadata(path).map_err(|e| fail(e.to_string()))?;
        if !meta.is_file() {
            return Err(fail("not a regular file".into()));
        }
        if meta.len() > MAX_CONFIG_BYTES {
            return Err(fail(format!(
                "{} bytes is larger than the {MAX_CONFIG_BYTES} accepted",
                meta.len()
            )));
        }
        let name = path
            .to_str()
            .ok_or_else(|| fail("the path is not UTF-8".into()))?;
        let config = ocio::Config::create_from_file(name).map_err(|e| fail(one_line(e)))?;
        Ok(OcioConfig {
            config,
            source: path.display().to_string(),
        })
    }

    /// `flag` (`--ocio`), else `$OCIO` when set and not empty, else the shipped config.
    pub fn select(flag: Option<&Path>, env: Option<&std::ffi::OsStr>) -> Result<OcioConfig> {
        match (flag, env.filter(|v| !v.is_empty())) {
            (Some(path), _) => OcioConfig::from_file(path),
            (None, Some(var)) => OcioConfig::from_file(Path::new(var)),
            (None, None) => Ok(OcioConfig::shipped()),
        }
    }

    /// The config's displays, in its order.
    pub fn displays(&self) -> Vec<String> {
        (0..self.config.num_displays())
            .map(|i| self.config.display(i))
            .collect()
    }

    /// The views of `display`, in the config's order.
    pub fn views(&self, display: &str) -> Vec<String> {
        (0..self.config.num_views(display))
            .map(|i| self.config.view(display, i))
            .collect()
    }

    /// The transform from colour space `input` to (`display`, `view`), each defaulting to the
    /// config's; an unknown name is an option error listing the choices.
    pub fn display_transform(
        &self,
        input: &str,
        display: Option<&str>,
        view: Option<&str>,
    ) -> Result<DisplayTransform> {
        let displays = self.displays();
        let display = match display {
            Some(d) => d.to_string(),
            None => self.config.default_display(),
        };
        if !displays.contains(&display) {
            return Err(Error::option(format!(
                "--display: '{display}' is not a display of {} (displays: {})",
                self.source,
                displays.join(", ")
            )));
        }
        let views = self.views(&display);
        let view = match view {
            Some(v) => v.to_string(),
            None => self.config.default_view(&display),
        };
        if !views.contains(&view) {
            return Err(Error::option(format!(
                "--view: '{view}' is not a view of '{display}' in {} (views: {})",
                self.source,
                views.join(", ")
            )));
        }
        if self.config.get_color_space(input).is_none() {
            return Err(Error::option(format!(
                "--colorspace: {} has no colour space '{input}' for the preview's input",
                self.source
            )));
        }
        let processor = self
            .config
            .get_display_view_processor(input, &display, &view)
            .map_err(|e| {
                Error::option(format!(
                    "--view: {}: '{display}' / '{view}': {}",
                    self.source,
                    one_line(e)
                ))
            })?;
        Ok(DisplayTransform {
            cpu: processor.default_cpu_processor(),
            input: input.into(),
            display,
            view,
        })
    }
}

impl DisplayTransform {
    /// Applies the transform to every pixel in place (scene-linear in, code values out).
    pub fn apply(&self, rgb: &mut [[f32; 3]]) {
        for pixel in rgb {
            self.cpu.apply_rgb(pixel);
        }
    }
}

/// An OCIO error's message on one line.
fn one_line(e: impl std::fmt::Display) -> String {
    e.to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_config_has_the_aces_2_default_view() {
        let config = OcioConfig::shipped();
        let t = config.display_transform("ACEScg", None, None).unwrap();
        assert_eq!(t.display, "sRGB - Display");
        assert_eq!(t.view, "ACES 2.0 - SDR 100 nits (Rec.709)");
        // Every working space's OCIO name is in the shipped config.
        for space in crate::spectral::working_space::WorkingSpace::ALL {
            assert!(
                config.config.get_color_space(space.ocio_name()).is_some(),
                "{space:?}"
            );
        }
    }

    #[test]
    fn unknown_names_are_one_line_errors_with_the_choices() {
        let config = OcioConfig::shipped();
        let e = config
            .display_transform("ACEScg", Some("CRT"), None)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("sRGB - Display") && !e.contains('\n'), "{e}");
        let e = config
            .display_transform("ACEScg", None, Some("Filmic"))
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("Un-tone-mapped") && !e.contains('\n'), "{e}");
        let e = config
            .display_transform("lin_nowhere", None, None)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("lin_nowhere"), "{e}");
    }

    #[test]
    fn raw_view_passes_values_through() {
        let config = OcioConfig::shipped();
        let t = config
            .display_transform("Linear Rec.709 (sRGB)", Some("sRGB - Display"), Some("Raw"))
            .unwrap();
        let mut px = [[0.25f32, 0.5, 2.0]];
        t.apply(&mut px);
        assert_eq!(px, [[0.25, 0.5, 2.0]]);
    }

    #[test]
    fn bad_config_files_are_errors_naming_the_file() {
        let dir = std::env::temp_dir().join(format!("spectral-render-ocio-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bad.ocio");
        std::fs::write(&path, "ocio_profile_version: 2\n\tnot: [yaml").unwrap();
        let e = OcioConfig::from_file(&path).err().unwrap().to_string();
        assert!(e.contains("bad.ocio") && !e.contains('\n'), "{e}");
        let e = OcioConfig::from_file(&dir).err().unwrap().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
