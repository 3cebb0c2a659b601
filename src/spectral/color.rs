//! Linear Rec.709 (sRGB primaries, D65 white) ⇄ CIE XYZ.
//!
//! The matrices are derived from the Rec.709 primaries (ITU-R BT.709-6) and the white point
//! *of our own D65 table integrated against our own CIE 1931 tables*, not from the rounded
//! (0.3127, 0.3290). So D65 white of luminance Y maps to RGB (Y, Y, Y) exactly, and
//! the reflectance round trip of docs/design.md §2 is not spoiled by a 1e-4 white-point mismatch
//! (the method of SMPTE RP 177-1993).

use super::{data, xyz};
use glam::{DMat3, DVec3};
use std::sync::OnceLock;

/// Rec.709 primaries' xy chromaticities (ITU-R BT.709-6, item 1.3).
const PRIMARIES: [[f64; 2]; 3] = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];

struct Matrices {
    rgb_to_xyz: DMat3,
    xyz_to_rgb: DMat3,
}

fn matrices() -> &'static Matrices {
    static M: OnceLock<Matrices> = OnceLock::new();
    M.get_or_init(|| {
        let w = xyz::dense_to_xyz(data::illuminant("CIE-D65").expect("D65 is embedded"));
        let white = DVec3::new(w[0] / w[1], 1.0, w[2] / w[1]);
        let col = |p: [f64; 2]| DVec3::new(p[0] / p[1], 1.0, (1.0 - p[0] - p[1]) / p[1]);
        let p = DMat3::from_cols(col(PRIMARIES[0]), col(PRIMARIES[1]), col(PRIMARIES[2]));
        let s = p.inverse() * white;
        let rgb_to_xyz = DMat3::from_cols(p.x_axis * s.x, p.y_axis * s.y, p.z_axis * s.z);
        Matrices {
            rgb_to_xyz,
            xyz_to_rgb: rgb_to_xyz.inverse(),
        }
    })
}

/// XYZ → linear Rec.709 RGB.
pub fn xyz_to_rgb(xyz: [f64; 3]) -> [f64; 3] {
    (matrices().xyz_to_rgb * DVec3::from(xyz)).into()
}

/// Linear Rec.709 RGB → XYZ.
pub fn rgb_to_xyz(rgb: [f64; 3]) -> [f64; 3] {
    (matrices().rgb_to_xyz * DVec3::from(rgb)).into()
}

/// The xy chromaticity of the white point used (our D65).
pub fn white_xy() -> [f64; 2] {
    let w = rgb_to_xyz([1.0, 1.0, 1.0]);
    let s = w[0] + w[1] + w[2];
    [w[0] / s, w[1] / s]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_maps_to_equal_rgb() {
        let w = xyz::dense_to_xyz(data::illuminant("CIE-D65").unwrap());
        let rgb = xyz_to_rgb(w.map(|c| c / w[1]));
        for c in rgb {
            assert!((c - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn close_to_the_standard_matrix() {
        // IEC 61966-2-1 sRGB: Y row = 0.2126, 0.7152, 0.0722.
        let y = [
            rgb_to_xyz([1.0, 0.0, 0.0])[1],
            rgb_to_xyz([0.0, 1.0, 0.0])[1],
            rgb_to_xyz([0.0, 0.0, 1.0])[1],
        ];
        for (a, b) in y.iter().zip([0.2126, 0.7152, 0.0722]) {
            assert!((a - b).abs() < 1e-3, "{y:?}");
        }
        let xy = white_xy();
        assert!(
            (xy[0] - 0.3127).abs() < 2e-4 && (xy[1] - 0.3290).abs() < 2e-4,
            "{xy:?}"
        );
    }
}
