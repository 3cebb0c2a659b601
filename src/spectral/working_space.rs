//! The RGB working spaces of the EXR's RGB layer (`--colorspace`): which primaries and white
//! the R, G, B channels use, the matrix from our absolute XYZ to them, and their names in the
//! ACES OCIO configs.
//!
//! Our XYZ is referred to our own D65 (`color::white_xy`, the D65 table integrated against
//! the CIE tables). A space with a D65 white takes that white exactly, so D65 white stays
//! (Y, Y, Y) as in `color.rs`; ACEScg's white (ACES, ~D60) is reached by the Bradford
//! chromatic adaptation, as OCIO's ACES configs and colour-science's `RGB_to_RGB` do. XYZ is
//! the identity, with OpenEXR's XYZ chromaticities (primaries (1, 0), (0, 1), (0, 0), white
//! (1/3, 1/3): ImfChromaticities.h), so a reader that builds its matrix from the header gets
//! the identity too.

use super::color;
use glam::{DMat3, DVec3};

/// An RGB working space for the EXR's RGB layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WorkingSpace {
    /// Linear Rec.709 / sRGB primaries, D65 (ITU-R BT.709-6 item 1.3).
    #[default]
    LinRec709,
    /// ACEScg: AP1 primaries, ACES white (Academy S-2014-004, SMPTE ST 2065-1 for the white).
    AcesCg,
    /// Linear P3 primaries with D65 white (SMPTE EG 432-1).
    LinP3D65,
    /// CIE 1931 XYZ itself (D65-referred, not adapted).
    Xyz,
}

/// The xy chromaticities of a space: red, green, blue primaries and the white point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chromaticities {
    pub primaries: [[f64; 2]; 3],
    pub white: [f64; 2],
}

/// The ACES white point (Academy TB-2014-004, §4.1).
const ACES_WHITE: [f64; 2] = [0.32168, 0.33767];

/// The Bradford cone-response matrix (Lam 1985; as tabulated by Lindbloom and colour-science's
/// `CAT_BRADFORD`), rows = responses of XYZ.
const BRADFORD: [[f64; 3]; 3] = [
    [0.8951, 0.2664, -0.1614],
    [-0.7502, 1.7135, 0.0367],
    [0.0389, -0.0685, 1.0296],
];

impl WorkingSpace {
    pub const ALL: [WorkingSpace; 4] = [
        WorkingSpace::LinRec709,
        WorkingSpace::AcesCg,
        WorkingSpace::LinP3D65,
        WorkingSpace::Xyz,
    ];

    /// The name `--colorspace` takes.
    pub fn name(self) -> &'static str {
        match self {
            WorkingSpace::LinRec709 => "lin_rec709",
            WorkingSpace::AcesCg => "acescg",
            WorkingSpace::LinP3D65 => "lin_p3d65",
            WorkingSpace::Xyz => "xyz",
        }
    }

    /// The space's name in the ACES CG and studio configs (v4, ACES 2.0), the EXR's
    /// `colorspace` attribute and the preview's input colour space.
    pub fn ocio_name(self) -> &'static str {
        match self {
            WorkingSpace::LinRec709 => "Linear Rec.709 (sRGB)",
            WorkingSpace::AcesCg => "ACEScg",
            WorkingSpace::LinP3D65 => "Linear P3-D65",
            WorkingSpace::Xyz => "CIE XYZ-D65 - Scene-referred",
        }
    }

    pub fn from_name(name: &str) -> Option<WorkingSpace> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The primaries and white that the `chromaticities` attribute records.
    pub fn chromaticities(self) -> Chromaticities {
        let d65 = color::white_xy();
        match self {
            WorkingSpace::LinRec709 => Chromaticities {
                primaries: [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]],
                white: d65,
            },
            WorkingSpace::AcesCg => Chromaticities {
                primaries: [[0.713, 0.293], [0.165, 0.830], [0.128, 0.044]],
                white: ACES_WHITE,
            },
            WorkingSpace::LinP3D65 => Chromaticities {
                primaries: [[0.680, 0.320], [0.265, 0.690], [0.150, 0.060]],
                white: d65,
            },
            WorkingSpace::Xyz => Chromaticities {
                primaries: [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]],
                white: [1.0 / 3.0, 1.0 / 3.0],
            },
        }
    }

    /// The matrix from our (D65-referred) XYZ to this space's RGB.
    pub fn from_xyz(self) -> DMat3 {
        match self {
            WorkingSpace::Xyz => DMat3::IDENTITY,
            _ => {
                let c = self.chromaticities();
                let to_xyz = rgb_to_xyz_matrix(c);
                to_xyz.inverse() * bradford(xy_to_xyz(color::white_xy()), xy_to_xyz(c.white))
            }
        }
    }

    /// Every pixel of `xyz` in this space, as f32.
    pub fn convert(self, xyz: &[[f32; 3]]) -> Vec<[f32; 3]> {
        let m = self.from_xyz();
        xyz.iter()
            .map(|p| {
                (m * DVec3::from(p.map(f64::from)))
                    .to_array()
                    .map(|c| c as f32)
            })
            .collect()
    }
}

