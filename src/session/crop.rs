//! A crop window: the pixels a render renders (`--crop`).
//!
//! A window is given in pixels (`x0,y0,x1,y1`, whole numbers, half-open: pixels x0..x1 of
//! rows y0..y1) or in NDC (any value with a decimal point: fractions of the image's width
//! and height, y down from the top as pbrt-v4's `--cropwindow`). NDC windows become pixels
//! as pbrt-v4's film does (`FilmBaseParameters`): [⌈W·x0⌉, ⌈W·x1⌉) × [⌈H·y0⌉, ⌈H·y1⌉), so
//! windows that share an NDC edge share no pixel and leave none out.
//!
//! USD's `dataWindowNDC` is (xmin, ymin, xmax, ymax) with y up from the bottom (NDC of
//! `UsdRenderSettingsBase`): it is the window (xmin, 1 − ymax, xmax, 1 − ymin) here
//! ([`CropSpec::from_data_window_ndc`]). A stage's window ([`stage_window`]) is the window
//! of every render of the stage that gives no `--crop`: the image is that window's, but the
//! render is not a part unless `--part` makes it one.
//!
//! A crop render renders every sample of its window's pixels, and only those: its camera
//! samples are those of the whole render for the same (seed, pixel, sample). Integrators
//! that splat (light, bdpt, vcm) keep every splat of those samples' light paths, wherever it
//! lands, so crops that tile the image partition the whole render's work and merge into it
//! bit for bit (`session::part`).

use crate::error::{Error, Reason, Result};
use crate::scene::Scene;
use crate::sensor::film::Tile;

/// The window of `scene`'s RenderSettings `dataWindowNDC` on its camera's image, when it is
/// not the whole image; an error names the prim when the window holds no whole pixel.
pub fn stage_window(scene: &Scene) -> Result<Option<Crop>> {
    let Some(w) = &scene.data_window else {
        return Ok(None);
    };
    let (width, height) = (scene.camera.width as usize, scene.camera.height as usize);
    CropSpec::from_data_window_ndc(w.ndc)
        .and_then(|spec| spec.resolve(width, height))
        .map(Some)
        .map_err(|e| Error::prim(&scene.source, &w.prim_path, format!("dataWindowNDC: {e}")))
}

/// A window as given: pixels or NDC, not yet tied to a resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CropSpec {
    Pixels([u64; 4]),
    Ndc([f64; 4]),
}

impl CropSpec {
    /// `x0,y0,x1,y1`: whole numbers are pixels; a value with a decimal point makes the
    /// window NDC.
    pub fn parse(s: &str) -> Reason<CropSpec> {
        let values: Vec<&str> = s.split(',').map(str::trim).collect();
        if values.len() != 4 {
            return Err(format!(
                "'{s}' is not x0,y0,x1,y1 (pixels, or NDC with decimal points)"
            ));
        }
        if values.iter().any(|v| v.contains(['.', 'e', 'E'])) {
            let mut w = [0.0; 4];
            for (x, v) in w.iter_mut().zip(&values) {
                *x = v
                    .parse::<f64>()
                    .ok()
                    .filter(|x| (0.0..=1.0).contains(x))
                    .ok_or_else(|| format!("'{s}': '{v}' is not an NDC value in [0, 1]"))?;
            }
            Ok(CropSpec::Ndc(w))
        } else {
            let mut w = [0; 4];
            for (x, v) in w.iter_mut().zip(&values) {
                *x = v
                    .parse::<u64>()
                    .map_err(|_| format!("'{s}': '{v}' is not a pixel index (0 or more)"))?;
            }
            Ok(CropSpec::Pixels(w))
        }
    }

    /// USD's `dataWindowNDC` (xmin, ymin, xmax, ymax, y up).
    pub fn from_data_window_ndc(w: [f64; 4]) -> Reason<CropSpec> {
        if !w.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)) {
            return Err(format!("dataWindowNDC {w:?} is not within [0, 1]"));
        }
        Ok(CropSpec::Ndc([w[0], 1.0 - w[3], w[2], 1.0 - w[1]]))
    }

    /// The window's pixels on a `width` × `height` image; an empty window or one outside
    /// the image is refused.
    pub fn resolve(&self, width: usize, height: usize) -> Reason<Crop> {
        let [x0, y0, x1, y1] = match *self {
            CropSpec::Pixels(p) => p.map(|v| usize::try_from(v).unwrap_or(usize::MAX)),
            CropSpec::Ndc([a, b, c, d]) => {
                let px = |v: f64, n: usize| (v * n as f64).ceil() as usize;
                [px(a, width), px(b, height), px(c, width), px(d, height)]
            }
        };
        if x0 >= x1 || y0 >= y1 || x1 > width || y1 > height {
            return Err(format!(
                "the window {x0},{y0},{x1},{y1} (pixels) is empty or not within the \
                 {width}×{height} image"
            ));
        }
        Ok(Crop { x0, y0, x1, y1 })
    }
}

