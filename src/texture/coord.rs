//! Texture coordinates with their screen-space footprint, and where the footprint comes from.
//!
//! A [`TexCoord`] is st with its derivatives per pixel step (∂s/∂x, ∂t/∂x), (∂s/∂y, ∂t/∂y).
//! They come from ∂p/∂x, ∂p/∂y at the hit (the camera's approximation, PBR 4ed §10.1.1,
//! `Camera::approximate_dp_dxy`) and the triangle's ∂p/∂u, ∂p/∂v by least squares
//! ([`TexCoord::from_differentials`], PBR 4ed §10.1.1 eq. 10.8, pbrt-v4
//! `SurfaceInteraction::ComputeDifferentials`). A zero footprint ([`TexCoord::point`]) is the
//! finest level, bilinear.

use glam::{Affine2, Vec2, Vec3};

/// st with its derivatives along the film's x and y (one pixel step, already scaled by the
/// sample-count factor of [`TextureFilter::Camera`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TexCoord {
    pub uv: Vec2,
    pub duvdx: Vec2,
    pub duvdy: Vec2,
}

impl From<Vec2> for TexCoord {
    fn from(uv: Vec2) -> TexCoord {
        TexCoord::point(uv)
    }
}

/// pbrt-v4 clamps the st derivatives to ±1e8 (`ComputeDifferentials`).
const MAX_DERIVATIVE: f32 = 1e8;

impl TexCoord {
    /// st without a footprint: the finest level, bilinear.
    #[inline]
    pub fn point(uv: Vec2) -> TexCoord {
        TexCoord {
            uv,
            duvdx: Vec2::ZERO,
            duvdy: Vec2::ZERO,
        }
    }

    /// st at a point whose position changes by `dpdx`, `dpdy` per pixel, on a surface with
    /// tangents `dpdu`, `dpdv`: the least-squares solution of dp/dx = ∂p/∂u du/dx + ∂p/∂v dv/dx
    /// (PBR 4ed §10.1.1, eq. 10.8: (AᵀA)⁻¹ Aᵀ b with A = [∂p/∂u ∂p/∂v]). A singular AᵀA
    /// (degenerate st) or a non-finite result gives 0 (pbrt-v4: `invDet` and every derivative
    /// set to 0 when not finite), and derivatives are clamped to ±1e8.
    #[inline]
    pub fn from_differentials(uv: Vec2, [dpdu, dpdv]: [Vec3; 2], [dpdx, dpdy]: [Vec3; 2]) -> Self {
        let (a00, a01, a11) = (dpdu.dot(dpdu), dpdu.dot(dpdv), dpdv.dot(dpdv));
        let det = f64::from(a00) * f64::from(a11) - f64::from(a01) * f64::from(a01);
        let inv = (1.0 / det) as f32;
        let inv = if inv.is_finite() { inv } else { 0.0 };
        let solve = |d: Vec3| {
            let (b0, b1) = (dpdu.dot(d), dpdv.dot(d));
            Vec2::new(a11 * b0 - a01 * b1, a00 * b1 - a01 * b0) * inv
        };
        let clamp = |v: Vec2| {
            v.to_array().map(|x| {
                if x.is_finite() {
                    x.clamp(-MAX_DERIVATIVE, MAX_DERIVATIVE)
                } else {
                    0.0
                }
            })
        };
        TexCoord {
            uv,
            duvdx: Vec2::from_array(clamp(solve(dpdx))),
            duvdy: Vec2::from_array(clamp(solve(dpdy))),
        }
    }

    /// The filter width in st units: 2 · max |∂s/∂x|, |∂s/∂y|, |∂t/∂x|, |∂t/∂y| (pbrt-v4
    /// `MIPMap::Filter`, for the trilinear and bilinear filters).
    #[inline]
    pub fn filter_width(&self) -> f32 {
        2.0 * self.duvdx.abs().max(self.duvdy.abs()).max_element()
    }

    /// Through an affine map of st (UsdTransform2d): the point maps, derivatives by the
    /// linear part.
    #[inline]
    pub fn transformed(&self, t: &Affine2) -> TexCoord {
        TexCoord {
            uv: t.transform_point2(self.uv),
            duvdx: t.transform_vector2(self.duvdx),
            duvdy: t.transform_vector2(self.duvdy),
        }
    }
}