/// XYZ of chromaticity `xy` at Y = 1.
fn xy_to_xyz([x, y]: [f64; 2]) -> DVec3 {
    DVec3::new(x / y, 1.0, (1.0 - x - y) / y)
}

/// RGB → XYZ for the primaries and white of `c` (SMPTE RP 177-1993 §3.3: the primaries'
/// XYZ scaled so that RGB (1, 1, 1) is the white of luminance 1).
fn rgb_to_xyz_matrix(c: Chromaticities) -> DMat3 {
    let p = DMat3::from_cols(
        xy_to_xyz(c.primaries[0]),
        xy_to_xyz(c.primaries[1]),
        xy_to_xyz(c.primaries[2]),
    );
    let s = p.inverse() * xy_to_xyz(c.white);
    DMat3::from_cols(p.x_axis * s.x, p.y_axis * s.y, p.z_axis * s.z)
}

/// The von Kries adaptation in Bradford cone space from white `from` to white `to` (XYZ).
fn bradford(from: DVec3, to: DVec3) -> DMat3 {
    let m = DMat3::from_cols_array_2d(&BRADFORD).transpose();
    let (a, b) = (m * from, m * to);
    m.inverse() * DMat3::from_diagonal(b / a) * m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rec709_is_the_renderers_matrix() {
        let m = WorkingSpace::LinRec709.from_xyz();
        for xyz in [[0.3, 0.5, 0.2], [1.0, 0.0, 0.0], [0.95, 1.0, 1.09]] {
            let ours = color::xyz_to_rgb(xyz);
            let got = m * DVec3::from(xyz);
            for c in 0..3 {
                assert!((got[c] - ours[c]).abs() < 1e-12, "{got:?} {ours:?}");
            }
        }
    }

    #[test]
    fn white_stays_white_in_every_space_but_xyz() {
        let d65 = xy_to_xyz(color::white_xy());
        for space in [
            WorkingSpace::LinRec709,
            WorkingSpace::AcesCg,
            WorkingSpace::LinP3D65,
        ] {
            let rgb = space.from_xyz() * d65;
            for c in 0..3 {
                assert!((rgb[c] - 1.0).abs() < 1e-12, "{space:?}: {rgb:?}");
            }
        }
        assert_eq!(WorkingSpace::Xyz.from_xyz(), DMat3::IDENTITY);
    }

    #[test]
    fn acescg_matches_the_published_rec709_matrix() {
        // Rec.709 → ACEScg (Bradford), as in the ACES configs' `UTILITY - ACES-AP1_to_
        // LINEAR-REC709_BFD` inverse: first row 0.61309732, 0.33952285, 0.04737928. Our D65
        // is 1e-4 off the rounded one, hence the tolerance.
        let m = WorkingSpace::AcesCg.from_xyz() * WorkingSpace::LinRec709.from_xyz().inverse();
        let row = [m.x_axis.x, m.y_axis.x, m.z_axis.x];
        for (a, b) in row.iter().zip([0.61309732, 0.33952285, 0.04737928]) {
            assert!((a - b).abs() < 5e-4, "{row:?}");
        }
    }

    #[test]
    fn names_round_trip() {
        for s in WorkingSpace::ALL {
            assert_eq!(WorkingSpace::from_name(s.name()), Some(s));
        }
        assert_eq!(WorkingSpace::from_name("srgb"), None);
    }
}