/// A window of pixels: columns x0..x1 of rows y0..y1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crop {
    pub x0: usize,
    pub y0: usize,
    pub x1: usize,
    pub y1: usize,
}

impl Crop {
    pub fn width(&self) -> usize {
        self.x1 - self.x0
    }

    pub fn height(&self) -> usize {
        self.y1 - self.y0
    }

    pub fn pixel_count(&self) -> usize {
        self.width() * self.height()
    }

    /// `x0,y0,x1,y1` (what `parse` reads back).
    pub fn label(&self) -> String {
        format!("{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }

    /// The window of a label.
    pub fn from_label(s: &str) -> Option<Crop> {
        match CropSpec::parse(s).ok()? {
            CropSpec::Pixels(p) => {
                let [x0, y0, x1, y1] = p.map(|v| v as usize);
                (x0 < x1 && y0 < y1).then_some(Crop { x0, y0, x1, y1 })
            }
            CropSpec::Ndc(_) => None,
        }
    }

    /// The whole image's window.
    pub fn whole(width: usize, height: usize) -> Crop {
        Crop {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    /// The tiles clipped to the window (tiles outside it left out, in their order).
    pub fn clip(&self, tiles: &[Tile]) -> Vec<Tile> {
        tiles
            .iter()
            .map(|t| Tile {
                x0: t.x0.max(self.x0),
                y0: t.y0.max(self.y0),
                x1: t.x1.min(self.x1),
                y1: t.y1.min(self.y1),
            })
            .filter(|t| t.x0 < t.x1 && t.y0 < t.y1)
            .collect()
    }

    /// The window's rows of a row-major image `width` pixels wide.
    pub fn cut<T: Copy>(&self, image: &[T], width: usize) -> Vec<T> {
        (self.y0..self.y1)
            .flat_map(|y| &image[y * width + self.x0..y * width + self.x1])
            .copied()
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ndc_windows_that_share_an_edge_tile_the_image() {
        // Thirds of 10 pixels: ⌈10/3⌉ = 4, ⌈20/3⌉ = 7.
        let cuts = [0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0];
        let mut next = 0;
        for w in cuts.windows(2) {
            let c = CropSpec::Ndc([w[0], 0.0, w[1], 1.0])
                .resolve(10, 5)
                .unwrap();
            assert_eq!(c.x0, next);
            next = c.x1;
        }
        assert_eq!(next, 10);
        assert_eq!(
            CropSpec::parse("0.5,0,1.0,0.25").unwrap().resolve(8, 8),
            Ok(Crop {
                x0: 4,
                y0: 0,
                x1: 8,
                y1: 2
            })
        );
    }

    #[test]
    fn pixel_windows_are_checked_against_the_image() {
        let c = CropSpec::parse("2,1,5,3").unwrap().resolve(8, 4).unwrap();
        assert_eq!((c.width(), c.height(), c.label()), (3, 2, "2,1,5,3".into()));
        assert_eq!(Crop::from_label(&c.label()), Some(c));
        for bad in [
            "2,1,9,3",
            "3,1,3,2",
            "0,0,1",
            "a,0,1,1",
            "-1,0,1,1",
            "0,0,1.5,1",
        ] {
            let r = CropSpec::parse(bad).and_then(|s| s.resolve(8, 4));
            assert!(r.is_err(), "{bad}");
        }
    }

    #[test]
    fn usd_data_window_has_y_up() {
        let s = CropSpec::from_data_window_ndc([0.0, 0.75, 0.5, 1.0]).unwrap();
        assert_eq!(s.resolve(4, 4).unwrap(), Crop::whole(2, 1));
        let t = Tile {
            x0: 0,
            y0: 0,
            x1: 16,
            y1: 16,
        };
        assert_eq!(Crop::whole(2, 1).clip(&[t]).len(), 1);
        assert_eq!(Crop::whole(2, 1).cut(&[1, 2, 3, 4, 5, 6], 3), vec![1, 2]);
    }
}