/// Where texture footprints come from in a render.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum TextureFilter {
    /// No footprint: every lookup is bilinear at the finest level (meters, which have no
    /// pixels).
    #[default]
    Finest,
    /// The camera's pixel footprint at the hit (`Camera::approximate_dp_dxy`) times
    /// `spp_scale`.
    Camera { spp_scale: f32 },
}

impl TextureFilter {
    /// The camera's footprint for a render of `spp` samples per pixel: scaled by
    /// max(1/8, 1/√spp) as pbrt-v4 (`Approximate_dp_dxy`), since the pixel's samples already
    /// average over the pixel. A time-budgeted render (`None`: the count is not known in
    /// advance) takes 1/8, pbrt's floor, reached at 64 spp, so its image does not depend on
    /// how many passes fitted.
    pub fn camera(spp: Option<u64>) -> TextureFilter {
        let scale = match spp {
            Some(n) if n > 0 => (1.0 / (n as f32).sqrt()).max(0.125),
            _ => 0.125,
        };
        TextureFilter::Camera { spp_scale: scale }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn least_squares_recovers_st_derivatives() {
        // A plane with ∂p/∂u = (2, 0, 0), ∂p/∂v = (1, 3, 0): dp = (3, 3, 0) is du = dv = 1.
        let dp = [Vec3::new(2.0, 0.0, 0.0), Vec3::new(1.0, 3.0, 0.0)];
        let tc = TexCoord::from_differentials(
            Vec2::ZERO,
            dp,
            [Vec3::new(3.0, 3.0, 0.0), Vec3::new(-2.0, 0.0, 0.0)],
        );
        assert!((tc.duvdx - Vec2::ONE).length() < 1e-6, "{tc:?}");
        assert!((tc.duvdy - Vec2::new(-1.0, 0.0)).length() < 1e-6, "{tc:?}");
        // A component along the normal is ignored (least squares projects onto the plane).
        let off =
            TexCoord::from_differentials(Vec2::ZERO, dp, [Vec3::new(3.0, 3.0, 5.0), Vec3::ZERO]);
        assert!((off.duvdx - Vec2::ONE).length() < 1e-6);
        assert_eq!(tc.filter_width(), 2.0);
    }

    #[test]
    fn degenerate_systems_give_zero_not_nan() {
        let d = [Vec3::X, Vec3::new(0.0, 1e30, 0.0)];
        for dpduv in [
            [Vec3::ZERO; 2],
            [Vec3::X, Vec3::X],
            [Vec3::X, 2.0 * Vec3::X],
            [Vec3::splat(f32::NAN), Vec3::X],
            [Vec3::splat(1e-30), Vec3::new(0.0, 1e-30, 0.0)],
        ] {
            for dpdxy in [d, [Vec3::splat(f32::INFINITY), Vec3::splat(f32::NAN)]] {
                let tc = TexCoord::from_differentials(Vec2::ONE, dpduv, dpdxy);
                assert!(
                    tc.duvdx.is_finite() && tc.duvdy.is_finite(),
                    "{dpduv:?} {tc:?}"
                );
                assert!(tc.filter_width() <= 2e8);
            }
        }
        // A huge but finite footprint is clamped.
        let tc = TexCoord::from_differentials(Vec2::ONE, [Vec3::X, Vec3::Y], d);
        assert_eq!(tc.duvdy.y, MAX_DERIVATIVE);
    }

    #[test]
    fn spp_scale_follows_pbrt() {
        let s = |n| match TextureFilter::camera(n) {
            TextureFilter::Camera { spp_scale } => spp_scale,
            TextureFilter::Finest => unreachable!(),
        };
        assert_eq!(s(Some(1)), 1.0);
        assert_eq!(s(Some(16)), 0.25);
        assert_eq!(s(Some(1024)), 0.125);
        assert_eq!(s(None), 0.125);
    }

    #[test]
    fn transforms_map_derivatives_by_the_linear_part() {
        let tc = TexCoord {
            uv: Vec2::new(0.5, 0.5),
            duvdx: Vec2::new(0.1, 0.0),
            duvdy: Vec2::new(0.0, 0.2),
        };
        let t = Affine2::from_scale_angle_translation(Vec2::splat(2.0), 0.0, Vec2::ONE);
        let m = tc.transformed(&t);
        assert_eq!(m.uv, Vec2::new(2.0, 2.0));
        assert_eq!(
            (m.duvdx, m.duvdy),
            (Vec2::new(0.2, 0.0), Vec2::new(0.0, 0.4))
        );
    }
}
